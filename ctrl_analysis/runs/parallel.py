"""Every core and beyond one machine: chunks of a batch and independent studies in parallel processes or on Dask.

A Monte Carlo batch is a list of seeds; each run depends only on its own seed (the noise of run
``b`` is drawn from ``default_rng(seeds[b])``, see :func:`ctrl_analysis.noise.draw_noise`) and
the engine steps runs independently, so splitting the seeds into chunks, simulating the chunks
anywhere and concatenating what each chunk returns gives, bit for bit, what one process gives.

* :func:`map_chunks` — apply a function to a list of arguments, in order, serially (``jobs=1``), in
  ``jobs`` local processes, or on a ``dask.distributed`` cluster (``scheduler``);
* :func:`monte_carlo` — split ``seeds`` into chunks, run ``fn(seeds_chunk)`` on each, gather;
* :func:`sweep` — a parameter grid times seeds as one flat batch axis, chunked over workers, gathered
  back into the grid's shape;
* :func:`gather` — concatenate chunk results (arrays, dicts or tuples of arrays, runs on axis 0).

The function passed must be importable by name in a worker (defined at module level, not a lambda
or a closure) and must reduce its chunk to the arrays the caller needs (per-run metrics rather
than whole trajectories), which also bounds memory: a batch of 10^6 runs never exists at once.

``scheduler``: ``None`` runs on this machine's processes, or on the process-wide cluster when one
is active (:func:`use_cluster`); ``False`` always on this machine; ``"local"`` starts a Dask
``LocalCluster`` with ``jobs`` single-threaded workers; any other string is the address of a
running Dask scheduler (``"tcp://host:8786"``); a ``distributed.Client`` is used as given.

:func:`~ctrl_analysis.runs.cluster.use_cluster` makes a Dask cluster process-wide (the command line's ``--scheduler``);
the cluster's address check and its failures in bounded time are in :mod:`ctrl_analysis.runs.cluster`.

Local worker processes die with the process that started them (``prctl(PR_SET_PDEATHSIG)`` on
Linux, a watchdog thread elsewhere) and ignore SIGINT: Ctrl-C is handled once, by the parent, which
stops them.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence

import numpy as np

from .._validate import check_int, check_seeds, check_str
from .cluster import (  # noqa: F401 - the cluster's public names, from here too
    _CLUSTER,
    WORKER_TIMEOUT,
    ClusterError,
    _check_scheduler,
    _client,
    _close,
    _cluster_workers,
    _map_on_dask,
    _quiet_dask,
    active_cluster,
    check_scheduler_address,
    default_jobs,
    silence_dask_logs,
    use_cluster,
)
from .progress import _CONTEXT, bar
from .taskpool import (
    _LANE,
    _STATE,
    _by_value,
    _stop_workers,
    _timed,
    _timed_call,
    map_on_pool,
    pool_available,
    trace_event,
)
from .taskpool import _die_with_parent as _worker_init

__all__ = ["MAX_CHUNKS", "WORKER_TIMEOUT", "active_cluster", "check_scheduler_address",
           "chunk_slices", "default_jobs", "gather", "grid_points", "map_chunks", "monte_carlo", "picklable",
           "sweep", "use_cluster"]



def chunk_slices(n: int, *, chunks: int | None = None, chunk_size: int | None = None) -> list[slice]:
    """Consecutive slices splitting ``range(n)`` into ``chunks`` near-equal pieces or pieces of ``chunk_size``.

    Parameters
    ----------
    n : int
        Items (>= 1).
    chunks : int, optional
        Number of pieces (>= 1; at most ``n`` are made). Default 1.
    chunk_size : int, optional
        Largest piece (>= 1); overrides ``chunks``.

    Returns
    -------
    list of slice

    Raises
    ------
    ValueError
        If an argument is out of range, or more than :data:`MAX_CHUNKS` pieces would be made.
    """
    n = check_int("n", n, minimum=1)
    if chunk_size is not None:
        size = check_int("chunk_size", chunk_size, minimum=1)
    else:
        k = check_int("chunks", 1 if chunks is None else chunks, minimum=1)
        size = math.ceil(n / min(k, n))
    _check_pieces(n, size, "chunk_size" if chunk_size is not None else "chunks")
    return [slice(lo, min(lo + size, n)) for lo in range(0, n, size)]


#: Most pieces :func:`chunk_slices` makes (each is a task: more is a mistake, and a list that large
#: would take gigabytes).
MAX_CHUNKS = 10**6


def _check_pieces(n: int, size: int, name: str) -> None:
    """Raise unless splitting ``n`` items into pieces of ``size`` makes at most :data:`MAX_CHUNKS` pieces."""
    pieces = -(-n // size)
    if pieces > MAX_CHUNKS:
        raise ValueError(f"{name} would split n = {n} into {pieces} pieces, more than MAX_CHUNKS = {MAX_CHUNKS}: "
                         f"use larger pieces")


def _sequence(name: str, value) -> list:
    """``value`` as a list; a string, a mapping or a non-iterable raises a TypeError naming ``name``."""
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__iter__"):
        raise TypeError(f"{name} must be a sequence (list, tuple, range or array), got {value!r}")
    return list(value)


def _in_pool_worker() -> bool:
    """Whether this process works in a run's shared pool (:mod:`ctrl_analysis.runs.taskpool`): it maps in place."""
    return _STATE["worker"]


