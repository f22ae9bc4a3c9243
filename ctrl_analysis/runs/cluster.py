"""Dask clusters for :mod:`ctrl_analysis.runs.parallel`: address checks, a process-wide cluster, bounded-time failures.

:func:`use_cluster` connects to a cluster once and makes it process-wide: while it is active every
:func:`~ctrl_analysis.runs.parallel.map_chunks` call without a ``scheduler`` (or with the one the cluster was made from)
and every batch of :meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` (two runs or more, no callable
input, a picklable loop) runs its chunks there, with the same numbers as on one process. The command line's
``--scheduler`` does this, so every study's Monte Carlo batches and sweeps go to the cluster without the study
knowing.

The cluster path fails in bounded time, in one line: :func:`use_cluster` (and a ``scheduler`` address given to
``map_chunks``) first asks the address for a Dask scheduler's handshake and identity within the connection
time-out, so a port where nothing listens, or where something other than a Dask scheduler answers (an HTTP
server, a service that speaks first), is an :class:`OSError` naming the address within that time; while chunks
run, a lost scheduler, or no worker connected to it for ``worker_timeout`` seconds (:data:`WORKER_TIMEOUT` by
default: every worker killed, or none ever joined), is a :class:`ClusterError`, and the process-wide cluster is
then marked failed so later batches fail at once. Dask's own log records and warnings are silenced meanwhile (a
``"local"`` cluster's scheduler and workers too), since these failures are reported by the exception.
"""

from __future__ import annotations

import contextlib
import os
import re
import threading

from .._validate import check_int, check_positive, check_str

__all__ = ["WORKER_TIMEOUT", "ClusterError", "active_cluster", "check_scheduler_address", "default_jobs",
           "silence_dask_logs", "use_cluster"]


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


#: Seconds a Dask run waits while no worker is connected to its scheduler (every worker lost, or none
#: joined) before it stops with a :class:`ClusterError`; long enough for a nanny to restart a worker.
WORKER_TIMEOUT = 60.0


#: Seconds between two looks at the cluster while its chunks run (when none finished meanwhile).
_POLL_S = 1.0


#: The process-wide cluster of :func:`use_cluster`: its client, the ``scheduler`` it was given, its
#: address, the chunks it ran, its worker time-out, and why it failed (``None`` while it works).
_CLUSTER: dict = {"client": None, "scheduler": None, "address": None, "chunks": 0, "worker_timeout": WORKER_TIMEOUT,
                  "failed": None, "starting": 0}


class ClusterError(RuntimeError):
    """The Dask cluster failed while chunks ran on it.

    Its scheduler was lost, or no worker was connected for :data:`WORKER_TIMEOUT` seconds. The message
    names the scheduler's address and says how many chunks were unfinished.
    """


_ADDRESS = re.compile(r"^(?:(tcp|tls|ucx|ws|wss)://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):(\d{1,5})$")


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
                        worker_timeout=worker_timeout, failed=None, starting=jobs if scheduler == "local" else 0)
        try:
            yield client
        finally:
            _CLUSTER.update(client=None, scheduler=None, worker_timeout=WORKER_TIMEOUT, failed=None, starting=0)
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
        started = sum(_CLUSTER["client"].nthreads(callback_timeout=5).values())
    except Exception:  # noqa: BLE001 - a cluster that cannot say still takes one chunk
        started = 1
    return max(1, started, _CLUSTER["starting"])  # a local cluster's workers still starting count


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
        for lg, level in zip(loggers, levels, strict=True):
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
        # no dashboard; the scheduler's HTTP routes still start, on a port the system picks (their default,
        # 8787, warns "Port 8787 is already in use" whenever another cluster runs on the machine)
        # the scheduler now, its workers in the background (each importing the library as it starts,
        # ctrl_analysis.runs._warm): the driver goes on meanwhile, and the first chunks wait for them
        cluster = LocalCluster(n_workers=0, threads_per_worker=1, processes=True, dashboard_address=None,
                               worker_dashboard_address=None, silence_logs=logging.CRITICAL,
                               scheduler_kwargs={"dashboard_address": ":0"}, preload=["ctrl_analysis.runs._warm"])
        cluster.scale(jobs)
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


#: What several chunks share (the function, a member of their argument tuples) is sent to the cluster once, as a
#: future, from this size on (bytes, pickled): below it, sending it with every chunk costs less than a round trip.
SCATTER_BYTES = 1 << 20


def _pickled_size(obj) -> int:
    """Bytes of ``obj`` as Dask would send it (cloudpickle); 0 for what cannot be pickled (Dask reports that)."""
    import numpy as np

    if isinstance(obj, np.ndarray):
        return obj.nbytes
    if obj is None or isinstance(obj, (bool, int, float, str, bytes)):
        return len(obj) if isinstance(obj, (str, bytes)) else 8
    try:
        import cloudpickle

        return len(cloudpickle.dumps(obj))
    except Exception:  # noqa: BLE001 - anything unpicklable is Dask's to report, with its own message
        return 0


def _call(fn, arg):
    """``fn(arg)`` on a worker: what :func:`_shared_once` sent as futures arrives here as the objects."""
    return fn(arg)


def _shared_once(client, fn, args: list):
    """``fn`` and ``args`` with what several calls share, and is large, replaced by futures of one copy.

    Dask otherwise embeds a chunk's inputs in its task, so a loop and its held inputs shared by every chunk
    travel once per chunk ("Sending large graph of size 12.8 MiB", again and again). Shared means the same
    object (by identity) in two calls or more: ``fn`` itself, or a member of the argument tuples. Each is
    scattered to every worker once (``broadcast``); workers resolve the futures before the call, so ``fn``
    sees the same objects and the results are the same bit for bit.
    """
    if len(args) < 2:
        return fn, args
    seen: dict = {}

    def count(obj, depth):
        seen.setdefault(id(obj), [obj, 0])[1] += 1
        if depth:
            for m in _members(obj):
                count(m, depth - 1)

    for a in args:
        count(a, _SCATTER_DEPTH)
    big = {i: m for i, (m, n) in seen.items() if n > 1 and _pickled_size(m) >= SCATTER_BYTES}
    send_fn = _pickled_size(fn) >= SCATTER_BYTES
    if not big and not send_fn:
        return fn, args
    futures: dict = {}

    def swap(obj, depth):
        if id(obj) in big:  # sent once, when first met: a shared object's own members are not looked into
            if id(obj) not in futures:
                futures[id(obj)] = client.scatter(obj, broadcast=True, hash=False)
            return futures[id(obj)]
        if not depth:
            return obj
        if isinstance(obj, dict):
            return {k: swap(v, depth - 1) for k, v in obj.items()}
        if isinstance(obj, list):
            return [swap(v, depth - 1) for v in obj]
        if isinstance(obj, tuple) and type(obj) is tuple:
            return tuple(swap(v, depth - 1) for v in obj)
        return obj

    return (client.scatter(fn, broadcast=True, hash=False) if send_fn else fn), [swap(a, _SCATTER_DEPTH) for a in args]


#: How deep :func:`_shared_once` looks into a call's argument: its members and theirs (tuples, lists, dicts).
_SCATTER_DEPTH = 2


def _members(obj) -> list:
    """The members Dask resolves futures in: of a plain tuple, a list, a dict's values."""
    if isinstance(obj, dict):
        return list(obj.values())
    if isinstance(obj, list) or type(obj) is tuple:
        return list(obj)
    return []


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
    call, call_args = _shared_once(client, fn, args)
    futures = client.map(_call, [call] * len(args), call_args, pure=False)
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
