"""Run every benchmark in one process (single-threaded BLAS) and print one table.

Usage::

    python benchmarks/run_all.py [--T 2.0] [--repeat 5] [--readme]

``--readme`` also writes the table and notes into ``benchmarks/README.md`` between the
``<!-- results -->`` markers, so the README shows exactly what was printed. Not a test: timings
never decide pass/fail; each benchmark checks that the implementations it compares agree.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
from pathlib import Path

import _common  # noqa: F401  (before numpy: single-threaded BLAS)
import bench_arena
import bench_ckf
import bench_example1
import bench_ikf_mfac
import bench_pendulum
from _common import table

BENCHMARKS = (bench_example1, bench_ikf_mfac, bench_ckf, bench_pendulum, bench_arena)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--T", type=float, default=2.0, help="simulated seconds of Example 1 (default 2)")
    ap.add_argument("--io-T", type=float, default=0.05, help="seconds run by the adaptive input_output_response")
    ap.add_argument("--repeat", type=int, default=5, help="timing repeats; the median is reported (default 5)")
    ap.add_argument("--readme", action="store_true", help="write the results into benchmarks/README.md")
    args = ap.parse_args(argv)

    rows, base, comp, notes = [], {}, {}, []
    for bench in BENCHMARKS:
        kw = {"T": args.T, "io_T": args.io_T} if bench is bench_example1 else {}
        r, b, c, n = bench.run(repeat=args.repeat, **kw)
        rows += r
        base[bench.NAME], comp[bench.NAME] = b, c
        notes += [f"{bench.NAME}: {x}" for x in n]
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    head = (f"Python {platform.python_version()}, {os.cpu_count()} cores, load average {load:.1f} at the end; "
            f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}; medians of {args.repeat} repeats; Example "
            f"1 over {args.T:g} s ({round(args.T / bench_example1.H)} RK4 steps); the study benchmarks (not the "
            "arena's) have no compiled reference (— in the last ratio column)")
    text = "\n".join([head, "", table(rows, base, comp), "", *[f"- {x}" for x in notes]])
    print(text)
    if args.readme:
        path = Path(__file__).with_name("README.md")
        readme = path.read_text(encoding="utf-8")
        a, b = "<!-- results -->", "<!-- /results -->"
        if a not in readme or b not in readme:
            sys.stderr.write(f"run_all: error: {path} has no {a} ... {b} section\n")
            return 1
        pre, rest = readme.split(a, 1)
        post = rest.split(b, 1)[1]
        path.write_text(f"{pre}{a}\n{text}\n{b}{post}", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
