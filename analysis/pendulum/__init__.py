"""Study `pendulum`: Li, Ji & Feng 2008, sub-optimal filter in the fuzzy control of an inverted pendulum.

Model (§3.1): ``ẋ = A x + B u + Γ w``, ``y = C x + v``, ``x = [φ, φ']`` (rad, rad/s),
``A = [[0, 1], [a21, 0]]``, ``B = [0, 2.6683]ᵀ``, ``Γ = [0, 1]ᵀ``, ``C = [1, 0]``, ``Q = 100``, ``R = 50``.

* :mod:`.paper` — the printed values and every reconstruction (frozen objects);
* :mod:`.verify` — §2/§4: the steady-state gain, the Riccati ODE, the printed P and K under every
  interpretation, the stability of the printed filter;
* :mod:`.loops` — §3.2/§5: the fuzzy closed loop (with and without the filter, and beyond the paper);
* :mod:`.quantities` — quantities and findings; :mod:`.figures` — the figures.
"""

from __future__ import annotations

from ctrl_analysis.report import StudyContext, StudyInfo, StudyResult
from ctrl_analysis.study import record_parameters

from . import figures, loops, paper, quantities, verify

__all__ = ["INFO", "MISSING", "run"]

INFO = StudyInfo(
    name='pendulum',
    seed_file='004_5e64e0f766ab04b2.txt',
    paper='Li, Ji & Feng 2008, sub-optimal filter in the fuzzy control of an inverted pendulum',
    reproduces='steady-state Kalman / alpha-beta gain verification, Riccati convergence, fuzzy closed loop (Fig. 3-4)',
)

#: What is still not reproduced.
MISSING = [
    "Fig. 3-4 as printed: the paper's axes, time scale and noise realisation are not legible in the extracted text, "
    "so the figures are redrawn from the reconstructed loop, not compared point by point",
    "the paper's membership functions, rule table and sampling period are not printed (reconstructed)",
    "the 'physical experiment' of §5 (real rig) cannot be reproduced",
    "Fig. 1 (Kalman–Bucy filter structure) and Fig. 2 (fuzzy controller structure) are block diagrams without "
    "data; not redrawn (their content is §1's equations and the §3.2 controller)",
]


def run(ctx: StudyContext, settings=None) -> StudyResult:
    """Reproduce the study: the verify part (§2, §4), then the fuzzy closed loop (§3.2, §5).

    ``settings`` = ``(Verify, ClosedLoop)`` overrides the defaults (``--quick``: :func:`paper.quick`).
    """
    result = StudyResult(INFO)
    result.missing = list(MISSING)
    P, L = settings or (paper.quick() if ctx.quick else (paper.VERIFY, paper.LOOP))
    L = _with_runs(L, ctx)
    record_parameters(result, P, prefix="verify")
    record_parameters(result, L, prefix="loop")
    result.settings.update({"verify.a21": P.a21, "verify.l_from_B2": P.length, "loop.sigma_w": L.sigma_w,
                            "runs": L.runs, "quick": ctx.quick, "noise_models": verify.NOISE_DESCRIPTION})

    ctx.progress("verify part: ARE, Riccati ODE, printed P and K")
    v = verify.compute_verify(P)
    quantities.record_verify(result, v)
    _verify_figures(ctx, result, v)

    seeds = loops.seeds_for(ctx.seed, L.runs)
    result.seeds = {"closed_loop": seeds}
    d = loops.compute_loops(L, P.a21, seeds, progress=ctx.progress)
    quantities.record_loop(result, d, v)
    _loop_figures(ctx, result, d)
    return result


def _with_runs(L, ctx: StudyContext):
    """``--runs`` overrides the default number of Monte Carlo runs."""
    import dataclasses

    return dataclasses.replace(L, runs=ctx.runs) if ctx.runs is not None else L


