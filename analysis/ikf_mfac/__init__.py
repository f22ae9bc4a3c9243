"""Study `ikf-mfac`: Lu & Hou 2022, MFAC with disturbance rejection based on a modified Kalman filter (IKF-MFAC).

The paper's values and reconstructions are in :mod:`.paper`, the plants in :mod:`.plants`, the
closed loops (library blocks wired by :class:`~ctrl_analysis.engine.loop.Loop`) in :mod:`.loops`, the
Monte Carlo quantities and sweeps in :mod:`.quantities`, Table 1's cells and the paper's claims judged
run by run in :mod:`.claims`, the study as a function of its parameters for the plausible box (many points at
once) in :mod:`.evaluate`, the findings in :mod:`.findings` and the figures in :mod:`.figures`.
"""

from __future__ import annotations

import numpy as np

from ctrl_analysis.noise import run_seeds
from ctrl_analysis.reporting import sensitivity
from ctrl_analysis.reporting.report import StudyContext, StudyInfo, StudyResult
from ctrl_analysis.reporting.study import record_parameters, study_params
from ctrl_analysis.runs import parallel

from . import figures as F
from .claims import judge_claims, record_fig2, record_noise_margin, record_table1
from .evaluate import MonteCarlo, evaluate, evaluate_many, fig2_data
from .findings import (
    missing,
    record_consistency,
    record_ranking,
    record_rearm,
    record_reset_erratum,
    record_steady_gain,
    record_td_scan,
    record_where_ikf_wins,
)
from .paper import EX1, EX2, FIG2, SCHEMES
from .quantities import (
    d_mfac_rearm_variant,
    ratio_rows,
    run_with_sweeps,
    sweep_table,
    td_step_scan,
)

__all__ = ["INFO", "SWEEPS", "run"]

INFO = StudyInfo(
    name='ikf-mfac',
    seed_file='000_1281acf4834e65d1.txt',
    paper='Lu & Hou 2022, model-free adaptive control with disturbance rejection based on a modified Kalman filter '
    '(IKF-MFAC)',
    reproduces='Table 1 (RMSE/SNR of MFAC, TD-MFAC, D-MFAC, IKF-MFAC, Monte Carlo), Fig. 2-6, the paper\'s claims '
               '(rankings, Fig. 2, noise levels) judged run by run over the plausible box, steady IKF gain, '
               'TD step count, sweeps over noise, Q/R, rho and lambda',
)

#: Grids of the sweeps beyond the paper.
_GAINS = {"q": (0.03, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0), "rho": (0.2, 0.4, 0.6, 0.8, 1.0),
          "lam": (0.5, 1.0, 2.0, 4.0, 8.0)}
SWEEPS = {"ex1": {"noise": (0.02, 0.05, 0.1, 0.2, 0.3, 0.4), **_GAINS},
          "ex2": {"noise": (0.25, 0.5, 1.0, 1.5, 2.0), **_GAINS}}
#: TD step counts scanned (x1 after the steps) on Table 1's seeds, around and above each chosen count.
TD_COUNTS = {"ex1": (1, 2, 4, 8, 12, 16, 17, 18, 19, 20, 24, 32, 48, 64),
             "ex2": (1, 4, 8, 16, 24, 28, 30, 31, 32, 33, 34, 35, 36, 40, 48, 64)}


