"""A batch of :meth:`~ctrl_analysis.engine.loop.Loop.simulate` split over processes or a Dask cluster's workers.

The chunks' responses are joined into one, equal bit for bit to one process (runs are
independent); per-run inputs, initial states and run-time parameters are cut with each chunk.
"""

from __future__ import annotations

import threading

import numpy as np

from ..runs.parallel import _CLUSTER, _cluster_workers, chunk_slices, map_chunks

__all__ = ["ProcessEngine", "in_chunk", "simulate_chunks"]


class ProcessEngine:
    """The engine of a batch split over processes or a Dask cluster's workers (:func:`simulate_chunks`).

    Each chunk runs in its worker on the engine that worker selects (compiled or numpy); the chunks'
    responses are joined into one, equal bit for bit to one process.

    Parameters
    ----------
    loop : Loop
        Picklable (it is sent to the workers).
    """

    name = "processes"

    def __init__(self, loop):
        self.loop = loop

    def run(self, plan, batch, save, execution):
        """Step ``batch`` through the loop in ``execution.jobs`` processes (the ``Engine`` protocol).

        Parameters
        ----------
        plan : Plan
            The loop's plan (``self.loop.plan``).
        batch : Batch
        save : Save
        execution : Execution

        Returns
        -------
        LoopResponse
        """
        return simulate_chunks(self.loop, batch, save, execution)


def simulate_chunks(loop, batch, save, execution):
    """:meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` with its batch split over ``jobs`` processes.

    The chunks' responses are joined into one, equal bit for bit to ``jobs=1`` (runs are independent).

    Parameters
    ----------
    loop : Loop
        Picklable: each process simulates its chunk of runs with it.
    batch : Batch
        The whole batch (:func:`~ctrl_analysis.engine.batch.resolve_batch`); each chunk gets its
        runs' inputs, initial states, parameters and seeds (:meth:`Batch.take`).
    save : Save
    execution : Execution
        ``jobs`` processes; each chunk runs with ``jobs=1`` and no progress bar of its own.

    Returns
    -------
    LoopResponse
    """
    from dataclasses import replace

    from .response import LoopResponse

    plan = loop.plan
    jobs = execution.jobs
    chunks = jobs if _CLUSTER["client"] is None else max(jobs, _cluster_workers())
    inner = replace(execution, jobs=1, progress=False)
    tasks = [(loop, batch.n_steps, dict(batch.take(plan, sl.start, sl.stop), save=save, execution=inner))
             for sl in chunk_slices(batch.B, chunks=chunks)]
    parts = map_chunks(_simulate_task, tasks, jobs=min(jobs, len(tasks)), desc="batch chunks")
    first = parts[0]
    xs = None if first.x is None else np.concatenate([p.x for p in parts], axis=1)
    x_final = None if first.x_final is None else np.concatenate([p.x_final for p in parts], axis=0)
    signals = {s: np.concatenate([p.signals[s] for p in parts], axis=1) for s in first.signals}
    return LoopResponse(t=first.t, x=xs, diverged=np.concatenate([p.diverged for p in parts]),
                        diverged_step=np.concatenate([p.diverged_step for p in parts]),
                        diverged_where=np.concatenate([p.diverged_where for p in parts]), where_names=first.where_names,
                        seeds=batch.seeds, bound=first.bound, signals=signals, slices=plan.slices,
                        external=plan.external, outlist=plan.outlist, state_names=first.state_names, x_final=x_final)


#: Set while this thread runs one chunk: the chunk is not split again (a Dask worker thread in the client's own
#: process, ``LocalCluster(processes=False)``, sees the process-wide cluster too).
_IN_CHUNK = threading.local()


def in_chunk() -> bool:
    """Whether this thread is running one chunk of a split batch (which then runs in place).

    Returns
    -------
    bool
    """
    return getattr(_IN_CHUNK, "active", False)


def _simulate_task(task):
    """One chunk of :meth:`Loop.simulate` with ``jobs > 1`` (module level: run in a worker process)."""
    loop, n_steps, kw = task
    outer = in_chunk()
    _IN_CHUNK.active = True
    try:
        return loop.simulate(n_steps, **kw)
    finally:
        _IN_CHUNK.active = outer
