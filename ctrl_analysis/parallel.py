"""Every core and beyond one machine: chunks of a batch and independent studies in parallel processes or on Dask.

A Monte Carlo batch is a list of seeds; each run depends only on its own seed (the noise of run
``b`` is drawn from ``default_rng(seeds[b])``, see :func:`ctrl_analysis.simulate.draw_noise`) and
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

:func:`use_cluster` connects to a cluster once and makes it process-wide: while it is active every
:func:`map_chunks` call without a ``scheduler`` (or with the one the cluster was made from) and every batch of
:meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` (two runs or more, no callable input, a
picklable loop) runs its chunks there, with the same numbers as on one process. The command line's
``--scheduler`` does this, so every study's Monte Carlo batches and sweeps go to the cluster without
the study knowing.

The cluster path fails in bounded time, in one line: :func:`use_cluster` (and a ``scheduler`` address
given to :func:`map_chunks`) first asks the address for a Dask scheduler's handshake and identity within
the connection time-out, so a port where nothing listens, or where something other than a Dask
scheduler answers (an HTTP server, a service that speaks first), is an :class:`OSError` naming the
address within that time; while chunks run, a lost scheduler, or no worker connected to it for
``worker_timeout`` seconds (:data:`WORKER_TIMEOUT` by default: every worker killed, or none ever
joined), is a :class:`ClusterError`, and the process-wide cluster is then marked failed so later
batches fail at once. Dask's own log records and warnings are silenced meanwhile (a ``"local"``
cluster's scheduler and workers too), since these failures are reported by the exception.

Local worker processes die with the process that started them (``prctl(PR_SET_PDEATHSIG)`` on
Linux, a watchdog thread elsewhere) and ignore SIGINT: Ctrl-C is handled once, by the parent, which
stops them.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import signal
import threading
from collections.abc import Callable, Sequence

import numpy as np

from ._validate import check_int, check_positive, check_str
from .noise import _check_seeds
from .progress import bar

__all__ = ["MAX_CHUNKS", "WORKER_TIMEOUT", "active_cluster", "check_scheduler_address",
           "chunk_slices", "default_jobs", "gather", "grid_points", "map_chunks", "monte_carlo", "picklable",
           "sweep", "use_cluster"]

#: Seconds a Dask run waits while no worker is connected to its scheduler (every worker lost, or none
#: joined) before it stops with a :class:`ClusterError`; long enough for a nanny to restart a worker.
WORKER_TIMEOUT = 60.0

#: Seconds between two looks at the cluster while its chunks run (when none finished meanwhile).
_POLL_S = 1.0

#: The process-wide cluster of :func:`use_cluster`: its client, the ``scheduler`` it was given, its
#: address, the chunks it ran, its worker time-out, and why it failed (``None`` while it works).
_CLUSTER: dict = {"client": None, "scheduler": None, "address": None, "chunks": 0, "worker_timeout": WORKER_TIMEOUT,
                  "failed": None}


class ClusterError(RuntimeError):
    """The Dask cluster failed while chunks ran on it: its scheduler was lost, or no worker was connected for
    the worker time-out. The message names the scheduler's address and says how many chunks were unfinished."""

_ADDRESS = re.compile(r"^(?:(tcp|tls|ucx|ws|wss)://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):(\d{1,5})$")


