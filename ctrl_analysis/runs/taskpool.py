"""One pool of worker processes for a whole run: every study's chunks share all the cores.

``reproduce all`` runs its studies side by side, each in a driver process. Before, each driver started its
own pool with ``jobs // studies`` processes, so a study's Monte Carlo batches could never use the cores
another study left idle while it drew figures or ran its serial parts. Now the command starts one pool of
``jobs`` worker processes (:func:`shared_pool`), and :func:`~ctrl_analysis.runs.parallel.map_chunks` in a driver
sends its calls there (:func:`map_on_pool`): the chunks of every study wait in one queue, first come first
served, and each runs on whichever worker is free. What a chunk computes does not depend on where it runs,
so the results are those of ``--jobs 1`` bit for bit.

The drivers talk to the pool's owner (the command's process) through a local socket whose address and key
travel in the environment (``CTRL_ANALYSIS_POOL``); a thread there serves each ``map_chunks`` call: it
submits the calls, cloudpickled as for Dask, and sends each result back as it finishes. A worker process of
the pool never sends calls back to the pool (a chunk that maps again runs its calls in place), so no call
waits for a worker that waits for it.

With ``CTRL_ANALYSIS_TRACE=DIR`` every process of a run appends what it did to ``DIR/<pid>.jsonl``
(:func:`trace_event`): each study's start and end, and each ``map_chunks`` call's submission, return and
its calls' starts and ends (``time.time``, one clock for all processes), wherever they ran, with CPU seconds
(``time.process_time``) beside them: a trace recorded with more processes than cores still says what each
piece of work costs. This is what
``benchmarks/scaling.py`` replays for other numbers of workers.
"""

from __future__ import annotations

import contextlib
import heapq
import json
import os
import signal
import threading
import time

__all__ = ["driver", "lane_fields", "map_on_pool", "pool_available", "shared_pool", "trace_event"]

_ENV = "CTRL_ANALYSIS_POOL"
_STATE: dict = {"owner": None, "worker": False}  # owner: the pid of the process that opened the pool
_CALL = threading.local()  # .inside: this thread runs a call of a map (its own maps are part of it, untraced)
_LANE = threading.local()  # .fan, .key, .priority: in a thread of chains.drive, the chain this thread advances


def pool_available() -> bool:
    """Whether this process is a driver that may send its calls to a run's shared pool.

    Returns
    -------
    bool
        True in a process started while :func:`shared_pool` is open (a study's driver), False in the
        pool's owner, in the pool's workers and outside a run.
    """
    return bool(os.environ.get(_ENV)) and _STATE["owner"] != os.getpid() and not _STATE["worker"]


def _die_with_parent(parent: int) -> None:
    """Initialiser of local worker processes: die with the parent, leave Ctrl-C to it.

    On Linux ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` has the kernel kill this process when its parent
    dies (even by ``kill -9``); elsewhere a daemon thread polls the parent's pid. SIGINT is ignored:
    the parent catches Ctrl-C once, stops the workers and reports.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        armed = libc.prctl(1, int(signal.SIGKILL), 0, 0, 0) == 0  # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        armed = False
    if os.getppid() != parent:  # the parent died before the signal was armed
        os._exit(1)
    if not armed:
        def watch():
            while os.getppid() == parent:
                threading.Event().wait(1.0)
            os._exit(1)

        threading.Thread(target=watch, daemon=True, name="ctrl-analysis-parent-watch").start()


def _stop_workers(ex) -> None:
    """Cancel what has not started and kill the pool's workers (after an exception or Ctrl-C in the parent)."""
    procs = list((getattr(ex, "_processes", None) or {}).values())  # shutdown() forgets them
    for proc in procs:
        with contextlib.suppress(OSError, AttributeError, ValueError):
            proc.kill()
    for proc in procs:
        with contextlib.suppress(OSError, AttributeError, ValueError, AssertionError):
            proc.join(5)
    ex.shutdown(wait=True, cancel_futures=True)


def _by_value(fn, arg) -> bytes:
    """``(fn, arg)`` pickled with cloudpickle, as Dask sends tasks: a lambda, a class defined in a script or a
    notebook, an exec'd kernel travel by value, so what runs on a cluster also runs in local processes."""
    import cloudpickle

    return cloudpickle.dumps((fn, arg))


def _worker_init(parent: int) -> None:
    """A pool worker: dies with the owner, leaves Ctrl-C to it, and never maps onto the pool itself."""
    _die_with_parent(parent)
    _STATE["worker"] = True
    os.environ.pop(_ENV, None)


