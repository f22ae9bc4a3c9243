"""The simulation engine: discrete loops, sampled-data loops and smooth ODE loops, over a batch of runs.

Conventions
-----------
* Every state array has shape ``(B, n)``: ``B`` independent runs (Monte Carlo seeds or points of a
  parameter grid) advance together; time is the Python loop, the batch is vectorised.
* A continuous right-hand side is ``rhs(t, x, u, params) -> dx/dt`` (python-control's order); it
  must accept ``x`` of shape ``(B, n)`` and ``u`` of shape ``(B, m)`` (or ``None``).
* Noise is drawn before the loop, one :class:`numpy.random.Generator` per run seeded with that
  run's recorded seed, so a batch equals the stacked single runs and the same seed always gives the
  same numbers. White noise in a sampled-data loop is drawn once per step and held over it.
* A run whose state becomes non-finite or exceeds ``bound`` is flagged (run index and step), its
  state set to NaN from then on, and it is excluded by :attr:`SimResult.ok`; it is never silently
  averaged.
* A batch whose working arrays exceed :data:`CHUNK_BYTES` is stepped in chunks of runs (each run's
  result unchanged); a stored result larger than half the physical memory raises a
  :class:`MemoryError` saying what to do (:func:`check_result_memory`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ._validate import (
    check_callable,
    check_finite,
    check_in,
    check_int,
    check_positive,
)
from .engine.integrators import (
    MAX_SUBSTEPS,
    STEPPERS,
    _flag_divergence,
    euler_step,
    rk4_step,
)
from .engine.ivp import simulate_ivp
from .engine.memory import CHUNK_BYTES, RESULT_BYTES, check_result_memory, chunk_bounds  # noqa: F401
from .engine.simresult import SimResult, _check_bound, _prepare
from .noise import _check_seeds, draw_noise, gaussian_noise, run_seeds, uniform_noise  # noqa: F401 (public API)

__all__ = [
    "CHUNK_BYTES",
    "MAX_SUBSTEPS",
    "STEPPERS",
    "SimResult",
    "check_result_memory",
    "chunk_bounds",
    "continuous_nlsys",
    "draw_noise",
    "euler_step",
    "gaussian_noise",
    "rk4_step",
    "run_seeds",
    "simulate_discrete",
    "simulate_ivp",
    "simulate_sampled",
    "uniform_noise",
]


# ----------------------------------------------------------------------------------------------
# The older runners (a Loop with blocks is the engine's way; these take plain functions)
# ----------------------------------------------------------------------------------------------

def _store(buf, k, value, n_rows, B):
    """Store ``value`` (reshaped to ``(B, -1)``) as row ``k`` of ``buf``, allocating it on first use."""
    arr = np.asarray(value, dtype=float).reshape(B, -1)
    if buf is None:
        buf = np.empty((n_rows, B, arr.shape[1]))
    buf[k] = arr
    return buf


# ----------------------------------------------------------------------------------------------
# Runners
# ----------------------------------------------------------------------------------------------

def simulate_sampled(
    rhs: Callable,
    x0,
    h: float,
    n_steps: int,
    *,
    controller: Callable | None = None,
    noise=None,
    method: str = "rk4",
    substeps: int = 1,
    t0: float = 0.0,
    params=None,
    observe: Callable | None = None,
    store_states: bool = True,
    bound: float = 1e8,
    seeds=None,
    chunk_runs: int | None = None,
    max_bytes: float | None = None,
) -> SimResult:
    """Sampled-data loop: a continuous part integrated with a fixed step, inputs held per sample.

    At each sample ``k`` (time ``t_k = t0 + k h``) the discrete part runs once,
    ``u_k = controller(k, t_k, x_k, w_k)`` (``u_k = w_k`` without a controller), and the continuous
    part ``x' = rhs(t, x, u_k, params)`` is integrated over ``[t_k, t_k + h]`` with ``substeps``
    fixed steps of ``method`` (``"rk4"`` or ``"euler"``), ``u_k`` and the noise ``w_k`` held.

    Parameters
    ----------
    rhs : callable
        ``rhs(t, x, u, params)`` with ``x`` of shape ``(B, n)``; returns the same shape.
    x0 : array_like, shape (n,) or (B, n)
        Initial state (broadcast over the runs of ``noise`` when 1-D).
    h : float
        Sampling period (> 0).
    n_steps : int
        Number of samples N; states are returned at N+1 instants.
    controller : callable, optional
        ``controller(k, t, x, w) -> u`` of shape ``(B, m)``; may keep its own state.
    noise : ndarray, shape (n_steps, B, m), optional
        Held noise, e.g. from :func:`draw_noise`.
    observe : callable, optional
        ``observe(k, t, x, u) -> (B, p)`` stored at every instant (``u`` is ``None`` at the last).
    store_states : bool
        Keep the whole state trajectory (``False`` saves memory in large batches).
    bound : float
        A run whose state leaves ``|x| <= bound`` or becomes non-finite is flagged as diverged.
    seeds : list, optional
        Per-run seeds, recorded in the result.
    chunk_runs : int, optional
        Step the batch in chunks of at most this many runs (default: chunks only when the working
        arrays of the whole batch exceed ``max_bytes``). Only without a ``controller`` (which may
        keep state across calls); ``rhs`` and ``observe`` must treat runs independently, with
        parameters shared by all runs. Each run's result is the same bit for bit.
    max_bytes : float, optional
        Working memory per chunk (default :data:`CHUNK_BYTES`).

    Returns
    -------
    SimResult

    Raises
    ------
    MemoryError
        If the stored states of the whole batch would exceed half the physical memory.
    """
    check_callable("rhs", rhs, "rhs(t, x, u, params)")
    check_callable("controller", controller, "controller(k, t, x, w)", optional=True)
    check_callable("observe", observe, "observe(k, t, x, u)", optional=True)
    h = check_positive("h", h, scalar=True)
    n_steps = check_int("n_steps", n_steps, minimum=1)
    substeps = check_int("substeps", substeps, minimum=1, maximum=MAX_SUBSTEPS)
    check_in("method", method, STEPPERS)
    bound = _check_bound(bound)
    t0 = check_finite("t0", t0, scalar=True)
    step = STEPPERS[method]
    x, noise, B = _prepare(x0, noise, seeds)
    if noise is not None and noise.shape[0] < n_steps:
        raise ValueError(f"noise must have at least n_steps={n_steps} rows, got {noise.shape[0]}")

    if store_states:
        check_result_memory(8.0 * (n_steps + 1) * B * x.shape[1], RESULT_BYTES, "simulate_sampled")
    limit = CHUNK_BYTES if max_bytes is None else check_positive("max_bytes", max_bytes)
    size = B if chunk_runs is None else check_int("chunk_runs", chunk_runs, minimum=1)
    if chunk_runs is None and 8 * 16 * x.shape[1] * B > limit:
        size = max(1, int(limit // (8 * 16 * x.shape[1])))
    if size < B:
        if controller is not None:
            raise ValueError("chunk_runs must be None (or >= the batch size) with a controller: a controller "
                             f"may keep state across calls, got chunk_runs={chunk_runs}")
        parts = [simulate_sampled(rhs, x[lo:hi], h, n_steps, noise=None if noise is None else noise[:, lo:hi],
                                  method=method, substeps=substeps, t0=t0, params=params, observe=observe,
                                  store_states=store_states, bound=bound, chunk_runs=hi - lo)
                 for lo, hi in chunk_bounds(B, size)]
        return _join(parts, seeds)

    t = t0 + h * np.arange(n_steps + 1)
    xs = np.empty((n_steps + 1, B, x.shape[1])) if store_states else None
    us = None
    ys = None
    diverged = np.zeros(B, dtype=bool)
    div_step = np.full(B, -1, dtype=int)
    dt = h / substeps
    with np.errstate(all="ignore"):
        for k in range(n_steps):
            if xs is not None:
                xs[k] = x
            w = None if noise is None else noise[k]
            u = controller(k, t[k], x, w) if controller is not None else w
            if observe is not None:
                ys = _store(ys, k, observe(k, t[k], x, u), n_steps + 1, B)
            if u is not None:
                us = _store(us, k, u, n_steps, B)
            tk = t[k]
            for _ in range(substeps):
                x = step(rhs, tk, x, u, dt, params)
                tk += dt
            x = _flag_divergence(x, bound, diverged, div_step, k + 1)
        if xs is not None:
            xs[n_steps] = x
        if observe is not None:
            ys = _store(ys, n_steps, observe(n_steps, t[n_steps], x, None), n_steps + 1, B)
    return SimResult(t=t, x=xs, u=us, y=ys, diverged=diverged, diverged_step=div_step,
                     seeds=None if seeds is None else list(seeds), bound=bound)


def _join(parts: list, seeds) -> SimResult:
    """One :class:`SimResult` from results of consecutive chunks of a batch (runs on axis 1)."""

    def cat(name, axis):
        arrays = [getattr(p, name) for p in parts]
        return None if arrays[0] is None else np.concatenate(arrays, axis=axis)

    first = parts[0]
    return SimResult(t=first.t, x=cat("x", 1), u=cat("u", 1), y=cat("y", 1), diverged=cat("diverged", 0),
                     diverged_step=cat("diverged_step", 0), seeds=None if seeds is None else list(seeds),
                     bound=first.bound)


def simulate_discrete(
    step: Callable,
    x0,
    n_steps: int,
    *,
    noise=None,
    params=None,
    observe: Callable | None = None,
    store_states: bool = True,
    bound: float = 1e8,
    seeds=None,
) -> SimResult:
    """Discrete loop ``x(k+1) = step(k, x(k), w(k), params)`` over a batch of runs.

    ``step`` receives ``x`` of shape ``(B, n)`` and the noise row ``w(k)`` of shape ``(B, m)``
    (``None`` without noise). Divergence is detected as in :func:`simulate_sampled`.
    ``observe(k, x, w) -> (B, p)`` is stored for ``k = 0..N-1``.

    Parameters
    ----------
    step : callable
        ``step(k, x, w, params) -> x_next``.
    x0 : array_like, shape (n,) or (B, n)
    n_steps : int
    noise : ndarray, shape (n_steps, B, m), optional
    params, observe, store_states, bound, seeds
        As in :func:`simulate_sampled`.

    Returns
    -------
    SimResult
    """
    check_callable("step", step, "step(k, x, w, params)")
    check_callable("observe", observe, "observe(k, x, w)", optional=True)
    n_steps = check_int("n_steps", n_steps, minimum=1)
    bound = _check_bound(bound)
    x, noise, B = _prepare(x0, noise, seeds)
    if noise is not None and noise.shape[0] < n_steps:
        raise ValueError(f"noise must have at least n_steps={n_steps} rows, got {noise.shape[0]}")
    xs = np.empty((n_steps + 1, B, x.shape[1])) if store_states else None
    ys = None
    diverged = np.zeros(B, dtype=bool)
    div_step = np.full(B, -1, dtype=int)
    with np.errstate(all="ignore"):
        for k in range(n_steps):
            if xs is not None:
                xs[k] = x
            w = None if noise is None else noise[k]
            if observe is not None:
                ys = _store(ys, k, observe(k, x, w), n_steps, B)
            x = np.asarray(step(k, x, w, params), dtype=float).reshape(B, -1)
            x = _flag_divergence(x, bound, diverged, div_step, k + 1)
        if xs is not None:
            xs[n_steps] = x
    return SimResult(t=np.arange(n_steps + 1, dtype=float), x=xs, u=None, y=ys, diverged=diverged,
                     diverged_step=div_step, seeds=None if seeds is None else list(seeds), bound=bound)




# ----------------------------------------------------------------------------------------------
# python-control interoperability
# ----------------------------------------------------------------------------------------------

def continuous_nlsys(rhs: Callable, *, states, inputs, outputs=None, output: Callable | None = None,
                     params=None, name: str | None = None):
    """Wrap a batched right-hand side as a :class:`control.NonlinearIOSystem` (``control.nlsys``).

    python-control calls the update function with 1-D ``x`` and ``u``; they are lifted to a batch of
    one, so the same ``rhs`` serves the engine and :func:`control.interconnect`.

    Parameters
    ----------
    rhs : callable
        ``rhs(t, x, u, params)`` accepting ``x`` of shape ``(1, n)`` and ``u`` of shape ``(1, m)``.
    states, inputs, outputs : int or list of str
        Signal counts or names, as for :func:`control.nlsys`.
    output : callable, optional
        ``output(t, x, u, params)`` (batched like ``rhs``); default: the full state.

    Returns
    -------
    control.NonlinearIOSystem
    """
    import control as ct

    check_callable("rhs", rhs, "rhs(t, x, u, params)")
    check_callable("output", output, "output(t, x, u, params)", optional=True)

    def updfcn(t, x, u, p):
        return np.asarray(rhs(t, np.atleast_2d(x), np.atleast_2d(u), p if p else params)).reshape(-1)

    outfcn = None
    if output is not None:
        def outfcn(t, x, u, p):
            return np.asarray(output(t, np.atleast_2d(x), np.atleast_2d(u), p if p else params)).reshape(-1)

    if outputs is None:
        outputs = states
    return ct.nlsys(updfcn, outfcn, states=states, inputs=inputs, outputs=outputs, name=name)