def run(ctx: StudyContext, params=None) -> StudyResult:
    """Reproduce Table 1 and Fig. 2-6 by Monte Carlo, judge the claims over the plausible box, and beyond the paper.

    ``params`` overrides the settings (:func:`ctrl_analysis.reporting.study.study_params`): ``"ex1"``, ``"ex2"`` (the
    examples,
    :data:`.paper.EX1`, :data:`.paper.EX2`) and ``"fig2"`` (:data:`.paper.FIG2`), each an object or a dict of its
    fields.
    """
    result = StudyResult(INFO)
    chosen = study_params({"ex1": EX1, "ex2": EX2, "fig2": FIG2}, params, result)
    examples, fig2p = {"ex1": chosen["ex1"], "ex2": chosen["ex2"]}, chosen["fig2"]
    for key, ex in chosen.items():
        record_parameters(result, ex, key)
    runs = ctx.runs_or(200, 10)
    seeds = run_seeds(ctx.seed, runs)
    sweep_seeds = seeds[: min(runs, 50)]
    fig2_seeds = seeds[: min(runs, 100)]
    result.seeds = {"table1": seeds, "sweeps": sweep_seeds, "fig2": fig2_seeds}
    result.settings["sweeps"] = SWEEPS
    ctx.progress(f"ikf-mfac: Table 1 ({runs} runs) and the sweeps ({len(sweep_seeds)} runs a point), side by side")
    all_runs, points, noise_runs = {}, {}, {}
    # the eight (example, scheme) batches are independent: side by side over --jobs processes (or the cluster)
    tasks = [(ex, s, seeds, sweep_seeds, SWEEPS[key]) for key, ex in examples.items() for s in SCHEMES]
    outs = iter(parallel.map_chunks(_table_task, tasks, jobs=ctx.jobs, scheduler=ctx.scheduler,
                                    desc="ikf-mfac: Table 1 and the sweeps"))
    for key in examples:
        done = {s: next(outs) for s in SCHEMES}
        all_runs[key] = {s: d[0] for s, d in done.items()}
        points[key] = {s: d[1] for s, d in done.items()}
        noise_runs[key] = {s: [d[2][("noise", lv)] for lv in SWEEPS[key]["noise"]] for s, d in done.items()}
    sweeps = {key: sweep_table(points[key], SWEEPS[key]) for key in examples}
    per_run = {}
    for key in examples:
        per_run[key] = {s: (all_runs[key][s].rmse, all_runs[key][s].snr) for s in SCHEMES}
        where = {s: [f"run {b} at k = {k}" for b,
                     k in zip(np.flatnonzero(r.diverged), r.diverged_step[r.diverged], strict=True)]
                 for s, r in all_runs[key].items()}
        record_table1(result, key, per_run[key], where)
        record_noise_margin(result, key, SWEEPS[key]["noise"], {s: sweeps[key][s]["noise"] for s in SCHEMES},
                            noise_runs[key])
    fig2, fig2_first = fig2_data(examples["ex1"], fig2p, fig2_seeds, keep_first=True)
    record_fig2(result, fig2p.R, len(fig2_seeds), fig2, examples["ex1"].Q)
    judge_claims(result, {k: {s: per_run[k][s][0] for s in SCHEMES} for k in examples},
                 {"levels": {k: SWEEPS[k]["noise"] for k in examples}, "rows": noise_runs}, fig2)
    record_ranking(result, per_run)
    record_consistency(result, examples["ex1"].n, examples["ex2"].n)
    record_steady_gain(result, examples["ex2"], examples["ex2"].n)
    for key, ex in examples.items():
        record_rearm(result, key, ex, d_mfac_rearm_variant(ex, seeds))
    ctx.progress("ikf-mfac: TD steps per sample")
    # Table 1's TD-MFAC runs are the scan's row at the count used (same seeds, same loop)
    table_td = {key: {(ex.td_feedthrough, ex.td_substeps): per_run[key]["td_mfac"][0]}
                for key, ex in examples.items() if ex.td_reading == "substeps"}
    # --quick: the literal TD (one step a sample) on the numpy engine, its loop is the only one no other
    # run shares: compiling it on a cold cache costs ~1.5 s, running it ~0.1 s
    scans = {key: {"runs": len(seeds),
                   "rows": td_step_scan(ex, seeds, (ex.td_substeps,) if ctx.quick else TD_COUNTS[key], (True,),
                                        known=table_td.get(key))
                   | td_step_scan(ex, seeds, (1,) if ctx.quick else (1, ex.td_substeps), (False,),
                                  engine="numpy" if ctx.quick else "auto")}
             for key, ex in examples.items()}
    td_scan = record_td_scan(result, scans, {key: ex.td_substeps for key, ex in examples.items()})
    ratio = {key: ratio_rows(points[key]["ikf_mfac"], SWEEPS[key], ex) for key, ex in examples.items()}
    record_where_ikf_wins(result, sweeps, ratio, SWEEPS)
    _sensitivity(ctx, result, seeds, chosen)
    record_reset_erratum(result, examples["ex1"])
    result.missing = missing(result)
    _figures(ctx, result, chosen, all_runs, per_run, sweeps, ratio, seeds, fig2_first, td_scan)
    return result