def map_chunks(fn: Callable, args: Sequence, *, jobs: int = 1, scheduler=None, desc: str = "",
               unit: str = "chunk", on_result: Callable | None = None) -> list:
    """``[fn(a) for a in args]``, computed serially, in local processes or on Dask; results in order.

    Parameters
    ----------
    fn : callable
        A function of one argument; it and ``args`` travel to worker processes by cloudpickle (lambdas and
        functions defined in a script or a notebook too).
    args : sequence
        One argument per call (e.g. chunks of seeds, study names).
    jobs : int
        Local processes (>= 1); ``1`` runs in this process. With ``scheduler="local"``, Dask workers.
    scheduler : None, str or distributed.Client
        See the module docstring.
    desc : str
        Label of the progress bar (one unit per finished call).
    unit : str
        What one call is, for the bar (``"chunk"``, ``"study"``).
    on_result : callable, optional
        ``on_result(i, fn(args[i]))``, called in this process as each call finishes (in the order they
        finish), e.g. to commit a study's output while the others still run.

    Returns
    -------
    list
        ``fn(a)`` for every ``a``, in the order of ``args``.

    Raises
    ------
    OSError
        When a scheduler address given here does not answer as a Dask scheduler (see :func:`use_cluster`).
    ClusterError
        On Dask, when the scheduler is lost, or no worker is connected to it for the worker time-out
        (:func:`use_cluster`'s ``worker_timeout``, else :data:`WORKER_TIMEOUT`) while calls are unfinished;
        the process-wide cluster is then marked failed, and later calls there raise it at once.
    """
    jobs = check_int("jobs", jobs, minimum=1)
    args = _sequence("args", args)
    if not callable(fn):
        raise TypeError(f"fn must be callable, got {type(fn).__name__}")
    scheduler = _check_scheduler(scheduler)
    check_str("desc", desc, empty=True)
    check_str("unit", unit)
    if on_result is not None and not callable(on_result):
        raise TypeError(f"on_result must be callable on_result(i, result), got {on_result!r:.80}")
    done_one = on_result or (lambda i, value: None)
    # no scheduler, or the one the process-wide cluster was made from (a study handed --scheduler):
    # the cluster already running, not a second LocalCluster or client per call
    if _CLUSTER["client"] is not None and args and scheduler in (None, _CLUSTER["scheduler"]):
        scheduler = _CLUSTER["client"]
        _CLUSTER["chunks"] += len(args)
    out = [None] * len(args)
    with bar(len(args), desc=desc, unit=unit) as pb:
        if scheduler is not None and scheduler is not False:
            with _quiet_dask():
                client, own = _client(scheduler, jobs)
                try:
                    _map_on_dask(client, fn, args, out, done_one, pb)
                finally:
                    if own:
                        _close(client)
            return out
        submitted, cpu, tcpu, times = time.time(), time.process_time(), time.thread_time(), [None] * len(args)

        def one(i, timed_value):
            out[i], times[i] = timed_value[0], timed_value[1:]
            done_one(i, out[i])
            pb.update(1)

        where = "here"
        lane = getattr(_LANE, "key", None) is not None  # a chain of drive(): even one call goes to the pool
        if jobs > 1 and (len(args) > 1 or lane) and pool_available():  # a study's driver: the run's one pool
            where = "pool"
            map_on_pool(fn, args, one)
        elif jobs == 1 or len(args) <= 1 or _in_pool_worker():
            for i, a in enumerate(args):
                one(i, _timed(fn, a))
        else:
            where = "processes"
            _map_on_processes(fn, args, jobs, one)
        event = {"kind": "map", "study": _CONTEXT["label"], "where": where, "submitted": submitted,
                 "returned": time.time(), "cpu_submitted": cpu, "cpu_returned": time.process_time(), "calls": times}
        if lane:  # one chain of drive(): its own thread's CPU clock
            event.update(fan=_LANE.fan, lane=_LANE.key, priority=_LANE.priority, tcpu_submitted=tcpu,
                         tcpu_returned=time.thread_time())
        trace_event(event)
    return out


