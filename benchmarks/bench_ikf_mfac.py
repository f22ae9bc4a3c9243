"""Benchmark: Table 1 of ikf-mfac (4 schemes x 2 examples x R runs) on the batched engine vs a plain float loop.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_ikf_mfac.py [--runs 200] [--float-runs 200]

The engine runs each scheme's R Monte Carlo runs side by side (`analysis.ikf_mfac.loops.run_scheme`,
library blocks wired by `Loop`), on the numpy engine and on the compiled one (every block has a kernel:
one numba function per loop). The float loop is what a careful engineer writes by hand: one run
at a time, Python floats and `math`, every equation once per step (the TD's steps once per sample,
not twice as the feedthrough block's output and update do), same noise. Both must agree run by run.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import math

import _common  # noqa: F401  (before numpy: single-threaded BLAS; the repository root on sys.path)
import numpy as np

from analysis.ikf_mfac.loops import noise_draws, run_scheme
from analysis.ikf_mfac.paper import EX1, EX2, SCHEMES
from analysis.ikf_mfac.plants import reference
from ctrl_analysis.metrics import rmse
from ctrl_analysis.noise import run_seeds


def _sign(a: float) -> float:
    return (a > 0.0) - (a < 0.0)


def _fhan(x1, x2, r, h0):
    d = r * h0 * h0
    a0 = h0 * x2
    y = x1 + a0
    a1 = math.sqrt(d * (d + 8.0 * abs(y)))
    a2 = a0 + _sign(y) * (a1 - d) * 0.5
    sy = (_sign(y + d) - _sign(y - d)) * 0.5
    a = (a0 + y - a2) * sy + a2
    sa = (_sign(a + d) - _sign(a - d)) * 0.5
    return -r * (a / d - _sign(a)) * sa - r * _sign(a)


def float_run(ex, scheme: str, v: list) -> list:
    """One closed-loop run with Python floats; returns y(1..N)."""
    N, ks = ex.n, ex.k_start
    y = [ex.y_init] * (ks - 1)
    u = [ex.u_init] * (ks - 1)
    ref_next = [1.0 if k <= 500 else -1.0 for k in range(N + 1)] if ex.reference == "step" else \
        [3 * math.sin(k * math.pi / 150) + math.cos(k * math.pi / 300) for k in range(N + 1)]
    sw = math.inf if ex.switch_k is None else ex.switch_k
    # plant gives y(ks) from y(ks-1), u(ks-1)
    yk = y[-1] / (1 + y[-1] ** 2) + u[-1] ** 3
    y.append(yk)
    phi, yf_prev = ex.phi0, ex.y_init
    x1, x2 = ex.y_init, 0.0                    # TD
    yh, P = ex.y_init, ex.P0                   # IKF
    phi_model = ex.phi0                        # φ̂(k−1) of the data model
    in_band, armed, age = False, False, 0.0    # D-MFAC
    for k in range(ks, N + 1):
        ym = y[k - 1] + v[k - 1]
        if scheme == "td_mfac":
            for _ in range(ex.td_substeps):
                fh = _fhan(x1 - ym, x2, ex.td_r, ex.td_h0)
                x1, x2 = x1 + ex.td_h * x2, x2 + ex.td_h * fh
            yf = x1
        elif scheme == "ikf_mfac":
            y_prior = yh + phi_model * (u[k - 2] - u[k - 3])
            P_prior = P + ex.Q
            K = P_prior / (P_prior + ex.R)
            yh = y_prior + K * (ym - y_prior)
            P = (1 - K) * P_prior
            yf = yh
        else:
            yf = ym
        du = u[k - 2] - u[k - 3]
        phi = phi + ex.eta * du * (yf - yf_prev - phi * du) / (ex.mu + du * du)
        if abs(phi) <= ex.epsilon or abs(du) <= ex.epsilon or _sign(phi) != _sign(ex.phi0):
            phi = ex.phi_reset
        e = ref_next[k] - yf
        inc = ex.rho * phi * e / (ex.lam + phi * phi)
        if scheme == "d_mfac":
            now_in = abs(e) < ex.e_m
            entering = now_in and not in_band
            start = entering if ex.rearm else (entering and not armed)
            armed = armed or entering
            age = 0.0 if start else age + 1.0
            if now_in and armed:
                inc /= age + 1.0
            in_band = now_in
        uk = u[k - 2] + inc
        u.append(uk)
        phi_model, yf_prev = phi, yf
        if k < N:
            yk, y1, y2, u1 = y[k - 1], y[k - 2], y[k - 3], u[k - 2]
            if k <= sw:
                y.append(yk / (1 + yk * yk) + uk ** 3)
            else:
                r = 1 + math.floor(k / 500 + 0.5)
                y.append((yk * y1 * y2 * u1 * (y2 - 1) + r * uk) / (1 + y1 * y1 + y2 * y2))
    return y


NAME = "ikf-mfac Table 1 (4 schemes x 2 examples)"


def run(repeat=3, runs=200, float_runs=20, sizes=(1, 100)):
    """Rows for ``run_all.py``: the float loop, and the engine (numpy; compiled at B = 1, 100 and ``runs``).

    Per run of one scheme on one example. Returns ``(rows, float-loop seconds per run, None (no
    compiled reference), notes)``.
    """
    from _common import Row, round_robin

    from ctrl_analysis.engine import codegen as _kernels

    seeds = run_seeds(0, runs)
    work = []
    for ex in (EX1, EX2):
        v = noise_draws(ex, seeds)
        work += [(ex, s, v) for s in SCHEMES]
    c0 = _kernels.compile_seconds()
    for ex, s, v in work:  # compile (or load from the disk cache) each loop structure once, not timed
        run_scheme(ex, s, v[:, :1], engine="compiled")
    notes = [f"compiled engine: generating + compiling (or loading from the disk cache) the 4 loop runners took "
             f"{_kernels.compile_seconds() - c0:.2f} s, not counted in the rows",
             f"float loop timed on {float_runs} runs a scheme"]
    fns = {("numpy", runs): lambda: [run_scheme(ex, s, v, engine="numpy") for ex, s, v in work]}
    for B in sorted(set(sizes) | {runs}):
        fns["compiled", B] = lambda B=B: [run_scheme(ex, s, v[:, :B], engine="compiled") for ex, s, v in work]
    fns["float"] = lambda: [[float_run(ex, s, v[:, b].tolist()) for b in range(float_runs)] for ex, s, v in work]
    timed = round_robin(fns, repeat)  # every method once per round: a change in the machine's load hits all alike
    t_flt, ys = timed.pop("float")
    worst = {}
    for key, (_, res) in timed.items():
        w = 0.0
        for (ex, _, _), r, y in zip(work, res, ys, strict=True):
            m = min(float_runs, r.y.shape[1])
            ref = reference(ex.reference, ex.n)
            ok = ~r.diverged[:m]
            e_eng, e_flt = rmse(ref[:, None], r.y[:, :m])[ok], rmse(ref[:, None], np.array(y).T[:, :m])[ok]
            w = max(w, float(np.max(np.abs(e_eng - e_flt) / e_flt, initial=0.0)))
        worst[key] = w
    same = all(np.array_equal(a.y, b.y, equal_nan=True)
               for a, b in zip(timed["numpy", runs][1], timed["compiled", runs][1], strict=True))
    n = len(work)
    rows = [Row(NAME, f"float loop (plain Python), {float_runs} runs a scheme", n * float_runs, t_flt,
                f"reference (runs 0..{float_runs - 1})")]
    for (engine, B), (t, _) in timed.items():
        agree = f"RMSE rel. {worst[engine, B]:.1e} vs float loop"
        if engine == "compiled" and B == runs:
            agree += "; = numpy engine bit for bit" if same else "; DIFFERS from the numpy engine"
        rows.append(Row(NAME, f"engine (`run_scheme`, {engine}), B = {B} a scheme", n * B, t, agree))
    return rows, t_flt / (n * float_runs), None, notes


def main():
    from _common import table

    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=200, help="the study's batch (Table 1's runs)")
    ap.add_argument("--float-runs", type=int, default=20, help="runs per scheme timed in the float loop")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    rows, base, comp, notes = run(repeat=args.repeat, runs=args.runs, float_runs=args.float_runs)
    print(table(rows, {NAME: base}, {NAME: comp}))
    print("\n".join(f"- {x}" for x in notes))


if __name__ == "__main__":
    main()