def default_jobs() -> int:
    """Cores this process may use (``os.sched_getaffinity`` where available, else ``os.cpu_count()``).

    Returns
    -------
    int
        At least 1.
    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - macOS / Windows
        return max(1, os.cpu_count() or 1)


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


def check_scheduler_address(scheduler: str) -> str:
    """``scheduler`` if it is ``"local"`` or a Dask scheduler address ``[tcp|tls|ucx|ws|wss://]host:port``.

    Parameters
    ----------
    scheduler : str
        ``"local"``, or e.g. ``"tcp://10.0.0.5:8786"``, ``"127.0.0.1:8786"``.

    Returns
    -------
    str
        ``scheduler`` unchanged.

    Raises
    ------
    ValueError
        If it is neither, or the port is not in 1..65535.

    Examples
    --------
    >>> check_scheduler_address("tcp://127.0.0.1:8786")
    'tcp://127.0.0.1:8786'
    """
    check_str("scheduler", scheduler)
    if scheduler == "local":
        return scheduler
    m = _ADDRESS.match(scheduler)
    if m is None or not 1 <= int(m.group(3)) <= 65535:
        raise ValueError(f"scheduler must be 'local' or a Dask scheduler address [tcp://]host:port with a port in "
                         f"1..65535, such as tcp://127.0.0.1:8786, got {scheduler!r}")
    return scheduler


def _check_scheduler(scheduler):
    """None, False, "local", a "host:port" address or a ``distributed.Client``."""
    if scheduler is None or scheduler is False or type(scheduler).__name__ == "Client":
        return scheduler
    if not isinstance(scheduler, str):
        raise ValueError(f"scheduler must be None, False, 'local', a scheduler address such as 'tcp://host:8786' "  # noqa: TRY004
                         f"or a distributed.Client, got {scheduler!r}")
    return check_scheduler_address(scheduler)


@contextlib.contextmanager
def use_cluster(scheduler, jobs: int | None = None, timeout: float = 10.0, worker_timeout: float = WORKER_TIMEOUT):
    """Make a Dask cluster process-wide while the block runs: chunk mappings and batches go there.

    Connects before yielding (so a bad address fails before any work), and closes what it started
    on exit. Dask's log records (of this process, and of a ``"local"`` cluster's processes) are
    silenced while the block runs: a failure of the cluster is reported by the exception raised.

    Parameters
    ----------
    scheduler : str or distributed.Client
        ``"local"`` (a ``LocalCluster`` of ``jobs`` single-threaded worker processes), the address of a
        running scheduler (``"tcp://host:8786"``), or a client to use as given.
    jobs : int, optional
        Workers of a ``"local"`` cluster (default :func:`default_jobs`).
    timeout : float
        Seconds to wait for the scheduler's answer (> 0): connection, Dask's handshake and its identity.
    worker_timeout : float
        Seconds a mapping waits while no worker is connected to the scheduler before it raises
        :class:`ClusterError` (> 0; default :data:`WORKER_TIMEOUT`).

    Yields
    ------
    distributed.Client

    Raises
    ------
    ValueError
        For a malformed address.
    OSError
        Within ``timeout``, when no scheduler answers at the address (connection refused, no route,
        time-out) or what answers is not a Dask scheduler (an HTTP server, a service that speaks
        first, a Dask worker); the message names the address.
    ClusterError
        From the block's mappings, when the scheduler is lost or no worker is left (see :func:`map_chunks`).
    """
    scheduler = _check_scheduler(scheduler)
    if scheduler is None or scheduler is False:
        raise ValueError("scheduler must be 'local', a scheduler address or a distributed.Client, got "
                         f"{scheduler!r}")
    jobs = default_jobs() if jobs is None else check_int("jobs", jobs, minimum=1)
    timeout = check_positive("timeout", timeout, scalar=True)
    worker_timeout = check_positive("worker_timeout", worker_timeout, scalar=True)
    if _CLUSTER["client"] is not None:
        raise RuntimeError("a process-wide cluster is already active (use_cluster blocks do not nest)")
    with _quiet_dask():
        client, own = _client(scheduler, jobs, timeout)
        _CLUSTER.update(client=client, scheduler=scheduler, address=_address(client, scheduler), chunks=0,
                        worker_timeout=worker_timeout, failed=None)
        try:
            yield client
        finally:
            _CLUSTER.update(client=None, scheduler=None, worker_timeout=WORKER_TIMEOUT, failed=None)
            if own:
                _close(client)


def active_cluster() -> dict | None:
    """The process-wide cluster of :func:`use_cluster`, or ``None``.

    Returns
    -------
    dict or None
        ``{"client", "address", "chunks", "worker_timeout", "failed"}``: ``chunks`` counts the calls run
        there so far; ``failed`` is why the cluster failed (a :class:`ClusterError`'s message), or ``None``.
    """
    return dict(_CLUSTER) if _CLUSTER["client"] is not None else None


def _address(client, scheduler=None) -> str:
    return str(getattr(getattr(client, "scheduler", None), "address", None) or scheduler)


def _cluster_workers() -> int:
    """Worker threads of the process-wide cluster (at least 1; 1 when it failed or does not answer in 5 s)."""
    if _CLUSTER["failed"] is not None:
        return 1
    try:
        return max(1, sum(_CLUSTER["client"].nthreads(callback_timeout=5).values()))
    except Exception:  # noqa: BLE001 - a cluster that cannot say still takes one chunk
        return 1


def _connected_workers(client) -> int | None:
    """Workers connected to the client's scheduler, or None when it does not answer within 5 s."""
    try:
        return len(client.nthreads(callback_timeout=5))
    except Exception:  # noqa: BLE001 - a scheduler that cannot say is treated as having no worker
        return None


def _close(client) -> None:
    cluster = getattr(client, "cluster", None)
    with contextlib.suppress(Exception):  # a lost scheduler: nothing left to tell it
        client.close(timeout=5)
    if cluster is not None:
        cluster.close()


def silence_dask_logs():
    """Silence every logger of Dask's tree (``distributed``, ``tornado``) in this process; returns the undo.

    Dask's configuration gives some of its loggers levels of their own (``distributed.client``), so each
    is raised, not only the root of the tree. The command line calls this for its whole run: a client
    whose scheduler was lost keeps trying to reconnect in the background and logs a traceback when it
    gives up, possibly after the cluster's block has ended.

    Returns
    -------
    callable
        ``undo()`` puts every level back.
    """
    import logging

    import distributed  # noqa: F401 - importing it applies Dask's logging configuration, which would undo ours

    names = [name for name in list(logging.root.manager.loggerDict) if name.split(".")[0] in ("distributed", "tornado")]
    loggers = [logging.getLogger(name) for name in {"distributed", "tornado", *names}]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL + 1)

    def undo():
        for lg, level in zip(loggers, levels):
            lg.setLevel(level)

    return undo


