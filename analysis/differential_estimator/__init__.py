"""Study `differential-estimator`: Qi, Chen, Xue & Yuan 2004, a differential state estimator for nonlinear systems.

Modules: :mod:`.paper` (printed values and reconstructions), :mod:`.loops` (the loops of Examples
1-2 from library blocks), :mod:`.linear_checks`, :mod:`.example1`, :mod:`.example2` (quantities
and findings), :mod:`.figures`.
"""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np

from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.noise import run_seeds
from ctrl_analysis.reporting import sensitivity
from ctrl_analysis.reporting.report import StudyContext, StudyInfo, StudyResult
from ctrl_analysis.reporting.study import record_parameters, study_params
from ctrl_analysis.runs import parallel

from . import claims, example1, example2, figures, linear_checks
from .paper import EX1, EX2, LINEAR, READINGS

__all__ = ["INFO", "run"]

INFO = StudyInfo(
    name='differential-estimator',
    seed_file='002_a1e12cd95cff3523.txt',
    paper='Qi, Chen, Xue & Yuan 2004, a new differential state estimator and controller for nonlinear stochastic '
    'systems',
    reproduces='eq. (9) check, Fig. 1 root locus, Fig. 2 Bode, Examples 1-2 (Fig. 3-5), robustness map, '
               'a fair ESO-vs-Σ comparison',
)

MISSING = [
    ("Fig. 3-5 are redrawn from the reconstruction (step, horizon, ESO tuning, b1..b3, setpoint softener "
     "unprinted); the paper's traces cannot be compared point by point"),
    ("Fig. 5's tracking in the printed configuration (Σ a = 5, K = [2184, 506, 39]): the linearised loop is "
     "unstable and x1 oscillates about v (claim ex2-tracks); it is reproduced only with the study's stable preset "
     "fast_estimator (a larger Σ bandwidth)"),
]


def run(ctx: StudyContext, params=None) -> StudyResult:
    """Reproduce the study: linear part, Example 1 (+ fair comparison), Example 2 (+ robustness), claims, sensitivity.

    ``params`` overrides the settings (:func:`ctrl_analysis.reporting.study.study_params`): ``"linear"``, ``"ex1"``,
    ``"ex2"``,
    ``"claims"`` (defaults :data:`.paper.LINEAR`, :data:`.paper.EX1`, :data:`.paper.EX2`, :data:`.paper.READINGS`;
    with ``--quick`` shorter Examples 1-2 and a coarser Example 2 grid), each an object or a dict of its fields.
    """
    result = StudyResult(INFO)
    quick1, quick2 = replace(EX1, T=2.0), replace(EX2, T=5.0, sweep_b1=(-10.0, 0.0, 10.0),
                                                   sweep_b2=(-10.0, 2.0, 10.0), sweep_b3=(0.1, 10.0))
    chosen = study_params({"linear": LINEAR, "ex1": quick1 if ctx.quick else EX1, "ex2": quick2 if ctx.quick else EX2,
                           "claims": READINGS}, params, result)
    lin, p1, p2, r = chosen["linear"], chosen["ex1"], chosen["ex2"], chosen["claims"]
    runs = ctx.runs_or(100, 3)
    for prefix, obj in chosen.items():
        record_parameters(result, obj, prefix)
    _linear(ctx, result, lin)
    _examples(ctx, result, p1, p2, runs)
    claims.judge(result, p1, p2, r)
    _sensitivity(ctx, result, chosen)
    result.missing = list(MISSING)  # the differing cells are listed by the report, from their verdicts
    return result


#: Monte Carlo runs per evaluation of the plausible box (the main run's first seeds: common random numbers).
BOX_RUNS = 8


