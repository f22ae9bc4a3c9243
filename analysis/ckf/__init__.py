"""Study `ckf`: Gong & Wu 2010, characteristic-model-based Kalman filter with golden-section adaptive control.

Three closed loops (no filter, digital LPF, CKF) on a reconstructed high-order plant, run as one
batch through :class:`ctrl_analysis.engine.loop.Loop` (:mod:`.loops`), with the characteristic model identified
online; Table 1 and the paper's claims checked with Monte Carlo numbers, beside the frozen-Φ ablation
(the identification held at θ0), the identification signal, the projection, the full-order Kalman filter
and a second plant (:mod:`.quantities`, :mod:`.beyond`); every claim re-judged across the plausible range of
every reconstruction (:func:`evaluate`); Fig. 2-12 (:mod:`.figures`). Every value the extracted text lost is a
reconstruction in :mod:`.paper`.
"""

from __future__ import annotations

import dataclasses
import functools

from ctrl_analysis.reporting import sensitivity
from ctrl_analysis.reporting.report import StudyContext, StudyInfo, StudyResult
from ctrl_analysis.reporting.study import record_parameters, study_params

from . import beyond, figures
from . import quantities as qty
from .loops import simulate_cases, split_cases
from .paper import PAPER, READINGS, frozen

__all__ = ["INFO", "evaluate", "run", "simulate_study"]

INFO = StudyInfo(
    name='ckf',
    seed_file='001_98762e3e5a8851d8.txt',
    paper='Gong & Wu 2010, characteristic-model-based Kalman filter with golden-section adaptive control',
    reproduces='Fig. 2-9 and Table 1: no filter vs LPF vs CKF under golden-section control with the characteristic '
               'model identified online; the frozen-Φ ablation, identified parameters, Q sweep, full-order KF and a '
               'second plant beyond the paper',
)

#: Reconstructions the quick sweep varies (the full run varies every one with a plausible range); a reading of the
#: claims re-judges the baseline's cached runs, so it costs no simulation.
QUICK_SWEEP = ("P0_rls", "lpf_omega", "claims.z_significant")


def simulate_study(p, runs, seed, options=None):
    """Run the three cases (per identification option) and return ``{option: {case: signals}}``."""
    res, index = simulate_cases(p, runs, seed, options=options)
    data = {}
    for (opt, case), d in split_cases(res, index).items():
        data.setdefault(opt, {})[case] = d
    return data


def record_main(result, data, p, plant_order, r=READINGS):
    """Table 1, the filter errors, the operation counts and the judged claims: shared by :func:`run` and
    :func:`evaluate`, so the sensitivity sweep judges with the main run's code."""
    qty.table1(result, data, p)
    errs = qty.filter_errors(result, data, p)
    qty.cost(result, p, plant_order)
    qty.record_claims(result, p, r)
    return errs


def evaluate(params) -> StudyResult:
    """One evaluation of the sensitivity sweep: ``params[""]`` simulated over ``sweep_runs`` runs (same seeds as
    the main run's first runs), its paper cell and claims recorded by :func:`record_main` with the readings
    ``params["claims"]`` (a reading alone re-judges the cached runs of the baseline)."""
    p = params[""]
    result = StudyResult(INFO)
    data = _sweep_runs(p, params["run"].seed)
    record_main(result, data, p, _order(p.plant), params["claims"])
    return result


@functools.lru_cache(maxsize=2)
def _sweep_runs(p, seed):
    return simulate_study(p, p.sweep_runs, seed)[p.id_signal]


@dataclasses.dataclass(frozen=True)
class SweepRun:
    """What an evaluation of the sweep takes from the CLI, not from the paper (nothing here is varied)."""

    seed: int


def _order(plant):
    from .loops import plant_tf

    return len(plant_tf(plant).poles())


def run(ctx: StudyContext, params=None) -> StudyResult:
    """Reproduce Table 1 and Fig. 2-9 with the live identification, then the ablation and the studies beyond
    the paper (Fig. 10-12), then the sensitivity of every claim to every reconstruction.

    ``params`` overrides the settings (:func:`ctrl_analysis.reporting.study.study_params`): ``{"": Paper}`` (the paper's
    values and reconstructions, :data:`.paper.PAPER`) and ``{"claims": Readings}`` (:data:`.paper.READINGS`),
    each an object or a dict of its fields; ``--quick`` then shortens the horizon and the option and sweep runs.
    """
    result = StudyResult(INFO)
    chosen = study_params({"": PAPER, "claims": READINGS}, params, result)
    p, r = chosen[""], chosen["claims"]
    if ctx.quick:
        p = dataclasses.replace(p, t_end=min(p.t_end, 30.0), option_runs=min(p.option_runs, 3),
                                sweep_runs=min(p.sweep_runs, 3))
    record_parameters(result, p)
    record_parameters(result, r, prefix="claims")
    runs = ctx.runs_or(p.runs, 4)
    result.seeds = {"base": ctx.seed, "runs": runs}
    ctx.progress(f"ckf: {runs} runs x 3 cases, {p.t_end:g} s at Ts = {p.Ts:g} s, live identification")
    data = simulate_study(p, runs, ctx.seed)[p.id_signal]
    errs = record_main(result, data, p, _order(p.plant), r)
    ctx.progress("ckf: frozen-Φ ablation")
    data_f = simulate_study(frozen(p), runs, ctx.seed)[p.id_signal]
    beyond.ablation(result, p, data, data_f)
    beyond.paper_number(result, p, data)
    extra = beyond.beyond(ctx, result, p, data, errs)
    beyond.claims_table(result, p, r)
    ctx.progress("ckf: sensitivity of the claims to every reconstruction")
    _sensitivity(ctx, result, p, r)
    figures.save_all(ctx, result, p, data, data_f, extra)
    result.missing = qty.missing(result)
    return result


def _sensitivity(ctx, result, p, r):
    """Sweep every plausible range one at a time (quick: :data:`QUICK_SWEEP` only) and mark the claims."""
    note = (f"each evaluation: the three cases over {p.sweep_runs} runs of {p.t_end:g} s on the main run's first "
            "seeds (common random numbers)")
    sens = sensitivity.explore(evaluate, {"": p, "claims": r, "run": SweepRun(ctx.seed)}, jobs=ctx.jobs,
                               names=QUICK_SWEEP if ctx.quick else None, **(sensitivity.QUICK if ctx.quick else {}), note=note)
    sensitivity.apply(result, sens)
    ctx.save_figure(result, sensitivity.plot_sensitivity(result), "sensitivity.png",
                    caption=sensitivity.caption(result, note))
