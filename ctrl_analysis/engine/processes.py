"""A batch of :meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` split over processes or a Dask cluster's workers.

The chunks' responses are joined into one, equal bit for bit to one process (runs are
independent); per-run inputs, initial states and run-time parameters are cut with each chunk.
"""

from __future__ import annotations

import numpy as np

from ..parallel import _CLUSTER, _cluster_workers, chunk_slices, map_chunks

__all__ = ["simulate_chunks"]


def simulate_chunks(loop, jobs: int, n_steps: int, held: dict, x, opts: dict, seeds):
    """:meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` with its batch split over ``jobs`` processes.

    The chunks' responses are joined into one, equal bit for bit to ``jobs=1`` (runs are independent).

    Parameters
    ----------
    loop : Loop
    jobs : int
        Processes.
    n_steps : int
    held : dict of str -> ndarray
        The external inputs, as :meth:`Loop.simulate` prepared them (``(N+1,)`` or ``(N+1, B)``).
    x : ndarray, shape (B, n)
        Initial states of the whole batch.
    opts : dict
        The remaining keyword arguments of :meth:`Loop.simulate` (``params`` is cut to each chunk's runs).
    seeds : list or None
        Recorded in the response.

    Returns
    -------
    LoopResponse
    """
    from .params import take
    from .response import LoopResponse

    tasks = []
    chunks = jobs if _CLUSTER["client"] is None else max(jobs, _cluster_workers())
    for sl in chunk_slices(x.shape[0], chunks=chunks):
        inputs = {s: (a[:, sl] if a.ndim == 2 else a) for s, a in held.items()}
        x0 = {name: x[sl, bsl] for name, bsl in loop.slices.items()}
        tasks.append((loop, n_steps, dict(opts, inputs=inputs, x0=x0, runs=sl.stop - sl.start, progress=False,
                                          params=take(opts["params"], x.shape[0], loop, sl.start, sl.stop))))
    parts = map_chunks(_simulate_task, tasks, jobs=min(jobs, len(tasks)), desc="batch chunks")
    first = parts[0]
    xs = None if first.x is None else np.concatenate([p.x for p in parts], axis=1)
    x_final = None if first.x_final is None else np.concatenate([p.x_final for p in parts], axis=0)
    signals = {s: np.concatenate([p.signals[s] for p in parts], axis=1) for s in first.signals}
    return LoopResponse(t=first.t, x=xs, u=None, y=None,
                        diverged=np.concatenate([p.diverged for p in parts]),
                        diverged_step=np.concatenate([p.diverged_step for p in parts]),
                        diverged_where=np.concatenate([p.diverged_where for p in parts]), where_names=first.where_names,
                        seeds=None if seeds is None else list(seeds), bound=first.bound, signals=signals,
                        slices=dict(loop.slices), external=loop.external, outlist=loop.outlist,
                        state_names=first.state_names, x_final=x_final)


def _simulate_task(task):
    """One chunk of :meth:`Loop.simulate` with ``jobs > 1`` (module level: run in a worker process)."""
    loop, n_steps, kw = task
    return loop.simulate(n_steps, **kw)
