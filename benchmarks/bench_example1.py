"""Benchmark: Example 1 of the differential-estimator paper (plant (19) + Σ + Han's nonlinear ESO), RK4, h = 1 ms.

The hot loop every Monte Carlo study runs: a 10-state continuous loop with held white noise,
integrated with classical RK4. Compared, on the same equations, the same noise and the same step:

* ``float loop``: the loop a competent engineer writes in plain Python — Python floats, the RK4
  stages unrolled, the noise read from lists, the study's quantity (mean |x_i - x̂_i| over the
  samples) accumulated in floats; one run at a time;
* ``compiled``: the very same function compiled by numba (``njit``, one thread, ``cache=True``);
  its compile time is reported separately;
* ``engine B = 1, 100, 1000``: :class:`ctrl_analysis.engine.loop.Loop` with the library blocks
  (:class:`~ctrl_analysis.estimators.differential.DifferentialEstimator` ``(5, 7.0)``,
  :class:`~ctrl_analysis.estimators.eso.ExtendedStateObserver` with Han's fal and the step-size
  gains) and the plant (19) written here as a small kernel-first block (a
  :class:`~ctrl_analysis.engine.kernels.KernelBlock`, as the docs describe), Monte Carlo runs on the batch axis;
* ``python-control, discrete``: the loop's ``control.interconnect`` advanced as a discrete-time
  ``control.nlsys`` whose update is one RK4 step (:func:`ctrl_analysis.engine.integrators.rk4_step`), run by
  ``input_output_response``; one run;
* ``python-control, adaptive``: ``input_output_response`` on the continuous interconnect (RK45),
  the noise as a zero-order hold, with the loosest ``rtol`` (from 1e-3 down) whose error against a
  fine reference is no larger than RK4's at 1 ms; it is slow, so it runs ``--io-T`` seconds and is
  scaled to ``--T``.

Every method's agreement with the engine (run 0, the same noise) is checked and printed.
"""

from __future__ import annotations

import math
import time

import _common  # noqa: F401  (single-threaded BLAS, repository on sys.path)
import numpy as np
from _common import Row, median_time, round_robin

from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.blocks import ContinuousBlock, signal_names
from ctrl_analysis.engine.integrators import rk4_step
from ctrl_analysis.engine.kernels import KernelBlock, Kernels, Layout
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.estimators.eso import ExtendedStateObserver
from ctrl_analysis.noise import draw_noise, run_seeds, uniform_noise

NAME = "Example 1 (10 states, RK4)"
H = 1e-3
B1, B2, W_FREQ = 3.0, 1.0, 0.3  # eq. (19)
XI, ETA = 0.1, 0.001  # ξ ~ U[-0.1, 0.1], η ~ U[-0.001, 0.001]
ALPHA = (1.0, 0.5, 0.25)  # fal exponents (α = 1: linear first channel)


PLANT19 = Layout("b1", "b2", "w_freq")  # the plant's parameters, by name
AT = PLANT19.at


def plant19_rhs(t, x, u, p, dx):
    """Eq. (19) on one run (floats) or on columns of a batch: x1' = x2, x2' = -(b1 x1 + b2 x1² x2) + w + ξ."""
    c = math.cos(p[AT.w_freq] * t)
    w = 1.0 if c > 0 else (-1.0 if c < 0 else 0.0)  # w = sign(cos(ω t))
    dx[0] = x[1]
    dx[1] = -(p[AT.b1] * x[0] + p[AT.b2] * x[0] * x[0] * x[1]) + w + u[0]


def plant19_output(t, x, u, p, y):
    """Outputs y = x1 + η, x1, x2."""
    y[0] = x[0] + u[1]
    y[1] = x[0]
    y[2] = x[1]


class Plant19(KernelBlock, ContinuousBlock):
    """Eq. (19): x1' = x2, x2' = -(b1 x1 + b2 x1² x2) + sign(cos(ω t)) + ξ; y = x1 + η.

    Written once, as its kernels: the batched methods (numpy engine, python-control) and the
    compiled engine run the same two functions.
    """

    inputs, outputs, states = ("xi", "eta"), ("y", "x[0]", "x[1]"), ("x[0]", "x[1]")
    feedthrough = True
    kernels = Kernels(output=plant19_output, rhs=plant19_rhs)

    def __init__(self, b1=B1, b2=B2, w_freq=W_FREQ):
        self.b1, self.b2, self.w_freq = float(b1), float(b2), float(w_freq)
        self.kernel_params = PLANT19.pack(b1=b1, b2=b2, w_freq=w_freq)


