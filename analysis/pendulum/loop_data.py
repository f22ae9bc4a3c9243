"""Everything the `pendulum` study's closed-loop part computes (:class:`LoopData`, :func:`compute_loops`).

Both noise regimes over the Monte Carlo runs (:func:`.loops.compute_regime`), the rule-sign and
sampling-period checks, the recovery sweeps and the σ_w/σ_v sweep (:func:`qr_sweep`, on the batch axis
through :func:`.box.simulate_points`); :func:`seeds_for` gives the per-run seeds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ctrl_analysis.noise import run_seeds

from .box import ab_gains, simulate_points
from .loops import (
    CASES,
    LITERAL_CASES,
    _replace,
    build_filter,
    compute_regime,
    fuzzy_controller,
    recovery_sweep,
    simulate_case,
)

__all__ = ["LoopData", "compute_loops", "qr_sweep", "seeds_for"]


def qr_sweep(p, a21: float, seeds) -> dict:
    """Beyond the paper: σ_w/σ_v swept at the main σ_v and T; per ratio, the steady angle-estimate error RMS and the
    steady angle RMS of no filter, the paper's K and the steady-state gain optimal for that ratio, and its α; the share
    of
    healthy (not diverged) runs each mean is taken over."""
    ratios = np.geomspace(p.qr_sweep[0], p.qr_sweep[1], int(p.qr_sweep[2]))
    names = ("nofilter", "filter", "kf_ss")
    kinds = {"nofilter": None, "filter": "alpha-beta", "kf_ss": "kf-ss"}  # "filter": the paper's K, always
    qs = [_replace(p, sigma_w=float(r * p.sigma_v)) for r in ratios]
    # every ratio and case side by side on the batch axis (:func:`simulate_points`; same runs as simulate_case)
    runs = simulate_points([(q, a21, kinds[n]) for q in qs for n in names], seeds)
    out = {"ratios": ratios, "alpha_opt": [g[0] for g in ab_gains([(q, a21, "kf-ss") for q in qs])],
           "est": {k: [] for k in names}, "angle": {k: [] for k in names}, "healthy": {k: [] for k in names}}
    for i, _q in enumerate(qs):
        for j, name in enumerate(names):
            run = runs[i * len(names) + j].noisy
            ss = (run.t >= p.t_ss)
            ok = ~run.diverged
            out["healthy"][name].append(float(np.mean(ok)))
            if not ok.any():
                out["est"][name].append(np.nan)
                out["angle"][name].append(np.nan)
                continue
            angle_in = p.step - run.e[ss][:, ok]
            out["est"][name].append(float(np.sqrt(np.mean((angle_in - run.phi[ss][:, ok]) ** 2))))
            out["angle"][name].append(float(np.sqrt(np.mean((run.phi[ss][:, ok] - p.step) ** 2))))
    return {k: (np.asarray(v) if not isinstance(v, dict) else {n: np.asarray(x) for n, x in v.items()})
            for k, v in out.items()}


@dataclass
class LoopData:
    """Everything the closed-loop part computes: both regimes over the Monte Carlo runs, the checks and sweeps."""

    p: object
    a21: float
    seeds: list
    main: dict
    literal: dict
    sign_check: dict
    period_check: dict
    angles: np.ndarray
    recovered: dict
    lookup_error: float
    kf_ss_gain: tuple
    kf_ss_qr_gain: tuple
    qr: dict

    @property
    def lit(self):
        """The literal regime's parameters."""
        return self.p.literal()


def compute_loops(p, a21: float, seeds, progress=lambda msg: None, qr_seeds=None) -> LoopData:
    """Both regimes (main: every case of :data:`CASES`; literal: :data:`LITERAL_CASES`) on the same noise, the
    rule-sign and sampling-period checks (noise-free, one run), the recovery sweeps and the σ_w/σ_v sweep."""
    progress(f"closed loop, main regime: {len(CASES)} cases × {len(seeds)} runs")
    main = compute_regime(p, a21, seeds)
    progress(f"closed loop, literal regime: {len(LITERAL_CASES)} cases × {len(seeds)} runs")
    literal = compute_regime(p.literal(), a21, seeds, LITERAL_CASES)
    sign = {s: simulate_case(_replace(p, rule_sign=s), a21, [0], noise=False) for s in (1, -1)}
    period = {T: simulate_case(_replace(p, T=T), a21, [0], noise=False) for T in p.period_check}
    angles = np.linspace(*p.recover_angles[:2], int(p.recover_angles[2]))
    progress("recovery sweeps (linear, nonlinear) and the σ_w/σ_v sweep")
    recovered = {nl: recovery_sweep(p, a21, angles, nonlinear=nl) for nl in (False, True)}
    qr = qr_sweep(p, a21, seeds[:30] if qr_seeds is None else qr_seeds)
    direct, table = fuzzy_controller(p, lookup=False), fuzzy_controller(p, lookup=True)
    e, ec = np.meshgrid(np.linspace(-0.1, 0.1, 97), np.linspace(-1.5, 1.5, 97))
    err = float(np.max(np.abs(direct.evaluate(e, ec) - table.evaluate(e, ec))))
    ss, ssq = build_filter("kf-ss", p, a21), build_filter("kf-ss-qr", p, a21)
    return LoopData(p=p, a21=a21, seeds=list(seeds), main=main, literal=literal, sign_check=sign,
                    period_check=period, angles=angles, recovered=recovered, lookup_error=err,
                    kf_ss_gain=(ss.alpha, ss.beta), kf_ss_qr_gain=(ssq.alpha, ssq.beta), qr=qr)


def seeds_for(base_seed: int, runs: int) -> list:
    """Per-run seeds (recorded in results.json)."""
    return run_seeds(base_seed, runs)
