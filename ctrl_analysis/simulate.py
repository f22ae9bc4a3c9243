"""Runners that take plain functions (sampled-data, discrete, adaptive ODE), over a batch of runs.

:func:`simulate_sampled` and :func:`simulate_discrete` are thin wrappers: they put the caller's
functions (``rhs``, ``controller``, ``observe``, ``step``) into a :class:`~ctrl_analysis.engine.loop.Loop`
as blocks, and the loop does the time loop, the RK4/Euler steps, the chunks, the storage and the
divergence test. :func:`simulate_ivp` (from :mod:`ctrl_analysis.engine.ivp`) integrates with an
adaptive solver. Seeds and noise are re-exported from :mod:`ctrl_analysis.noise`.

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
    check_names,
    check_positive,
)
from .engine import Execution, Save
from .engine.blocks import MAX_SIGNALS, ContinuousBlock, DiscreteBlock, signal_names
from .engine.integrators import MAX_SUBSTEPS, STEPPERS, euler_step, rk4_step
from .engine.ivp import simulate_ivp
from .engine.loop import Loop, place
from .engine.memory import CHUNK_BYTES, RESULT_BYTES, check_result_memory, chunk_bounds  # noqa: F401 (public API)
from .engine.simresult import SimResult, _check_bound, _prepare
from .noise import draw_noise, gaussian_noise, run_seeds, uniform_noise

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
# The older runners: plain functions run as blocks of a Loop (a Loop of blocks is the engine's way)
# ----------------------------------------------------------------------------------------------

class _FromFunction:
    """A block whose per-step method is ``fn(t, x, u)`` and whose outputs are its states."""

    def __init__(self, fn, states, inputs):
        self.fn, self.states, self.inputs, self.outputs = fn, states, inputs, states


class _Plant(_FromFunction, ContinuousBlock):
    """``dx/dt = fn(t, x, u)``."""

    def rhs(self, t, x, u, params=None):
        return self.fn(t, x, u)


class _Step(_FromFunction, DiscreteBlock):
    """``x(k+1) = fn(t_k, x(k), u(k))``."""

    def update(self, t, x, u, params=None):
        return self.fn(t, x, u)


class _PerSample(DiscreteBlock):
    """``fn(t, u)`` evaluated once at every sample instant and held over the sample (no state).

    A :class:`~ctrl_analysis.engine.blocks.StaticBlock` feeding a continuous block is re-evaluated at
    every integration stage; this block runs once per instant, so ``fn`` may keep state of its own
    between calls, as a runner's ``controller`` and ``observe`` may.
    """

    states = ()
    feedthrough = True

    def __init__(self, fn, inputs, outputs):
        self.fn, self.inputs, self.outputs = fn, inputs, outputs

    def update(self, t, x, u, params=None):
        return x

    def output(self, t, x, u, params=None):
        return self.fn(t, u)


def _rows(value, B):
    """A callback's result as a ``(B, p)`` float array, as the runners store it."""
    return np.asarray(value, dtype=float).reshape(B, -1)


def _split(s, n_a, n_b):
    """``k``, ``a`` and ``b`` (``None`` without columns) from a per-sample block's input columns ``[a | b | k]``."""
    return int(s[0, -1]), s[:, :n_a].copy(), (s[:, n_a:n_a + n_b].copy() if n_b else None)


def _loop_inputs(noise, n_steps, base, k):
    """The noise channels' signal names, and the loop's external inputs: the channels and the sample index ``k``."""
    names = ()
    if noise is not None:
        if noise.shape[0] < n_steps:
            raise ValueError(f"noise must have at least n_steps={n_steps} rows, got {noise.shape[0]}")
        if not np.all(np.isfinite(noise[:n_steps])):
            raise ValueError("noise must be finite (no NaN or inf)")
        names = signal_names(base, noise.shape[2])
    inputs = {s: noise[:n_steps, :, j] for j, s in enumerate(names)}
    if k:
        inputs["k"] = np.arange(n_steps + 1, dtype=float)
    return names, inputs


def _recorder(observe, inputs, n_a, rows):
    """A placed block appending ``observe(k, t, a, b)`` to ``rows[k]`` for ``k < len(rows)``.

    ``observe``'s width is known only from its results, so they are kept here, not as signals;
    chunks of runs are stepped in order, so ``rows[k]`` joined holds every run's row ``k``.
    """
    def record(t, s):
        k, a, b = _split(s, n_a, len(inputs) - n_a - 1)
        if k < len(rows):
            rows[k].append(_rows(observe(k, t, a, b), len(s)))
        return np.empty((len(s), 0))

    return place(_PerSample(record, inputs, ()), "observe")