def _map_on_processes(fn, args: list, jobs: int, one) -> None:
    """``one(i, (fn(args[i]), start, end))`` for every call, computed in a pool of local processes of this call."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures import as_completed as done

    method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
    ex = ProcessPoolExecutor(max_workers=min(jobs, len(args)), mp_context=mp.get_context(method),
                             initializer=_worker_init, initargs=(os.getpid(),))
    try:
        futures = {ex.submit(_timed_call, _by_value(fn, a)): i for i, a in enumerate(args)}
        for fut in done(futures):
            one(futures[fut], fut.result())
    except BaseException:  # a failed call or Ctrl-C: nothing more starts, no worker outlives this call
        _stop_workers(ex)
        raise
    ex.shutdown(wait=True)


def gather(parts: list):
    """Concatenate chunk results along axis 0: arrays, and dicts / tuples / lists of them (recursively).

    Parameters
    ----------
    parts : list
        One result per chunk, all of the same structure.

    Returns
    -------
    The same structure with every array the concatenation of the chunks' arrays.
    """
    if not isinstance(parts, (list, tuple)):
        raise TypeError(f"parts must be a list of chunk results, got {parts!r}")
    if not parts:
        raise ValueError("parts must contain at least one chunk result")
    first = parts[0]
    if isinstance(first, dict):
        return {k: gather([p[k] for p in parts]) for k in first}
    if isinstance(first, tuple):
        return tuple(gather([p[i] for p in parts]) for i in range(len(first)))
    if isinstance(first, list):
        return [x for p in parts for x in p]
    return np.concatenate([np.asarray(p) for p in parts], axis=0)


def monte_carlo(fn: Callable, seeds: Sequence, *, jobs: int = 1, scheduler=None, chunk_size: int | None = None,
                desc: str = ""):
    """Run ``fn(seeds_chunk)`` on chunks of ``seeds`` and gather the results (runs on axis 0).

    Parameters
    ----------
    fn : callable
        Module-level ``fn(seeds) -> array, or dict/tuple of arrays`` with one row per seed.
    seeds : sequence of int
        Per-run seeds, non-negative integers (e.g. :func:`ctrl_analysis.noise.run_seeds`).
    jobs, scheduler, desc
        As in :func:`map_chunks`.
    chunk_size : int, optional
        Runs per chunk (default: one chunk per job).

    Returns
    -------
    The gathered result: what ``fn(list(seeds))`` returns in one process, bit for bit.
    """
    seeds = check_seeds(seeds)  # non-negative integers, as noise.draw_noise takes them
    if not seeds:
        raise ValueError("seeds must contain at least one seed")
    jobs = check_int("jobs", jobs, minimum=1)
    parts = chunk_slices(len(seeds), chunks=jobs, chunk_size=chunk_size)
    return gather(map_chunks(fn, [seeds[s] for s in parts], jobs=jobs, scheduler=scheduler, desc=desc))


def grid_points(grid: dict) -> dict:
    """Every point of a parameter grid (cartesian product, first name slowest), as flat arrays.

    Parameters
    ----------
    grid : dict of str -> sequence of float
        Values of each parameter.

    Returns
    -------
    dict of str -> ndarray, shape (P,)
    """
    if not isinstance(grid, dict):
        raise TypeError(f"grid must be a dict of parameter name -> values, got {grid!r}")
    if not grid:
        raise ValueError("grid must name at least one parameter")
    for name in grid:
        check_str("grid", name)
    axes = [np.asarray(v, dtype=float).reshape(-1) for v in grid.values()]
    for name, a in zip(grid, axes, strict=True):
        if a.size == 0:
            raise ValueError(f"grid[{name!r}] must hold at least one value")
    mesh = np.meshgrid(*axes, indexing="ij")
    return {name: m.reshape(-1) for name, m in zip(grid, mesh, strict=True)}


def _sweep_chunk(task):
    fn, points, seeds = task
    return fn(points, seeds)


def sweep(fn: Callable, grid: dict, seeds: Sequence, *, jobs: int = 1, scheduler=None,
          chunk_size: int | None = None, desc: str = ""):
    """A parameter grid times seeds as one flat batch axis, chunked over workers, gathered into the grid's shape.

    The batch axis holds every (point, seed) pair, point-major: run ``b = p * S + s`` is grid
    point ``p`` (:func:`grid_points` order) with seed ``seeds[s]``.

    Parameters
    ----------
    fn : callable
        Module-level ``fn(points, seeds) -> array or dict/tuple of arrays`` with one row per run,
        where ``points`` maps each parameter name to a ``(b,)`` array and ``seeds`` is a list of
        ``b`` seeds (row ``i`` is the pair ``points[...][i]``, ``seeds[i]``).
    grid : dict of str -> sequence of float
        The parameter values.
    seeds : sequence of int
        Seeds run at every point, non-negative integers.
    jobs, scheduler, desc
        As in :func:`map_chunks`.
    chunk_size : int, optional
        Runs per chunk (default: about four chunks per job).

    Returns
    -------
    The gathered result with the run axis reshaped to ``grid shape + (len(seeds),)``, bit for bit
    what ``fn`` returns on the whole batch in one process.
    """
    jobs = check_int("jobs", jobs, minimum=1)
    if not callable(fn):
        raise TypeError(f"fn must be callable fn(points, seeds), got {fn!r}")
    seeds = check_seeds(seeds)
    if not seeds:
        raise ValueError("seeds must contain at least one seed")
    pts = grid_points(grid)
    S = len(seeds)
    P = next(iter(pts.values())).size
    flat_pts = {k: np.repeat(v, S) for k, v in pts.items()}
    flat_seeds = seeds * P
    n = P * S
    parts = chunk_slices(n, chunks=4 * jobs, chunk_size=chunk_size)
    tasks = [(fn, {k: v[s] for k, v in flat_pts.items()}, flat_seeds[s]) for s in parts]
    out = gather(map_chunks(_sweep_chunk, tasks, jobs=jobs, scheduler=scheduler, desc=desc))
    shape = tuple(np.asarray(v).size for v in grid.values()) + (S,)
    return _reshape(out, shape)


def _reshape(out, shape):
    if isinstance(out, dict):
        return {k: _reshape(v, shape) for k, v in out.items()}
    if isinstance(out, tuple):
        return tuple(_reshape(v, shape) for v in out)
    return out.reshape(shape + out.shape[1:])


def picklable(obj) -> bool:
    """Whether ``obj`` pickles with cloudpickle (a loop must, to run in worker processes); warns when it does not.

    The warning is given once per process for each reason (a study runs many batches of the same
    loop: the same sentence eight times says nothing more).

    Parameters
    ----------
    obj : object

    Returns
    -------
    bool
    """
    import pickle
    import warnings

    import cloudpickle

    try:
        cloudpickle.dumps(obj)  # as the chunks travel (_by_value, Dask): lambdas and script-defined classes do
    except (pickle.PicklingError, AttributeError, TypeError) as exc:
        message = (f"running a batch in parallel (jobs > 1 or a cluster) needs a picklable loop ({exc}); "
                   f"running the batch in this process")
        if message not in _WARNED:
            _WARNED.add(message)
            warnings.warn(message, RuntimeWarning, stacklevel=3)
        return False
    return True


#: The warnings :func:`picklable` has given in this process.
_WARNED: set[str] = set()
