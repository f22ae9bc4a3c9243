"""Benchmark (not a test): arena tunings per second on the compiled engine against the numpy engine.

One tuning is one configuration scored on one case (S noisy + S noise-free records); the same
configurations, signals and noise run on both engines (``estimate(..., engine=...)``), after a
warm-up call that compiles the runner (its time is not counted).

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_arena.py [--configs 60]
"""

from __future__ import annotations

import argparse
import time

import _common  # noqa: F401  (single-threaded BLAS, repository on sys.path)

from ctrl_analysis.arena.interface import FAMILIES
from ctrl_analysis.arena.tuning import Case, Setup, _grid, evaluate, param_values


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--configs", type=int, default=60)
    args = ap.parse_args()
    setup = Setup()
    case = Case("sines", "uniform", 0.01, 4.0, (1, 2, 3))
    print(f"{'family':10s} {'compiled /s':>12s} {'numpy /s':>10s} {'ratio':>6s}")
    for fam in FAMILIES:
        z, _ = _grid(fam)
        z = z.repeat(-(-args.configs // len(z)), axis=0)[:args.configs]
        configs = [(0, v) for v in param_values(fam, z, case, setup)]
        rates = {}
        for engine in ("compiled", "numpy"):
            if fam.name == "algebraic" and engine == "compiled":
                engine_used = "numpy"  # FIR in numpy on both
            else:
                engine_used = engine
            evaluate((fam.name, setup, (case,), configs[:2], engine_used))  # warm-up / compile
            t0 = time.perf_counter()
            evaluate((fam.name, setup, (case,), configs, engine_used))
            rates[engine] = len(configs) / (time.perf_counter() - t0)
        print(f"{fam.name:10s} {rates['compiled']:12.1f} {rates['numpy']:10.1f} {rates['compiled'] / rates['numpy']:6.1f}")


if __name__ == "__main__":
    main()
