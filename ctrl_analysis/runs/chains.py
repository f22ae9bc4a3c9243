"""Chains of maps advanced side by side, and one pool for a command that maps many times.

A chain is a generator that yields a list of arguments, is sent ``[fn(a) for a in args]``, yields its
next list, and so on, and returns its result: a tuning that proposes configurations round after round
from the last round's scores, or a study's part whose next step reads its last map. :func:`drive`
advances several independent chains: in a pool, each in a thread of its own, so that a chain whose
round is slow never holds back another chain's next round (the calls of all chains wait in the pool's
one queue, by priority then first come); elsewhere in lockstep (:func:`lockstep`, one ``map_chunks``
per round). Every chain is sent the same values either way.

:func:`pool_here` opens one pool of local processes for a block of a command (``ctrl-analysis arena``),
instead of one set of processes per ``map_chunks`` call.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Callable

from .._validate import check_int, check_str
from .cluster import _CLUSTER, _check_scheduler
from .parallel import _in_pool_worker, map_chunks
from .progress import _CONTEXT
from .taskpool import _LANE, pool_available, trace_event

__all__ = ["drive", "lockstep", "pool_here"]


def _on_cluster(scheduler) -> bool:
    """Whether ``map_chunks(..., scheduler=scheduler)`` goes to a Dask cluster (given, or process-wide)."""
    return scheduler not in (None, False) or (scheduler is None and _CLUSTER["client"] is not None)


def _to_pool(jobs: int, scheduler) -> bool:
    """Whether ``map_chunks(..., jobs, scheduler)`` here would go to a run's shared pool."""
    return jobs > 1 and not _on_cluster(scheduler) and pool_available()


@contextlib.contextmanager
def pool_here(jobs: int, scheduler=None):
    """One pool of ``jobs`` local processes for every :func:`map_chunks` of the block, opened once.

    Without it each ``map_chunks`` call with ``jobs > 1`` starts and stops its own processes, which
    then load the compiled runners again; a command that maps many times (``ctrl-analysis arena``) keeps
    one pool instead, and :func:`drive` can advance its chains side by side in it. Nothing is opened
    (the block runs as it would have) with ``jobs=1``, on a Dask cluster, in a process that already sends
    its calls to a pool, or in a pool's worker. Results do not depend on it.

    Parameters
    ----------
    jobs : int
        Worker processes (>= 1).
    scheduler : None, False, str or distributed.Client
        As :func:`map_chunks`: a cluster (given, or process-wide with ``None``) opens no pool.

    Yields
    ------
    bool
        Whether a pool was opened.
    """
    from .taskpool import shared_pool

    jobs = check_int("jobs", jobs, minimum=1)
    scheduler = _check_scheduler(scheduler)
    if jobs == 1 or _on_cluster(scheduler) or pool_available() or _in_pool_worker():
        yield False
        return
    with shared_pool(jobs, here=True):
        yield True


_FANS = iter(range(1, 1 << 62))


def _check_chains(chains) -> None:
    if not isinstance(chains, dict) or not all(hasattr(g, "send") and hasattr(g, "throw") for g in chains.values()):
        raise TypeError(f"chains must be a dict of generators, got {chains!r:.80}")


def lockstep(chains: dict):
    """Several chains of :func:`drive` as one: each round yields their lists joined, in the order of ``chains``.

    Parameters
    ----------
    chains : dict
        Key -> generator (as :func:`drive`).

    Returns
    -------
    generator
        A chain whose result is ``{key: that chain's result}``, in the order of ``chains``.
    """
    _check_chains(chains)
    return _lockstep(chains)


def _lockstep(chains):
    out, asked = {}, {}
    for k, g in chains.items():
        try:
            asked[k] = list(next(g))
        except StopIteration as done:
            out[k] = done.value
    while asked:
        parts = iter((yield [a for args in asked.values() for a in args]))
        nxt = {}
        for k, args in asked.items():
            try:
                nxt[k] = list(chains[k].send([next(parts) for _ in args]))
            except StopIteration as done:
                out[k] = done.value
        asked = nxt
    return {k: out[k] for k in chains}