def han_eso(h=H):
    """Han's third-order fal ESO with the step-size gains (as the study's ``make_eso``), δ = h."""
    gains = (1.0 / h, 1.0 / (1.6 * h**1.5), 1.0 / (8.6 * h**2.2))
    return ExtendedStateObserver(gains, b0=0.0, alpha=list(ALPHA), delta=h)


def build_loop(h=H, substeps=1):
    sigma, eso = DifferentialEstimator(5, 7.0), han_eso(h)
    return Loop([place(Plant19(), "plant"), place(sigma, "sigma"),
                 place(eso, "eso", inputs=["y", "uc"], outputs=signal_names("eso_xhat", 3))], dt=h, substeps=substeps)


def coefficients(loop):
    """The float loop's constants, read from the blocks (one source of the parameters)."""
    plant, sigma, eso = (p.block for p in loop.placed)
    return ((plant.b1, plant.b2, plant.w_freq) + tuple(float(v) for v in sigma.a_coeffs)
            + tuple(float(v) for v in eso.L) + tuple(float(v) for v in eso.alpha) + (float(eso.delta),)
            + tuple(float(v) for v in eso._delta_pow))


# ------------------------------------------------------------------ the float loop (and, compiled, the reference)
def rhs_float(t, x1, x2, z1, z2, z3, z4, z5, e1, e2, e3, xi, eta, c):
    """Right-hand side of the whole loop on Python floats (Σ: eq. (2); ESO: Han's fal)."""
    b1, b2, wf, a1, a2, a3, a4, a5, L1, L2, L3, al1, al2, al3, delta, dp1, dp2, dp3 = c
    y = x1 + eta
    cw = math.cos(wf * t)
    w = 1.0 if cw > 0 else (-1.0 if cw < 0 else 0.0)
    ez = y - z1
    ee = y - e1
    ae = abs(ee)
    if ae <= delta:
        g1, g2, g3 = ee / dp1, ee / dp2, ee / dp3
    else:
        g1 = math.copysign(ae**al1, ee)
        g2 = math.copysign(ae**al2, ee)
        g3 = math.copysign(ae**al3, ee)
    return (x2, -(b1 * x1 + b2 * x1 * x1 * x2) + w + xi,
            a1 * ez + z2, a2 * ez + z3, a3 * ez + z4, a4 * ez + z5, a5 * ez,
            L1 * g1 + e2, L2 * g2 + e3, L3 * g3)


