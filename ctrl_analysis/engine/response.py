"""The result of a :class:`~ctrl_analysis.engine.loop.Loop` simulation: every signal by name, over the batch."""

from __future__ import annotations

import numpy as np

from .._validate import check_int
from .simresult import BatchRuns

__all__ = ["LoopResponse"]


class LoopResponse(BatchRuns):
    """What a :class:`~ctrl_analysis.engine.loop.Loop` simulation returns: every signal by name, over the batch.

    Parameters
    ----------
    t : numpy.ndarray, shape (N+1,)
        The stored sample instants.
    x : numpy.ndarray, shape (N+1, B, n) or None
        The states at those instants (``None`` when not stored, ``Save(states=False)``).
    diverged : numpy.ndarray of bool, shape (B,)
    diverged_step : numpy.ndarray of int, shape (B,)
        First step index at which the run left the bound or went non-finite (``-1`` if never).
    signals : dict of str -> numpy.ndarray, shape (N+1, B)
        Every kept signal at every stored instant (external inputs included).
    slices : dict of str -> slice
        Each block's part of the state vector.
    external, outlist : tuple of str
        The loop's external inputs and reported outputs.
    state_names : sequence of str
        ``block.state`` of every state, in state-vector order.
    seeds : list or None
        Per-run seeds, as recorded.
    bound : float
        The divergence bound used.
    x_final : numpy.ndarray, shape (B, n), optional
        The states at the last instant (also when the trajectory is not stored).
    diverged_where : numpy.ndarray of int, shape (B,), optional
        Per run: the index in ``where_names`` of the state or signal that first went bad (-1: none).
    where_names : sequence of str, optional
        How a divergence names each state, then each signal.

    Attributes
    ----------
    signals, t, x, diverged, diverged_step, seeds, bound, x_final, diverged_where, where_names
        As given.
    info : dict
        Free-form notes a caller may add.
    states : dict of str -> ndarray, shape (N+1, B, n)
        Each block's states (views into ``x``), when stored.
    final_states : dict of str -> ndarray, shape (B, n)
        Each block's state at the last instant, e.g. the ``x0`` of a continuation.
    """

    def __init__(self, *, t, x, diverged, diverged_step, signals, slices, external, outlist, state_names, seeds=None,
                 bound=np.inf, x_final=None, diverged_where=None, where_names=None):
        self.t = t
        self.x = x
        self.diverged = diverged
        self.diverged_step = diverged_step
        self.seeds = seeds
        self.bound = bound
        self.info = {}
        self.diverged_where = (np.full(diverged.size, -1, dtype=int) if diverged_where is None
                               else np.asarray(diverged_where, dtype=int))
        self.where_names = list(where_names or [])
        self.signals = signals
        self.x_final = x_final
        self._slices = slices
        self.external = external
        self.outlist = outlist
        self.state_names = list(state_names)

    def __repr__(self) -> str:
        return (f"LoopResponse(runs={self.runs}, instants={len(self.t)}, signals={list(self.signals)}, "
                f"diverged={int(self.diverged.sum())})")

    @property
    def states(self) -> dict:
        """Each block's state trajectory (views into ``x``; empty when states were not stored).

        Returns
        -------
        dict of str -> numpy.ndarray, shape (N+1, B, n)
        """
        if self.x is None:
            return {}
        return {name: self.x[:, :, sl] for name, sl in self._slices.items()}

    @property
    def final_states(self) -> dict:
        """Each block's state at the last instant, also when the trajectory was not stored.

        Returns
        -------
        dict of str -> numpy.ndarray, shape (B, n)
            Ready to pass as ``x0`` to continue the simulation (with ``t0`` the last instant).
        """
        if self.x_final is None:
            return {}
        return {name: self.x_final[:, sl] for name, sl in self._slices.items()}

    def divergences(self) -> list[dict]:
        """One record per diverged run: ``run``, ``step``, ``t``, ``seed`` and ``where``.

        ``where`` names what went bad first: a state (``block.state``) that left the bound or is not finite, or a
        signal that is not finite (``block.signal (output of block 'block')``, or an input of the loop).

        Returns
        -------
        list of dict
        """
        return super().divergences()

    def _where(self, b: int) -> dict:
        code = int(self.diverged_where[b])
        return {"where": self.where_names[code] if 0 <= code < len(self.where_names) else None}

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.signals[name]
        except KeyError:
            raise KeyError(f"no signal {name!r}; signals are {sorted(self.signals)}") from None

    def to_timeresponse(self, run: int = 0, outputs=None):
        """One run as a ``control.TimeResponseData``.

        Parameters
        ----------
        run : int
            Which run of the batch (0-based).
        outputs : sequence of str, optional
            Signals to report as outputs (default: the loop's ``outputs``).

        Returns
        -------
        control.TimeResponseData
            Time, outputs, the loop's states (when stored) and its external inputs.
        """
        import control as ct

        run = check_int("run", run, minimum=0, maximum=self.runs - 1)
        outs = list(self.outlist if outputs is None else outputs)
        y = np.stack([self[n][:, run] for n in outs])
        u = np.stack([self[n][:, run] for n in self.external]) if self.external else None
        x = self.x[:, run, :].T if self.x is not None else None
        return ct.TimeResponseData(self.t, y, x, u, output_labels=outs,
                                   input_labels=list(self.external) or None,
                                   state_labels=self.state_names if x is not None else None,
                                   issiso=False)