def _timed_call(blob: bytes):
    """``fn(arg)`` from cloudpickled bytes, with when it started and ended (``time.time``) and its CPU seconds."""
    import pickle

    start, cpu = time.time(), time.process_time()
    fn, arg = pickle.loads(blob)
    value = _timed(fn, arg)[0]
    return value, start, time.time(), time.process_time() - cpu


def _timed(fn, arg):
    """``(fn(arg), start, end)``; maps inside the call are part of it, and are not traced on their own.

    Parameters
    ----------
    fn : callable
    arg : object

    Returns
    -------
    tuple
        The value, ``time.time()`` before and after, and the CPU seconds of this process meanwhile.
    """
    outer = getattr(_CALL, "inside", False)
    _CALL.inside = True
    start, cpu = time.time(), time.process_time()
    try:
        return fn(arg), start, time.time(), time.process_time() - cpu
    finally:
        _CALL.inside = outer


@contextlib.contextmanager
def driver():
    """The block is a study's driver: its maps are traced, though it runs as a call of the command's own map.

    Yields
    ------
    None
    """
    outer = getattr(_CALL, "inside", False)
    _CALL.inside = False
    try:
        yield
    finally:
        _CALL.inside = outer


def trace_event(event: dict) -> None:
    """Append ``event`` to this process's trace file, when ``$CTRL_ANALYSIS_TRACE`` names a folder.

    Nothing is written from inside a traced call (its nested maps are part of its duration).

    Parameters
    ----------
    event : dict
        JSON-serialisable, with a ``"kind"`` (``"study"`` or ``"map"``).
    """
    folder = os.environ.get("CTRL_ANALYSIS_TRACE")
    if not folder or getattr(_CALL, "inside", False):
        return
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, f"{os.getpid()}.jsonl"), "a", encoding="utf-8") as fh:
        fh.write(json.dumps(event) + "\n")


class _Feed:
    """Calls waiting for a worker of the pool: lowest priority first, then first come; at most ``depth`` handed
    to the executor at once, so a call sent later with a lower priority (a chain on the critical path, a
    figure it sent) overtakes the calls still waiting."""

    def __init__(self, ex, depth: int):
        self._ex, self._depth = ex, depth
        self._waiting: list = []
        self._seq = self._busy = 0
        self._closed = False
        self._cv = threading.Condition()
        threading.Thread(target=self._run, daemon=True, name="ctrl-analysis-pool-feed").start()

    def submit(self, priority, blob: bytes, done, dropped) -> None:
        """Queue ``blob``; ``done(future)`` when it has run (skipped once ``dropped`` is set)."""
        with self._cv:
            heapq.heappush(self._waiting, (priority, self._seq, blob, done, dropped))
            self._seq += 1
            self._cv.notify()

    def close(self) -> None:
        with self._cv:
            self._closed = True
            self._cv.notify_all()

    def _run(self) -> None:
        from concurrent.futures import Future

        while True:
            with self._cv:
                while not self._closed and (not self._waiting or self._busy >= self._depth):
                    self._cv.wait()
                if self._closed:
                    return
                _, _, blob, done, dropped = heapq.heappop(self._waiting)
                if dropped.is_set():
                    continue
                self._busy += 1
            try:
                fut = self._ex.submit(_timed_call, blob)
            except BaseException as exc:  # noqa: BLE001 - the pool is shutting down: the call fails
                fut = Future()
                fut.set_exception(exc)
            fut.add_done_callback(lambda f, done=done: self._finished(f, done))

    def _finished(self, fut, done) -> None:
        with self._cv:
            self._busy -= 1
            self._cv.notify()
        done(fut)


def lane_fields() -> dict:
    """What a traced event sent from a chain of ``chains.drive`` says of it (``{}`` elsewhere).

    Returns
    -------
    dict
        ``fan``, ``lane``, its ``priority`` in the pool and this thread's CPU clock (``tcpu_submitted`` =
        ``tcpu_returned``): an async call (a figure) sent from the chain, which the chain does not wait for.
    """
    if getattr(_LANE, "key", None) is None:
        return {}
    now = time.thread_time()
    return {"fan": _LANE.fan, "lane": _LANE.key, "priority": _LANE.priority, "tcpu_submitted": now,
            "tcpu_returned": now}


