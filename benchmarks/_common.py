"""Helpers shared by the benchmarks: single-threaded BLAS, medians of repeats, one table.

Import this module before numpy (it sets ``OPENBLAS_NUM_THREADS=1`` and friends) and put the
repository root on ``sys.path``.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before numpy / numba are imported

import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def median_time(fn, repeat: int) -> tuple[float, object]:
    """Median wall time of ``repeat`` calls of ``fn()`` and the last call's result."""
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def round_robin(fns: dict, repeat: int, warmup: int = 0) -> dict:
    """Median wall time of each ``fns[name]()`` over ``repeat`` rounds, the methods interleaved in every round.

    Interleaving makes a change in the machine's load (a shared machine) hit every method alike, so
    ratios stay meaningful when absolute times drift. ``warmup`` untimed rounds come first. A
    method's previous result is dropped before it runs again, so a large result's memory is
    returned and reused, as in a loop that reduces each result and lets it go (otherwise every
    call faults in fresh pages, and the kernel may have to compact memory for its huge pages).
    Returns ``name -> (median seconds, last result)``.
    """
    times = {name: [] for name in fns}
    out = {}
    for r in range(warmup + repeat):
        for name, fn in fns.items():
            out.pop(name, None)
            t0 = time.perf_counter()
            out[name] = fn()
            if r >= warmup:
                times[name].append(time.perf_counter() - t0)
    return {name: (statistics.median(times[name]), out[name]) for name in fns}


@dataclass
class Row:
    """One line of the benchmark table: a method, its runs, its median time, and its agreement."""

    bench: str
    method: str
    runs: int
    seconds: float
    agreement: str = ""
    note: str = ""

    @property
    def per_run(self) -> float:
        return self.seconds / self.runs


def table(rows: list[Row], baseline: dict[str, float], compiled: dict[str, float | None]) -> str:
    """Markdown table: per-run time, speed-up over the float loop, and ratio to the compiled reference (— if none)."""
    head = ("| benchmark | method | runs | median total (s) | per run (ms) | float loop / this | "
            "this / compiled | agreement |")
    lines = [head, "| --- | --- | ---: | ---: | ---: | ---: | ---: | --- |"]
    for r in rows:
        speed = baseline[r.bench] / r.per_run
        vs_c = "—" if compiled[r.bench] is None else f"{r.per_run / compiled[r.bench]:.2f}"
        lines.append(f"| {r.bench} | {r.method} | {r.runs} | {r.seconds:.3f} | {1e3 * r.per_run:.3f} | "
                     f"{speed:.2f} | {vs_c} | {r.agreement} |")
    return "\n".join(lines)