def _sensitivity(ctx, result, chosen):
    """Every claim and printed cell judged over the plausible box (:func:`.claims.evaluate`); figure sensitivity.png.

    The box's points differ in the simulation step, the horizon and the integrator of both examples, so no two
    share a simulation: each point is evaluated on its own (``explore`` without ``batch``), made cheap instead
    (:func:`.claims.evaluate`: fewer runs on common seeds, no figure-only work).
    """
    runs = 3 if ctx.quick else BOX_RUNS
    names = None if not ctx.quick else ["ex1.eso_tuning_ratio", "ex2.b1", "claims.fair_margin"]
    ctx.progress(f"plausible box: every claim and cell over the reconstructions' ranges ({runs} runs per evaluation)")
    evaluate = functools.partial(claims.evaluate, runs=runs, seed=ctx.seed,
                                 grid=None if not ctx.quick else {"sweep_b1": (1.0,), "sweep_b2": (2.0,),
                                                                  "sweep_b3": (1.0,)})
    note = (f"{runs} Monte Carlo runs per evaluation (the main run's first {runs} seeds at every point: common random "
            f"numbers; the main run has {ctx.runs_or(100, 3)}); Example 2's robustness grid reduced to b1 ∈ "
            f"{claims.EVAL_GRID['sweep_b1']}, b2 ∈ {claims.EVAL_GRID['sweep_b2']}, b3 ∈ {claims.EVAL_GRID['sweep_b3']} "
            "and its stable preset not simulated (no claim reads it)")
    sens = sensitivity.explore(evaluate, chosen, names=names, jobs=ctx.jobs, scheduler=ctx.scheduler,
                               **(sensitivity.QUICK if ctx.quick else {}), note=note)
    sensitivity.apply(result, sens)
    ctx.save_figure(result, sensitivity.plot_sensitivity(result), "sensitivity.png",
                    caption=sensitivity.caption(result, note))


def _linear(ctx, result, lin):
    ctx.progress("linear part: eq. (9), (5), Fig. 1-2")
    eq9 = linear_checks.eq9_checks(result, lin)
    linear_checks.eq5_checks(result, lin)
    linear_checks.lowpass_checks(result, lin)
    linear_checks.controller_poles(result, lin)
    n0, a = lin.fig1_n0, lin.fig1_a
    fig = figures.plot_root_locus(
        DifferentialEstimator(n0, a), printed_K=eq9["K_printed_by_n"][lin.eq9_n], printed_n=lin.eq9_n,
        title=f"Fig. 1  Root locus of G(s) = K(s+{a:g})^{n0 - 1}/s^{n0} (n0 = {n0}, a = {a:g}); "
              "× = closed-loop poles at the design gain")
    ctx.save_figure(result, fig, "fig1_root_locus.png",
                    caption=f"Redraws the paper's Fig. 1: root locus of Σ's loop G(s) = K(s+a)^(n0−1)/s^n0 for n0 = "
                    f"{n0}, "
                            f"a = {a:g}, with the closed-loop poles at the design gain (the breakaway point s = −n0 "
                            f"a); "
                            "see the check 'breakaway point' and the erratum on eq. (9)'s exponent.")
    est2 = DifferentialEstimator(lin.fig2_n0, lin.fig2_a)
    ctx.save_figure(result, figures.plot_bode(est2, title=f"Fig. 2  Bode plot of Φ(s), y → z₁ (n0 = {est2.n0}, "
                                                          f"a = {est2.a:g}, K = {est2.K:.4g})"), "fig2_bode.png",
                    caption="Redraws the paper's Fig. 2: Bode plot of Σ's transfer function Φ(s) from the measurement "
                    "y "
                            "to the estimate z1; a low-pass with unit DC gain (its −3 dB bandwidth and resonance peak "
                            "are "
                            "quantities 'Fig. 2: -3 dB bandwidth of Φ' and 'Fig. 2: resonance peak of |Φ|'; claim "
                            "lowpass).")
    ctx.save_figure(result, figures.plot_normalised_magnitude(lin.table_n0, title="Beyond the paper: |Φ(jω)| of Σ "
                    "at the design gain, against ω/a, n0 = 2..8"), "extra_phi_magnitude_vs_n0.png",
                    caption="Beyond the paper: |Φ(jω)| of Σ at the design gain against the normalised frequency ω/a "
                            "for n0 = 2 to 8; the bandwidth scales with a, and n0 sets the bandwidth ω_b/a and the "
                            "resonance peak; every n0 rolls off at the same −20 dB/decade (Φ has relative degree 1; "
                            "finding lowpass-claim).")