def _result(res, u_sig, rows, seeds, bound) -> SimResult:
    """The runners' :class:`SimResult` from the loop's response: ``u`` from signals ``u_sig``, ``y`` from ``rows``."""
    n = len(res.t) - 1
    return SimResult(t=res.t, x=res.x, u=np.stack([res[s][:n] for s in u_sig], axis=-1) if u_sig else None,
                     y=None if rows is None else np.stack([np.concatenate(r) for r in rows]), diverged=res.diverged,
                     diverged_step=res.diverged_step, seeds=None if seeds is None else list(seeds), bound=bound)


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

    A thin wrapper over :class:`~ctrl_analysis.engine.loop.Loop` (numpy engine), which steps,
    chunks, stores and tests for divergence: ``rhs`` becomes a continuous block whose outputs are
    its states, ``controller`` and ``observe`` blocks run once per sample, the noise channels
    external inputs. New code can build such a loop from blocks directly.

    Parameters
    ----------
    rhs : callable
        ``rhs(t, x, u, params)`` with ``x`` of shape ``(B, n)``; returns the same shape. ``u`` is
        ``None`` without a controller and without noise.
    x0 : array_like, shape (n,) or (B, n)
        Initial state (broadcast over the runs of ``noise`` when 1-D).
    h : float
        Sampling period (> 0).
    n_steps : int
        Number of samples N; states are returned at N+1 instants.
    controller : callable, optional
        ``controller(k, t, x, w) -> u`` of shape ``(B, m)``, called once per sample ``k = 0..N-1``
        with the whole plant state; may keep its own state. The call at ``k = 0`` is made before
        the loop is built (it tells ``m``).
    noise : ndarray, shape (n_steps, B, m), optional
        Held noise, e.g. from :func:`draw_noise` (finite; rows after ``n_steps`` are not used).
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
        If the stored trajectories of the whole batch would exceed half the physical memory.
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
    x, noise, B = _prepare(x0, noise, seeds)
    w_sig, inputs = _loop_inputs(noise, n_steps, "w" if controller is not None else "u",
                                 controller is not None or observe is not None)
    # when to chunk: the legacy rule (working arrays of the whole batch), so a batch stepped whole
    # before still is; the loop steps the chunks
    limit = CHUNK_BYTES if max_bytes is None else check_positive("max_bytes", max_bytes)
    size = B if chunk_runs is None else check_int("chunk_runs", chunk_runs, minimum=1)
    if chunk_runs is None and 8 * 16 * x.shape[1] * B > limit:
        size = max(1, int(limit // (8 * 16 * x.shape[1])))
    if size < B and controller is not None:
        raise ValueError("chunk_runs must be None (or >= the batch size) with a controller: a controller "
                         f"may keep state across calls, got chunk_runs={chunk_runs}")

    x_sig, u_sig, blocks, rows = signal_names("x", x.shape[1]), w_sig, [], None
    if controller is not None:
        u0 = _rows(controller(0, np.float64(t0), x, None if noise is None else noise[0]), B)
        u_sig = signal_names("u", u0.shape[1])  # sized by the first call, which the block returns at k = 0

        def discrete_part(t, s):
            k, xk, wk = _split(s, len(x_sig), len(w_sig))
            if k == 0:
                return u0
            # no controller call at the last sample (u has N rows); a finite placeholder, never read, so the
            # loop's test of its signals does not take it for a diverged run
            return np.zeros_like(u0) if k == n_steps else _rows(controller(k, t, xk, wk), len(s))

        blocks.append(place(_PerSample(discrete_part, x_sig + w_sig + ("k",), u_sig), "controller"))
    blocks.insert(0, place(_Plant(lambda t, xx, u: rhs(t, xx, u if u_sig else None, params), x_sig, u_sig), "plant"))
    if observe is not None:
        rows = [[] for _ in range(n_steps + 1)]
        blocks.append(_recorder(lambda k, t, xk, uk: observe(k, t, xk, uk if k < n_steps else None),
                                x_sig + u_sig + ("k",), len(x_sig), rows))
    res = Loop(blocks, h, method=method, substeps=substeps).simulate(
        n_steps, inputs=inputs, x0={"plant": x}, runs=B,
        save=Save(keep=u_sig, states=store_states),
        execution=Execution(engine="numpy", bound=bound, chunk_runs=size, progress=False), t0=t0)
    return _result(res, u_sig, rows, seeds, bound)


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

    A thin wrapper over :class:`~ctrl_analysis.engine.loop.Loop` (numpy engine, ``dt = 1``): ``step``
    becomes a discrete block, ``observe`` a block run once per sample.

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
    check_result_memory(8.0 * (n_steps + 1) * B * (x.shape[1] + 1), RESULT_BYTES,
                        f"simulate_discrete(n_steps={n_steps}, {B} runs)")
    w_sig, inputs = _loop_inputs(noise, n_steps, "w", True)
    x_sig, rows = signal_names("x", x.shape[1]), None

    def update(t, xk, s):
        k, _, wk = _split(s, 0, len(w_sig))
        return _rows(step(k, xk, wk, params), len(xk))

    blocks = [place(_Step(update, x_sig, w_sig + ("k",)), "step")]
    if observe is not None:
        rows = [[] for _ in range(n_steps)]
        blocks.append(_recorder(lambda k, t, xk, wk: observe(k, xk, wk), x_sig + w_sig + ("k",), len(x_sig), rows))
    res = Loop(blocks, 1.0).simulate(n_steps, inputs=inputs, x0={"step": x}, runs=B,
                                     save=Save(keep=(), states=store_states),
                                     execution=Execution(engine="numpy", bound=bound, chunk_runs=B, progress=False))
    return _result(res, (), rows, seeds, bound)


# ----------------------------------------------------------------------------------------------
# python-control interoperability
# ----------------------------------------------------------------------------------------------

def _signal_spec(name: str, value):
    """A signal count (0 to MAX_SIGNALS) or a list of names, as :func:`control.nlsys` takes them."""
    if isinstance(value, (list, tuple, str)):
        return check_names(name, value)
    return check_int(name, value, minimum=0, maximum=MAX_SIGNALS)


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
    states, inputs = _signal_spec("states", states), _signal_spec("inputs", inputs)
    outputs = None if outputs is None else _signal_spec("outputs", outputs)

    def updfcn(t, x, u, p):
        return np.asarray(rhs(t, np.atleast_2d(x), np.atleast_2d(u), p if p else params)).reshape(-1)

    outfcn = None
    if output is not None:
        def outfcn(t, x, u, p):
            return np.asarray(output(t, np.atleast_2d(x), np.atleast_2d(u), p if p else params)).reshape(-1)

    if outputs is None:
        outputs = states
    return ct.nlsys(updfcn, outfcn, states=states, inputs=inputs, outputs=outputs, name=name)

