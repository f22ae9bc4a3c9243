"""`--scheduler` on a real Dask cluster: a scheduler and two workers in separate processes (loopback only).

A study run through the cluster gives the same quantities, seeds and findings as a run in one
process, and the workers did the work; a malformed or unreachable address is one line, exit 2,
before any study starts.
"""

import json
import os
import shutil
import socket
import subprocess
import sys
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
STUDIES = {{"skeleton": "analysis._skeleton"}}
MEMORY = {{}}
def load_study(name):
    return importlib.import_module(STUDIES[name])
"""


def _registry(tmp_path: Path) -> dict:
    pkg = tmp_path / "registry" / "analysis"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text(REGISTRY)
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(pkg.parent), str(REPO)]), "OPENBLAS_NUM_THREADS": "1",
            "CTRL_ANALYSIS_PROGRESS": "0"}


def _cli(*argv, env):
    return subprocess.run([sys.executable, "-m", "ctrl_analysis.cli", *argv], capture_output=True, text=True,
                          cwd=env["PYTHONPATH"].split(os.pathsep)[0], timeout=limit(600), env=env, check=False)


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


@pytest.fixture
def cluster(tmp_path):
    """``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1; stopped (and checked gone) after."""
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
            yield address, client, env
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


@pytest.mark.parametrize("address", ["banana", "tcp://127.0.0.1:99999", "unreachable"])
def test_a_bad_scheduler_address_is_one_line_and_exit_2_before_any_work(tmp_path, address):
    if address == "unreachable":
        address = f"tcp://127.0.0.1:{_free_port()}"  # nothing listens there
    proc = _cli("reproduce", STUDY, "--quick", "--out", str(tmp_path / "out"), "--scheduler", address,
                env={**_registry(tmp_path), "CTRL_ANALYSIS_SCHEDULER_TIMEOUT": "1"})
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("ctrl-analysis: error: --scheduler") and address in lines[0]
    out = tmp_path / "out"
    assert proc.stdout == "" and not (out / STUDY).exists()
    assert not out.exists() or sorted(p.name for p in out.iterdir()) == []  # no lock, no staging folder left
