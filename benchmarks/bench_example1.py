"""Benchmark: Example 1 of the differential-estimator study (plant (19) + Σ + Han's nonlinear ESO).

Times, in one process with ``OPENBLAS_NUM_THREADS=1``:

1. the engine (:func:`ctrl_analysis.simulate.simulate_sampled`, RK4, h = 1 ms) with B = 1 and
   B = 100 Monte Carlo runs on the batch axis;
2. a plain-Python float loop of the same equations (one run, same step, same RK4, same noise);
3. :func:`control.input_output_response` on the same right-hand side wrapped by
   :func:`ctrl_analysis.simulate.continuous_nlsys`, the noise fed as a zero-order-hold input
   (each sample repeated at the end of its interval, so the linear interpolation python-control
   applies to ``U`` becomes a hold).

and prints the times and the ratios the toolkit targets: B=100 cost / B=1 cost (<= 10),
per-run plain Python / per-run batched (>= 3), input_output_response / engine. It also checks
that the three agree on run 0.

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_example1.py [--T 2.0] [--io-T 0.2]

Not a test: run it by hand.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy is imported

import argparse  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from analysis.differential_estimator.examples import EX1, example1_rhs, make_eso  # noqa: E402
from ctrl_analysis.estimators.differential import DifferentialEstimator  # noqa: E402
from ctrl_analysis.simulate import (  # noqa: E402
    continuous_nlsys,
    draw_noise,
    run_seeds,
    simulate_sampled,
    uniform_noise,
)


def plain_python_run(p, noise_1run: np.ndarray) -> np.ndarray:
    """Plant (19) + Σ (2) + Han's ESO, one run, float arithmetic only, classical RK4 with the noise held.

    Returns the state trajectory, shape (N+1, 10).
    """
    est = DifferentialEstimator(p.n0, p.a)
    eso = make_eso(p)
    a1, a2, a3, a4, a5 = (float(v) for v in est.a_coeffs)
    L1, L2, L3 = (float(v) for v in eso.L)
    al1, al2, al3 = (float(v) for v in eso.alpha)
    delta = float(eso.delta)
    b1, b2, wf = p.b1, p.b2, p.w_freq
    inner = [delta ** (1.0 - al) for al in (al1, al2, al3)]

    def fal(e, al, k):
        if abs(e) <= delta:
            return e / inner[k]
        return math.copysign(abs(e) ** al, e)

    def f(t, s, xi, eta):
        x1, x2, z1, z2, z3, z4, z5, e1, e2, e3 = s
        y = x1 + eta
        c = math.cos(wf * t)
        w = (c > 0) - (c < 0)
        ez = y - z1
        ee = y - e1
        return (
            x2,
            -(b1 * x1 + b2 * x1 * x1 * x2) + w + xi,
            z2 + a1 * ez, z3 + a2 * ez, z4 + a3 * ez, z5 + a4 * ez, a5 * ez,
            e2 + L1 * fal(ee, al1, 0), e3 + L2 * fal(ee, al2, 1), L3 * fal(ee, al3, 2),
        )

    h = p.h
    n = noise_1run.shape[0]
    out = np.empty((n + 1, 10))
    s = (0.0,) * 10
    out[0] = s
    for k in range(n):
        t = k * h
        xi, eta = float(noise_1run[k, 0]), float(noise_1run[k, 1])
        k1 = f(t, s, xi, eta)
        k2 = f(t + 0.5 * h, tuple(a + 0.5 * h * b for a, b in zip(s, k1)), xi, eta)
        k3 = f(t + 0.5 * h, tuple(a + 0.5 * h * b for a, b in zip(s, k2)), xi, eta)
        k4 = f(t + h, tuple(a + h * b for a, b in zip(s, k3)), xi, eta)
        s = tuple(a + (h / 6.0) * (b + 2.0 * c + 2.0 * d + e) for a, b, c, d, e in zip(s, k1, k2, k3, k4))
        out[k + 1] = s
    return out


def io_response_run(p, noise_1run: np.ndarray, T: float):
    """The same system through control.input_output_response (adaptive RK45), noise as a ZOH input."""
    import control as ct

    est = DifferentialEstimator(p.n0, p.a)
    rhs = example1_rhs(p, est, make_eso(p))
    sys_ = continuous_nlsys(rhs, states=10, inputs=["xi", "eta"], name="example1")
    n = int(round(T / p.h))
    tk = p.h * np.arange(n + 1)
    eps = 1e-9 * p.h
    # ZOH: sample k at t_k and again just before t_(k+1) -> linear interpolation holds it
    T_in = np.empty(2 * n)
    T_in[0::2] = tk[:-1]
    T_in[1::2] = tk[1:] - eps
    U = np.repeat(noise_1run[:n].T, 2, axis=1)
    t0 = time.perf_counter()
    resp = ct.input_output_response(sys_, T_in, U, X0=np.zeros(10), t_eval=tk[:-1])
    return time.perf_counter() - t0, resp


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--T", type=float, default=2.0, help="simulated seconds for the engine and plain loop (default 2)")
    ap.add_argument("--io-T", type=float, default=0.2,
                    help="simulated seconds for input_output_response (slow; default 0.2)")
    ap.add_argument("--repeat", type=int, default=2, help="timing repeats, best kept (default 2)")
    args = ap.parse_args(argv)

    p = replace(EX1, T=args.T)
    n = int(round(p.T / p.h))
    seeds = run_seeds(0, 100)
    noise = draw_noise(seeds, n, uniform_noise([-p.xi_bound, -p.eta_bound], [p.xi_bound, p.eta_bound]))
    est = DifferentialEstimator(p.n0, p.a)
    eso = make_eso(p)

    def engine(B):
        rhs = example1_rhs(p, est, eso)
        best, res = math.inf, None
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            res = simulate_sampled(rhs, np.zeros(10), p.h, n, noise=noise[:, :B], seeds=seeds[:B])
            best = min(best, time.perf_counter() - t0)
        return best, res

    print(f"Example 1, RK4 h = {p.h * 1e3:g} ms, {p.T:g} s = {n} steps, OPENBLAS_NUM_THREADS="
          f"{os.environ.get('OPENBLAS_NUM_THREADS')}")
    t1, r1 = engine(1)
    t100, r100 = engine(100)
    best_py = math.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        xs_py = plain_python_run(p, noise[:, 0])
        best_py = min(best_py, time.perf_counter() - t0)
    t_io, resp = io_response_run(p, noise[:, 0], args.io_T)
    n_io = int(round(args.io_T / p.h))
    t_io_scaled = t_io * n / n_io  # per the same simulated horizon

    d_py = float(np.max(np.abs(xs_py - r1.x[:, 0])))
    d_batch = float(np.max(np.abs(r100.x[:, 0] - r1.x[:, 0])))
    x_io = np.asarray(resp.states).T
    ref = r1.x[:n_io, 0]
    scale = np.maximum(np.max(np.abs(ref), axis=0), 1e-12)
    rel_io = np.max(np.abs(x_io - ref), axis=0) / scale  # per state, relative to its range

    rows = [
        ("engine, B = 1", t1, t1),
        ("engine, B = 100", t100, t100 / 100),
        ("plain-Python float loop, 1 run", best_py, best_py),
        (f"input_output_response, 1 run ({args.io_T:g} s, scaled to {p.T:g} s)", t_io_scaled, t_io_scaled),
    ]
    print(f"{'method':<58} {'total (s)':>10} {'per run (s)':>12}")
    for name, tot, per in rows:
        print(f"{name:<58} {tot:>10.3f} {per:>12.4f}")
    r_batch = t100 / t1
    r_py = best_py / (t100 / 100)
    r_io = t_io_scaled / t1
    print()
    print(f"B=100 cost / B=1 cost                    = {r_batch:6.2f}   "
          f"(target <= 10: {'met' if r_batch <= 10 else 'MISSED'})")
    print(f"plain-Python per run / batched per run   = {r_py:6.2f}   (target >= 3: {'met' if r_py >= 3 else 'MISSED'})")
    print(f"input_output_response / engine (B = 1)   = {r_io:6.2f}")
    print(f"engine B = 1 per step                    = {1e6 * t1 / n:6.0f} µs")
    print()
    print(f"agreement, run 0: max |plain - engine| = {d_py:.2e}; max |B=100 row 0 - B=1| = {d_batch:.2e}")
    print(f"input_output_response (RK45, default rtol 1e-3) vs engine, max error / state range: "
          f"x1, x2 {rel_io[:2].max():.1e}; Σ z1, z2 {rel_io[2:4].max():.1e}; ESO x̂1, x̂2 {rel_io[7:9].max():.1e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
