"""Benchmark: one run per ``Loop.simulate`` call, compiled, against a plain float loop and a hand-written numba loop.

python-control users simulate one run at a time, so a simulation's fixed cost (checking the
arguments, finding the compiled runner, allocating the result, building the response) matters as
much as its speed per step. Two loops, each timed as one call of one run:

* **Example 1** of the differential-estimator paper (10 states, RK4, h = 1 ms, 2 s: 2000 samples),
  :mod:`bench_example1`'s loop, float loop and hand-compiled loop (the study's quantity computed
  on the fly, nothing stored);
* **a small user loop**: a first-order plant ``x' = (-x + K u)/tau`` (RK4) under a discrete PI
  controller, both written kernel-first as a user would (CONTRIBUTING.md), 2000 samples; its
  float loop and its numba loop written by hand.

The "engine" rows store every signal and state (``simulate``'s default: what a one-run user looks
at), the "kept" rows only what the quantity needs (the hand loops store nothing); the "fixed cost"
row is a one-sample call, what every call pays whatever its length.
``OPENBLAS_NUM_THREADS=1``, one process; interleaved rounds, the median and the best round reported
(on a shared machine the best round is the least disturbed).

Run: ``python benchmarks/bench_one_run.py [--repeat R]``.
"""

from __future__ import annotations

import statistics
import time

import _common  # noqa: F401  (single-threaded BLAS, repository on sys.path)
import numpy as np
from bench_example1 import H, build_loop, coefficients, compiled_loop, float_loop

from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.blocks import ContinuousBlock, DiscreteBlock
from ctrl_analysis.engine.kernels import KernelBlock, Kernels, Layout
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.noise import draw_noise, run_seeds, uniform_noise

N = 2000
TAU, K, KP, KI, DT = 0.5, 2.0, 1.5, 2.0, 1e-2

LAG = Layout("tau", "K")
PI_LAYOUT = Layout("kp", "ki", "dt")


def lag_rhs(t, x, u, p, dx):
    """x' = (-x + K u) / tau."""
    dx[0] = (-x[0] + p[1] * u[0]) / p[0]


def lag_output(t, x, u, p, y):
    y[0] = x[0]


class Lag(KernelBlock, ContinuousBlock):
    """A user's first-order plant, kernel-first."""

    inputs, outputs, states = ("u",), ("y",), ("y",)
    feedthrough = False
    kernels = Kernels(output=lag_output, rhs=lag_rhs)

    def __init__(self, tau=TAU, K=K):
        self.kernel_params = LAG.pack(tau=tau, K=K)


def pi_output(t, x, u, p, y):
    """u = kp e + ki (integral of e), e = r - y."""
    y[0] = p[0] * (u[0] - u[1]) + p[1] * x[0]


def pi_update(t, x, u, p, x_next):
    x_next[0] = x[0] + p[2] * (u[0] - u[1])


class PI(KernelBlock, DiscreteBlock):
    """A user's discrete PI controller, kernel-first."""

    inputs, outputs, states = ("r", "y"), ("u",), ("i",)
    feedthrough = True
    kernels = Kernels(output=pi_output, update=pi_update)

    def __init__(self, kp=KP, ki=KI, dt=DT):
        self.kernel_params = PI_LAYOUT.pack(kp=kp, ki=ki, dt=dt)


def user_float(r, n, h):
    """The small loop by hand in Python floats (RK4 of the plant, PI updated once per sample)."""
    x = i = 0.0
    acc = 0.0
    for k in range(n + 1):
        e = r[k] - x
        u = KP * e + KI * i
        acc += abs(e)
        if k == n:
            break
        i = i + h * e
        k1 = (-x + K * u) / TAU
        k2 = (-(x + 0.5 * h * k1) + K * u) / TAU
        k3 = (-(x + 0.5 * h * k2) + K * u) / TAU
        k4 = (-(x + h * k3) + K * u) / TAU
        x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return x, acc


