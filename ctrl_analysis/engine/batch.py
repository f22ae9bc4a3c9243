"""A resolved batch: what one :meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` call runs, validated once.

:func:`resolve_batch` turns the call's ``inputs``, ``x0``, ``params``, ``runs`` and ``seeds`` into a
:class:`Batch`: the held inputs and the callable ones, the initial-state matrix ``(B, n_states)``,
the run-time parameters of every block they change (:class:`~ctrl_analysis.engine.params.Variant`:
one parameter row per run), the seeds and the batch size ``B``. An
engine (:mod:`ctrl_analysis.engine.engines`) runs a plan over a batch; :meth:`Batch.take` cuts it to a
chunk of runs, as the per-run inputs, initial states and parameters of a chunk in another process.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validate import check_array, check_finite, check_int
from .blocks import Block
from .engines import kept_columns
from .memory import RESULT_BYTES, check_result_memory
from .params import resolve, runs_of, take

__all__ = ["Batch", "resolve_batch"]


@dataclass(frozen=True)
class Batch:
    """The runs of one simulation, resolved against a loop's :class:`~ctrl_analysis.engine.plan.Plan`.

    Attributes
    ----------
    n_steps : int
        Samples N (signals at N+1 instants).
    t : numpy.ndarray, shape (N+1,)
        The sample instants ``t0 + k dt``.
    held : dict of str -> numpy.ndarray
        External inputs given as arrays: a scalar (0-d), ``(N,)`` or ``(N+1,)`` shared, ``(N, B)`` or
        ``(N+1, B)`` per run.
    funcs : dict of str -> callable
        External inputs given as functions ``f(t)``.
    per_run_funcs : frozenset of str
        The callable inputs returning one value per run (sliced with a chunk).
    x0 : numpy.ndarray, shape (B, n_states)
        Every run's initial state.
    variants : dict of str -> Variant
        The run-time parameters of the blocks ``params`` changes.
    params : dict or None
        ``params`` as given (cut per chunk by :meth:`take`).
    seeds : list of int or None
        Per-run seeds, recorded in the response.
    B : int
        Runs.
    """

    n_steps: int
    t: np.ndarray
    held: dict
    funcs: dict
    per_run_funcs: frozenset
    x0: np.ndarray
    variants: dict
    params: dict | None
    seeds: list | None
    B: int

    def take(self, plan, lo: int, hi: int) -> dict:
        """The keyword arguments of ``Loop.simulate`` that run runs ``lo:hi`` of this batch alone.

        Parameters
        ----------
        plan : Plan
            The loop's plan (its state slices).
        lo, hi : int
            The runs, ``0 <= lo < hi <= B``.

        Returns
        -------
        dict
            ``inputs``, ``x0``, ``params``, ``runs``, ``seeds`` and ``t0``.
        """
        return {"inputs": {s: (a[:, lo:hi] if a.ndim == 2 else a) for s, a in self.held.items()},
                "x0": {name: self.x0[lo:hi, sl] for name, sl in plan.slices.items()},
                "params": take(self.params, self.B, plan, lo, hi), "runs": hi - lo,
                "seeds": None if self.seeds is None else self.seeds[lo:hi], "t0": float(self.t[0])}


def _held(s, v, n_steps):
    """One external input given as a value: checked, as an array."""
    if type(v) is float:  # the common case at one run, checked without numpy's overhead
        if not math.isfinite(v):
            raise ValueError(f"inputs[{s!r}] must be finite (no NaN or inf)")
        return np.float64(v)
    try:
        a = check_array(f"inputs[{s!r}]", v)
    except TypeError:
        raise TypeError(f"inputs[{s!r}] must be a number, an array or a callable f(t), got {v!r:.80}") from None
    if a.ndim > 2 or (a.ndim >= 1 and a.shape[0] not in (n_steps, n_steps + 1)):
        raise ValueError(f"inputs[{s!r}] must be a scalar or have shape (N,) or (N, B) with N = {n_steps} "
                         f"or {n_steps + 1} rows, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"inputs[{s!r}] must be finite (no NaN or inf)")
    return a


def _inputs(plan, inputs, n_steps, runs):
    """External inputs -> (held arrays, callables, B or None)."""
    if inputs is not None and not isinstance(inputs, dict):
        raise TypeError(f"inputs must be a dict of signal name -> value, got {inputs!r:.80}")
    inputs = inputs or {}
    if inputs.keys() != set(plan.external):
        unknown = sorted(set(inputs) - set(plan.external))
        if unknown:
            raise ValueError(f"inputs names signals that are not external inputs of the loop: {unknown}; "
                             f"external inputs are {list(plan.external)}")
        missing = [s for s in plan.external if s not in inputs]
        raise ValueError(f"inputs must give every external input; missing {missing}")
    B, held, funcs = runs, {}, {}
    for s, v in inputs.items():
        if callable(v):
            funcs[s] = v
            continue
        a = _held(s, v, n_steps)
        if a.ndim == 2:
            if B is not None and a.shape[1] != B:
                raise ValueError(f"input {s!r} has {a.shape[1]} runs, expected {B}")
            B = a.shape[1]
        held[s] = a
    return held, funcs, B


def _default_x0(plan) -> np.ndarray:
    """Every block's ``initial_state()`` as one row (asked at every call: a block's attributes may change)."""
    row = np.empty(plan.n_states)
    for p in plan.placed:
        sl = plan.slices.get(p.name)
        if sl is not None and sl.stop > sl.start:
            if type(p.block).initial_state is Block.initial_state:
                row[sl] = 0.0  # Block's default, zeros: one per state of the plan's slice
                continue
            v = np.asarray(p.block.initial_state(), dtype=float).reshape(-1)
            if v.shape != (sl.stop - sl.start,) or not np.isfinite(v).all():
                raise ValueError(f"x0[{p.name!r}]: the block's initial_state() must be finite, with one value "
                                 f"per state, got {v}")
            row[sl] = v
    return row


def _x0(plan, x0, B, variants):
    """The batch's initial states: ``x0`` where given, else each block's ``initial_state()`` under its run-time
    parameters (a per-run ``x0`` given through ``params`` gives each run its own)."""
    x = np.empty((B, plan.n_states))
    x[:] = _default_x0(plan)
    if not x0 and not variants:
        return x
    unknown = set(x0) - set(plan.slices)
    if unknown:
        raise ValueError(f"x0 names unknown blocks {sorted(unknown)}; blocks with states are {list(plan.slices)}")
    for p in plan.placed:
        if p.name not in plan.slices or (p.name not in x0 and p.name not in variants):
            continue
        n = plan.slices[p.name].stop - plan.slices[p.name].start
        if p.name not in x0:
            var = variants[p.name]
            v = var.x0 if var.x0 is not None else np.asarray(var.block.initial_state(), dtype=float).reshape(-1)
        else:
            v = np.asarray(x0[p.name], dtype=float)
        if v.shape not in ((n,), (B, n)):
            raise ValueError(f"x0[{p.name!r}] must have shape ({n},) or ({B}, {n}), got {v.shape}")
        if not np.isfinite(v).all():
            raise ValueError(f"x0[{p.name!r}] must be finite")
        x[:, plan.slices[p.name]] = v
    return x


def resolve_batch(plan, n_steps, *, inputs=None, x0=None, params=None, runs=None, seeds=None, t0=0.0,
                  save=None) -> Batch:
    """Validate one call's inputs, initial states, parameters and seeds into a :class:`Batch`.

    The batch size is ``runs`` when given, else the runs of a per-run input, initial state or
    parameter (their first or second axis, as documented by ``Loop.simulate``), else 1.

    Parameters
    ----------
    plan : Plan
        The loop's plan (:attr:`Loop.plan <ctrl_analysis.engine.loop.Loop.plan>`).
    n_steps : int
    inputs, x0, params, runs, seeds, t0
        As :meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` takes them.
    save : Save, optional
        What the simulation will store: its size is checked against
        :data:`~ctrl_analysis.engine.memory.RESULT_BYTES` as soon as ``B`` is known, before any
        parameter is resolved or any state allocated.

    Returns
    -------
    Batch

    Raises
    ------
    TypeError, ValueError
        Naming the argument and the rule.
    MemoryError
        If what ``save`` stores would not fit (:func:`~ctrl_analysis.engine.memory.check_result_memory`).
    """
    if runs is not None:
        runs = check_int("runs", runs, minimum=1)
    t0 = float(t0) if type(t0) is float and math.isfinite(t0) else float(check_finite("t0", t0, scalar=True))
    if x0 is not None and not isinstance(x0, dict):
        raise TypeError(f"x0 must be a dict of block name -> initial state, got {x0!r:.80}")
    if seeds is not None:
        if isinstance(seeds, (str, bytes)) or not hasattr(seeds, "__len__"):
            raise TypeError(f"seeds must be a sequence of one seed per run, got {seeds!r:.80}")
        seeds = [check_int("seeds", s, minimum=0) for s in seeds]
    held, funcs, B = _inputs(plan, inputs, n_steps, runs)
    if B is None and x0:
        B = max((np.ndim(v) == 2 and np.shape(v)[0]) or 1 for v in x0.values())
        B = None if B == 1 else B
    if B is None and params:
        B = runs_of(plan, params)  # per-run parameters say how many runs
    B = 1 if B is None else B
    if seeds is not None and len(seeds) != B:
        raise ValueError(f"seeds must have one entry per run ({B}), got {len(seeds)}")
    if save is not None:
        width = kept_columns(plan, save.keep)[1].size + (plan.n_states if save.states else 0)
        nbytes = 8 * (n_steps // save.every + 1) * max(width, 1) * B
        if nbytes > RESULT_BYTES:
            check_result_memory(nbytes, RESULT_BYTES, f"Loop.simulate(n_steps={n_steps}, runs={B})")
    variants = resolve(plan, params, B) if params is not None else {}  # validated here, before any work
    t = t0 + plan.dt * np.arange(n_steps + 1)
    # a callable input returning one value per run is sliced with its chunk
    per_run = frozenset(s for s, f in funcs.items() if np.ndim(f(t[0])) == 1 and np.size(f(t[0])) == B > 1) \
        if funcs else frozenset()
    return Batch(n_steps=n_steps, t=t, held=held, funcs=funcs, per_run_funcs=per_run,
                 x0=_x0(plan, x0 or {}, B, variants), variants=variants, params=params, seeds=seeds, B=B)
