"""The arena's tuning caps at a coarse sample period, and the α-β-γ filter beyond constant acceleration (issue 31).

At ``dt = 10 ms`` the reference bandwidth ``ω = √(L/ε)`` of a small noise bound is close to the sample rate, and
the families tuned by a bandwidth (Σ, the ESOs, the filtered difference) met the old cap ``ω dt <= 1`` (RK4 with two
substeps). The cap is now ``OMEGA_DT_MAX = 8`` with ``substeps_for(ω dt)`` RK4 steps per sample. This script tunes
those families on records at ``dt = 10 ms`` twice, with the old cap (``tuning.OMEGA_DT_MAX = 1``) and with the new
one, and counts the tunings whose best bandwidth sits at the cap, and what lifting it changed in the tuned error.
It also sets the Singer manoeuvre-model family beside the constant-acceleration α-β-γ filter on the same records.

Records: the arena's five built-in signal classes × uniform and Gaussian noise × ε = 0.0005, 0.002 and 0.01, L = 4,
dt = 10 ms, 2000 samples (2 s start-up window), 3 seeded records each from seed 101 (the arena's benchmark uses
seeds from 0). Two costs per case (worst and RMS): 60 tunings per family.

    OPENBLAS_NUM_THREADS=1 python benchmarks/arena_caps.py [--jobs 2] [--json F]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

SIGNALS = ("sines", "steps", "ramps", "chirp", "mixed")
NOISES = ("uniform", "gaussian")
LEVELS = (0.0005, 0.002, 0.01)
L_TRUE, DT, N, SEEDS = 4.0, 0.01, 2000, (101, 102, 103)
CAPPED = ("sigma", "sigma5", "sigman", "leso2", "leso3", "neso", "difflp")
COSTS = ("worst", "rms")


def tune(names, cap, jobs) -> dict:
    """``{family: [(case key, cost, fastest pole × dt, metric)]}`` with the bandwidth cap ``cap``."""
    from ctrl_analysis.arena import tuning
    from ctrl_analysis.arena.interface import SIGMA_ORDER
    from ctrl_analysis.runs.chains import pool_here

    cases = [tuning.Case(s, n, e, L_TRUE, SEEDS) for s in SIGNALS for n in NOISES for e in LEVELS]
    setup = tuning.Setup(dt=DT, n=N, transient=2.0)
    saved = tuning.OMEGA_DT_MAX
    tuning.OMEGA_DT_MAX = cap
    try:
        with pool_here(jobs):
            done = tuning.tune_families(list(names), cases, setup, rounds=2, jobs=jobs)
    finally:
        tuning.OMEGA_DT_MAX = saved
    out = {}
    for name in names:
        rows = []
        for c, best in zip(cases, done[name]["best"], strict=True):
            for j, cost in enumerate(COSTS):
                params, m = best[cost]
                rows.append((c.key, cost, float(params[0]) * SIGMA_ORDER.get(name, 1) * DT, float(m[j])))
        out[name] = rows
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--json", default=None, help="write the rows to this file too")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    old = tune(CAPPED, 1.0, args.jobs)
    new = tune(CAPPED + ("abg", "singer"), 8.0, args.jobs)
    report = {"cap": {}, "singer_over_abg": {}}
    print(f"{'family':8s} {'at ω dt = 1 (old cap)':>22s} {'at ω dt = 8 (new cap)':>22s} "
          f"{'tuned error new/old: min median max (where the old cap bound)':>40s}")
    for name in CAPPED:
        hit_old = [abs(r[2] - 1.0) < 1e-9 for r in old[name]]
        hit_new = [abs(r[2] - 8.0) < 1e-9 for r in new[name]]
        ratio = np.array([b[3] / a[3] for a, b, h in zip(old[name], new[name], hit_old, strict=True) if h])
        fastest = max(r[2] for r in new[name])
        report["cap"][name] = {"old_hits": int(sum(hit_old)), "new_hits": int(sum(hit_new)), "tunings": len(hit_old),
                               "ratio_where_bound": ratio.tolist(), "fastest_new_omega_dt": fastest}
        spread = f"{ratio.min():.3f} {np.median(ratio):.3f} {ratio.max():.3f}" if ratio.size else "-"
        print(f"{name:8s} {sum(hit_old):>15d} of {len(hit_old):<4d} {sum(hit_new):>15d} of {len(hit_new):<4d} "
              f"{spread:>30s}   (fastest tuned ω dt now {fastest:.2f})")
    for cost in COSTS:
        r = np.array([s[3] / a[3] for s, a in zip(new["singer"], new["abg"], strict=True) if s[1] == cost])
        report["singer_over_abg"][cost] = r.tolist()
        print(f"Singer / constant-acceleration α-β-γ, tuned {cost} error: {r.min():.3f}..{r.max():.3f}, median "
              f"{np.median(r):.3f}; Singer better in {int(np.sum(r < 0.99))} of {r.size}, worse in "
              f"{int(np.sum(r > 1.01))} (beyond 1 %)")
    print(f"{time.perf_counter() - t0:.0f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
