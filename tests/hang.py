"""The suite's time limits are hang detectors: each is a generous base, scaled with this machine's load and speed.

A limit must never be reached by a slow or loaded machine without a real hang (a test that waits for a
subprocess, a cluster or a study). Every limit in the suite is ``limit(base)``: ``base`` is several times the
longest run seen on the 2-core development machine, multiplied by :func:`factor`, which measures, once per
process, how loaded (the 1-minute load average per core) and how slow (a fixed pure-Python loop against its
time on the development machine) this machine is. ``CTRL_ANALYSIS_HANG_FACTOR`` overrides the measurement.
"""

from __future__ import annotations

import functools
import os
import time

#: Seconds the calibration loop takes on the 2-core development machine (idle).
REFERENCE_S = 0.012


def _calibration() -> float:
    t = time.perf_counter()
    s = 0
    for i in range(300_000):
        s += i * i
    return time.perf_counter() - t


@functools.lru_cache(maxsize=1)
def factor() -> float:
    """How many times longer than on the idle development machine work may take here (>= 1)."""
    env = os.environ.get("CTRL_ANALYSIS_HANG_FACTOR")
    if env:
        return max(1.0, float(env))
    try:
        load = os.getloadavg()[0] / (os.cpu_count() or 1)
    except OSError:
        load = 1.0
    slow = min(_calibration() for _ in range(3)) / REFERENCE_S
    return max(1.0, load) * max(1.0, slow)


def limit(seconds: float) -> float:
    """``seconds`` (a generous base) scaled by :func:`factor`."""
    return seconds * factor()