def make_float_loop(rhs):
    """The straightforward one-run loop around ``rhs`` (plain Python, or numba when ``rhs`` is compiled)."""

    def run(xi, eta, n, h, c):
        x1 = x2 = z1 = z2 = z3 = z4 = z5 = e1 = e2 = e3 = 0.0
        s1 = s2 = s3 = s4 = 0.0  # sums of |x1 - z1|, |x2 - z2|, |x1 - x̂1|, |x2 - x̂2|
        hh, h6 = 0.5 * h, h / 6.0
        for k in range(n + 1):
            s1 += abs(x1 - z1)
            s2 += abs(x2 - z2)
            s3 += abs(x1 - e1)
            s4 += abs(x2 - e2)
            if k == n:
                break
            t = k * h
            a, b = xi[k], eta[k]
            p = rhs(t, x1, x2, z1, z2, z3, z4, z5, e1, e2, e3, a, b, c)
            q = rhs(t + hh, x1 + hh * p[0], x2 + hh * p[1], z1 + hh * p[2], z2 + hh * p[3], z3 + hh * p[4],
                    z4 + hh * p[5], z5 + hh * p[6], e1 + hh * p[7], e2 + hh * p[8], e3 + hh * p[9], a, b, c)
            r = rhs(t + hh, x1 + hh * q[0], x2 + hh * q[1], z1 + hh * q[2], z2 + hh * q[3], z3 + hh * q[4],
                    z4 + hh * q[5], z5 + hh * q[6], e1 + hh * q[7], e2 + hh * q[8], e3 + hh * q[9], a, b, c)
            v = rhs(t + h, x1 + h * r[0], x2 + h * r[1], z1 + h * r[2], z2 + h * r[3], z3 + h * r[4],
                    z4 + h * r[5], z5 + h * r[6], e1 + h * r[7], e2 + h * r[8], e3 + h * r[9], a, b, c)
            x1 = x1 + h6 * (p[0] + 2.0 * q[0] + 2.0 * r[0] + v[0])
            x2 = x2 + h6 * (p[1] + 2.0 * q[1] + 2.0 * r[1] + v[1])
            z1 = z1 + h6 * (p[2] + 2.0 * q[2] + 2.0 * r[2] + v[2])
            z2 = z2 + h6 * (p[3] + 2.0 * q[3] + 2.0 * r[3] + v[3])
            z3 = z3 + h6 * (p[4] + 2.0 * q[4] + 2.0 * r[4] + v[4])
            z4 = z4 + h6 * (p[5] + 2.0 * q[5] + 2.0 * r[5] + v[5])
            z5 = z5 + h6 * (p[6] + 2.0 * q[6] + 2.0 * r[6] + v[6])
            e1 = e1 + h6 * (p[7] + 2.0 * q[7] + 2.0 * r[7] + v[7])
            e2 = e2 + h6 * (p[8] + 2.0 * q[8] + 2.0 * r[8] + v[8])
            e3 = e3 + h6 * (p[9] + 2.0 * q[9] + 2.0 * r[9] + v[9])
        m = n + 1.0
        return (x1, x2, z1, z2, z3, z4, z5, e1, e2, e3), (s1 / m, s2 / m, s3 / m, s4 / m)

    return run


float_loop = make_float_loop(rhs_float)


def compiled_loop():
    """The float loop compiled by numba (one thread); returns (function, compile seconds)."""
    import numba

    fn = numba.njit(cache=True)(make_float_loop(numba.njit(cache=True)(rhs_float)))
    t0 = time.perf_counter()
    fn(np.zeros(2), np.zeros(2), 1, H, coefficients(build_loop()))
    return fn, time.perf_counter() - t0


# ------------------------------------------------------------------ engine and python-control
def engine_errors(res):
    """The study's quantities from a LoopResponse: mean |x1 - z1|, |x2 - z2|, |x1 - x̂1|, |x2 - x̂2| per run."""
    x1, x2 = res["x[0]"], res["x[1]"]
    return np.stack([np.mean(np.abs(x1 - res["xhat[0]"]), axis=0), np.mean(np.abs(x2 - res["xhat[1]"]), axis=0),
                     np.mean(np.abs(x1 - res["eso_xhat[0]"]), axis=0),
                     np.mean(np.abs(x2 - res["eso_xhat[1]"]), axis=0)],
                    axis=1)


def final_state(res, run=0):
    s = res.states
    return np.concatenate([s["plant"][-1, run], s["sigma"][-1, run], s["eso"][-1, run]])


def pc_discrete(loop, noise1, n):
    """python-control: the continuous interconnect advanced by one RK4 step per sample (a discrete nlsys)."""
    import control as ct

    sys_c = loop.interconnect()
    h = loop.dt

    def upd(t, x, u, params=None):
        return rk4_step(lambda tt, xx, uu, pp: sys_c._rhs(tt, xx, uu), t, x, u, h)

    sys_d = ct.nlsys(upd, lambda t, x, u, params=None: x, inputs=sys_c.ninputs, states=sys_c.nstates,
                     outputs=sys_c.nstates, dt=h)
    U = np.empty((sys_c.ninputs, n + 1))
    names = sys_c.input_labels
    U[names.index("xi")] = np.append(noise1[:n, 0], noise1[n - 1, 0])
    U[names.index("eta")] = np.append(noise1[:n, 1], noise1[n - 1, 1])
    U[names.index("uc")] = 0.0
    resp = ct.input_output_response(sys_d, h * np.arange(n + 1), U, X0=np.zeros(sys_c.nstates))
    return sys_c, resp