def _examples(ctx, result, p1, p2, runs):
    """Example 1 and Example 2 side by side: each records into its own result (in its own process with
    ``--jobs`` > 1), merged here in the order they would have run one after the other, so results.json is the
    same as from one process (:meth:`StudyResult.merge <ctrl_analysis.reporting.results.StudyResult.merge>`).

    They share nothing: Example 2 reads no quantity Example 1 records. Local processes only (``scheduler=False``):
    each writes its figures into this study's folder.
    """
    ctx.progress(f"Examples 1 and 2 side by side: {runs} runs each, Example 1 with the fair comparison and the n0 "
                 "sweep, Example 2 with its linearisation and robustness grid")
    tasks = [(key, p, runs, result.info, ctx.out_dir, ctx.seed, ctx.quick) for key, p in (("ex1", p1), ("ex2", p2))]
    for part in parallel.map_chunks(_example_part, tasks, jobs=min(ctx.jobs, 2), scheduler=False,
                                    desc="differential-estimator: examples"):
        result.merge(part)


def _example_part(task) -> StudyResult:
    """One example recorded into a result of its own (a call of :func:`_examples`, module level: run in a worker)."""
    key, p, runs, info, out_dir, seed, quick = task
    part, ctx = StudyResult(info), StudyContext(out_dir=out_dir, seed=seed, quick=quick)
    (_example1 if key == "ex1" else _example2)(ctx, part, p, runs)
    ctx.wait_figures()
    return part


def _example1(ctx, result, p, runs):
    seeds = run_seeds(ctx.seed, runs)
    result.seeds["ex1"] = seeds
    ctx.progress(f"Example 1: {runs} runs, RK4 h = {p.h * 1e3:g} ms, T = {p.T:g} s (Σ + two ESOs)")
    d = example1.simulate(p, seeds)
    example1.main_quantities(result, p, d)
    ctx.progress("Example 1: Euler and half-step sensitivities, fair comparison, n0 sweep, a badly tuned ESO")
    example1.sensitivities(result, p, d)
    trade = example1.fair_comparison(result, p, d)
    example1.n0_sweep(result, p, d)
    example1.eso_divergence(result, p, seeds)
    b, s = example1.shown_run(d)
    t = p.h * np.arange(s["x[1]"].shape[0])
    ctx.save_figure(result, figures.plot_x2(t, s["x[1]"], s["sig[1]"], f"Fig. 3 — Example 1: x2 and Σ's "
                    f"estimate z2 (n0 = {p.n0}, a = {p.a:g}; seed {seeds[b]})", r"$\hat x_2 = z_2$ (Σ)"),
                    "fig3_sigma_x2.png",
                    caption="Redraws the paper's Fig. 3 (Example 1): the true x2 and Σ's estimate z2 (state reading) "
                            "in one run, the error, and a 0.5 s zoom; its mean error over the runs is the §4 Example "
                            "1 Σ |ε̄2| cell.")
    ctx.save_figure(result, figures.plot_x2(t, s["x[1]"], s["eso[0][1]"], f"Fig. 4 — Example 1: x2 and "
                    f"Han's nonlinear ESO estimate (textbook gains; seed {seeds[b]})", r"$\hat x_2$ (ESO)"),
                    "fig4_eso_x2.png",
                    caption="Redraws the paper's Fig. 4 (Example 1): the true x2 and the estimate of Han's nonlinear "
                            "ESO with textbook gains (the paper prints none) in the same run, the error, and a 0.5 s "
                            "zoom where the high-frequency noise that fills the full-length traces is resolved; its "
                            "mean error is the ESO |ε̄2| cell.")
    sp = np.mean(d["err"]["sigma"][d["ok"]], axis=0)
    ctx.save_figure(result,
                    figures.plot_tradeoff(trade, sp, f"Beyond the paper, Example 1: mean x2 error against mean x1 "
                    f"error over the −3 dB bandwidth\n(Σ and ESOs, {int(d['ok'].sum())} runs each)"),
                    "ex1_tradeoff.png",
                    caption="Beyond the paper (the fair comparison): mean x2 error against mean x1 error for Σ "
                            "(sweeping a; labels give its −3 dB bandwidth) and the linear ESO (sweeping ω_o), with "
                            "Han's fal ESO at two tunings (textbook gains; Σ's bandwidth) and Σ as in the paper "
                            "(star). Lower left is better; points at equal bandwidth compare the observers fairly "
                            "(findings ex1-fair-equal-bandwidth, ex1-tradeoff).")