@contextlib.contextmanager
def shared_pool(jobs: int, *, here: bool = False):
    """Open one pool of ``jobs`` worker processes for every driver process started inside the block.

    Parameters
    ----------
    jobs : int
        Worker processes (>= 1).
    here : bool
        Whether this process is a driver too: its own ``map_chunks`` calls go to the pool (one command
        that maps many times, ``ctrl-analysis arena``), rather than only the processes it starts
        (``reproduce all``'s study drivers; its own maps start them).

    Yields
    ------
    None
    """
    import multiprocessing as mp
    import secrets
    from concurrent.futures import ProcessPoolExecutor
    from multiprocessing.connection import Listener

    from .._validate import check_int

    jobs = check_int("jobs", jobs, minimum=1)
    method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
    ex = ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context(method), initializer=_worker_init,
                             initargs=(os.getpid(),))
    for f in [ex.submit(time.sleep, 0.01) for _ in range(jobs)]:  # the workers start now, before any thread
        f.result()
    key = secrets.token_bytes(16)
    listener = Listener(family="AF_UNIX" if hasattr(os, "fork") else "AF_INET", authkey=key)
    stop = threading.Event()

    feed = _Feed(ex, jobs + 1)

    def serve(conn):
        import queue

        with conn:
            try:
                msg = conn.recv()
            except (EOFError, OSError):
                return
            priority, blobs = msg  # map_on_pool sends (priority, calls)
            finished, dropped = queue.SimpleQueue(), threading.Event()
            for i, b in enumerate(blobs):
                feed.submit(priority, b, lambda fut, i=i: finished.put((i, fut)), dropped)
            try:
                for _ in range(len(blobs)):
                    i, fut = finished.get()
                    try:
                        value = fut.result()
                    except BaseException as exc:  # noqa: BLE001 - the driver raises it, as map_chunks does
                        conn.send(("error", i, _sendable(exc)))
                        raise
                    conn.send(("ok", i, value))
            except BaseException:  # noqa: BLE001 - a failed call or a driver gone: its other calls are dropped
                dropped.set()

    def accept():
        while not stop.is_set():
            try:
                conn = listener.accept()
            except (OSError, EOFError):
                if stop.is_set():
                    return
                continue
            threading.Thread(target=serve, args=(conn,), daemon=True, name="ctrl-analysis-pool-call").start()

    acceptor = threading.Thread(target=accept, daemon=True, name="ctrl-analysis-pool")
    acceptor.start()
    before = os.environ.get(_ENV)
    os.environ[_ENV] = json.dumps({"address": listener.address, "key": key.hex()})
    # a forked driver inherits this dict, not the pid; "here": this process sends its calls to the pool too
    _STATE["owner"] = None if here else os.getpid()
    try:
        yield
    finally:
        _STATE["owner"] = None
        if before is None:
            os.environ.pop(_ENV, None)
        else:
            os.environ[_ENV] = before
        stop.set()
        feed.close()
        listener.close()
        _stop_workers(ex)


def _sendable(exc: BaseException) -> BaseException:
    """``exc`` if it pickles, else a RuntimeError with its one line (what the driver re-raises)."""
    import pickle

    try:
        pickle.dumps(exc)
    except Exception:  # noqa: BLE001 - an exception that cannot travel is sent as its text
        return RuntimeError(f"{type(exc).__name__}: {exc}")
    return exc


def map_on_pool(fn, args: list, done_one, priority: int | None = None) -> list:
    """``[fn(a) for a in args]`` on the run's shared pool, from a driver; results in order.

    Parameters
    ----------
    fn : callable
        A function of one argument (sent with each argument by cloudpickle).
    args : list
        One argument per call.
    done_one : callable
        ``done_one(i, (value, start, end, cpu))``, called here as each call finishes.
    priority : int, optional
        Lower goes first among the calls waiting for a worker (default: the chain's of
        ``chains.drive`` this thread advances, else 0).

    Returns
    -------
    list
        ``(fn(a), start, end, cpu)`` for every ``a``.

    Raises
    ------
    RuntimeError
        When the pool's owner is gone (the connection closed before every result came back).
    """
    from multiprocessing.connection import Client

    where = json.loads(os.environ[_ENV])
    address = where["address"]
    out = [None] * len(args)
    with Client(tuple(address) if isinstance(address, list) else address, authkey=bytes.fromhex(where["key"])) as c:
        c.send((getattr(_LANE, "priority", 0) if priority is None else priority, [_by_value(fn, a) for a in args]))
        for _ in range(len(args)):
            try:
                kind, i, value = c.recv()
            except (EOFError, OSError) as exc:
                raise RuntimeError(f"the run's process pool went away ({type(exc).__name__})") from None
            if kind == "error":
                raise value
            out[i] = value
            done_one(i, value)
    return out