@contextlib.contextmanager
def _quiet_dask():
    """Silence Dask's loggers (:func:`silence_dask_logs`, undone after) and its large-graph warning in the block.

    The cluster's failures are reported by the exceptions of :func:`use_cluster` and :func:`map_chunks`
    (one line each); Dask's own records (a reconnection's traceback, a worker's departure) would only
    repeat them on stderr, many lines at a time. A batch's tasks carry their loop, so graphs of several
    MiB are expected, not a mistake.
    """
    import dask

    undo = silence_dask_logs()
    try:
        with dask.config.set({"distributed.admin.large-graph-warning-threshold": "1 PiB"}):
            yield
    finally:
        undo()


def _client(scheduler, jobs, timeout: float = 30.0):
    """A ``distributed.Client`` for ``scheduler`` and whether we own it (must close it).

    An address is asked first (:func:`_ask_scheduler`), so that what is not a Dask scheduler fails within
    ``timeout`` in one line (OSError) instead of hanging or failing deep inside Dask.
    """
    import logging

    from distributed import Client, LocalCluster

    if isinstance(scheduler, Client):
        return scheduler, False
    if scheduler == "local":
        cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, dashboard_address=None,
                               worker_dashboard_address=None, silence_logs=logging.CRITICAL)
        return Client(cluster), True
    if not isinstance(scheduler, str) or not scheduler:
        raise ValueError(f"scheduler must be None, 'local', a scheduler address or a distributed.Client, "
                         f"got {scheduler!r}")
    _ask_scheduler(scheduler, timeout)
    try:
        return Client(scheduler, timeout=f"{timeout}s"), True
    except (OSError, TimeoutError) as exc:
        raise OSError(f"no Dask scheduler answers at {scheduler!r} within {timeout:g} s "
                      f"({' '.join(str(exc).split())[:200]})") from None