def main(repeat=7, calls=20):
    import numba

    rows = []
    # Example 1
    loop = build_loop()
    c = coefficients(loop)
    noise = draw_noise(run_seeds(0, 1), N, uniform_noise([-0.1, -0.001], [0.1, 0.001]))
    xi, eta = noise[:, 0, 0], noise[:, 0, 1]
    ref, _ = compiled_loop()
    inputs = {"xi": xi[:, None], "eta": eta[:, None], "uc": 0.0}
    ex = Execution(engine="compiled")
    # what the study's quantity needs (the hand loops store nothing: they accumulate it on the fly)
    six = Save(keep=["x[0]", "x[1]", "xhat[0]", "xhat[1]", "eso_xhat[0]", "eso_xhat[1]"], states=False)
    loop.simulate(2, inputs={"xi": 0.0, "eta": 0.0, "uc": 0.0}, execution=ex)  # compile (or load) once
    fns1 = {"float loop": lambda: float_loop(xi.tolist(), eta.tolist(), N, H, c),
            "hand numba": lambda: ref(xi, eta, N, H, c),
            "engine": lambda: loop.simulate(N, inputs=inputs, execution=ex),
            "engine, 6 kept": lambda: loop.simulate(N, inputs=inputs, save=six, execution=ex),
            "fixed cost": lambda: loop.simulate(1, inputs={"xi": 0.0, "eta": 0.0, "uc": 0.0}, execution=ex)}
    # the small user loop
    user = Loop([place(Lag(), "plant"), place(PI(), "pi")], dt=DT)
    r = np.where(np.arange(N + 1) < N // 2, 1.0, -0.5)
    user_nb = numba.njit(cache=True)(user_float)
    user_nb(r, 2, DT)
    user.simulate(2, inputs={"r": 1.0}, execution=ex)
    rl = r.tolist()
    fns2 = {"float loop": lambda: user_float(rl, N, DT), "hand numba": lambda: user_nb(r, N, DT),
            "engine": lambda: user.simulate(N, inputs={"r": r}, execution=ex),
            "engine, 1 kept": lambda: user.simulate(N, inputs={"r": r}, save=Save(keep=["y"], states=False),
                                                    execution=ex),
            "fixed cost": lambda: user.simulate(1, inputs={"r": 1.0}, execution=ex)}
    # agreement of the user loop: engine vs float loop (same RK4 and PI arithmetic)
    res = user.simulate(N, inputs={"r": r}, execution=ex)
    x_end, _ = user_float(rl, N, DT)
    rows.append(f"small user loop: engine's final plant state vs the float loop's: "
                f"{abs(res.final_states['plant'][0, 0] - x_end):.1e}")
    for name, fns in (("Example 1 (10 states, RK4, 2000 samples)", fns1), ("small user loop (2 states, 2000 samples)",
                                                                          fns2)):
        times = {k: [] for k in fns}
        for rnd in range(repeat + 1):  # every method once per round (load changes hit all alike); round 0: warm-up
            for k, f in fns.items():
                t0 = time.perf_counter()
                for _ in range(calls):
                    f()
                if rnd:
                    times[k].append((time.perf_counter() - t0) / calls)
        rows.append(f"\n{name}, one run per call ({repeat} rounds of {calls} calls: median, and best round)")
        med = {k: statistics.median(v) for k, v in times.items()}
        best = {k: min(v) for k, v in times.items()}
        for k in fns:
            rows.append(f"  {k:<14} {med[k] * 1e6:9.1f} us {med[k] / med['hand numba']:6.2f}x hand numba   "
                        f"best {best[k] * 1e6:9.1f} us {best[k] / best['hand numba']:6.2f}x hand numba, "
                        f"{best[k] / best['float loop']:7.4f}x float loop")
    print("\n".join(rows))


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7, help="timing rounds, median reported (default 7)")
    ap.add_argument("--calls", type=int, default=20, help="calls per round (default 20)")
    a = ap.parse_args()
    t0 = time.perf_counter()
    main(a.repeat, a.calls)
    print(f"\n({time.perf_counter() - t0:.0f} s)")