def _example2(ctx, result, p, runs):
    ctx.progress("Example 2: linearisation (control.linearize) and the stable preset")
    lin = example2.linear_analysis(result, p)
    example2.nonminimum_phase(result, p)
    n_grid = len(p.sweep_b1) * len(p.sweep_b2) * len(p.sweep_b3)
    seeds = run_seeds(ctx.seed, runs + n_grid)
    result.seeds["ex2"], result.seeds["ex2_sweep"] = seeds[:runs], seeds[runs:]
    ctx.progress(f"Example 2: presets a = {p.a:g} and a = {lin['a_new']:g}, {runs} runs + {n_grid} grid points each")
    d = example2.simulate(p, seeds, lin["a_new"], runs)
    q = example2.quantities(result, p, d, lin)
    t, per = d["t"], d["per"]
    pick, tr = d["pick"], d["traces"]
    traces = [(f"{name} (Σ n0 = {p.n0}, a = {d['a'][j]:g}; seed {d['seeds'][pick[j] - j * per]})",
               {"x[0]": tr["x[0]"][:-1, j], "xhat[0]": tr["xhat[0]"][:-1, j], "x[1]": tr["x[1]"][:-1, j],
                "xhat[1]": tr["xhat[1]"][:-1, j]})
              for j, name in enumerate(("paper's configuration", "preset fast_estimator"))]
    ctx.save_figure(result, figures.plot_fig5(t[:-1], d["r"], d["theta"][:, 0], traces, "Fig. 5 — Example 2: "
                    "setpoint, output and estimates under controller (18), as printed (a = 5) and preset a = "
                    f"{lin['a_new']:g}"), f"fig5_tracking_a5_and_a{lin['a_new']:g}.png",
                    caption="Redraws the paper's Fig. 5 (Example 2): setpoint, output x1 and Σ's estimates x̂ against "
                            f"the true states under controller (18), in the paper's configuration (a = {p.a:g}) and "
                            f"with the study's preset a = {lin['a_new']:g} beside it (one run each). In the paper's "
                            "configuration x1 oscillates about v (the linearised loop is unstable, finding "
                            "ex2-literal-unstable); only the preset tracks v.")
    n = len(t) - 1
    zoom = slice(n - int(round(2.0 / p.h)), n)
    b = pick[0]
    pair = lin["pair"]
    ctx.save_figure(result, figures.plot_literal(
        t[:-1], d["theta"][:, 0], tr["x[0]"][:-1, 0], tr["u"][:-1, 0], zoom,  # the traces' column 0 is run pick[0]
        f"Example 2 as printed (Σ a = {p.a:g}, K = [2184, 506, 39]): output and control (seed {d['seeds'][b]})",
        f"last 2 s: amplitude {q['amp'][b]:.3g}, {q['freq'][b]:.2f} Hz (linearised pair {pair.real:+.1f} ± "
        f"{abs(pair.imag):.1f}j rad/s)"), "fig_ex2_literal.png",
        caption="Beyond the paper: Example 2 in the printed configuration (Σ a = 5, K read as [2184, 506, 39]; "
                "b1..b3 and the setpoint softener reconstructed): output and control over the whole run and the "
                "last 2 s, where a sustained oscillation appears; its amplitude and frequency are compared with the "
                "linearised closed loop's complex pole pair.")
    maps = [(f"{'as printed' if name == 'literal' else 'stable preset fast_estimator'} (Σ a = {d['a'][j]:g})",
             q["maps"][name]["outcome"], q["maps"][name]["lin"])
            for j, name in enumerate(("literal", "fast_estimator"))]
    ctx.save_figure(result, figures.plot_stability_map(
        np.asarray(p.sweep_b1), np.asarray(p.sweep_b2), p.sweep_b3, maps,
        f"Beyond the paper, Example 2 over (b1, b2, b3): linearised max Re λ (colour), simulated outcome "
        f"(markers, {p.T:g} s)"), "fig_ex2_stability_map.png",
        caption="Beyond the paper: robustness of Example 2 over the plant parameters (b1, b2, b3): colour is the "
                "largest real part of the linearised closed loop's eigenvalues, markers the simulated outcome of each "
                "grid point (settles / oscillates / diverges, one marker per b3, left to right), for the printed a "
                "and the stable preset (claim ex2-robust).")
    return lin["a_new"]
