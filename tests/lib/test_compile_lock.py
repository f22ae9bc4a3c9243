"""A loop structure is compiled once per machine, not once per process that needs it at the same time.

A cold ``reproduce all --jobs 16`` compiled 10 structures 221 times: every worker that received a chunk of a
structure not yet in numba's disk cache compiled it itself. :func:`~ctrl_analysis.engine.jit.compile_lock` makes
the first process compile while the others wait, then load what it saved.
"""

import os
import subprocess
import sys
import threading
import time

import pytest
from hang import limit

from ctrl_analysis.engine import jit


def test_a_held_lock_makes_the_next_holder_wait_until_it_is_released(tmp_path):
    path = str(tmp_path / "x.lock")
    got = {}

    def second():
        with jit.compile_lock(path) as held:
            got["at"], got["held"] = time.monotonic(), held

    with jit.compile_lock(path) as held:
        assert held
        t = threading.Thread(target=second)
        t.start()
        time.sleep(0.3)
        assert "at" not in got  # still waiting
        released = time.monotonic()
    t.join(limit(10))
    assert got["held"] and got["at"] >= released


def test_a_wait_longer_than_compile_wait_gives_up_and_runs_unlocked(tmp_path, monkeypatch):
    monkeypatch.setattr(jit, "COMPILE_WAIT", 0.05)
    path = str(tmp_path / "x.lock")
    out = {}

    def second():
        with jit.compile_lock(path) as held:
            out["held"] = held

    with jit.compile_lock(path):
        t = threading.Thread(target=second)
        t.start()
        t.join(limit(10))
        assert out == {"held": False}


def test_once_compiled_a_block_runs_at_once_without_waiting_for_the_lock(tmp_path):
    """A block that ended without error leaves a marker; later blocks (warm workers loading from the cache) do not
    queue on the lock, even while another process holds it. A block that failed leaves none."""
    path = str(tmp_path / "x.lock")
    with pytest.raises(RuntimeError), jit.compile_lock(path) as held:
        assert held
        raise RuntimeError("numba could not compile it")
    assert not os.path.exists(jit._marker(path))
    with jit.compile_lock(path) as held:
        assert held
    assert os.path.exists(jit._marker(path))
    got = {}

    def later():
        with jit.compile_lock(path) as held:
            got["held"] = held

    import fcntl

    fd = os.open(path, os.O_RDWR)
    fcntl.flock(fd, fcntl.LOCK_EX)  # as if another process held it now
    try:
        t = threading.Thread(target=later)
        t.start()
        t.join(limit(10))
        assert got == {"held": False}  # ran at once, unlocked: it loads what is cached
    finally:
        os.close(fd)


def test_an_unwritable_lock_file_runs_the_block_unlocked(tmp_path):
    with jit.compile_lock(str(tmp_path / "no" / "such" / "dir.lock")) as held:
        assert held is False


CHILD = r"""
import os, sys, time
import numpy as np
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.engine import codegen

loop = Loop([place(DifferentialEstimator(4, 3.0), "sigma")], dt=1e-3)
open(sys.argv[1] + ".ready", "w").close()
while not os.path.exists(sys.argv[2] + ".ready"):  # both processes reach the compile together
    time.sleep(0.01)
loop.simulate(5, inputs={n: 0.0 for n in loop.external}, execution=Execution(engine="compiled"))
(run, _), = codegen._RUNNERS.values()
print(sum(run.stats.cache_misses.values()), sum(run.stats.cache_hits.values()))
"""


def test_two_processes_needing_a_new_structure_at_once_compile_it_once(tmp_path):
    env = dict(os.environ, CTRL_ANALYSIS_CACHE=str(tmp_path / "cache"), NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    a, b = str(tmp_path / "a"), str(tmp_path / "b")
    procs = [subprocess.Popen([sys.executable, "-c", CHILD, me, other], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for me, other in ((a, b), (b, a))]
    outs = [p.communicate(timeout=limit(120)) for p in procs]
    assert all(p.returncode == 0 for p in procs), [e for _, e in outs]
    counts = sorted(tuple(int(v) for v in o.split()) for o, _ in outs)
    # (misses, hits): one process compiled, the other loaded what it saved
    assert counts == [(0, 1), (1, 0)], counts
