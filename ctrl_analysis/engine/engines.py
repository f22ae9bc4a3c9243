"""Engines: running a :class:`~ctrl_analysis.engine.plan.Plan` over a :class:`~ctrl_analysis.engine.batch.Batch`.

Every engine follows one protocol, :class:`Engine`: ``run(plan, batch, save, execution)`` returns a
:class:`~ctrl_analysis.engine.response.LoopResponse`. :class:`NumpyEngine` steps the blocks' batched
methods (:func:`~ctrl_analysis.engine.numpy_engine.run_numpy`); :class:`CompiledEngine` runs one
generated numba function (:mod:`ctrl_analysis.engine.codegen`, :func:`~ctrl_analysis.engine.compiled.run_compiled`).
Both step the batch in chunks of runs (:attr:`Execution.chunk_runs <ctrl_analysis.engine.policies.Execution>`,
``max_bytes``) and write into one :class:`Record`; :func:`select_engine` picks the engine an
:class:`~ctrl_analysis.engine.policies.Execution` asks for (``"auto"``: compiled when every block has
a kernel, otherwise numpy, said once per loop), or, for a batch split over processes,
:class:`~ctrl_analysis.engine.processes.ProcessEngine`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

from .compiled import compiled_for, run_compiled
from .memory import CHUNK_BYTES, chunk_bounds
from .response import LoopResponse

__all__ = ["AUTO_BAR_WORK", "CLUSTER_MIN_WORK", "CompiledEngine", "Engine", "NumpyEngine", "Record", "kept_columns",
           "select_engine"]

#: Run-samples (runs x samples) from which a simulation shows a progress bar of its own (when stderr
#: is a terminal): about a second of work on the numpy engine.
AUTO_BAR_WORK = 2_000_000

#: Run-samples from which a compiled simulation goes to a process-wide Dask cluster by itself (``jobs=1``;
#: a numpy-engine one from a hundredth of it, being 30-100x slower a run-sample): below, shipping it (a
#: round trip, and every worker loading the loop's runner the first time) costs more than it saves; on
#: two workers ckf's 1-3·10^6 run-sample batches took 2.4 s longer shipped. ``Execution(jobs > 1)``
#: splits any batch as asked.
CLUSTER_MIN_WORK = 10_000_000


class Engine(Protocol):
    """What runs a plan over a batch: ``run(plan, batch, save, execution) -> LoopResponse``.

    Parameters
    ----------
    *args
        An engine's own (none for :class:`NumpyEngine`; the runner for :class:`CompiledEngine`).

    Attributes
    ----------
    name : str
        ``"numpy"``, ``"compiled"`` or ``"processes"``.
    """

    name: str

    def run(self, plan, batch, save, execution) -> LoopResponse:
        """Step every run of ``batch`` through ``plan``, storing what ``save`` asks, as ``execution`` says.

        Parameters
        ----------
        plan : Plan
            The loop's plan (:attr:`Loop.plan <ctrl_analysis.engine.loop.Loop.plan>`).
        batch : Batch
            The resolved runs (:func:`~ctrl_analysis.engine.batch.resolve_batch`).
        save : Save
        execution : Execution

        Returns
        -------
        LoopResponse
        """


@dataclass(frozen=True)
class Record:
    """The arrays a simulation writes into (one chunk's view of them from :meth:`part`).

    Attributes
    ----------
    keep : numpy.ndarray of int
        The signal columns stored.
    every : int
        Every ``every``-th sample is stored.
    store : numpy.ndarray, shape (N // every + 1, B, len(keep))
    xs : numpy.ndarray, shape (N // every + 1, B, n_states), or None
    x : numpy.ndarray, shape (B, n_states)
        The initial states, replaced by the final states as the runs end.
    diverged, div_step, div_where : numpy.ndarray, shape (B,)
        Divergence flags, first step, and what went bad first (a state index, or ``n_states`` plus
        a signal column).
    """

    keep: np.ndarray
    every: int
    store: np.ndarray
    xs: np.ndarray | None
    x: np.ndarray
    diverged: np.ndarray
    div_step: np.ndarray
    div_where: np.ndarray

    def part(self, lo: int, hi: int) -> Record:
        """Views of runs ``lo:hi``.

        Parameters
        ----------
        lo, hi : int

        Returns
        -------
        Record
        """
        return Record(self.keep, self.every, self.store[:, lo:hi], None if self.xs is None else self.xs[:, lo:hi],
                      self.x[lo:hi], self.diverged[lo:hi], self.div_step[lo:hi], self.div_where[lo:hi])


def kept_columns(plan, keep) -> tuple:
    """The signal names and columns ``Save.keep`` stores (all signals for ``None``), checked once per plan.

    Parameters
    ----------
    plan : Plan
    keep : tuple of str or None

    Returns
    -------
    tuple
        ``(names, columns)``.

    Raises
    ------
    ValueError
        For a name that is not a signal of the loop.
    """
    memo = plan.cache.setdefault("keep", {})
    if keep not in memo:
        names = plan.names if keep is None else keep
        for s in names:
            if s not in plan.col:
                raise ValueError(f"keep names unknown signal {s!r}; signals are {list(plan.names)}")
        memo[keep] = (tuple(names), np.array([plan.col[s] for s in names], dtype=np.intp))
    return memo[keep]


def _allocate(plan, batch, save) -> Record:
    n_kept = batch.n_steps // save.every + 1
    keep = kept_columns(plan, save.keep)[1]
    B = batch.B
    flags = np.empty((2, B), dtype=int)
    flags.fill(-1)
    return Record(keep, save.every, np.empty((n_kept, B, keep.size)),
                  np.empty((n_kept, B, plan.n_states)) if save.states else None,
                  batch.x0.copy(), np.zeros(B, dtype=bool), flags[0], flags[1])


def _respond(plan, batch, save, rec, bound) -> LoopResponse:
    names = kept_columns(plan, save.keep)[0]
    return LoopResponse(t=batch.t[::save.every], x=rec.xs, diverged=rec.diverged, diverged_step=rec.div_step,
                        seeds=batch.seeds, bound=bound, signals={s: rec.store[:, :, j] for j, s in enumerate(names)},
                        slices=plan.slices, external=plan.external, outlist=plan.outlist,
                        state_names=plan.state_names, x_final=rec.x, diverged_where=rec.div_where,
                        where_names=plan.where_names)


def _chunks(plan, batch, save, execution) -> list:
    """The chunks ``(lo, hi)`` the batch is stepped in: ``chunk_runs``, or as many runs as ``max_bytes`` allows."""
    B = batch.B
    if execution.chunk_runs is not None:
        return chunk_bounds(B, execution.chunk_runs)
    if B == 1:
        return [(0, 1)]
    n_keep = kept_columns(plan, save.keep)[1].size
    per_run = 8 * (batch.n_steps // save.every + 1) * max(n_keep + (plan.n_states if save.states else 0), 1)
    work = 8 * (8 * plan.n_states + 2 * len(plan.names)) + per_run  # temporaries + stored rows, per run
    limit = CHUNK_BYTES if execution.max_bytes is None else execution.max_bytes
    return chunk_bounds(B, max(1, min(B, int(limit // work))))


class _Progress:
    """The progress reporting of one simulation (a context manager giving ``update(n)`` or ``None``)."""

    def __init__(self, batch, execution):
        self.batch, self.progress = batch, execution.progress
        self.cm = None

    def __enter__(self):
        work = self.batch.B * self.batch.n_steps
        if self.progress is False or (self.progress is None and work < AUTO_BAR_WORK):
            return None
        from ..runs.progress import enabled, updater

        show = enabled() if self.progress is None else self.progress  # True: a bar (a no-op off a terminal)
        self.cm = updater(show, work, f"{self.batch.B} runs x {self.batch.n_steps} samples", "run-sample")
        return self.cm.__enter__()

    def __exit__(self, *exc):
        return None if self.cm is None else self.cm.__exit__(*exc)


class NumpyEngine:
    """The numpy engine: the blocks' batched methods, chunk by chunk (:mod:`~ctrl_analysis.engine.numpy_engine`)."""

    name = "numpy"

    def run(self, plan, batch, save, execution) -> LoopResponse:
        """Step ``batch`` through ``plan`` (see :class:`Engine`).

        Parameters
        ----------
        plan : Plan
        batch : Batch
        save : Save
        execution : Execution

        Returns
        -------
        LoopResponse
        """
        from .numpy_engine import run_numpy
        from .params import chunk_functions

        rec = _allocate(plan, batch, save)
        ids = {id(p.block): batch.variants[p.name] for p in plan.placed if p.name in batch.variants}
        with _Progress(batch, execution) as progress:
            for lo, hi in _chunks(plan, batch, save, execution):
                funcs = {s: (f if s not in batch.per_run_funcs else
                             (lambda tt, f=f, lo=lo, hi=hi: np.asarray(f(tt))[lo:hi])) for s, f in batch.funcs.items()}
                held = {s: (a[:, lo:hi] if a.ndim == 2 else a) for s, a in batch.held.items()}
                chunk_plan = replace(plan, **chunk_functions(plan, ids, lo, hi - lo))
                run_numpy(chunk_plan, batch.t, held, funcs, execution.bound, rec.part(lo, hi), progress)
        return _respond(plan, batch, save, rec, execution.bound)


class CompiledEngine:
    """The compiled engine: one generated numba function per loop structure, run chunk by chunk.

    Parameters
    ----------
    runner : tuple
        ``(run, P, per_run)`` from :func:`~ctrl_analysis.engine.compiled.compiled_for`.
    """

    name = "compiled"

    def __init__(self, runner):
        self.runner = runner

    def run(self, plan, batch, save, execution) -> LoopResponse:
        """Step ``batch`` through ``plan`` (see :class:`Engine`).

        Parameters
        ----------
        plan : Plan
        batch : Batch
        save : Save
        execution : Execution

        Returns
        -------
        LoopResponse
        """
        rec = _allocate(plan, batch, save)
        if batch.B == 1 and execution.chunk_runs is None and (execution.progress is False or (
                execution.progress is None and batch.n_steps < AUTO_BAR_WORK)):
            # one run, no bar: one call, no chunking or views (the fixed cost of a python-control-style call)
            run_compiled(plan, self.runner, batch.t, batch.held, execution.bound, rec)
            return _respond(plan, batch, save, rec, execution.bound)
        with _Progress(batch, execution) as progress:
            for lo, hi in _chunks(plan, batch, save, execution):
                # one call per chunk, or (with progress) about 20 calls over its runs (runs are independent:
                # the same numbers either way)
                parts = [(lo, hi)] if progress is None else \
                    [(lo + a, lo + b) for a, b in chunk_bounds(hi - lo, max(1, -(-(hi - lo) // 20)))]
                for a, b in parts:
                    held = batch.held if (a, b) == (0, batch.B) else \
                        {s: (v[:, a:b] if v.ndim == 2 else v) for s, v in batch.held.items()}
                    run_compiled(plan, self.runner, batch.t, held, execution.bound, rec.part(a, b), lo=a)
                    if progress is not None:
                        progress((b - a) * batch.n_steps)
        return _respond(plan, batch, save, rec, execution.bound)


NUMPY = NumpyEngine()


def _in_chunk() -> bool:
    from .processes import in_chunk

    return in_chunk()


def select_engine(plan, batch, execution, loop=None) -> Engine:
    """The engine ``execution`` asks for, for this plan and batch.

    With ``execution.jobs > 1`` (or a process-wide Dask cluster, :func:`~ctrl_analysis.runs.parallel.use_cluster`,
    and enough run-samples, :data:`CLUSTER_MIN_WORK`), several runs and a picklable ``loop``, a
    :class:`~ctrl_analysis.engine.processes.ProcessEngine` that splits the runs over processes. Otherwise
    ``execution.engine``: ``"auto"`` is compiled when every block has a kernel and no input is a callable
    (warning once per loop otherwise, :class:`~ctrl_analysis.engine.compiled.SlowPathWarning`);
    ``"compiled"`` raises when the loop cannot compile.

    Parameters
    ----------
    plan : Plan
    batch : Batch
    execution : Execution
    loop : Loop, optional
        The loop of ``plan``: needed to run in other processes (without it, one process).

    Returns
    -------
    Engine
    """
    split = loop is not None and batch.B > 1 and not batch.funcs and not _in_chunk()
    if split and execution.jobs > 1:
        from ..runs.parallel import picklable
        from .processes import ProcessEngine

        if picklable(loop):
            return ProcessEngine(loop)
    runner = compiled_for(plan, execution.engine, batch.funcs, batch.variants)
    if split and execution.jobs == 1:  # a numpy loop too: its blocks travel by cloudpickle, its rows cut by chunk
        from ..runs.parallel import active_cluster, picklable
        from .processes import ProcessEngine

        work = batch.B * batch.n_steps * (1 if runner is not None else 100)
        if active_cluster() is not None and work >= CLUSTER_MIN_WORK and picklable(loop):
            return ProcessEngine(loop)  # a process-wide Dask cluster's workers
    return NUMPY if runner is None else CompiledEngine(runner)
