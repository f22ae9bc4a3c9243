"""The record :func:`~ctrl_analysis.engine.ivp.simulate_ivp` returns (:class:`SimResult`) and its argument checks.

(:class:`~ctrl_analysis.engine.response.LoopResponse`, what ``Loop.simulate`` returns, is its own class.)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._validate import check_array, check_real, check_seeds

__all__ = ["BatchRuns", "SimResult"]


class BatchRuns:
    """What a batch's result says about its runs, from ``diverged``, ``diverged_step``, ``t`` and ``seeds``."""

    @property
    def ok(self) -> np.ndarray:
        """Mask of runs that stayed finite and bounded.

        Returns
        -------
        numpy.ndarray of bool, shape (B,)
        """
        return ~self.diverged

    @property
    def runs(self) -> int:
        """Number of runs in the batch.

        Returns
        -------
        int
        """
        return int(self.diverged.size)

    def divergences(self) -> list[dict]:
        """One record per diverged run: ``run`` (index), ``step``, ``t`` and ``seed``, and what :meth:`_where` adds.

        Returns
        -------
        list of dict
        """
        out = []
        for b in np.flatnonzero(self.diverged):
            k = int(self.diverged_step[b])
            out.append({"run": int(b), "step": k, "t": float(self.t[min(k, len(self.t) - 1)]),
                        "seed": None if self.seeds is None else self.seeds[b]} | self._where(int(b)))
        return out

    def _where(self, b: int) -> dict:
        """More about run ``b``'s divergence (nothing here)."""
        return {}


@dataclass
class SimResult(BatchRuns):
    """Trajectories of a batch of runs.

    Attributes
    ----------
    t : ndarray, shape (N+1,)
        Sample instants.
    x : ndarray, shape (N+1, B, n) or None
        States at the sample instants (``None`` when not stored).
    u : ndarray, shape (N, B, m) or None
        Inputs held over each step (controller output, or the noise when there is no controller).
    y : ndarray, shape (N+1, B, p) or None
        What ``observe`` returned at each sample instant.
    diverged : ndarray of bool, shape (B,)
    diverged_step : ndarray of int, shape (B,)
        First step index at which the run left the bound (``-1`` if never).
    seeds : list or None
        Per-run seeds, as recorded.
    """

    t: np.ndarray
    x: np.ndarray | None
    u: np.ndarray | None
    y: np.ndarray | None
    diverged: np.ndarray
    diverged_step: np.ndarray
    seeds: list | None = None
    bound: float = np.inf
    info: dict = field(default_factory=dict)


def _check_bound(bound) -> float:
    """``bound`` of the divergence test: a number > 0 (``inf`` turns the test off, NaN or -inf are errors)."""
    bound = check_real("bound", bound)
    if not bound > 0:
        raise ValueError(f"bound must be > 0 (inf disables the check), got {bound!r}")
    return bound


def _prepare(x0, noise, seeds):
    """``x0`` as a ``(B, n)`` float array, the checked noise and seeds, and the batch size ``B``."""
    x0 = check_array("x0", x0)
    if seeds is not None:
        seeds = check_seeds(seeds)
    if x0.ndim not in (1, 2) or x0.shape[-1] == 0:
        raise ValueError(f"x0 must have shape (n,) or (B, n) with n >= 1 states, got {x0.shape}")
    if not np.all(np.isfinite(x0)):
        raise ValueError("x0 must be finite (no NaN or inf)")
    B = x0.shape[0] if x0.ndim == 2 else 1
    if noise is not None:
        noise = np.asarray(noise, dtype=float)
        if noise.ndim != 3:
            raise ValueError(f"noise must have shape (n_steps, B, m), got {noise.shape}")
        if x0.ndim == 1:
            B = noise.shape[1]
        elif noise.shape[1] != B:
            raise ValueError(f"noise has {noise.shape[1]} runs but x0 has {B}")
    if seeds is not None and len(seeds) != B:
        raise ValueError(f"seeds must have one entry per run ({B}), got {len(seeds)}")
    x = np.array(np.broadcast_to(x0, (B, x0.shape[-1])), dtype=float)
    return x, noise, B