def _table_task(task):
    """One (example, scheme) batch of Table 1 and the sweeps (:func:`.quantities.run_with_sweeps`), in a worker."""
    return run_with_sweeps(*task)


#: Runs of one evaluation of the plausible box: Table 1's cells and every noise level; Fig. 2 per R.
BOX_RUNS, BOX_FIG2_RUNS = 40, 16
#: The exploration's refinement: a claim's boundary to 1/16 of its segment, a cell's to 1/64, one round of the
#: compass search for a cell no sample reaches.
BOX_SETTINGS = {"refine": 4, "cell_steps": 6, "search_rounds": 1}


def _sensitivity(ctx, result, seeds, chosen) -> None:
    """The claims and Table 1's cells over the plausible box, many points at once on the batch axis."""
    n_runs, n_fig2 = (4, 4) if ctx.quick else (BOX_RUNS, BOX_FIG2_RUNS)
    mc = MonteCarlo(tuple(seeds[:n_runs]), tuple(seeds[:n_fig2]), SWEEPS["ex1"]["noise"], SWEEPS["ex2"]["noise"])
    names = ("ex1.Q", "ex2.rearm") if ctx.quick else None
    ctx.progress("ikf-mfac: the claims and cells over the plausible box")
    sens = sensitivity.explore(evaluate, {**chosen, "mc": mc}, names=names, jobs=ctx.jobs, scheduler=ctx.scheduler,
                               batch=evaluate_many, **(BOX_SETTINGS | (sensitivity.QUICK if ctx.quick else {})),
                               note=f"each evaluation: the first {len(mc.runs)} recorded seeds for Table 1's cells "
                                    f"and every noise level, {len(mc.fig2)} per Fig. 2 R, the same at every point "
                                    "(common random numbers); the noise-level claim simulated only as far as it is "
                                    "undecided" + (" (--quick: two reconstructions only)" if ctx.quick else ""))
    sensitivity.apply(result, sens)