def pc_adaptive(sys_c, noise1, n, h, rtol):
    """python-control: input_output_response (RK45) on the continuous interconnect, noise as a ZOH."""
    import control as ct

    tk = h * np.arange(n + 1)
    eps = 1e-9 * h
    T_in = np.empty(2 * n)
    T_in[0::2] = tk[:-1]
    T_in[1::2] = tk[1:] - eps
    names = sys_c.input_labels
    U = np.zeros((sys_c.ninputs, 2 * n))
    U[names.index("xi")] = np.repeat(noise1[:n, 0], 2)
    U[names.index("eta")] = np.repeat(noise1[:n, 1], 2)
    resp = ct.input_output_response(sys_c, T_in, U, X0=np.zeros(sys_c.nstates), t_eval=tk[:-1],
                                    solve_ivp_kwargs={"rtol": rtol, "atol": rtol * 1e-3})
    return resp


def state_order(sys_c):
    """Indices mapping the interconnect's states onto the engine's (plant, Σ, ESO) order."""
    labels = sys_c.state_labels
    want = ([f"plant_x[{i}]" for i in range(2)] + [f"sigma_z[{i}]" for i in range(5)]
            + [f"eso_xhat[{i}]" for i in range(3)])
    return [labels.index(w) for w in want]


def run(T=2.0, io_T=0.05, repeat=3, sizes=(1, 100, 1000)):
    """Time every method; returns (rows, float-loop per-run seconds, compiled per-run seconds, notes)."""
    n = round(T / H)
    B_max = max(sizes)
    seeds = run_seeds(0, B_max)
    noise = draw_noise(seeds, n, uniform_noise([-XI, -ETA], [XI, ETA]))
    loop = build_loop()
    c = coefficients(loop)
    rows, notes = [], []

    from ctrl_analysis.engine import codegen as _kernels

    # float loop, one run at a time (the noise converted to lists once, inside the timing)
    def py(b=0):
        return float_loop(noise[:, b, 0].tolist(), noise[:, b, 1].tolist(), n, H, c)

    fn_c, t_compile = compiled_loop()
    n_c = 20
    xi_c = np.ascontiguousarray(noise[:, :n_c, 0].T)
    eta_c = np.ascontiguousarray(noise[:, :n_c, 1].T)

    def compiled():
        return [fn_c(xi_c[b], eta_c[b], n, H, c) for b in range(n_c)]

    notes.append(f"numba compile time of the reference: {t_compile:.2f} s (first call; cached on disk afterwards)")
    keep = ["x[0]", "x[1]", "xhat[0]", "xhat[1]", "eso_xhat[0]", "eso_xhat[1]"]  # what the study's quantities need
    c0 = _kernels.compile_seconds()
    loop.simulate(2, inputs={"xi": 0.0, "eta": 0.0, "uc": 0.0},
                  execution=Execution(engine="compiled"))  # compile (or load) once
    notes.append(f"compiled engine: generating + compiling (or loading from the disk cache) the loop runner "
                 f"took {_kernels.compile_seconds() - c0:.2f} s, not counted in the rows")
    fns = {"py": py, "ref": compiled}
    for engine in ("numpy", "compiled"):
        for B in sizes:
            def sim(B=B, engine=engine):
                inputs = {"xi": noise[:, :B, 0], "eta": noise[:, :B, 1], "uc": 0.0}
                return loop.simulate(n, inputs=inputs, runs=B, seeds=seeds[:B],
                                     save=Save(keep=keep, states=False), execution=Execution(engine=engine))

            fns[engine, B] = sim
    timed = round_robin(fns, repeat)  # every method once per round: load changes hit all alike
    t_py, (xf_py, err_py) = timed["py"]
    t_c, out_c = timed["ref"]
    res_by = {}
    for engine in ("numpy", "compiled"):
        for B in sizes:
            t_B, res_by[engine, B] = timed[engine, B]
            rows.append(Row(NAME, f"engine `Loop` ({engine}), B = {B}", B, t_B))
    # the single-run trace every other method is checked against: numpy engine, states kept
    res1 = loop.simulate(n, inputs={"xi": noise[:, :1, 0], "eta": noise[:, :1, 1], "uc": 0.0},
                         execution=Execution(engine="numpy"))
    xf_eng = final_state(res1)
    err_eng = engine_errors(res1)[0]
    err_big = engine_errors(res_by["compiled", max(sizes)])
    d_err_runs = max(float(np.max(np.abs(np.array(out_c[b][1]) - err_big[b]) / np.abs(err_big[b])))
                     for b in range(n_c))
    for r in rows:
        engine = "compiled" if "compiled" in r.method else "numpy"
        if r.runs == 1:
            d = max(float(np.max(np.abs(res_by[engine, 1][s] - res1[s]))) for s in keep)
            r.agreement = f"vs the numpy single-run trace: {d:.1e}"
        else:
            same = all(np.array_equal(res_by[engine, r.runs][s][:, 0], res_by[engine, 1][s][:, 0]) for s in keep)
            r.agreement = f"run 0 = its B = 1 run bit for bit: {same}"
    d_py = float(np.max(np.abs(np.array(xf_py) - xf_eng)))
    rel_err = float(np.max(np.abs(np.array(err_py) - err_eng) / np.abs(err_eng)))
    rows.insert(0, Row(NAME, "float loop (plain Python), 1 run", 1, t_py,
                       f"final state {d_py:.1e}, mean errors rel. {rel_err:.1e} (vs numpy engine)"))
    rows.insert(1, Row(NAME, f"compiled reference (numba, 1 thread), {n_c} runs", n_c, t_c,
                       f"mean errors rel. {d_err_runs:.1e} vs compiled engine B = {max(sizes)}, {n_c} runs"))

    # python-control, discrete (same RK4 step), one run
    t_pd, (sys_c, resp_d) = median_time(lambda: pc_discrete(loop, noise[:, 0], n), 1)
    order = state_order(sys_c)
    d_pd = float(np.max(np.abs(resp_d.states[order].T - res1.x[:, 0])))
    rows.append(Row(NAME, "python-control, discrete nlsys (one RK4 step per sample), 1 run", 1, t_pd,
                    f"states {d_pd:.1e}"))

    # python-control, adaptive: tolerance matched to RK4's accuracy at h (reference: 20 substeps)
    n_io = round(io_T / H)
    fine = build_loop(substeps=20).simulate(n_io, inputs={"xi": noise[:n_io, :1, 0], "eta": noise[:n_io, :1, 1],
                                                          "uc": 0.0}).x[:n_io, 0]
    scale = np.maximum(np.max(np.abs(fine), axis=0), 1e-12)
    rk4_err = float(np.max(np.abs(res1.x[:n_io, 0] - fine) / scale))
    chosen = None
    for rtol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8):
        t0 = time.perf_counter()
        resp = pc_adaptive(sys_c, noise[:, 0], n_io, H, rtol)
        t_io = time.perf_counter() - t0
        io_err = float(np.max(np.abs(resp.states[order].T - fine) / scale))
        notes.append(f"input_output_response rtol {rtol:g}: error / state range {io_err:.1e} "
                     f"(RK4 at 1 ms: {rk4_err:.1e}), {t_io:.2f} s for {io_T:g} s")
        chosen = (rtol, t_io, io_err)
        if io_err <= rk4_err:
            break
    rtol, t_io, io_err = chosen
    rows.append(Row(NAME, f"python-control, `input_output_response` RK45 rtol {rtol:g} ({io_T:g} s scaled to "
                          f"{T:g} s), 1 run", 1, t_io * n / n_io,
                    f"error {io_err:.1e} vs RK4's {rk4_err:.1e} (of state range)"))
    return rows, t_py, t_c / n_c, notes


if __name__ == "__main__":
    import argparse

    from _common import table

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--T", type=float, default=2.0)
    ap.add_argument("--io-T", type=float, default=0.05)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    rows, base, comp, notes = run(a.T, a.io_T, a.repeat)
    print(table(rows, {NAME: base}, {NAME: comp}))
    print("\n".join(notes))
