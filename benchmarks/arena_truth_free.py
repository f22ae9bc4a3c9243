"""The arena's truth-free mode against the truth, on records it was not tuned on (issue 31).

``ctrl-analysis arena --signal F.csv`` without ``--noise-bound``/``--accel-bound`` estimates the bounds from the
record (:func:`ctrl_analysis.arena.recordcheck.estimated_bounds`) and, without a derivative column, tunes and scores
on a surrogate (a zero-phase fit of the record plus uniform noise of the estimated bound). Here each record has its
truth, so both can be checked:

* the estimated bounds beside the true ones (ε̂/ε, L̂/L; for Gaussian noise the arena's ε is 3σ, and ε̂ = √3 σ̂ is
  the bound of uniform noise of the same spread, so ε̂/ε ≈ 0.58 is the right answer there);
* the **oracle pick**: every family tuned with the truth (true ε and L, the true derivative scoring);
* the **truth-free pick**: every family tuned without it (estimated bounds, the surrogate scoring);
* the truth-free pick's real worst-case error over the oracle pick's (both scored against the true derivative
  on the same window: the later of the two start-up windows), and the error the truth-free run printed over its
  pick's real error.

The records: the arena's five built-in signal classes × uniform and Gaussian noise × ε = 0.01 and 0.05, L = 4,
dt = 2 ms, 3000 samples, seed 101 (the arena's benchmark uses seeds from 0; its tunings never saw these).

    OPENBLAS_NUM_THREADS=1 python benchmarks/arena_truth_free.py [--jobs 2] [--quick]
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
LEVELS = (0.01, 0.05)
L_TRUE, DT, N, SEED = 4.0, 0.002, 3000, 101


def real_worst(name, params, t, y, d1, k0, dt) -> float:
    """Worst |f̂' - f'| of one family at ``params`` on the record, from sample ``k0``."""
    from ctrl_analysis.arena.interface import estimate, family

    fam = family(name)
    est = estimate(fam, [[params[p.name] for p in fam.params]], y[:, None], dt)[:, 0, 1]
    return float(np.max(np.abs(est[k0:] - d1[k0:])))


def one(kind, noise, eps, jobs) -> dict:
    from ctrl_analysis.arena.recommend import recommend_for_record, record_case
    from ctrl_analysis.arena.recordcheck import estimated_bounds
    from ctrl_analysis.arena.signals import add_noise, make_signal

    t = DT * np.arange(N)
    f, d1, _ = make_signal(kind, SEED, t, L_TRUE)
    y = add_noise(noise, f, eps, SEED + 1)
    oracle = recommend_for_record(t, y, d1, eps, L_TRUE, jobs=jobs)
    est = estimated_bounds(t, y)
    e_hat, l_hat = est["noise_bound"], est["accel_bound"]
    free = recommend_for_record(t, y, None, e_hat, l_hat, jobs=jobs)
    k0 = max(round(record_case(t, y, d1, eps, L_TRUE)[0].transient / DT),
             round(record_case(t, y, None, e_hat, l_hat)[0].transient / DT))
    o, w = oracle[0], free[0]
    real_o = real_worst(o["family"], o["params"], t, y, d1, k0, DT)
    real_w = real_worst(w["family"], w["params"], t, y, d1, k0, DT)
    return {"signal": kind, "noise": noise, "eps": eps, "eps_hat_ratio": e_hat / eps, "L_hat_ratio": l_hat / L_TRUE,
            "oracle": o["family"], "free": w["family"], "real_free_over_oracle": real_w / real_o,
            "printed_over_real": w["worst"] / real_w, "window_s": k0 * DT}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--quick", action="store_true", help="one level, uniform noise only")
    parser.add_argument("--json", default=None, help="write the rows to this file too")
    args = parser.parse_args(argv)
    rows, t0 = [], time.perf_counter()
    levels, noises = (LEVELS[:1], NOISES[:1]) if args.quick else (LEVELS, NOISES)
    print(f"{'record':28s} {'ε̂/ε':>6s} {'L̂/L':>6s} {'oracle':>10s} {'truth-free':>10s} {'real/oracle':>11s} "
          f"{'printed/real':>12s}", flush=True)
    for kind in SIGNALS:
        for noise in noises:
            for eps in levels:
                r = one(kind, noise, eps, args.jobs)
                rows.append(r)
                print(f"{kind + '/' + noise + '/' + format(eps, 'g'):28s} {r['eps_hat_ratio']:6.2f} "
                      f"{r['L_hat_ratio']:6.2f} {r['oracle']:>10s} {r['free']:>10s} "
                      f"{r['real_free_over_oracle']:11.2f} {r['printed_over_real']:12.2f}", flush=True)
    ratio = np.array([r["real_free_over_oracle"] for r in rows])
    printed = np.array([r["printed_over_real"] for r in rows])
    print(f"truth-free pick's real worst-case error / the oracle pick's: median {np.median(ratio):.2f}, worst "
          f"{np.max(ratio):.2f} ({len(rows)} records); printed / real error of the truth-free pick: "
          f"{np.min(printed):.2f}..{np.max(printed):.2f} (median {np.median(printed):.2f}); "
          f"{time.perf_counter() - t0:.0f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