def _figures(ctx, result, chosen, all_runs, per_run, sweeps, ratio, seeds, fig2_first, td_scan) -> None:
    """Fig. 2-6, the TD step scan, the Monte Carlo spread, the sweeps and the sensitivity (low resolution: --quick)."""
    ex1, ex2, fig2p = chosen["ex1"], chosen["ex2"], chosen["fig2"]
    examples = {"ex1": ex1, "ex2": ex2}
    dpi = 70 if ctx.quick else 120
    k1 = np.arange(1, ex1.n + 1)
    runs2 = result.get("fig2.diverged_runs").runs
    ctx.save_figure(result, F.plot_fig2(k1, all_runs["ex1"]["mfac"].first.y_ref, fig2_first, fig2p.R, runs2,
                                        result.get("fig2.diverged_runs").value, result.get("fig2.rejection").value,
                                        result.get("fig2.rise").value, ex1.Q, fig2p.rise_level, fig2p.steady),
               "fig2_ikf_q_over_r.png", dpi=dpi,
               caption="Redraws the paper's Fig. 2: IKF-MFAC in Example 1 for measurement variances R increasing at a "
                       f"fixed Q = {ex1.Q:g} (the paper's R values and Example 1's Q are not in the paper text: "
                       "reconstructed). Left: the output of one run per R. Right: what the paper's Fig. 2 claims, "
                       f"measured over {runs2} runs per R: the disturbance rejection (steady RMS of y − y* over k = "
                       f"{fig2p.steady[0]}..{fig2p.steady[1]}, smaller = stronger) and the response speed (samples "
                       f"from k = 3 until y first reaches {fig2p.rise_level:g}, larger = slower); an R at which at "
                       "least half the runs diverge is shaded and its count printed (claim fig2-larger-r).")
    for key, (fo, fe), kind in (("ex1", (3, 4), "constant"), ("ex2", (5, 6), "time-varying")):
        r = all_runs[key]
        ys = {s: r[s].first.y[:, 0] for s in SCHEMES}
        name = f"Example {key[-1]}, {kind} reference (seed {seeds[0]})"
        ctx.save_figure(result, F.plot_outputs(fo, f"{name}: outputs of the four schemes", r["mfac"].first.k,
                                          r["mfac"].first.y_ref, ys), f"fig{fo}_{kind}_outputs.png", dpi=dpi,
                   caption=f"Redraws the paper's Fig. {fo}: the reference y* and the true outputs of MFAC, TD-MFAC, "
                           f"D-MFAC and IKF-MFAC in Example {key[-1]} ({kind} reference), one panel per scheme on "
                           "the same axes, one run with the first seed; Table 1 averages such runs.")
        ctx.save_figure(result, F.plot_errors(fe, f"{name}: absolute tracking error |y*(k) − y(k)|", r["mfac"].first.k,
                                         r["mfac"].first.y_ref, ys), f"fig{fe}_{kind}_abs_error.png", dpi=dpi,
                   caption=f"Redraws the paper's Fig. {fe}: absolute tracking error |y* − y| of the four schemes "
                           f"in Example {key[-1]} ({kind} reference), the same run as Fig. {fo}.")
    ctx.save_figure(result, F.plot_spread(per_run, len(seeds)), "table1_rmse_spread.png", dpi=dpi,
               caption="Beyond the paper: the spread of the per-run RMSE of each scheme over the Monte Carlo runs "
                       "behind Table 1 (diverged runs excluded; the bar inside each violin is the median), with the "
                       "paper's printed RMSE marked; shows whether a printed value is a typical run or lies in a "
                       "tail (each Table 1 RMSE cell agrees when the printed value lies within the central 95 % of "
                       "these runs; its percentile is recorded).")
    ctx.save_figure(result, F.plot_td_scan(td_scan, {k: e.td_substeps for k, e in examples.items()},
                                           {k: result.get(f"{k}.mfac.rmse").value for k in examples}),
                    "td_substeps_scan.png", dpi=dpi,
                    caption=F.td_scan_caption(td_scan, {k: result.get(f"{k}.mfac.rmse").value for k in examples}))
    ctx.save_figure(result,
                    F.plot_noise_sweep({k: SWEEPS[k]["noise"] for k in examples}, sweeps,
                                       {"ex1": ex1.noise_std, "ex2": ex2.noise_std}),
               "beyond_rmse_vs_noise.png", dpi=dpi,
               caption="Beyond the paper: mean RMSE of the four schemes against the measurement-noise std in "
                       "both examples (the paper's level marked), every other parameter at the example's value "
                       "(Example 1's IKF Q, R reconstructed); a mean over at least 80 % of the runs is a filled "
                       "point, over 50-80 % a hollow annotated one, and a point where at least half the runs diverged "
                       "is left out; the diverged counts are in the panel titles (claim ikf-best-every-noise).")
    ctx.save_figure(result, F.plot_ratio_sweep(ratio, {k: e.Q / e.R for k, e in examples.items()}),
               "beyond_rmse_vs_q_over_r.png", dpi=dpi,
               caption="Beyond the paper: IKF-MFAC's mean RMSE against the IKF's q = Q/R in both examples, with the "
                       f"ratio used marked (Example 2: the paper's Q/R = {ex2.Q:g}/{ex2.R:g}; Example 1: "
                       "reconstructed, not printed) and the steady gain K∞(q) on a second axis; Q is varied at the "
                       "example's R; points with diverged runs follow the 80 % rule of the other sweeps.")
    ctx.save_figure(result, F.plot_gain_sweep(_GAINS, sweeps, {"rho": ex1.rho, "lam": ex1.lam}),
               "beyond_rmse_vs_rho_lambda.png", dpi=dpi,
               caption="Beyond the paper: mean RMSE of the four schemes against MFAC's step factor ρ and weight "
                       "λ (Example 1's printed values marked; Example 2 only says 'similar'), showing where IKF-MFAC's "
                       "advantage depends on the tuning; a mean over at least 80 % of the runs is a filled point, over "
                       "50-80 % a hollow annotated one, at least half diverged is left out; counts in the panel "
                       "titles.")
    ctx.save_figure(result, sensitivity.plot_sensitivity(result), "sensitivity.png", dpi=dpi,
                    caption=sensitivity.caption(result, result.sensitivity.get("note", "")))
