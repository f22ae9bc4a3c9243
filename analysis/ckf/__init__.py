"""Study `ckf`: Gong & Wu 2010, characteristic-model-based Kalman filter with golden-section adaptive control.

Three closed loops (no filter, digital LPF, CKF) on a reconstructed high-order plant, run as one
batch through :class:`ctrl_analysis.engine.loop.Loop` (:mod:`.loops`), with the characteristic model's RLS
running online; Table 1 and the paper's claims checked per run (the paper reads them off one run) over Monte
Carlo runs, beside the frozen-Φ ablation (the identification held at θ0), the identification signal, the
projection, the full-order Kalman filter and a second plant (:mod:`.quantities`, :mod:`.beyond`); every claim and
the printed cell judged over the plausible box, many points per simulation (:func:`evaluate_many`), under the
printed and the corrected reading of the no-filter loop's identification; Fig. 2-12 (:mod:`.figures`). Every value
the extracted text lost is a reconstruction in :mod:`.paper`.
"""

from __future__ import annotations

import collections
import dataclasses
import functools

import numpy as np

from ctrl_analysis.noise import run_seeds
from ctrl_analysis.reporting import sensitivity
from ctrl_analysis.reporting.report import StudyContext, StudyInfo, StudyResult
from ctrl_analysis.reporting.study import record_parameters, study_params

from . import beyond, figures
from . import quantities as qty
from .loops import BOX_SIGNALS, CASES, case_id, simulate_cases, simulate_specs
from .paper import PAPER, READINGS, frozen

__all__ = ["INFO", "RUNS_PER_PART", "SweepRun", "evaluate", "evaluate_many", "run", "simulate_main", "simulate_study"]

INFO = StudyInfo(
    name='ckf',
    seed_file='001_98762e3e5a8851d8.txt',
    paper='Gong & Wu 2010, characteristic-model-based Kalman filter with golden-section adaptive control',
    reproduces='Fig. 2-9 and Table 1: no filter vs LPF vs CKF under golden-section control with the characteristic '
               "model's RLS running online; the frozen-Φ ablation, identified parameters against the projection box, "
               'Q sweep, full-order KF and a second plant beyond the paper',
)

#: Reconstructions the quick box varies (the full run varies every one with a plausible range); a reading of the
#: claims re-judges the cached runs, so it costs no simulation.
QUICK_SWEEP = ("P0_rls", "lpf_omega", "claims.z_significant")


#: Above this many Monte Carlo runs a loop's runs are simulated in parts of at most this many (:func:`simulate_main`):
#: the per-run numbers of Table 1 and the claims cover every run, the traces are kept for the first part only.
#: A run's traces take about 9.6 MB (ten signals, three loops, 40 001 samples), so memory is bounded by the part,
#: not the run count. At the default 100 runs nothing changes.
RUNS_PER_PART = 128


def simulate_study(p, runs, seed, options=None, *, keep=None, seeds=None):
    """Run the three cases (per identification option) and return ``{option: {case: signals}}``.

    Without ``options`` the study's own identification (``p.id_signal``, the no-filter loop ``p.nofilter_id``),
    under the key ``p.id_signal``. ``keep`` (default :data:`.loops.SIGNALS`) and ``seeds`` (default
    ``run_seeds(seed, runs)``) pass to :func:`.loops.simulate_specs`."""
    data = {}
    extra = {} if keep is None else {"keep": keep}
    for (opt, case), d in simulate_cases(p, runs, seed, options=options, seeds=seeds, **extra).items():
        data.setdefault(opt, {})[case] = d
    return data


def simulate_main(p, runs, seed, part=None):
    """The three loops of ``p`` (its own identification) over ``runs`` runs: their traces and per-run numbers.

    Up to ``part`` runs (default :data:`RUNS_PER_PART`) one simulation keeps every run's traces. Above, the runs are
    simulated ``part`` at a time: the first part keeps its traces, the others only the loops' window sums, from which
    :func:`.quantities.metrics` computes each run's numbers (bit for bit those of one simulation: a run does not
    depend on the others in its batch). Memory is then bounded by the part.

    Parameters
    ----------
    p : CKFStudy
    runs : int
    seed : int
        Base seed (:func:`ctrl_analysis.noise.run_seeds`).
    part : int, optional
        Runs per simulation, at least 1.

    Returns
    -------
    data : dict
        ``{case: signals}`` of the first ``min(runs, part)`` runs (:func:`simulate_study`).
    m : dict
        ``{case: per-run numbers}`` of every run (:func:`.quantities.metrics`).
    """
    part = RUNS_PER_PART if part is None else int(part)
    if part < 1:
        raise ValueError(f"part must be at least 1, got {part}")
    if runs <= part:
        data = simulate_study(p, runs, seed)[p.id_signal]
        return data, qty.metrics(data, p)
    seeds = run_seeds(seed, runs)
    data = simulate_study(p, part, seed, seeds=seeds[:part])[p.id_signal]
    parts = [qty.metrics(data, p)]
    for a in range(part, runs, part):
        s = seeds[a:a + part]
        parts.append(qty.metrics(simulate_study(p, len(s), seed, keep=(), seeds=s)[p.id_signal], p))
    m = {case: {k: np.concatenate([pm[case][k] for pm in parts]) for k in parts[0][case]} for case in parts[0]}
    return data, m


def record_main(result, m, p, plant_order, r=READINGS):
    """Table 1, the filter errors, the operation counts and the judged claims from the per-run numbers ``m``
    (:func:`.quantities.metrics`): shared by :func:`run` and :func:`evaluate`, so the box judges with the main
    run's code."""
    qty.record_metrics(result, m, p, r=r)
    qty.cost(result, p, plant_order)
    qty.record_claims(result, p, m, r)


