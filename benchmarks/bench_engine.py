"""Benchmark: what the engine costs on Example 1 when a user brings their own block, and what storage costs.

Example 1 of the differential-estimator paper (plant (19), Σ (5, 7.0), Han's fal ESO, RK4 at
h = 1 ms, noise held per step), as in ``bench_example1.py``, whose float loop, compiled reference
and loop this script reuses. The plant is ``Plant19`` there: a block written by the user as the
documentation says (``docs/guide.rst``), so these rows are what a user's own block gets.

Rows:

* ``float loop`` and ``compiled reference``: the plain-Python loop and the same function compiled
  by numba, each computing the study's metric (mean |x_i - x̂_i| over the samples) as it goes;
* ``engine, B = 1``: one run of the user's loop on the compiled engine (compile time apart);
* ``engine, B = 1000, keep= / every=``: the Monte Carlo with the six signals the metric needs
  stored at every sample, at every 10th and every 100th sample, and with none stored (final
  state only). Decimation changes the metric (a mean over fewer samples): its relative change is
  printed in the last column, so the speed is weighed against what it costs.

    python benchmarks/bench_engine.py [--T 2.0] [--repeat 5]
"""

from __future__ import annotations

import argparse
import time

import _common  # noqa: F401  (single-threaded BLAS, repository on sys.path)
import numpy as np
from _common import Row, round_robin, table
from bench_example1 import (
    H,
    build_loop,
    coefficients,
    compiled_loop,
    engine_errors,
    float_loop,
)

from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.noise import draw_noise, run_seeds, uniform_noise

NAME = "Example 1, user block (engine)"
KEEP = ["x[0]", "x[1]", "xhat[0]", "xhat[1]", "eso_xhat[0]", "eso_xhat[1]"]


def run(T=2.0, repeat=5, B=1000):
    n = round(T / H)
    seeds = run_seeds(0, B)
    noise = draw_noise(seeds, n, uniform_noise([-0.1, -0.001], [0.1, 0.001]))
    loop = build_loop()
    c = coefficients(loop)
    fn_c, t_compile = compiled_loop()
    xi_c, eta_c = np.ascontiguousarray(noise[:, :, 0].T), np.ascontiguousarray(noise[:, :, 1].T)
    from ctrl_analysis.engine import codegen as _kernels

    c0 = _kernels.compile_seconds()
    loop.simulate(2, inputs={"xi": 0.0, "eta": 0.0, "uc": 0.0}, execution=Execution(engine="compiled"))
    t_engine_compile = _kernels.compile_seconds() - c0

    def inputs(b):
        return {"xi": noise[:, :b, 0], "eta": noise[:, :b, 1], "uc": 0.0}

    fns = {
        "float loop (plain Python), 1 run": (1, lambda: float_loop(noise[:, 0, 0].tolist(), noise[:, 0, 1].tolist(),
                                                                   n, H, c)),
        f"compiled reference (numba), {B} runs": (B, lambda: [fn_c(xi_c[b], eta_c[b], n, H, c) for b in range(B)]),
        "engine (compiled), B = 1, all signals and states": (1, lambda: loop.simulate(n, inputs=inputs(1))),
    }
    for every in (1, 10, 100):
        fns[f"engine (compiled), B = {B}, keep 6 signals, every = {every}"] = (
            B, lambda every=every: loop.simulate(n, inputs=inputs(B), save=Save(keep=KEEP, every=every, states=False)))
    fns[f"engine (compiled), B = {B}, keep nothing (final state)"] = (
        B, lambda: loop.simulate(n, inputs=inputs(B), save=Save(keep=[], states=False)))
    # the first call of the every = 1 row, in this fresh process: its 96 MB result is first-touch memory
    first = f"engine (compiled), B = {B}, keep 6 signals, every = 1"
    t0 = time.perf_counter()
    fns[first][1]()
    t_first = time.perf_counter() - t0
    timed = round_robin({k: f for k, (_, f) in fns.items()}, repeat, warmup=1)
    full = np.array([out[1] for out in timed[f"compiled reference (numba), {B} runs"][1]])
    rows = []
    for name, (runs, _) in fns.items():
        seconds, out = timed[name]
        agree = ""
        if name.startswith(f"engine (compiled), B = {B}, keep 6"):
            rel = np.max(np.abs(engine_errors(out) - full) / np.abs(full))
            agree = f"metric vs full-sample reference: max rel. {rel:.1e}"
        elif "B = 1," in name:
            agree = f"metric rel. {np.max(np.abs(engine_errors(out)[0] - full[0]) / np.abs(full[0])):.1e}"
        rows.append(Row(NAME, name, runs, seconds, agree))
    base = timed["float loop (plain Python), 1 run"][0]
    ref = timed[f"compiled reference (numba), {B} runs"][0] / B
    notes = [(f"numba compile of the reference: {t_compile:.2f} s; engine runner compile (or disk-cache load): "
              f"{t_engine_compile:.2f} s; neither is in the rows"),
             (f"one untimed round first; the first call of the keep 6, every = 1 row in the process took "
              f"{t_first:.3f} s ({t_first / B / ref:.2f}x the reference per run): its result, "
              f"{8 * (n + 1) * B * len(KEEP) / 2**20:.0f} MiB, is new memory the kernel zeroes (and may compact "
              f"for huge pages); later calls reuse the memory freed by the previous result")]
    return rows, base, ref, notes


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--T", type=float, default=2.0, help="simulated seconds (default 2.0)")
    ap.add_argument("--repeat", type=int, default=5, help="timing rounds, median reported (default 5)")
    a = ap.parse_args(argv)
    rows, base, ref, notes = run(a.T, a.repeat)
    print(table(rows, {NAME: base}, {NAME: ref}))
    for note in notes:
        print(f"- {note}")


if __name__ == "__main__":
    main()
