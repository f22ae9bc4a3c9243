"""`--scheduler` on a real Dask cluster: a scheduler and two workers in separate processes (loopback only).

A study run through the cluster gives the same quantities, seeds and findings as a run in one
process, and the workers did the work; a malformed or unreachable address, or one where something
other than a Dask scheduler answers, is one line, exit 2, before any study starts, and leaves no
--out folder behind. A cluster that fails mid-run (every worker killed, or the scheduler killed) ends
the run with one line and exit 1, within the worker time-out; `--scheduler local` prints nothing of
Dask's.
"""

import http.server
import json
import os
import shutil
import socket
import socketserver
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from hang import limit

REPO = Path(__file__).resolve().parents[2]
#: The skeleton study (analysis/_skeleton): a real study (Monte Carlo batch on the compiled engine, a
#: sensitivity sweep through map_chunks) whose one small loop structure compiles in about a second in each
#: worker, where a paper's study compiles several; registered by a stand-in ``analysis`` package first on
#: PYTHONPATH whose ``__path__`` also holds the real one (so ``analysis._skeleton`` is the repository's).
STUDY = "skeleton"
REGISTRY = f"""
import importlib
__path__.append({str(REPO / "analysis")!r})
STUDIES = {{"skeleton": "analysis._skeleton", "hold": "analysis.hold", "big": "analysis.big"}}
MEMORY = {{}}
def load_study(name):
    return importlib.import_module(STUDIES[name])
"""

#: Two stand-in studies beside the skeleton. ``hold`` maps two tasks over the cluster, each of which marks
#: that it started (a file in HOLD_DIR, written by the worker running it) and then waits for a release
#: file (2 minutes at most): a test can kill the cluster while its tasks are surely running. ``big`` maps
#: two tasks whose graph is 24 MB (Dask warns in six lines from 10 MB) through an unpicklable loop's
#: check twice (a batch of such a loop warns once): on ``--scheduler local`` it prints nothing.
STUDIES = {
    "hold": """
import os
import time
from pathlib import Path
from ctrl_analysis.runs.parallel import map_chunks
from ctrl_analysis.reporting.report import StudyInfo, StudyResult

INFO = StudyInfo(name="hold", seed_file="s.txt", paper="P", reproduces="r")


def task(i):
    hold = Path(os.environ["HOLD_DIR"])
    (hold / f"started-{i}").write_text(str(os.getpid()))
    end = time.monotonic() + 120
    while not (hold / "release").exists() and time.monotonic() < end:
        time.sleep(0.05)
    return i


def run(ctx, params=None):
    result = StudyResult(INFO)
    result.quantity("n", "tasks done", float(len(map_chunks(task, [0, 1], scheduler=ctx.scheduler))), runs=None)
    return result
""",
    "big": """
from ctrl_analysis.runs.parallel import map_chunks, picklable
from ctrl_analysis.reporting.report import StudyInfo, StudyResult

INFO = StudyInfo(name="big", seed_file="s.txt", paper="P", reproduces="r")


class Unpicklable:
    def __init__(self):
        import threading

        self.f = threading.Lock()  # a lambda would travel (cloudpickle); a lock does not


def run(ctx, params=None):
    result = StudyResult(INFO)
    sizes = map_chunks(len, [b"x" * 12_000_000, b"y" * 12_000_000], scheduler=ctx.scheduler)
    loop = Unpicklable()
    assert not picklable(loop) and not picklable(loop)  # what two batches of such a loop ask
    result.quantity("bytes", "bytes mapped", float(sum(sizes)), runs=None)
    return result
""",
}


def _registry(tmp_path: Path) -> dict:
    pkg = tmp_path / "registry" / "analysis"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text(REGISTRY)
    for name, text in STUDIES.items():
        (pkg / f"{name}.py").write_text(text)
    hold = tmp_path / "hold"
    hold.mkdir()
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(pkg.parent), str(REPO)]), "OPENBLAS_NUM_THREADS": "1",
            "CTRL_ANALYSIS_PROGRESS": "0", "HOLD_DIR": str(hold)}


def _cli(*argv, env, timeout=600):
    return subprocess.run([sys.executable, "-m", "ctrl_analysis.cli", *argv], capture_output=True, text=True,
                          cwd=env["PYTHONPATH"].split(os.pathsep)[0], timeout=limit(timeout), env=env, check=False)


