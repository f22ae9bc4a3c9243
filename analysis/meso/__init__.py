"""Study `meso`: Chen & Gao 2018, modified extended state observer: analysis and implementation.

Reproduces (a) the linear observer of eq. (29): bandwidth form, poles, Bode plots of the
disturbance-to-error transfer functions, the ε^(n+2−i) law (4)/(7) and the noise std per ε
(:mod:`.linear`); (b) situations 1 and 2 of §4 (eq. (27)-(32)): the closed loops of plant, ESO /
MESO, PD law (30) with the model term (12), batch least-squares identification (Table 1) and
W(s), built from blocks (:mod:`.loops`, :mod:`.identification`); (c) Tables 2-3, Fig. 3-6 and the
paper's claims the tables do not show (:mod:`.quantities`, :mod:`.findings`, :mod:`.figures`).
The paper's numbers and every reconstruction are in :mod:`.paper`.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict

from ctrl_analysis.noise import run_seeds
from ctrl_analysis.reporting import sensitivity
from ctrl_analysis.reporting.report import StudyContext, StudyInfo, StudyResult
from ctrl_analysis.reporting.study import record_parameters, study_params

from . import claims, figures, findings, linear, quantities
from .loops import pick, simulate_situation, situation_rows
from .paper import ANALYSIS, PAPER, QUICK, READINGS, SITUATIONS

__all__ = ["INFO", "run"]

INFO = StudyInfo(
    name='meso',
    seed_file='003_69569f7e4aa9c67b.txt',
    paper='Chen & Gao 2018, modified extended state observer: analysis and implementation',
    reproduces='linear ESO analysis (omega_o, poles, Bode, eps-scaling, noise), Tables 2-3, Fig. 3-6, '
               'Conclusion 3, M <= N, the identifiability gate',
)


def run(ctx: StudyContext, params=None) -> StudyResult:
    """Reproduce the linear analysis, situations 1 and 2 (Tables 2-3, Fig. 3-6), the claims and the findings.

    ``params`` overrides the settings (:func:`ctrl_analysis.reporting.study.study_params`): ``{"analysis": Analysis}``
    or a
    dict of its fields (default :data:`.paper.ANALYSIS`, or :data:`.paper.QUICK` with --quick: runs, horizons,
    grids, the box's noise runs). The paper's values and reconstructions (:data:`.paper.PAPER`, the situations, the
    readings) are not run-time parameters of this study: its modules read them directly, and the plausible box
    varies them through :func:`.claims.evaluate_many`.
    """
    result = StudyResult(INFO)
    an = study_params({"analysis": QUICK if ctx.quick else ANALYSIS}, params, result)["analysis"]
    seeds = run_seeds(ctx.seed, ctx.runs_or(an.runs, an.quick_runs))
    box_seeds = tuple(seeds[:an.quick_runs if ctx.quick else an.box_runs])
    horizons = {k: an.horizon(k) for k in SITUATIONS}
    result.seeds = {"noise": seeds}
    record_parameters(result, PAPER)
    record_parameters(result, READINGS, prefix="claims")
    for key, sit in SITUATIONS.items():
        record_parameters(result, sit, prefix=key)
    result.settings.update({"analysis": asdict(an), "runs": len(seeds), "quick": ctx.quick,
                            "table_metric": "e_mean = sum |e_k| / K over every 3-ms sample of the whole run"})

    ctx.progress("linear observer analysis")
    lin = linear.analyse(PAPER, an.eps_grid)
    ctx.save_figure(result, figures.plot_error_bode(lin), "leso_error_bode.png",
                    caption="Beyond the paper: Bode magnitude of the linear ESO's estimation errors e1, e2, e3 driven "
                    "by "
                            "dx3/dt (the derivative of the total disturbance) at the paper's ε and β = (3, 3, 1); the "
                            "flat low-frequency levels (DC gains ε³/β₃, β₁ε²/β₃, β₂ε/β₃) are the ε-powers of law "
                            "(4)/(7) "
                            "(quantities leso.*).")

    sims = {}
    for key, sit in SITUATIONS.items():
        rows = situation_rows(key, seeds)
        ctx.progress(f"{key}: {horizons[key]:g} s, {len(seeds)} Monte Carlo runs × 3 observers (ESO, MESO, "
                     f"MESO Table-1 literal) + noise-free and claim runs ({len(rows)} simulations on the batch axis)")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            sims[key] = simulate_situation(sit, rows, horizons[key], PAPER, window=an.eps_window,
                                           keep=_kept(rows), exact=[i for i, r in enumerate(rows)
                                                                    if r.observer == "meso" and r.seed is None],
                                           bound=an.bound, progress=ctx.progress, jobs=ctx.jobs)

    sc = quantities.eps_scaling(sims["s1"], an)
    ctx.save_figure(result, figures.plot_eps_scaling(sc, lin), "leso_eps_scaling.png",
                    caption="Beyond the paper: mean |e_i| of the ESO in situation 1 against ε on log-log axes, "
                    "noise-free "
                            "loop (left) and the steady noise std per ε (right), with reference lines of the slopes "
                            "law "
                            "(4)/(7) predicts; checks §5's claim that a larger ε lowers the noise sensitivity "
                            "(quantities leso.eps_slope.*, leso.noise_std.*).")
    out = claims.record(result, sims, lin, sc, horizons, an)
    _sensitivity(ctx, result, sims, an, box_seeds, horizons)
    _figures(ctx, result, sims)
    findings.add_findings(result, sims, lin, sc, out, horizons)
    result.missing = findings.missing(result)
    return result


def _sensitivity(ctx, result, sims, an, box_seeds, horizons) -> None:
    """Every claim and primary cell judged over the plausible box (:func:`.claims.evaluate_many`)."""
    ctx.progress(f"plausible box: {len(box_seeds)} noise runs per noise-on evaluation")
    claims.CACHE.clear()
    claims.remember(sims)
    params = {"": PAPER, "claims": READINGS, "box": claims.BoxSettings(box_seeds, tuple(horizons.items()), an)}
    names = None if not ctx.quick else [n for n in _varied() if n != "integrator"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        sens = sensitivity.explore(claims.evaluate, params, names=names, batch=claims.evaluate_many,
                                   jobs=ctx.jobs, scheduler=ctx.scheduler,
                                   **(sensitivity.QUICK if ctx.quick else BOX), note="")
    note = (f"the noise-free runs, and at a noise-on point {len(box_seeds)} noise runs (the main run's first seeds: "
            "common random numbers); each run simulated once and shared by every point that needs it"
            + (" (quick: the Euler integrator not tried)" if names else ""))
    sens.summary["note"] = note
    sensitivity.apply(result, sens)
    ctx.save_figure(result, sensitivity.plot_sensitivity(result), "sensitivity.png",
                    caption=sensitivity.caption(result, note))


#: explore's settings at default runs: 64 samples per algorithm; the bisections and the cell search bounded
BOX = {"samples": 64, "refine": 5, "cell_steps": 6, "search_rounds": 1}


def _varied() -> list:
    """The reconstructions the box varies (the algorithm axis apart)."""
    from ctrl_analysis.reporting.study import reconstructions_of

    return [("claims." if p is READINGS else "") + r["name"] for p in (PAPER, READINGS)
            for r in reconstructions_of(p) if r.get("plausible") is not None and r["plausible"].varied
            and r["plausible"].axis != "algorithm"]


def _kept(rows) -> list:
    """Runs whose trajectories the figures draw (noise off, and the first noise seed)."""
    keep = []
    for noise in (False, True):
        for o, v in (("eso", "none"), ("meso", "wellposed"), ("meso", "literal"), ("meso", "direct")):
            keep += pick(rows, o, v, noise)[:1]
    return keep + pick(rows, "meso", "literal", False, bypass_w=True)


def _figures(ctx, result, sims) -> None:
    c = figures.COLORS
    for key, sim in sims.items():
        sit, rows = SITUATIONS[key], sim.rows
        fig_no = (3, 4) if key == "s1" else (5, 6)
        seed = rows[pick(rows, "eso", "none", True)[0]].seed
        series = {"noise off": [
                      (pick(rows, "eso", "none", False)[0], "ESO", c["eso"]),
                      (pick(rows, "meso", "wellposed", False)[0], "MESO (well-posed LSM)", c["meso"])],
                  f"noise on, 0.002·U[−1, 1] (the paper's setting; run seed {seed})": [
                      (pick(rows, "eso", "none", True)[0], "ESO", c["eso"]),
                      (pick(rows, "meso", "wellposed", True)[0], "MESO (well-posed LSM)", c["meso"])]}
        title = (f"Fig. {fig_no[0]} (situation {key[1]}, b0 = {sit.b0:g}, b = {PAPER.b:g}): PD control with ESO "
                 f"and MESO at ε = {PAPER.epsilon:g} — control input, tracking and estimation errors "
                 f"(x3 = x2' − b0 u − XᵀΘ_used)")
        noisy = list(series)[1]
        ctx.save_figure(result, figures.plot_situation(sim, series, title, smooth={noisy: 1.0}), sit.figs[0],
                        caption=f"Redraws the paper's Fig. {fig_no[0]} (situation {key[1]}): the control input u, the "
                                "tracking error and the estimation errors e1-e3 of the ESO and the well-posed MESO at "
                                "equal ε and PD gains, with the measurement noise off (left) and on (middle, one run; "
                                "there the estimation errors are drawn faint with their 1-s centred moving average in "
                                "bold, since the noise band of one observer would hide the other's error). The "
                                "y-ranges of these two columns show the steady behaviour (1.2 × the 99.9th percentile "
                                "of |e| outside the start-up and the 4 s after the θ4 step at 30 s); the peaks they "
                                "clip are written in each panel and drawn at full scale, noise off, in the right "
                                "column (its time axis is broken between the start-up and the step; the two observers "
                                "are identical until the first identification batch ends, so only one trace shows "
                                "there). The ESO is drawn wide and faint beneath the MESO, whose control input nearly "
                                "coincides with it. x1 itself is not drawn: it lies on the reference to within the "
                                "tracking error of the second row. Compare the size of the MESO's and the ESO's "
                                f"errors with Table {2 if key == 's1' else 3}; long traces are thinned.")
        runs = [(pick(rows, "meso", "wellposed", True)[0], "MESO well-posed (noise on)", c["meso"]),
                (pick(rows, "meso", "literal", True)[0], "MESO Table-1 literal (noise on)", c["literal"]),
                (pick(rows, "meso", "literal", False, bypass_w=True)[0], "Table-1 literal without W(s) (noise off)",
                 c["noW"])]
        if key == "s2":
            runs.append((pick(rows, "meso", "direct", True)[0], "MESO direct (10) (noise on)", c["direct"]))
        title = (f"Fig. {fig_no[1]} (situation {key[1]}): LSM-identified parameters of d(t), batch N = {sit.N} "
                 f"({sit.N * PAPER.h:g} s)")
        ctx.save_figure(result, figures.plot_theta(sim, key, runs, title), sit.figs[1],
                        caption=f"Redraws the paper's Fig. {fig_no[1]} (situation {key[1]}): the four LSM-identified "
                                "parameters Θ of d(t) after each batch (markers) and the smoothed Θ in use (lines) "
                                "against their true values (dashed"
                                + ("; dotted: the trajectory-equivalent Θ, since θ3 is not identifiable in closed loop"
                                   if key == "s2" else "") + "), for the "
                                "well-posed MESO, the Table-1 literal accumulation and the literal rule without W(s)"
                                + (" and the direct rule (10)" if key == "s2" else "") + ". A diverged run's trace "
                                "stops where it diverged; y-ranges are fixed around the truth, so diverging traces "
                                "leave the panel"
                                + ("; θ3 is 0 by construction in situation 1, whose reduced regression (22) "
                                   "does not identify it" if key == "s1" else "")
                                + " (quantities " + key + ".theta_final, " + key + ".literal.*).")
    ctx.save_figure(result, figures.plot_identifiability(_cond_series(sims), PAPER.cond_threshold),
                    "identifiability.png",
                    caption="Beyond the paper: condition number of each LSM batch's regression (Theorem 1's "
                            "identifiability) over time, per situation and identification variant, against the "
                            "study's threshold (horizontal line, situation 2 only). The gate acts only on situation "
                            "2's "
                            "well-posed full regression (16): a batch above it falls back to the reduced regression "
                            "with θ3 held; situation 1's reduced regression (22) and the literal and direct variants "
                            "are not gated. The threshold admits situation 2's start-up batch and rejects the later, "
                            "near-collinear ones (quantity s2.gate_passes; finding identifiability-threshold).")


def _cond_series(sims) -> dict:
    import numpy as np

    out = {}
    for key, sim in sims.items():
        rows = sim.rows
        on = 10.0 ** sim.log10_cond[:, pick(rows, "meso", "wellposed", True)]
        series = [((np.nanmin(on, axis=1), np.nanmedian(on, axis=1), np.nanmax(on, axis=1)),
                   f"well-posed, noise on ({on.shape[1]} runs)",
                   {"color": "tab:blue", "ls": "-", "marker": "o", "ms": 3})]
        styles = {"wellposed": ("well-posed, noise off", "tab:cyan", "--", "s"),
                  "literal": ("Table-1 literal, noise off", "tab:orange", "-.", "^"),
                  "direct": ("direct (10), noise off", "tab:purple", ":", "D")}
        for v, (label, color, ls, m) in styles.items():
            idx = pick(rows, "meso", v, False)
            if idx:
                series.append((sim.exact_cond[idx[0]], label, {"color": color, "ls": ls, "marker": m, "ms": 4}))
        reg = "(22) [x̂1 x̂2 1]" if SITUATIONS[key].regression == "reduced" else "(16) [x̂1 x̂2 K̄+f 1] / (10)"
        out[f"situation {key[1]}: regression {reg}"] = (sim.t_batch, series,
                                                         SITUATIONS[key].regression != "reduced")
    return out
