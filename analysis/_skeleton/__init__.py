"""Study skeleton (not registered in the CLI): copy this package to start a new study.

A first-order lag driven by a unit step, measured in white noise and smoothed by a digital
low-pass: one printed value per quantity (textbook closed forms), three reconstructions with their
plausible ranges, two claims judged on the quantities and re-judged jointly over the
plausible box those ranges span, two figures. See CONTRIBUTING.md, "Add a study".
"""

from __future__ import annotations

from ctrl_analysis.noise import run_seeds
from ctrl_analysis.reporting import sensitivity
from ctrl_analysis.reporting.report import StudyContext, StudyInfo, StudyResult
from ctrl_analysis.reporting.study import record_parameters, study_params

from . import figures, loops, quantities
from .paper import EXAMPLE, QUICK

__all__ = ["INFO", "evaluate", "run"]

INFO = StudyInfo(
    name="skeleton",
    seed_file="(none: textbook closed forms)",
    paper="Skeleton study: first-order lag, white measurement noise, first-order digital low-pass",
    reproduces="y(τ) of the step response, the filter's noise-reduction ratio, Fig. 1",
)


def run(ctx: StudyContext, params=None) -> StudyResult:
    """Simulate the loop over the runs, record the quantities and the finding, draw Fig. 1.

    Parameters
    ----------
    ctx : StudyContext
        Output folder, runs, seed and ``quick`` from the CLI (or a test).
    params : dict, optional
        Overrides of the study's settings (:func:`ctrl_analysis.reporting.study.study_params`): ``{"ex": Example}``
        or ``{"ex": {field: value}}``; default :data:`~.paper.EXAMPLE`, or :data:`~.paper.QUICK`
        with ``ctx.quick``.

    Returns
    -------
    StudyResult
    """
    result = StudyResult(INFO)
    p = study_params({"ex": QUICK if ctx.quick else EXAMPLE}, params, result)["ex"]
    record_parameters(result, p, prefix="ex")
    seeds = run_seeds(ctx.seed, ctx.runs_or(100, quick_default=10))
    result.seeds["noise"] = seeds
    ctx.progress(f"simulating {len(seeds)} runs of {p.t_end:g} s")
    res = loops.simulate(p, seeds)
    for record in res.divergences():
        result.finding(f"diverged-run-{record['run']}", f"run diverged: {record}")
    _record(result, p, res)
    fig = figures.plot_step(res.t, res["y"][:, 0], res["y_meas"][:, 0], res["y_hat"][:, 0], tau=p.tau)
    ctx.save_figure(result, fig, "fig1_step_response.png")
    ctx.progress("sensitivity: each reconstruction across its plausible range")
    sens = sensitivity.explore(evaluate, {"ex": p}, jobs=ctx.jobs, **(sensitivity.QUICK if ctx.quick else {}),
                               note="20 runs per evaluation, same seeds")
    sensitivity.apply(result, sens)
    ctx.save_figure(result, sensitivity.plot_sensitivity(result), "sensitivity.png",
                    caption=sensitivity.caption(result, "20 runs per evaluation, same seeds"))
    return result


def _record(result: StudyResult, p, res) -> None:
    """The quantities and the claims: one code path for the main run and for every sensitivity evaluation."""
    quantities.record_step(result, p, res)
    quantities.record_noise(result, p, res)
    quantities.judge_claims(result, p)


def evaluate(params: dict) -> StudyResult:
    """The quantities and claims at ``params["ex"]`` on 20 runs (the sensitivity sweep's evaluation).

    Parameters
    ----------
    params : dict
        ``{"ex": Example}``.

    Returns
    -------
    StudyResult
    """
    p = params["ex"]
    result = StudyResult(INFO)
    _record(result, p, loops.simulate(p, run_seeds(0, 20)))
    return result