def drive(fn: Callable, chains: dict, *, jobs: int = 1, scheduler=None, desc: str = "", unit: str = "chunk",
          priority: dict | None = None) -> dict:
    """Advance independent chains of maps, each as soon as its own calls are back; their results by key.

    A chain is a generator: it yields a list of arguments, is sent ``[fn(a) for a in args]`` (computed
    by :func:`map_chunks`), yields its next list, and so on, and returns its result. In a pool
    (:func:`pool_here`, or a study's driver in ``reproduce all``) each chain is advanced by a thread of
    its own, so a chain whose round is slow never holds back another chain's next round; elsewhere
    (serially, in processes started per map, on Dask) the chains' lists of the same round go into one
    ``map_chunks`` call, one wait per round. Every chain is sent the same values either way.

    Parameters
    ----------
    fn : callable
        As :func:`map_chunks`.
    chains : dict
        Key -> generator, as above.
    jobs, scheduler, desc, unit
        As :func:`map_chunks` (each chain's bar is labelled ``desc (key)`` in a pool).
    priority : dict, optional
        Key -> int: in a pool, a chain with a lower number has its calls (and the figures it sends) run
        first among those waiting for a worker (default 0; e.g. a chain on the critical path).

    Returns
    -------
    dict
        Key -> the chain's returned value, in the order of ``chains``.

    Raises
    ------
    Exception
        The first failed chain's error (in the order of ``chains``), once every chain has stopped; the
        other chains start no further round after a failure.
    """
    jobs = check_int("jobs", jobs, minimum=1)
    if not callable(fn):
        raise TypeError(f"fn must be callable, got {type(fn).__name__}")
    _check_chains(chains)
    scheduler = _check_scheduler(scheduler)
    check_str("desc", desc, empty=True)
    check_str("unit", unit)
    priority = {} if priority is None else priority
    if not isinstance(priority, dict) or not all(k in chains and isinstance(v, int) and not isinstance(v, bool)
                                                 for k, v in priority.items()):
        raise TypeError(f"priority must be a dict of chain keys to int, got {priority!r:.80}")
    out: dict = {}
    if not _to_pool(jobs, scheduler):
        together = lockstep(chains)
        try:
            args = next(together)
            while True:
                args = together.send(map_chunks(fn, args, jobs=jobs, scheduler=scheduler, desc=desc, unit=unit))
        except StopIteration as done:
            return done.value
    fan, errors, stop = f"{os.getpid()}-{next(_FANS)}", {}, threading.Event()

    def advance(k, g):
        _LANE.fan, _LANE.key, _LANE.priority = fan, str(k), priority.get(k, 0)
        started, tcpu = time.time(), time.thread_time()
        try:
            args = next(g)
            while not stop.is_set():
                args = g.send(map_chunks(fn, list(args), jobs=jobs, scheduler=scheduler,
                                         desc=f"{desc} ({k})" if desc else "", unit=unit))
        except StopIteration as done:
            out[k] = done.value
        except BaseException as exc:  # noqa: BLE001 - raised below, in the caller's thread
            errors[k] = exc
            stop.set()
        finally:
            _LANE.key = None
            trace_event({"kind": "lane", "study": _CONTEXT["label"], "fan": fan, "lane": str(k), "start": started,
                         "end": time.time(), "tcpu_start": tcpu, "tcpu_end": time.thread_time(),
                         "priority": priority.get(k, 0)})

    submitted, cpu = time.time(), time.process_time()
    threads = [threading.Thread(target=advance, args=kg, daemon=True, name=f"ctrl-analysis-chain {kg[0]}")
               for kg in chains.items()]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    trace_event({"kind": "fan", "study": _CONTEXT["label"], "fan": fan, "submitted": submitted,
                 "returned": time.time(), "cpu_submitted": cpu, "cpu_returned": time.process_time()})
    for k in chains:
        if k in errors:
            raise errors[k]
    if len(out) < len(chains):
        raise RuntimeError("a chain stopped before returning its result")
    return {k: out[k] for k in chains}
