"""Study `ikf-mfac`: Lu & Hou 2022, model-free adaptive control with disturbance rejection based on a modified Kalman filter (IKF-MFAC).

The paper's values and reconstructions are in :mod:`.paper`, the plants in :mod:`.plants`, the
closed loops (library blocks wired by :class:`~ctrl_analysis.loop.Loop`) in :mod:`.loops`, the
Monte Carlo quantities and sweeps in :mod:`.quantities`, the findings in :mod:`.findings` and the
figures in :mod:`.figures`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ctrl_analysis.report import StudyContext, StudyInfo, StudyResult
from ctrl_analysis.simulate import run_seeds
from ctrl_analysis.study import record_parameters

from . import figures as F
from .findings import (
    missing,
    record_consistency,
    record_ranking,
    record_rearm,
    record_steady_gain,
    record_td_scan,
    record_where_ikf_wins,
)
from .loops import noise_draws, run_scheme
from .paper import EX1, EX2, SCHEMES
from .quantities import (
    d_mfac_rearm_variant,
    ratio_rows,
    record_table1,
    run_with_sweeps,
    sweep_table,
    td_step_scan,
)

__all__ = ["INFO", "SWEEPS", "run"]

INFO = StudyInfo(
    name='ikf-mfac',
    seed_file='000_1281acf4834e65d1.txt',
    paper='Lu & Hou 2022, model-free adaptive control with disturbance rejection based on a modified Kalman filter (IKF-MFAC)',
    reproduces='Table 1 (RMSE/SNR of MFAC, TD-MFAC, D-MFAC, IKF-MFAC, Monte Carlo), Fig. 2-6, steady IKF gain, '
               'sweeps over noise, Q/R, rho and lambda',
)

#: Grids of the sweeps beyond the paper.
_GAINS = {"q": (0.03, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0), "rho": (0.2, 0.4, 0.6, 0.8, 1.0), "lam": (0.5, 1.0, 2.0, 4.0, 8.0)}
SWEEPS = {"ex1": {"noise": (0.02, 0.05, 0.1, 0.2, 0.3, 0.4), **_GAINS},
          "ex2": {"noise": (0.25, 0.5, 1.0, 1.5, 2.0), **_GAINS}}
EXAMPLES = {"ex1": EX1, "ex2": EX2}


def run(ctx: StudyContext) -> StudyResult:
    """Reproduce Table 1 and Fig. 2-6 by Monte Carlo, check Table 1, and sweep beyond the paper."""
    result = StudyResult(INFO)
    for key, ex in EXAMPLES.items():
        record_parameters(result, ex, key)
    runs = ctx.runs_or(200, 10)
    seeds = run_seeds(ctx.seed, runs)
    sweep_seeds = seeds[: min(runs, 50)]
    result.seeds = {"table1": seeds, "sweeps": sweep_seeds}
    result.settings["sweeps"] = SWEEPS
    ctx.progress(f"ikf-mfac: Table 1 ({runs} runs) and the sweeps ({len(sweep_seeds)} runs a point), side by side")
    all_runs, points = {}, {}
    for key, ex in EXAMPLES.items():
        done = {s: run_with_sweeps(ex, s, seeds, sweep_seeds, SWEEPS[key]) for s in SCHEMES}
        all_runs[key] = {s: d[0] for s, d in done.items()}
        points[key] = {s: d[1] for s, d in done.items()}
    per_run = {key: record_table1(result, key, all_runs[key]) for key in EXAMPLES}
    record_ranking(result, per_run)
    record_consistency(result, EX1.n, EX2.n)
    record_steady_gain(result, EX2, EX2.n)
    for key, ex in EXAMPLES.items():
        record_rearm(result, key, ex, d_mfac_rearm_variant(ex, seeds))
    ctx.progress("ikf-mfac: TD steps per sample")
    scan_seeds = seeds[: min(runs, 100)]
    # --quick: the literal TD (one step a sample, 10 runs) on the numpy engine, its loop is the only
    # one no other run shares: compiling it on a cold cache costs ~1.5 s, running it ~0.1 s
    scans = {key: {"runs": len(scan_seeds),
                   "rows": td_step_scan(ex, scan_seeds, _scan_counts(ex, ctx.quick), (True,))
                   | td_step_scan(ex, scan_seeds, (1,) if ctx.quick else (1, ex.td_substeps), (False,),
                                  engine="numpy" if ctx.quick else "auto")}
             for key, ex in EXAMPLES.items()}
    record_td_scan(result, scans, {key: ex.td_substeps for key, ex in EXAMPLES.items()})
    sweeps = {key: sweep_table(points[key], SWEEPS[key]) for key in EXAMPLES}
    ratio = {key: ratio_rows(points[key]["ikf_mfac"], SWEEPS[key], ex) for key, ex in EXAMPLES.items()}
    record_where_ikf_wins(result, sweeps, ratio, SWEEPS)
    result.missing = missing(result)
    _figures(ctx, result, all_runs, per_run, sweeps, ratio, seeds)
    return result


def _scan_counts(ex, quick: bool) -> tuple:
    """TD step counts tried with x1 after the steps: the chosen one and the one below it (not with --quick)."""
    return (ex.td_substeps,) if quick else (1, 4, ex.td_substeps - 1, ex.td_substeps)


def _figures(ctx, result, all_runs, per_run, sweeps, ratio, seeds) -> None:
    """Fig. 2-6, the Monte Carlo spread and the three sweeps (at a lower resolution with --quick)."""
    dpi = 70 if ctx.quick else 120
    fig2_R = np.array([0.001, 0.01, 0.1, 1.0])
    v = np.tile(noise_draws(EX1, seeds[:1]), (1, fig2_R.size))
    y = run_scheme(dataclasses.replace(EX1, R=fig2_R), "ikf_mfac", v).y
    outs = {R: y[:, i] for i, R in enumerate(fig2_R)}
    k1 = np.arange(1, EX1.n + 1)
    ctx.save_figure(result, F.plot_fig2(k1, all_runs["ex1"]["mfac"].y_ref, outs, ratio["ex1"], EX1.Q,
                                    EX1.Q / EX1.R),
               "fig2_ikf_q_over_r.png", dpi=dpi,
               caption="Redraws the paper's Fig. 2: IKF-MFAC's output in Example 1 (one run) for measurement "
                       f"variances R = 0.001 to 1 at a fixed Q = {EX1.Q:g} (left; the paper does not print "
                       "Example 1's Q or R, so Q is the study's reconstruction), and beyond the paper the mean RMSE ± std over the "
                       "sweep's runs with the IKF's steady gain K∞ against q = Q/R, Q varied at the study's "
                       f"R = {EX1.R:g} (right); diverged runs are counted on the plot and excluded from the means.")
    for key, (fo, fe), kind in (("ex1", (3, 4), "constant"), ("ex2", (5, 6), "time-varying")):
        r = all_runs[key]
        ys = {s: r[s].y[:, 0] for s in SCHEMES}
        name = f"Example {key[-1]}, {kind} reference (seed {seeds[0]})"
        ctx.save_figure(result, F.plot_outputs(fo, f"{name}: outputs of the four schemes", r["mfac"].k,
                                          r["mfac"].y_ref, ys), f"fig{fo}_{kind}_outputs.png", dpi=dpi,
                   caption=f"Redraws the paper's Fig. {fo}: the reference y* and the true outputs of MFAC, TD-MFAC, "
                           f"D-MFAC and IKF-MFAC in Example {key[-1]} ({kind} reference), one run with the first "
                           "seed; Table 1 averages such runs.")
        ctx.save_figure(result, F.plot_errors(fe, f"{name}: absolute tracking error |y*(k) − y(k)|", r["mfac"].k,
                                         r["mfac"].y_ref, ys), f"fig{fe}_{kind}_abs_error.png", dpi=dpi,
                   caption=f"Redraws the paper's Fig. {fe}: absolute tracking error |y* − y| of the four schemes "
                           f"in Example {key[-1]} ({kind} reference), the same run as Fig. {fo}.")
    ctx.save_figure(result, F.plot_spread(per_run, len(seeds)), "table1_rmse_spread.png", dpi=dpi,
               caption="Beyond the paper: the spread of the per-run RMSE of each scheme over the Monte Carlo runs "
                       "behind Table 1 (diverged runs excluded; the bar inside each violin is the median), with the "
                       "paper's printed RMSE marked; shows whether a printed value is a typical run or lies in a "
                       "tail (the note of each Table 1 quantity gives the fraction).")
    ctx.save_figure(result, F.plot_noise_sweep({k: SWEEPS[k]["noise"] for k in EXAMPLES}, sweeps, {"ex1": EX1.noise_std, "ex2": EX2.noise_std}),
               "beyond_rmse_vs_noise.png", dpi=dpi,
               caption="Beyond the paper: mean RMSE of the four schemes against the measurement-noise std in "
                       "both examples (the paper's level marked), every other parameter at the example's value "
                       "(Example 1's IKF Q, R reconstructed); points whose mean excludes diverged runs are "
                       "ringed and the counts given in the panel titles (finding where-ikf-mfac-wins).")
    ctx.save_figure(result, F.plot_ratio_sweep(ratio, {k: e.Q / e.R for k, e in EXAMPLES.items()}),
               "beyond_rmse_vs_q_over_r.png", dpi=dpi,
               caption="Beyond the paper: IKF-MFAC's mean RMSE against the IKF's q = Q/R in both examples, with "
                       f"the ratio used marked (Example 2: the paper's Q/R = {EX2.Q:g}/{EX2.R:g}; Example 1: "
                       "reconstructed, not printed) and the steady gain K∞(q) on a second axis; Q is varied at the example's R.")
    ctx.save_figure(result, F.plot_gain_sweep(_GAINS, sweeps, {"rho": EX1.rho, "lam": EX1.lam}),
               "beyond_rmse_vs_rho_lambda.png", dpi=dpi,
               caption="Beyond the paper: mean RMSE of the four schemes against MFAC's step factor ρ and weight "
                       "λ (the paper's values marked), showing where IKF-MFAC's advantage depends on the tuning; "
                       "points whose mean excludes diverged runs are ringed and the counts given in the panel titles.")