#: Run as ``python -c DIE_WITH_PARENT parent_pid program args...``: on Linux, arrange to be killed when the
#: test process dies (even by SIGKILL, when the fixture's ``finally`` cannot run; a ``dask worker`` whose
#: scheduler is gone otherwise waits to reconnect for ever), then become ``program`` (the setting survives exec).
DIE_WITH_PARENT = """
import os, signal, sys
if sys.platform.startswith("linux"):
    import ctypes
    ctypes.CDLL(None).prctl(1, int(signal.SIGKILL), 0, 0, 0)  # 1 = PR_SET_PDEATHSIG
    if os.getppid() != int(sys.argv[1]):  # the test process died before that
        sys.exit(1)
os.execv(sys.argv[2], sys.argv[2:])
"""


def _dask(*argv, log, env):
    dask = shutil.which("dask", path=os.path.dirname(sys.executable)) or shutil.which("dask")
    return subprocess.Popen([sys.executable, "-c", DIE_WITH_PARENT, str(os.getpid()), dask, *argv], cwd=REPO, env=env,
                            stdout=log, stderr=subprocess.STDOUT)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _start_cluster(tmp_path, *, keep_client: bool):
    """``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1; stopped (and checked gone) after.

    Yields the address, a client of the test process (``None`` unless ``keep_client``: a test that kills the
    scheduler keeps none, whose reconnection would outlive it), the environment and the processes
    (scheduler first)."""
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = _registry(tmp_path)
    log = open(tmp_path / "dask.log", "w")  # noqa: SIM115 - closed in the finally below
    procs = [_dask("scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard", log=log, env=env)]
    try:
        for i in range(2):
            procs.append(_dask("worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard",
                               "--host", "127.0.0.1", "--name", f"w{i}", "--local-directory", str(tmp_path / f"w{i}"),
                               log=log, env=env))
        from distributed import Client

        with Client(address, timeout="60s") as client:
            client.wait_for_workers(2, timeout=limit(180))
            if keep_client:
                yield address, client, env, procs
        if not keep_client:
            yield address, None, env, procs
    finally:
        for p in procs[::-1]:  # the workers first (a worker whose scheduler is gone waits to reconnect)
            p.kill()
            try:
                p.wait(timeout=limit(30))
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(timeout=limit(30))
        log.close()
    assert all(p.poll() is not None for p in procs)


@pytest.fixture
def cluster(tmp_path):
    """A scheduler and two workers, with a client of the test process: ``(address, client, env)``."""
    for address, client, env, _ in _start_cluster(tmp_path, keep_client=True):
        yield address, client, env


@pytest.fixture
def bare_cluster(tmp_path):
    """A scheduler and two workers, no client of the test process: ``(address, env, [scheduler, w0, w1])``."""
    for address, _, env, procs in _start_cluster(tmp_path, keep_client=False):
        yield address, env, procs


def _quantities(out: Path) -> dict:
    data = json.loads((out / STUDY / "results.json").read_text(encoding="utf-8"))
    return {"quantities": {q["id"]: (q["value"], q["std"], q["runs"], q["verdict"]) for q in data["quantities"]},
            "seeds": data["seeds"], "findings": data["findings"], "cli": data["settings"]["cli"]}


def test_a_study_on_a_real_cluster_equals_the_run_in_one_process(tmp_path, cluster):
    address, client, env = cluster
    before = sum(client.run(lambda dask_worker: dask_worker.state.transition_counter).values())
    on_cluster = _cli("reproduce", STUDY, "--quick", "--out", str(tmp_path / "cluster"), "--scheduler", address,
                      env=env)
    assert on_cluster.returncode == 0, on_cluster.stderr[-2000:]
    # the workers did the work: they moved tasks through their states, and the run says how many chunks
    per_worker = client.run(lambda dask_worker: dask_worker.state.transition_counter)
    assert len(per_worker) == 2 and sum(per_worker.values()) > before
    line = [x for x in on_cluster.stdout.splitlines() if x.startswith("dask: ")]
    assert len(line) == 1 and line[0].endswith(f"ran on {address}")
    assert int(line[0].split()[1]) >= 2
    here = _cli("reproduce", STUDY, "--quick", "--out", str(tmp_path / "here"), "--jobs", "1", env=env)
    assert here.returncode == 0, here.stderr[-2000:]
    a, b = _quantities(tmp_path / "cluster"), _quantities(tmp_path / "here")
    assert a["quantities"] and a == b  # every value, std, run count and verdict bit for bit; seeds; findings