def evaluate(params) -> StudyResult:
    """One evaluation of the plausible box: :func:`evaluate_many` of one point."""
    return evaluate_many([params])[0]


def evaluate_many(points) -> list:
    """Evaluate many points of the plausible box at once, on the batch axis of one simulation.

    Each point ``params[""]`` is simulated over ``sweep_runs`` runs (the main run's first seeds, the same noise at
    every point: common random numbers) and its claims and cell recorded by :func:`record_main` with the readings
    ``params["claims"]``. Only the signals the claims read are kept, and each loop's per-run numbers are cached by
    what it simulates (a loop whose settings a point does not change, e.g. the filtered loops under the other
    algorithm or a point that moves only a reading, is not simulated again).
    """
    need, keys = [], []
    for params in points:
        p, seed = params[""], params["run"].seed
        ks = {case: (_sim_key(p, case), case, case_id(p, case), p.sweep_runs, seed) for case in CASES}
        keys.append(ks)
        need += [k for k in ks.values() if k not in _CACHE and k not in need]
    by_run: dict = {}
    for k in need:
        by_run.setdefault((k[3], k[4]), []).append(k)
    for (runs, seed), ks in by_run.items():
        data = simulate_specs([(k[0], k[1], k[2]) for k in ks], runs, seed, keep=BOX_SIGNALS)
        for k, d in zip(ks, data, strict=True):
            _remember(k, qty.case_metrics(d, k[0], k[1]))
    out = []
    for params, ks in zip(points, keys, strict=True):
        p = params[""]
        result = StudyResult(INFO)
        record_main(result, {case: _CACHE[k] for case, k in ks.items()}, p, _order(p.plant), params["claims"])
        out.append(result)
    return out


#: Per-run numbers of the loops simulated for the box, by what they simulate (bounded).
_CACHE: collections.OrderedDict = collections.OrderedDict()
_CACHE_SIZE = 4096


def _remember(key, value):
    _CACHE[key] = value
    while len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)


def _sim_key(p, case):
    """What a loop of case ``case`` simulates: ``p`` with the no-filter loop's identification (an algorithm axis that
    only that loop reads) normalised away in the filtered loops."""
    return p if case == "nofilter" else dataclasses.replace(p, nofilter_id="same")


@dataclasses.dataclass(frozen=True)
class SweepRun:
    """What an evaluation of the box takes from the CLI, not from the paper (nothing here is varied)."""

    seed: int


@functools.lru_cache(maxsize=8)
def _order(plant):
    from .loops import plant_tf

    return len(plant_tf(plant).poles())


def run(ctx: StudyContext, params=None) -> StudyResult:
    """Reproduce Table 1 and Fig. 2-9 with the live identification, then the ablation and the studies beyond
    the paper (Fig. 10-12), then every claim and the printed cell over the plausible box.

    ``params`` overrides the settings (:func:`ctrl_analysis.reporting.study.study_params`): ``{"": Paper}`` (the paper's
    values and reconstructions, :data:`.paper.PAPER`) and ``{"claims": Readings}`` (:data:`.paper.READINGS`),
    each an object or a dict of its fields; ``--quick`` then shortens the horizon and the option and box runs.
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
    data, m = simulate_main(p, runs, ctx.seed)
    record_main(result, m, p, _order(p.plant), r)
    if runs > RUNS_PER_PART:
        result.finding("traced-runs", f"{runs} runs, simulated {RUNS_PER_PART} at a time to bound the memory: Table 1, "
                       "the filter errors and every claim and cell cover every run (each run's window sums); the "
                       "numbers read from the traces (identification, noise-free fit, projection box, full-order KF, "
                       f"Q sweep, offset terms) and the figures cover the first {RUNS_PER_PART} runs, whose traces "
                       "alone are kept (each quantity's runs field says how many it covers).",
                       evidence={"runs": runs, "traced_runs": RUNS_PER_PART})
    ctx.progress("ckf: frozen-Φ ablation")
    data_f, m_f = simulate_main(frozen(p), runs, ctx.seed)
    ident = beyond.ablation(result, p, data, data_f, m_f)
    beyond.paper_number(result, p, data)
    extra = beyond.beyond(ctx, result, p, data, m)
    beyond.claims_table(result, p, {"live": m, "frozen": m_f, "plant2": extra["m2"]}, r)
    ctx.progress("ckf: the claims and the printed cell over the plausible box")
    _sensitivity(ctx, result, p, r)
    figures.save_all(ctx, result, p, data, data_f, extra, ident)
    result.missing = qty.missing(result)
    return result


def _sensitivity(ctx, result, p, r):
    """Judge every claim and the printed cell over the plausible box (quick: :data:`QUICK_SWEEP` only), many points
    per simulation (:func:`evaluate_many`), under both readings of the no-filter loop's identification."""
    note = (f"the three loops over {p.sweep_runs} runs of {p.t_end:g} s on the main run's first "
            "seeds (common random numbers; the same noise at every point), many points side by side on one "
            "simulation's batch axis")
    sens = sensitivity.explore(evaluate, {"": p, "claims": r, "run": SweepRun(ctx.seed)}, jobs=ctx.jobs,
                               batch=evaluate_many, names=QUICK_SWEEP if ctx.quick else None,
                               **(sensitivity.QUICK if ctx.quick else {}), note=note)
    sensitivity.apply(result, sens)
    ctx.save_figure(result, sensitivity.plot_sensitivity(result), "sensitivity.png",
                    caption=sensitivity.caption(result, note))