def _ask_scheduler(address: str, timeout: float) -> None:
    """Raise OSError (one line, naming ``address``) unless a Dask scheduler answers there within ``timeout`` s.

    Three steps share the time: a TCP connection (for TCP-based addresses: who does not listen is told
    apart from who does not speak Dask), Dask's handshake (a framed message each way: an HTTP server never
    answers it, a service that speaks first answers garbage, which Dask would read as a length of exabytes),
    and an ``identity`` request, whose answer must come from a ``Scheduler`` (not a worker or a nanny).
    They run in a thread of their own, with their own event loop, so the call works whether or not the
    caller runs one.
    """
    import asyncio
    import socket
    import time

    deadline = time.monotonic() + timeout
    m = _ADDRESS.match(address)
    if m is not None and (m.group(1) or "tcp") != "ucx":
        host = m.group(2).strip("[]")
        try:
            socket.create_connection((host, int(m.group(3))), timeout=timeout).close()
        except OSError as exc:
            why = exc.strerror or ("timed out" if isinstance(exc, TimeoutError) else type(exc).__name__)
            raise OSError(f"no Dask scheduler answers at {address!r} within {timeout:g} s ({why})") from None

    async def ask():
        from distributed.comm import connect
        from distributed.security import Security

        comm = await connect(address, timeout=max(0.1, deadline - time.monotonic()),
                             **Security().get_connection_args("client"))
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    answer: dict = {}

    def run():
        try:
            answer["identity"] = asyncio.run(asyncio.wait_for(ask(), max(0.1, deadline - time.monotonic())))
        except BaseException as exc:  # noqa: BLE001 - reported below, in this thread's caller
            answer["error"] = exc

    thread = threading.Thread(target=run, daemon=True, name="ctrl-analysis-scheduler-check")
    thread.start()
    thread.join(max(0.0, deadline - time.monotonic()) + 2.0)
    exc = answer.get("error")
    kind = answer["identity"].get("type") if isinstance(answer.get("identity"), dict) else None
    if kind == "Scheduler":
        return
    if "identity" not in answer and (exc is None or isinstance(exc, TimeoutError)):
        raise OSError(f"{address!r} is not a Dask scheduler: it accepts connections but gave no Dask handshake "
                      f"within {timeout:g} s")
    if kind is not None:
        raise OSError(f"{address!r} is a Dask {kind}, not a scheduler: give the scheduler's address")
    if isinstance(exc, MemoryError):  # its first bytes, read as the length of a Dask message, said exabytes
        what = "its first bytes are not Dask's framing"
    elif exc is not None:
        what = f"{type(exc).__name__}: {' '.join(str(exc).split())[:120]}"
    else:
        what = "no identity"
    raise OSError(f"{address!r} is not a Dask scheduler: it did not answer with Dask's protocol ({what})")


def _worker_init(parent: int) -> None:
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