class _SpeaksFirst(socketserver.BaseRequestHandler):
    """A service that greets first (as SSH does): Dask used to read its banner as a message of 3 EiB."""

    def handle(self):
        self.request.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
        while self.request.recv(4096):
            pass


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def _serve(kind: str):
    """A server on a free loopback port that is not a Dask scheduler, serving in a thread; ``server.shutdown()``."""
    if kind == "http":  # reads Dask's handshake as a request line and waits for its end: Dask used to hang
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Quiet)
    else:
        server = socketserver.ThreadingTCPServer(("127.0.0.1", 0), _SpeaksFirst)
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


@pytest.mark.parametrize("address", ["banana", "tcp://127.0.0.1:99999", "unreachable", "http", "speaks-first"])
def test_a_bad_scheduler_address_is_one_line_and_exit_2_before_any_work(tmp_path, address):
    server, kind = None, address
    if kind == "unreachable":
        address = f"tcp://127.0.0.1:{_free_port()}"  # nothing listens there
    elif kind in ("http", "speaks-first"):
        server = _serve(kind)
        address = f"tcp://127.0.0.1:{server.server_address[1]}"
    out = tmp_path / "deep" / "out"  # two folders this run would create
    try:
        # the time-out is 2 s; the hang detector's limit is many times that
        proc = _cli("reproduce", STUDY, "--quick", "--out", str(out), "--scheduler", address,
                    env={**_registry(tmp_path), "CTRL_ANALYSIS_SCHEDULER_TIMEOUT": "2"}, timeout=60)
    finally:
        if server is not None:
            server.shutdown()
            server.server_close()
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("ctrl-analysis: error: --scheduler") and address in lines[0]
    if kind == "unreachable":
        assert "no Dask scheduler answers" in lines[0]
    elif server is not None:
        assert "is not a Dask scheduler" in lines[0]
    assert proc.stdout == ""
    assert not (tmp_path / "deep").exists()  # nothing was written: no --out folder, no lock, no staging folder


def _wait_for(predicate, what: str, timeout: float = 180.0) -> None:
    end = time.monotonic() + limit(timeout)
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"{what} within {timeout} s")
        time.sleep(0.05)


@pytest.mark.parametrize("kill", ["workers", "scheduler"])
def test_a_cluster_killed_mid_run_ends_the_run_in_one_line(tmp_path, bare_cluster, kill):
    # every worker killed: the tasks would wait for ever (the old run never ended); the run stops after the
    # worker time-out. The scheduler killed: the old run printed a 35-47-line traceback.
    address, env, procs = bare_cluster
    hold = Path(env["HOLD_DIR"])
    out = tmp_path / "out"
    run = subprocess.Popen([sys.executable, "-m", "ctrl_analysis.cli", "reproduce", "hold", "--out", str(out),
                            "--scheduler", address], cwd=env["PYTHONPATH"].split(os.pathsep)[0],
                           env={**env, "CTRL_ANALYSIS_WORKER_TIMEOUT": "3"}, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)
    try:
        _wait_for(lambda: len(list(hold.glob("started-*"))) == 2, "both tasks did not start on the workers")
        for p in procs[1:] if kill == "workers" else procs[:1]:
            p.kill()
        stdout, stderr = run.communicate(timeout=limit(180))  # a hang detector: the run must end by itself
    finally:
        (hold / "release").write_text("")
        if run.poll() is None:
            run.kill()
            run.wait(timeout=limit(30))
    assert run.returncode == 1, stderr
    lines = stderr.strip().splitlines()
    why = (f"no Dask worker connected to the scheduler at {address} for 3 s: every worker was lost, or none joined"
           if kill == "workers" else f"lost the Dask scheduler at {address}")
    assert len(lines) == 1 and lines[0].startswith(f"ctrl-analysis: error: the Dask cluster failed: {why} ("), lines
    assert lines[0].endswith("; the run stopped: hold failed")
    assert stdout.strip().splitlines()[-1].startswith("ctrl-analysis: 0 of 1 studies OK, 1 failed, ")
    assert not out.exists()  # nothing was written: the folder this run made is gone


def test_scheduler_local_prints_nothing_of_dasks(tmp_path):
    # a 24 MB graph (Dask's six-line warning from 10 MB) and an unpicklable loop's check twice (one warning)
    proc = _cli("reproduce", "big", "--out", str(tmp_path / "out"), "--scheduler", "local", "--jobs", "1",
                env=_registry(tmp_path))
    assert proc.returncode == 0, proc.stderr
    # the picklable warning once (with the line of code Python shows beside it), nothing of Dask's
    assert proc.stderr.count("needs a picklable loop") == 1 and len(proc.stderr.strip().splitlines()) <= 2, \
        proc.stderr
    lines = proc.stdout.strip().splitlines()
    assert [x.split(":")[0] for x in lines] == ["== big", "dask", "ctrl-analysis"], lines
