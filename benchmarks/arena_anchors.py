"""The arena against PyNumDiff and `derivative` on records it was not tuned on, tuned with the truth and without.

Optional anchors (not project dependencies): ``pip install pynumdiff==0.3 derivative==0.6.3``.

Records: the arena's five built-in signal classes × uniform and Gaussian noise, ε = 0.01, L = 4, dt = 2 ms, 3000
samples, seed 101 (the arena's benchmark uses seeds from 0). For each record and each side, the best **causal**
and the best **offline** estimator, each tuned two ways:

* **with the truth**: the arena with the true ε, L and the true derivative as its scoring column; PyNumDiff's
  ``optimize(..., dxdt_truth=...)``; `derivative`'s one-sided (causal) and centred Savitzky–Golay on a window grid
  scored against the truth;
* **without it**: the arena with its bounds estimated from the record and scored on its surrogate
  (``ctrl-analysis arena --signal`` without bounds); PyNumDiff's ``optimize(..., bandlimit=...)`` given the same
  information, the bandwidth ``√(L̂/ε̂) / 2π`` Hz from the arena's estimates; `derivative` has no tuning without the
  truth and is left out there.

Every pick is then scored against the true derivative on one window (after the arena's start-up window, to the end):
RMS and worst error, the worst over the bound ``2√(εL)``, and the tuning time. The arena tunes each family for its
RMS and for its worst-case error: its RMS is its RMS-tuned pick's, its worst error its worst-case-tuned pick's (the
label says both where they differ); the anchors' picks are by RMS (PyNumDiff's optimiser minimises an RMS loss).
PyNumDiff's methods here:
``savgoldiff``, ``spectraldiff``, ``butterdiff`` (zero-phase) and ``rtsdiff`` (RTS smoother), all offline;
``splinediff`` took 227 s for one optimisation and is left out.

    OPENBLAS_NUM_THREADS=1 python benchmarks/arena_anchors.py [--records N] [--json F]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

SIGNALS = ("sines", "steps", "ramps", "chirp", "mixed")
NOISES = ("uniform", "gaussian")
EPS, L_TRUE, DT, N, SEED = 0.01, 4.0, 0.002, 3000, 101


def _score(d, d1, k0):
    e = d[k0:] - d1[k0:]
    return float(np.sqrt(np.mean(e * e))), float(np.max(np.abs(e)))


def arena_side(t, y, d1, truth: bool, jobs: int, k0: int) -> dict:
    """The arena's best causal and best offline picks scored on the truth: ``{kind: (family, rms, worst, s)}``, the
    RMS from its RMS-tuned pick and the worst error from its worst-case-tuned pick (the arena tunes each family for
    both)."""
    from ctrl_analysis.arena.interface import estimate, family
    from ctrl_analysis.arena.recommend import recommend_for_record
    from ctrl_analysis.arena.recordcheck import estimated_bounds

    t0 = time.perf_counter()
    if truth:
        ranking = recommend_for_record(t, y, d1, EPS, L_TRUE, jobs=jobs, offline=True)
    else:
        est = estimated_bounds(t, y)
        ranking = recommend_for_record(t, y, None, est["noise_bound"], est["accel_bound"], jobs=jobs, offline=True)
    took = time.perf_counter() - t0
    out = {}
    for kind, causal in (("causal", True), ("offline", False)):
        side = [x for x in ranking if x["causal"] == causal]
        picks = {"rms": min(side, key=lambda x: x["rms"]), "worst": side[0]}  # the ranking is by worst-case error
        scored = {}
        for what, r in picks.items():
            fam = family(r["family"])
            par = r["rms_params"] if what == "rms" else r["params"]
            d = estimate(fam, [[par[p.name] for p in fam.params]], y[:, None], DT)[:, 0, 1]
            scored[what] = _score(d, d1, k0)[0 if what == "rms" else 1]
        label = picks["rms"]["family"] + ("" if picks["rms"] is picks["worst"] else "/" + picks["worst"]["family"])
        out[kind] = (label, scored["rms"], scored["worst"], took)
    return out


def pynumdiff_side(y, d1, truth: bool, bandlimit: float) -> dict:
    """PyNumDiff's methods tuned by its own optimiser: ``{method: (estimate, seconds)}``."""
    import pynumdiff
    from pynumdiff import optimize

    methods = {"savgoldiff": pynumdiff.polynomial_fit.savgoldiff, "spectraldiff": pynumdiff.basis_fit.spectraldiff,
               "butterdiff": pynumdiff.smooth_finite_difference.butterdiff, "rtsdiff": pynumdiff.kalman_smooth.rtsdiff}
    out = {}
    for name, fn in methods.items():
        t0 = time.perf_counter()
        kw = {"dxdt_truth": d1} if truth else {"bandlimit": bandlimit}
        params = optimize.optimize(fn, y, DT, **kw)[0]
        out[name] = (fn(y, DT, **params)[1], time.perf_counter() - t0)
    return out


