"""Benchmark: the fuzzy closed loop of the pendulum study (lookup vs direct inference; Loop vs a float loop).

Times, in one process with ``OPENBLAS_NUM_THREADS=1``:

1. one fuzzy evaluation (B = 1 and B = 100 inputs) by the query table
   (:class:`~ctrl_analysis.controllers.fuzzy.FuzzyLookupController`, bilinear) and by direct
   Mamdani inference (:class:`~ctrl_analysis.controllers.fuzzy.FuzzyController`);
2. the closed loop without filter (cart–pendulum RK4 with 4 substeps, sensor, backward difference,
   lookup controller) per sample: the engine (:class:`ctrl_analysis.engine.loop.Loop`) with the numpy path
   (B = 1, 100) and the compiled path (every block has a kernel: B = 1, 100 = the study's batch, and
   1000) against a straightforward plain-Python float loop of the same equations (one run, same
   noise, same table), and checks that run 0 agrees. The compiled path's one-off compile time
   (numba, then cached on disk) is reported separately and kept out of the timings.

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_pendulum.py [--t-end 1.0] [--repeat 3]

Not a test: run it by hand.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy is imported

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from analysis.pendulum import loops, paper
from ctrl_analysis.noise import draw_noise, gaussian_noise


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def float_loop(p, a21, table, w, v):
    """The no-filter loop in plain Python floats: the same equations, order and RK4 as the engine.

    The noise records and the query table are converted to Python lists once (inside the timing), so
    no step reads a numpy scalar.
    """
    fc = table.controller
    U = table.U.tolist()
    E0, EC0, dE, dEC = float(table.E[0]), float(table.EC[0]), float(table.dE), float(table.dEC)
    nE, nEC = table.E.size, table.EC.size
    w, v = w.tolist(), v.tolist()
    b2, T, h, substeps = p.b2, p.T, p.T / p.substeps, p.substeps
    Ke, Kec, Ku, Xe, Xec, step = fc.Ke, fc.Kec, fc.Ku, fc.X_e, fc.X_ec, p.step
    phi, dphi, e_prev = 0.0, 0.0, 0.0
    out = [phi]
    for k in range(len(w)):
        y = phi + v[k]
        e = step - y
        ec = (e - e_prev) / T
        e_prev = e
        E = min(max(Ke * e, -Xe), Xe)
        EC = min(max(Kec * ec, -Xec), Xec)
        fe, fcc = (E - E0) / dE, (EC - EC0) / dEC
        i, j = min(max(int(math.floor(fe)), 0), nE - 2), min(max(int(math.floor(fcc)), 0), nEC - 2)
        a, b = fe - i, fcc - j
        Ui, Ui1 = U[i], U[i + 1]
        u = Ku * ((1 - a) * ((1 - b) * Ui[j] + b * Ui[j + 1]) + a * ((1 - b) * Ui1[j] + b * Ui1[j + 1]))
        bu, wk = b2 * u, w[k]  # φ'' = a21 φ + b2 u + w, inputs held over the sample
        for _ in range(substeps):
            k1a, k1b = dphi, a21 * phi + bu + wk
            k2a, k2b = dphi + 0.5 * h * k1b, a21 * (phi + 0.5 * h * k1a) + bu + wk
            k3a, k3b = dphi + 0.5 * h * k2b, a21 * (phi + 0.5 * h * k2a) + bu + wk
            k4a, k4b = dphi + h * k3b, a21 * (phi + h * k3a) + bu + wk
            phi += h / 6 * (k1a + 2 * k2a + 2 * k3a + k4a)
            dphi += h / 6 * (k1b + 2 * k2b + 2 * k3b + k4b)
        out.append(phi)
    return np.array(out)


NAME = "pendulum fuzzy loop (no filter, 1 s)"
ENGINES = (("numpy", (1, 100)), ("compiled", (1, 100, 1000)))


def engine_rows(p, a21, seeds, repeat):
    """``{(engine, B): (seconds, ClosedLoopRun)}`` for :data:`ENGINES` and the compile seconds (first call)."""
    from ctrl_analysis.engine import codegen as _kernels

    c0 = _kernels.compile_seconds()
    loops.simulate_case(p, a21, seeds[:1], engine="compiled")  # compile (or load from the disk cache) first
    compile_s = _kernels.compile_seconds() - c0
    out = {}
    for eng, batches in ENGINES:
        for B in batches:
            out[eng, B] = best_of(lambda B=B, eng=eng: loops.simulate_case(p, a21, seeds[:B], engine=eng), repeat)
    return out, compile_s


def run(repeat=3, t_end=1.0):
    """Rows for ``run_all.py``: the float loop (1 run) and the engine at B = 1 and 100.

    Returns ``(rows, float-loop seconds per run, None (no compiled reference), notes)``.
    """
    from _common import Row

    p = dataclasses.replace(paper.LOOP, t_end=t_end)
    a21 = paper.VERIFY.a21
    table = loops.fuzzy_controller(p, lookup=True)
    N = int(round(p.t_end / p.T))
    seeds = list(range(1000))
    nz = draw_noise(seeds[:1], N, gaussian_noise(p.sigma_w), gaussian_noise(p.sigma_v))
    t_float, phi_float = best_of(lambda: float_loop(p, a21, table, nz[:, 0, 0], nz[:, 0, 1]), repeat)
    rows = [Row(NAME, "float loop (plain Python), 1 run", 1, t_float, "")]
    res, compile_s = engine_rows(p, a21, seeds, repeat)
    for (eng, B), (t, r) in res.items():
        same = np.array_equal(r.phi[:, 0], res["numpy", 1][1].phi[:, 0])
        rows.append(Row(NAME, f"engine `Loop` ({eng}), B = {B}", B, t,
                        f"run 0 = numpy B = 1 run bit for bit: {same}"))
    rows[0].agreement = f"φ vs engine run 0: {np.max(np.abs(res['numpy', 1][1].phi[:, 0] - phi_float)):.1e} rad"
    notes = [f"{N} samples, RK4 with 4 substeps; best of {repeat} repeats; compiled path: {compile_s:.2f} s compile "
             "(0 when the runner is in the disk cache), not in the timings"]
    direct, rng = loops.fuzzy_controller(p, lookup=False), np.random.default_rng(0)
    for B in (1, 100):
        u = np.stack([rng.uniform(-0.1, 0.1, B), rng.uniform(-1.5, 1.5, B)], axis=1)
        x, n = np.zeros((B, 0)), (200 if B == 1 else 20)
        td, ud = best_of(lambda x=x, u=u, n=n: [direct.output(0.0, x, u) for _ in range(n)][-1], repeat)
        tl, ul = best_of(lambda x=x, u=u, n=n: [table.output(0.0, x, u) for _ in range(n)][-1], repeat)
        notes.append(f"one fuzzy evaluation, B = {B}: direct Mamdani {td / n * 1e6:.0f} µs, query table "
                     f"{tl / n * 1e6:.0f} µs ({td / tl:.0f}x); max |difference| {np.max(np.abs(ud - ul)):.3g} m/s²")
    return rows, t_float, None, notes


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=1.0)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    p = dataclasses.replace(paper.LOOP, t_end=args.t_end)
    a21 = paper.VERIFY.a21
    direct, table = loops.fuzzy_controller(p, lookup=False), loops.fuzzy_controller(p, lookup=True)

    print("1. one fuzzy evaluation")
    rng = np.random.default_rng(0)
    for B in (1, 100):
        u = np.stack([rng.uniform(-0.1, 0.1, B), rng.uniform(-1.5, 1.5, B)], axis=1)
        x = np.zeros((B, 0))
        n = 2000 if B == 1 else 200
        td, ud = best_of(lambda x=x, u=u, n=n: [direct.output(0.0, x, u) for _ in range(n)][-1], args.repeat)
        tl, ul = best_of(lambda x=x, u=u, n=n: [table.output(0.0, x, u) for _ in range(n)][-1], args.repeat)
        print(f"   B = {B:3d}: direct {td / n * 1e6:8.1f} µs, lookup {tl / n * 1e6:6.1f} µs, "
              f"ratio {td / tl:6.1f}; max |difference| {np.max(np.abs(ud - ul)):.3g} m/s²")

    print("2. closed loop without filter, cost per sample")
    N = int(round(p.t_end / p.T))
    seeds = list(range(1000))
    nz = draw_noise(seeds[:1], N, gaussian_noise(p.sigma_w), gaussian_noise(p.sigma_v))
    res, compile_s = engine_rows(p, a21, seeds, args.repeat)
    t_float, phi_float = best_of(lambda: float_loop(p, a21, table, nz[:, 0, 0], nz[:, 0, 1]), args.repeat)
    print(f"   plain-Python float loop, 1 run: {t_float / N * 1e6:8.1f} µs/sample")
    for (eng, B), (t, r) in res.items():
        print(f"   engine (Loop, {eng:8s}), B = {B:4d}: {t / N * 1e6:8.1f} µs/sample, "
              f"{t / N / B * 1e6:8.2f} µs/sample/run, float loop / this per run: {t_float / (t / B):6.1f}; "
              f"run 0 = numpy B = 1: {np.array_equal(r.phi[:, 0], res['numpy', 1][1].phi[:, 0])}")
    print(f"   compile (first call, then cached on disk): {compile_s:.2f} s")
    print(f"   run 0: max |φ_engine − φ_float| = {np.max(np.abs(res['numpy', 1][1].phi[:, 0] - phi_float)):.3g} rad")


if __name__ == "__main__":
    main()
