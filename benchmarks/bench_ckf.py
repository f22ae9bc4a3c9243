"""Benchmark of the `ckf` study: CKF cost per step vs a full-order Kalman filter, and the closed loop.

Run by hand (never a timed test)::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_ckf.py [--T 20] [--repeat 3]

1. Filters alone, on recorded measurement and control: the 2-state characteristic-model Kalman
   filter (parameters as inputs) against a time-varying full-order Kalman filter that knows the
   plant, for plants of order n = 5 (the study's), 10 and 20; per-step cost (batch B = 1 and 100)
   and the ratio full / CKF.
2. The closed loop of the study (plant, LPF, CKF, RLS, golden-section control; CKF case): the engine
   (``Loop``), numpy and compiled, at B = 3, 99 and 300 (3 cases x 1, 33 and 100 runs; 300 is the
   study's batch) against a plain-Python float loop of the same equations (one run); they must
   agree to round-off. Medians of repeats, the methods interleaved in every round; the compiled
   engine's compile (or disk-cache load) is done once before timing and reported separately.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import control as ct

from analysis.ckf.loops import plant_tf, simulate_cases
from analysis.ckf.paper import PAPER
from ctrl_analysis.estimators.kalman import (
    CharacteristicKalmanFilter,
    LinearKalmanFilter,
)
from ctrl_analysis.estimators.lowpass import LowPassFilter
from ctrl_analysis.plants import DiscreteLTI


def per_step(block, x, u, n_steps):
    """Seconds per step of ``output`` + ``update`` (what a loop calls every sample)."""
    t0 = time.perf_counter()
    for _ in range(n_steps):
        block.output(0.0, x, u)
        x = block.update(0.0, x, u)
    return (time.perf_counter() - t0) / n_steps


def bench_filters(n_steps=500):
    rows = []
    for n in (5, 10, 20):
        poles = -np.linspace(1.0, 8.0, n)
        sys = DiscreteLTI(ct.zpk([], poles, float(np.prod(-poles))), PAPER.Ts)
        full = LinearKalmanFilter(sys.A, sys.B, sys.C, PAPER.kf_Q * np.outer(sys.B, sys.B), 1.0, 1.0)
        ckf = CharacteristicKalmanFilter(Q=1e-5, R=1.0)
        for B in (1, 100):
            u_full = np.ones((B, 2))
            u_ckf = np.tile([1.0, 1.0, 1.9, -0.9, 0.01], (B, 1))
            t_full = per_step(full, np.tile(full.initial_state(), (B, 1)), u_full, n_steps)
            t_ckf = per_step(ckf, np.tile(ckf.initial_state(), (B, 1)), u_ckf, n_steps)
            rows.append((n, B, t_ckf * 1e6, t_full * 1e6, t_full / t_ckf))
    return rows


def float_loop(p, v, n):
    """The CKF case of the study in plain Python floats (one run, identification from the LPF output).

    The noise record is converted to a Python list once (inside the timing): no step reads a numpy scalar.
    """
    v = v.tolist()
    sysd = DiscreteLTI(plant_tf(p.plant), p.Ts)
    A, Bv, C = sysd.A.tolist(), sysd.B.tolist(), sysd.C.tolist()
    nx = len(Bv)
    Ad, Bd = LowPassFilter(p.lpf_omega, p.lpf_order).discretize(p.Ts)
    ad, bd = float(Ad[0, 0]), float(Bd[0])
    Q, R, lam, mt = p.Q, p.R, p.forgetting, p.max_trace
    Q00, Q01, Q11 = (Q, 0.0, Q) if np.ndim(Q) == 0 else (Q[0][0], Q[0][1], Q[1][1])  # the study's Q = q I
    x, w, u1, s1, s2 = [0.0] * nx, 0.0, 0.0, 0.0, 0.0
    xh0 = xh1 = 0.0
    P00, P01, P11 = p.P0_ckf, 0.0, p.P0_ckf
    th = list(p.theta0)
    Pr = [[p.P0_rls if i == j else 0.0 for j in range(3)] for i in range(3)]
    e1 = r1 = ui = 0.0
    started = False
    out = []
    for k in range(n + 1):
        y = sum(C[j] * x[j] for j in range(nx))
        ym = y + v[k]
        ylpf = ad * w + bd * ym
        f1, f2, g0 = th
        # CKF (11), Joseph form
        xp0, xp1 = f1 * xh0 + f2 * xh1 + g0 * u1, xh0
        a0, a1 = f1 * P00 + f2 * P01, f1 * P01 + f2 * P11
        Pp00, Pp01, Pp11 = a0 * f1 + a1 * f2 + Q00, a0 + Q01, P00 + Q11
        S = Pp00 + R
        K0, K1 = Pp00 / S, Pp01 / S
        rr = ym - xp0
        yckf, xf1 = xp0 + K0 * rr, xp1 + K1 * rr
        m0, b10 = 1.0 - K0, Pp01 - K1 * Pp00
        nP00, nP01 = m0 * m0 * Pp00 + K0 * K0 * R, m0 * b10 + K0 * K1 * R
        nP11 = -K1 * b10 + (Pp11 - K1 * Pp01) + K1 * K1 * R
        yfb = ym if k * p.Ts < p.t_filter - 1e-9 else yckf
        # golden section + maintaining tracking + logic integral
        r = p.reference
        e = yfb - r
        ep, rp = (e1, r1) if started else (e, r)
        ul = -(p.l1 * f1 * e + p.l2 * f2 * ep) / (g0 + p.mu)
        u0 = (r - f1 * r - f2 * rp) / g0
        ui = (1.0 if e * (e - ep) > 0.0 else p.c2) * ui - p.k_I * e  # c1 = 1
        u = u0 + ul + ui
        out.append((y, yckf, u))
        # RLS (9) on z = s(k), h = [s(k-1), s(k-2), u(k-1)], s = LPF output; projection; trace bound
        h = (s1, s2, u1)
        Ph = [sum(Pr[i][j] * h[j] for j in range(3)) for i in range(3)]
        inv = 1.0 / (lam + sum(h[i] * Ph[i] for i in range(3)))
        D = [Ph[i] * inv for i in range(3)]
        innov = ylpf - sum(h[i] * th[i] for i in range(3))
        th = [min(max(th[i] + D[i] * innov, p.lower[i]), p.upper[i]) for i in range(3)]
        Pn = [[(Pr[i][j] - D[i] * Ph[j]) / lam for j in range(3)] for i in range(3)]
        Pr = [[0.5 * (Pn[i][j] + Pn[j][i]) for j in range(3)] for i in range(3)]
        tr = Pr[0][0] + Pr[1][1] + Pr[2][2]
        if tr > mt:
            Pr = [[v_ * (mt / tr) for v_ in row] for row in Pr]
        # state updates
        x = [sum(A[i][j] * x[j] for j in range(nx)) + Bv[i] * u for i in range(nx)]
        w, s2, s1, u1 = ylpf, s1, ylpf, u
        xh0, xh1, P00, P01, P11 = yckf, xf1, nP00, nP01, nP11
        e1, r1, started = e, r, True
    return np.array(out)


RUNS = (1, 33, 100)  # per case: B = 3, 99, 300 (the study's batch)


def bench_loop(T, repeat, runs=RUNS):
    """Median seconds of the float loop and of both engines; ``(times, float, error, steps, compile s)``.

    ``times[(engine, r)]`` is the engine's time for ``r`` runs per case (B = 3 r).
    """
    from _common import round_robin


    p = dataclasses.replace(PAPER, t_end=T)
    n = round(T / p.Ts)
    t0 = time.perf_counter()
    simulate_cases(dataclasses.replace(p, t_end=0.05), 1, seed=0, engine="compiled")  # compile or load once
    t_compile = time.perf_counter() - t0
    d = simulate_cases(p, 1, seed=0, engine="compiled")[(p.id_signal, "ckf")]
    v = d["y_m"][:, 0] - d["y"][:, 0]
    fns = {"float": lambda: float_loop(p, v, n)}
    for engine in ("numpy", "compiled"):
        for r in runs:
            fns[(engine, r)] = (lambda e=engine, r=r: simulate_cases(p, r, seed=0, engine=e))
    timed = round_robin(fns, repeat)
    fl = timed["float"][1]
    err = max(np.max(np.abs(fl[:, 0] - d["y"][:, 0])), np.max(np.abs(fl[:, 2] - d["u"][:, 0])))
    times = {k: v[0] for k, v in timed.items() if k != "float"}
    return times, timed["float"][0], err, n, t_compile


NAME = "ckf closed loop (CKF case, 20 s)"


def run(repeat=3, T=20.0):
    """Rows for ``run_all.py``: the float loop (1 run) and both engines at B = 3, 99 and 300 (3 cases x runs).

    Returns ``(rows, float-loop seconds per run, None (no compiled reference), notes)``.
    """
    from _common import Row

    times, t_float, err, n, t_compile = bench_loop(T, repeat)
    rows = [Row(NAME, "float loop (plain Python, CKF case), 1 run", 1, t_float, f"largest y, u difference {err:.1e}")]
    rows += [Row(NAME, f"engine `Loop` ({engine}), B = {3 * r} (3 cases x {r})", 3 * r, t,
                 "same loop, all three cases on the batch axis") for (engine, r), t in times.items()]
    notes = [f"{T:g} s = {n} samples; median of {repeat} repeats (one closed loop is long)",
             f"compiled engine: compile (or load from the disk cache) the loop runner once, {t_compile:.2f} s, "
             "before timing",
             "filters alone, µs per step (output + update), CKF (2 states) vs full-order KF: "
             + "; ".join(f"n = {k}, B = {B}: {tc:.0f} vs {tf:.0f} ({r:.1f}x)" for k, B, tc, tf, r in bench_filters())]
    return rows, t_float, None, notes


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--T", type=float, default=20.0, help="closed-loop horizon in seconds")
    ap.add_argument("--repeat", type=int, default=3, help="timing repeats (median)")
    args = ap.parse_args(argv)
    print("## Filters alone: cost per step (output + update), µs")
    print("| plant order n | B | CKF (2 states) | full-order KF | full / CKF |")
    print("|---|---|---|---|---|")
    for n, B, tc, tf, ratio in bench_filters():
        print(f"| {n} | {B} | {tc:.1f} | {tf:.1f} | {ratio:.2f} |")
    times, t_float, err, n, t_compile = bench_loop(args.T, args.repeat)
    print(f"\n## Closed loop, {args.T:g} s = {n} steps (3 cases per batch: B = 3 x runs; medians of {args.repeat})")
    print("| method | B | time [s] | µs per step per run | float loop / this (per run) |")
    print("|---|---|---|---|---|")
    print(f"| plain-Python float loop (CKF case) | 1 | {t_float:.3f} | {t_float / n * 1e6:.1f} | 1.0 |")
    for (engine, r), t in times.items():
        print(f"| engine `Loop` ({engine}) | {3 * r} | {t:.3f} | {t / n / (3 * r) * 1e6:.2f} | "
              f"{t_float / (t / (3 * r)):.1f} |")
    print(f"\ncompiled engine: compile or cache load {t_compile:.2f} s (not in the times above)")
    print(f"max |float loop − engine| over y and u: {err:.3g}")


if __name__ == "__main__":
    main()