def derivative_side(t, y, d1, k0) -> dict:
    """`derivative`'s Savitzky–Golay, one-sided (causal) and centred, on a window grid scored on the truth."""
    from derivative import dxdt

    out = {}
    for kind, right in (("causal", False), ("offline", True)):
        t0 = time.perf_counter()
        best = None
        for w in np.unique(np.round(np.geomspace(0.01, 1.0, 12) / DT) * DT):
            d = dxdt(y, t, kind="savitzky_golay", left=w, right=w if right else 0.0, order=2)
            s = _score(d, d1, k0)
            if best is None or s[0] < best[0][0]:
                best = (s, d)
        out[kind] = (best[1], time.perf_counter() - t0)
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=len(SIGNALS) * len(NOISES))
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    from ctrl_analysis.arena.bound import lower_bound
    from ctrl_analysis.arena.recommend import record_case
    from ctrl_analysis.arena.recordcheck import estimated_bounds
    from ctrl_analysis.arena.signals import add_noise, make_signal

    bound = lower_bound(EPS, L_TRUE)
    rows = []
    recs = [(s, n) for s in SIGNALS for n in NOISES][:args.records]
    for kind, noise in recs:
        t = DT * np.arange(N)
        f, d1, _ = make_signal(kind, SEED, t, L_TRUE)
        y = add_noise(noise, f, EPS, SEED + 1)
        est = estimated_bounds(t, y)
        k0 = max(round(record_case(t, y, d1, EPS, L_TRUE)[0].transient / DT),
                 round(record_case(t, y, None, est["noise_bound"], est["accel_bound"])[0].transient / DT))
        band = float(np.sqrt(est["accel_bound"] / est["noise_bound"]) / (2 * np.pi))
        row = {"record": f"{kind}/{noise}", "window_s": k0 * DT}
        for truth in (True, False):
            tag = "truth" if truth else "free"
            for side, v in arena_side(t, y, d1, truth, args.jobs, k0).items():
                row[f"arena_{side}_{tag}"] = v
            p = pynumdiff_side(y, d1, truth, band)
            scored = {m: (*_score(d, d1, k0), s) for m, (d, s) in p.items()}
            m = min(scored, key=lambda k: scored[k][0])
            row[f"pynumdiff_offline_{tag}"] = (m, *scored[m][:2], sum(v[2] for v in scored.values()))
            if truth:
                for side, (d, took) in derivative_side(t, y, d1, k0).items():
                    row[f"derivative_{side}_truth"] = ("savitzky_golay", *_score(d, d1, k0), took)
        rows.append(row)
        print(json.dumps(row), flush=True)
    cols = ["arena_causal_truth", "derivative_causal_truth", "arena_offline_truth", "pynumdiff_offline_truth",
            "derivative_offline_truth", "arena_causal_free", "arena_offline_free", "pynumdiff_offline_free"]
    print("\n| record | " + " | ".join(cols) + " |")
    print("|---|" + "---|" * len(cols))
    for r in rows:
        print(f"| {r['record']} | " + " | ".join(f"{r[c][0]} {r[c][1]:.4g} ({r[c][2] / bound:.2f}×)" for c in cols)
              + " |")
    for c in cols:
        rms = [r[c][1] for r in rows]
        print(f"{c}: median RMS {np.median(rms):.4g}, median tuning time {np.median([r[c][3] for r in rows]):.1f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
