"""Benchmark of the estimator arena: the runs of one tuning batch against a float loop, numba and python-control.

Run by hand (never a timed test)::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_arena.py [--repeat 5]

1. The arena's hot loop on one family, the 3-state linear ESO (RK4, 2 substeps per sample, the
   arena's default 4000 samples at dt = 2 ms): :func:`ctrl_analysis.arena.interface.estimate`
   (the engine ``Loop``, numpy and compiled, per-run gains) at B = 1, 96 and 480 runs (480 is
   ``RUNS_PER_CALL``, one batch of the tuning) against the straightforward float loop of the same
   equations (one run, Python floats, RK4 unrolled), the same function compiled by numba (one
   thread) and python-control (the discrete LTI map of the two RK4 substeps, one
   ``forced_response`` per run). All must agree to round-off on ``f̂'``.
2. Notes: tunings per second of every family, ``evaluate`` on the compiled and numpy engines (one
   tuning = one configuration on one case of 3 noisy + 3 noise-free records), medians of interleaved
   rounds; ``--tunings`` prints them as a table.

Medians of repeats, the methods interleaved in every round; compile (or disk-cache load) before timing.
"""

from __future__ import annotations

import time

import _common  # noqa: F401  (single-threaded BLAS, repository on sys.path)
import numpy as np
from _common import Row, round_robin

from ctrl_analysis.arena.interface import FAMILIES, estimate
from ctrl_analysis.arena.signals import add_noise, make_signal
from ctrl_analysis.arena.tuning import (
    RUNS_PER_CALL,
    Case,
    Setup,
    _grid,
    evaluate,
    param_values,
)

NAME = "arena, 3-state linear ESO (RK4, 2 substeps)"
SETUP = Setup()  # dt = 2 ms, 4000 samples: the arena's default record
OMEGA = 20.0  # √(L/ε) at ε = 0.01, L = 4: the reference bandwidth of the default cases
SIZES = (1, 96, RUNS_PER_CALL)


def float_loop(y, dt, w):
    """One record through the linear ESO in plain Python floats: ``f̂'`` at every sample (before its update)."""
    L1, L2, L3 = 3.0 * w, 3.0 * w * w, w * w * w
    h = 0.5 * dt
    hh, h6 = 0.5 * h, h / 6.0
    x1 = x2 = x3 = 0.0
    out = [0.0] * len(y)
    for k in range(len(y)):
        out[k] = x2
        v = y[k]
        for _ in range(2):
            e = v - x1
            p1, p2, p3 = L1 * e + x2, L2 * e + x3, L3 * e
            e = v - (x1 + hh * p1)
            q1, q2, q3 = L1 * e + x2 + hh * p2, L2 * e + x3 + hh * p3, L3 * e
            e = v - (x1 + hh * q1)
            r1, r2, r3 = L1 * e + x2 + hh * q2, L2 * e + x3 + hh * q3, L3 * e
            e = v - (x1 + h * r1)
            s1, s2, s3 = L1 * e + x2 + h * r2, L2 * e + x3 + h * r3, L3 * e
            x1 = x1 + h6 * (p1 + 2.0 * q1 + 2.0 * r1 + s1)
            x2 = x2 + h6 * (p2 + 2.0 * q2 + 2.0 * r2 + s2)
            x3 = x3 + h6 * (p3 + 2.0 * q3 + 2.0 * r3 + s3)
    return out


def compiled_loop():
    """:func:`float_loop` compiled by numba (one thread); ``(function, compile seconds)``."""
    import numba

    fn = numba.njit(cache=True)(float_loop)
    t0 = time.perf_counter()
    fn(np.zeros(3), SETUP.dt, OMEGA)
    return fn, time.perf_counter() - t0


def pc_system(dt, w):
    """python-control: the discrete LTI map of two RK4 substeps of the linear ESO (the engine's arithmetic map)."""
    import control as ct

    A = np.array([[-3 * w, 1, 0], [-3 * w**2, 0, 1], [-(w**3), 0, 0]])
    B = np.array([[3 * w], [3 * w**2], [w**3]])
    h = 0.5 * dt
    Ah = A * h
    P = np.eye(3) + Ah + Ah @ Ah / 2 + Ah @ Ah @ Ah / 6 + Ah @ Ah @ Ah @ Ah / 24  # RK4 of x' = Ax + Bv
    Q = (np.eye(3) + Ah / 2 + Ah @ Ah / 6 + Ah @ Ah @ Ah / 24) @ B * h
    Ad, Bd = P @ P, P @ Q + Q
    return ct.ss(Ad, Bd, np.array([[0.0, 1.0, 0.0]]), 0.0, dt)


def records(n_runs):
    """``n_runs`` noisy records (sines, uniform ε = 0.01, L = 4): ``(N, n_runs)``."""
    t = SETUP.dt * np.arange(SETUP.n)
    return np.array([add_noise("uniform", make_signal("sines", s, t, 4.0)[0], 0.01, s + 1)
                     for s in range(n_runs)]).T