def _verify_figures(ctx, result, v) -> None:
    ctx.save_figure(result, figures.plot_riccati_convergence(v.t, v.traj, v.cont.P, v.a21, v.P.Q, v.P.R),
                    "sec4_riccati_convergence.png",
                    caption="Beyond the paper (§2/§4 check): the Riccati differential equation integrated from four "
                            "initial covariances converges to the algebraic solution P̄, so the steady-state gain "
                            "K = P̄CᵀR⁻¹ the paper uses is well defined.")
    ctx.save_figure(result, figures.plot_gain_interpretations(v.rows, v.P.K_printed, v.rows[0], v.P.a21_printed),
                    "sec4_gain_interpretations.png",
                    caption="Checks §4's printed gain K = [0.950, 0.863]ᵀ (red star) against the steady-state gains of "
                            "every interpretation tried (continuous, discrete α-β over sampling periods, Q/R swapped); "
                            "dimensionless gains and gains in 1/s in separate panels (finding gain-not-reproducible).")
    ctx.save_figure(result, figures.plot_filter_bode(v.bode_filters, v.omega,
                                                     plant_poles=(v.a21 ** 0.5, v.P.a21_printed ** 0.5)),
                    "sec4_filter_bode.png",
                    caption="Beyond the paper (§4 gives no frequency response): Bode plots of what the correct "
                            "steady-state filter passes from the measured angle to the estimated angle and rate "
                            "(u held at 0), with the pendulum's unstable pole √a21 dotted, to show the filter's "
                            "bandwidth against it. The low-frequency gain of φ̂/y is k2/(k2 − a21) (2.0 and 1.9 here, about 6 dB), not 1, "
                            "because a constant angle with u = 0 is not a motion of the pendulum; in the loop the "
                            "filter also takes u.")


def _loop_figures(ctx, result, d) -> None:
    p, r = d.p, d.runs
    table = loops.fuzzy_controller(p, lookup=True)
    ctx.save_figure(result, figures.plot_control_surface(table.E, table.EC, table.U, p.Ku, p.Ke, p.Kec),
                    "sec3_fuzzy_control_surface.png",
                    caption="The §3.2 fuzzy controller as built: control surface u(e, ec) on the quantised universes "
                            "and slices at fixed ec, with the paper's scaling gains Ke, Kec, Ku; the membership functions "
                            "and the rule table are not printed and are reconstructed (seven triangular terms, "
                            "U = sat(E + EC, ±3)).")
    ctx.save_figure(result, figures.plot_fig3_states({"paper's K = [0.950, 0.863] as a discrete α-β filter": r["filter"],
                                                      "correct steady-state gain (beyond the paper)": r["kf_ss"]}, p.T),
                    "fig3_states_filtering.png",
                    caption="Redraws the paper's Fig. 3: pendulum angle and rate, measured and filtered, in the closed "
                            "loop after a 0.1 rad step, with the paper's K used as a discrete α-β filter and with the "
                            "correct steady-state gain (one run). With the paper's K (α = 0.950) the estimate nearly "
                            "coincides with the measurement, so the grey 'before' trace lies on the blue one.")
    ctx.save_figure(result, figures.plot_fig4_output({"no filter": r["nofilter"],
                                                      "paper's K as a discrete α-β filter": r["filter"],
                                                      "correct steady-state gain (beyond)": r["kf_ss"]}, p.step),
                    "fig4_output_filtering.png",
                    caption="Redraws the paper's Fig. 4: the pendulum angle φ(t) after a 0.1 rad step without a filter "
                            "and with the two filters: run 0, and the mean ± 1 std band over all Monte Carlo runs; "
                            "overshoot, settling time and RMS per case are quantities cl.* and beyond.kf_ss.*.")
    est = {"paper's K, discrete α-β": r["filter"], "time-varying KF": r["kf"], "correct steady-state gain": r["kf_ss"],
           "paper's continuous filter as printed": r["paper_continuous"]}
    ctx.save_figure(result, figures.plot_beyond(est, d.angles, {"linear model": d.recovered[False],
                                                                "sin φ model": d.recovered[True]}, p.T),
                    "beyond_filters_and_recovery.png",
                    caption="Beyond the paper: the angle estimation error of each filter in the loop (paper's K as α-β, "
                            "time-varying KF, correct steady-state gain, the paper's continuous filter as printed), and "
                            "the largest initial angle the loop recovers from with the linear and the sin φ model.")