def map_chunks(fn: Callable, args: Sequence, *, jobs: int = 1, scheduler=None, desc: str = "",
               unit: str = "chunk", on_result: Callable | None = None) -> list:
    """``[fn(a) for a in args]``, computed serially, in local processes or on Dask; results in order.

    Parameters
    ----------
    fn : callable
        A module-level function (picklable by name) of one argument.
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
        if jobs == 1 or len(args) <= 1:
            for i, a in enumerate(args):
                out[i] = fn(a)
                done_one(i, out[i])
                pb.update(1)
            return out
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor
        from concurrent.futures import as_completed as done

        method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
        ex = ProcessPoolExecutor(max_workers=min(jobs, len(args)), mp_context=mp.get_context(method),
                                 initializer=_worker_init, initargs=(os.getpid(),))
        try:
            futures = {ex.submit(fn, a): i for i, a in enumerate(args)}
            for fut in done(futures):
                i = futures[fut]
                out[i] = fut.result()
                done_one(i, out[i])
                pb.update(1)
        except BaseException:  # a failed call or Ctrl-C: nothing more starts, no worker outlives this call
            _stop_workers(ex)
            raise
        ex.shutdown(wait=True)
    return out


def _map_on_dask(client, fn, args: list, out: list, done_one, pb) -> None:
    """Run ``fn`` on every argument on ``client``'s cluster into ``out``, watching the cluster meanwhile.

    Raises :class:`ClusterError` when the scheduler is lost (the client's futures are cancelled with it) or
    when, while calls are unfinished, no worker has been connected to the scheduler for the worker time-out
    (a scheduler left without workers keeps their tasks waiting for ever); on the process-wide cluster it
    is then marked failed.
    """
    import time
    from concurrent.futures import CancelledError

    from distributed import wait

    shared = client is _CLUSTER["client"]
    limit = _CLUSTER["worker_timeout"] if shared else WORKER_TIMEOUT
    address = _address(client)

    def fail(why: str, unfinished: int):
        exc = ClusterError(f"{why} ({unfinished} of {len(args)} chunks unfinished)")
        if shared:
            _CLUSTER["failed"] = str(exc)
        return exc

    if shared and _CLUSTER["failed"] is not None:
        raise ClusterError(_CLUSTER["failed"])
    if client.status not in ("running", "newly-created"):
        raise fail(f"lost the Dask scheduler at {address}: its client is {client.status}", len(args))
    futures = client.map(fn, args, pure=False)
    index = {f.key: i for i, f in enumerate(futures)}
    pending = set(futures)
    alone_since = None  # when the scheduler was first seen without a worker
    while pending:
        try:
            done, pending = wait(list(pending), timeout=_POLL_S, return_when="FIRST_COMPLETED")
        except TimeoutError:
            done = set()
        except CancelledError:  # the scheduler went away: every future of the client is cancelled
            if client.status == "running":  # no: a call itself raised it
                raise
            raise fail(f"lost the Dask scheduler at {address}", len(pending)) from None
        for fut in sorted(done, key=lambda f: index[f.key]):
            i = index[fut.key]
            try:
                out[i] = fut.result()
            except CancelledError:  # the scheduler went away: every future of the client is cancelled
                if client.status == "running":  # no: the call itself raised it
                    raise
                raise fail(f"lost the Dask scheduler at {address}", len(pending) + 1) from None
            done_one(i, out[i])
            pb.update(1)
        if done:
            alone_since = None
            continue
        if client.status in ("closing", "closed"):
            raise fail(f"lost the Dask scheduler at {address}", len(pending))
        workers = _connected_workers(client)
        if workers:
            alone_since = None
            continue
        now = time.monotonic()
        alone_since = now if alone_since is None else alone_since
        if now - alone_since < limit:
            continue
        if workers is None:
            raise fail(f"the Dask scheduler at {address} did not answer for {limit:g} s", len(pending))
        raise fail(f"no Dask worker connected to the scheduler at {address} for {limit:g} s: every worker "
                   f"was lost, or none joined", len(pending))


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
        Per-run seeds, non-negative integers (e.g. :func:`ctrl_analysis.simulate.run_seeds`).
    jobs, scheduler, desc
        As in :func:`map_chunks`.
    chunk_size : int, optional
        Runs per chunk (default: one chunk per job).

    Returns
    -------
    The gathered result: what ``fn(list(seeds))`` returns in one process, bit for bit.
    """
    seeds = _check_seeds(seeds)  # non-negative integers, as noise.draw_noise takes them
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
    for name, a in zip(grid, axes):
        if a.size == 0:
            raise ValueError(f"grid[{name!r}] must hold at least one value")
    mesh = np.meshgrid(*axes, indexing="ij")
    return {name: m.reshape(-1) for name, m in zip(grid, mesh)}


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
    seeds = _check_seeds(seeds)
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
    """Whether ``obj`` pickles (a loop must, to run in worker processes); warns when it does not.

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

    try:
        pickle.dumps(obj)
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