def bench_loop(repeat, sizes=SIZES):
    """Median seconds of every method; ``(times, agreement, compile seconds)``."""
    import control as ct

    y = records(max(sizes))
    dt = SETUP.dt
    ylist = y[:, 0].tolist()
    fn, t_compile = compiled_loop()
    t0 = time.perf_counter()
    estimate("leso3", [[OMEGA]], y[:50, :1], dt, engine="compiled")  # compile or load the runner once
    t_compile_engine = time.perf_counter() - t0
    sysd = pc_system(dt, OMEGA)
    n_c = 20
    fns = {"float": lambda: float_loop(ylist, dt, OMEGA),
           "numba": lambda: [fn(y[:, b], dt, OMEGA) for b in range(n_c)][0],  # noqa: RUF015 (all n_c runs timed)
           "python-control": lambda: ct.forced_response(sysd, U=y[:, 0]).outputs}
    for engine in ("numpy", "compiled"):
        for B in sizes:
            fns[(engine, B)] = (lambda e=engine, B=B: estimate("leso3", np.full((B, 1), OMEGA), y[:, :B], dt,
                                                               engine=e)[:, 0, 1])
    timed = round_robin(fns, repeat)
    ref = np.asarray(timed["float"][1])
    err = {k: float(np.max(np.abs(np.asarray(v[1]) - ref))) for k, v in timed.items() if k != "float"}
    return {k: v[0] for k, v in timed.items()}, err, (t_compile, t_compile_engine), n_c


def tunings_per_second(configs=60, repeat=3):
    """Per family: ``(name, compiled tunings/s, numpy tunings/s)`` of ``evaluate``, medians of interleaved rounds.

    One tuning is one configuration scored on one case of 3 noisy + 3 noise-free records (4000 samples
    each); ``configs`` configurations (the family's grid, repeated) are one call. Compile / warm-up
    before timing; the two engines alternate in every round, so a change in the machine's load hits
    both alike.
    """
    case = Case("sines", "uniform", 0.01, 4.0, (1, 2, 3))
    out = []
    for fam in FAMILIES:
        z, _ = _grid(fam)
        z = z.repeat(-(-configs // len(z)), axis=0)[:configs]
        cfg = [(0, v) for v in param_values(fam, z, case, SETUP)]
        fns = {}
        for engine in ("compiled", "numpy"):  # the algebraic family is an FIR in numpy on both
            evaluate((fam.name, SETUP, (case,), cfg[:2], engine))  # warm-up / compile
            fns[engine] = lambda e=engine, n=fam.name, c=cfg: evaluate((n, SETUP, (case,), c, e))
        timed = round_robin(fns, repeat)
        out.append((fam.name, len(cfg) / timed["compiled"][0], len(cfg) / timed["numpy"][0]))
    return out


def run(repeat=3):
    """Rows for the benchmark table: ``(rows, float-loop seconds per run, compiled seconds per run, notes)``."""
    times, err, (tc, tce), n_c = bench_loop(repeat)
    n = SETUP.n
    rows = [Row(NAME, "float loop (plain Python), 1 run", 1, times["float"]),
            Row(NAME, f"compiled reference (numba, 1 thread), {n_c} runs", n_c, times["numba"], f"{err['numba']:.1e}"),
            Row(NAME, "python-control `forced_response` (discrete map of the 2 RK4 substeps), 1 run", 1,
                times["python-control"], f"{err['python-control']:.1e}")]
    rows += [Row(NAME, f"`estimate` (engine `Loop`, {e}), B = {B}", B, times[(e, B)], f"{err[(e, B)]:.1e}")
             for e in ("numpy", "compiled") for B in SIZES]
    notes = [(f"{n} samples at dt = {SETUP.dt:g} s, ω_o = {OMEGA:g} rad/s; agreement: largest |f̂'| difference to "
              "the float loop on run 0"),
             f"compile (or disk-cache load) before timing: numba reference {tc:.2f} s, engine runner {tce:.2f} s",
             f"tunings per second (compiled / numpy engine, 6 records of 4000 samples a tuning, medians of {repeat} "
             "interleaved rounds of 60): "
             + "; ".join(f"{name} {c:.0f} / {p:.0f}" for name, c, p in tunings_per_second(repeat=repeat))]
    return rows, times["float"], times["numba"] / n_c, notes


def main(argv=None):
    import argparse

    from _common import table

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="timing repeats (median)")
    ap.add_argument("--tunings", action="store_true", help="only the tunings-per-second table")
    args = ap.parse_args(argv)
    if args.tunings:
        print("| family | tunings/s, compiled engine | tunings/s, numpy engine | compiled / numpy |")
        print("| --- | ---: | ---: | ---: |")
        for name, c, p in tunings_per_second(repeat=args.repeat):
            print(f"| `{name}` | {c:.0f} | {p:.0f} | {c / p:.1f} |")
        return
    rows, base, comp, notes = run(args.repeat)
    print(table(rows, {NAME: base}, {NAME: comp}))
    print()
    for x in notes:
        print(f"- {x}")


if __name__ == "__main__":
    main()
