"""The paper's claims judged on computed quantities, and the sensitivity sweep over every reconstruction.

:func:`record` records the primary cells (Tables 2-3), the quantities the claims rest on and the claim
verdicts; the main run (:func:`analysis.meso.run`) and :func:`evaluate` (one evaluation of the
sensitivity sweep) both call it, so the judging logic exists once. The sweep's runs are rows of the
main run's batch (:func:`sweep_rows`, common random numbers: the first ``SweepSettings.runs`` noise
seeds); :func:`evaluate` reads them from the main run's simulations when they are there and simulates
them otherwise (the Euler integrator, a standalone call).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ctrl_analysis.reporting.report import StudyInfo, StudyResult
from ctrl_analysis.reporting.study import reconstructions_of

from . import linear, quantities
from .loops import Row, SituationRun, simulate_situation
from .paper import (
    CLAIMS,
    METRICS,
    PAPER,
    READINGS,
    SITUATIONS,
    Analysis,
    Paper,
    Readings,
)

__all__ = ["SweepSettings", "base_rows", "evaluate", "judge", "record", "sweep_rows", "view"]

_CLAIM = {c.id: c for c in CLAIMS}


@dataclass(frozen=True)
class SweepSettings:
    """What every sweep evaluation shares (not a reconstruction: never varied)."""

    seeds: tuple = ()
    horizons: tuple = (("s1", 60.0), ("s2", 210.0))
    analysis: Analysis = Analysis()


def plant_b(key: str, paper: Paper) -> float:
    """Input gain of the simulated plant: situation 2 read with 0.95 u as an extra term has b = 3.95 + 0.95."""
    return paper.b + 0.95 if key == "s2" and paper.situation2_plant == "extra term" else paper.b


def base_rows(key: str, seeds, paper: Paper = PAPER, readings: Readings = READINGS, eps_grid=()) -> list:
    """The runs :func:`record` needs for situation ``key`` under the reconstructions ``paper`` and ``readings``.

    ESO and MESO (the chosen identification variant) with each seed and noise off; situation 1 also the
    ESO at the other ε of ``eps_grid`` (the ε-law), the MESO at ``readings.larger_eps`` (§5) and the MESO
    without θ4 (conclusion 3), all noise off.
    """
    common = dict(b_plant=plant_b(key, paper), x0=tuple(paper.x0), xhat0=tuple(paper.x_hat0))
    # the identifiability gate acts only on situation 2's full regression, i.e. on its MESO runs
    gate = paper.cond_threshold if SITUATIONS[key].regression == "full" else PAPER.cond_threshold
    rows = [Row(o, v, s, threshold=gate if o == "meso" else PAPER.cond_threshold, **common)
            for o, v in (("eso", "none"), ("meso", paper.table_identification_variant)) for s in list(seeds) + [None]]
    if key == "s1":
        rows += [Row("eso", "none", None, epsilon=e, **common) for e in eps_grid if e != PAPER.epsilon]
        rows += [Row("meso", "wellposed", None, epsilon=readings.larger_eps, **common),
                 Row("meso", "no_const", None, **common)]
    return rows


def _variants(params: dict):
    """Every parameter set the sweep evaluates: the chosen one and each plausible value, one at a time."""
    out = [params]
    for prefix, obj in params.items():
        if prefix == "sweep":
            continue
        for rec in reconstructions_of(obj):
            plaus = rec.get("plausible")
            if plaus is not None and plaus.varied:
                for v in plaus.values():
                    out.append({**params, prefix: dataclasses.replace(obj, **{rec["name"]: v})})
    return out


def sweep_rows(key: str, seeds, eps_grid, integrator: str = PAPER.integrator) -> list:
    """Rows of every sweep evaluation with this integrator (added to the main run's batch; duplicates once)."""
    rows = []
    for p in _variants({"": PAPER, "claims": READINGS}):
        if p[""].integrator == integrator:
            rows += base_rows(key, seeds, p[""], p["claims"], eps_grid)
    return list(dict.fromkeys(rows))


def view(sim: SituationRun, rows) -> SituationRun:
    """The runs ``rows`` of ``sim``, relabelled with the paper's defaults so the recording code picks them.

    A row simulated with a reconstruction's alternative (another x0, plant gain, gate, identification
    variant) is relabelled as the default row: :func:`record` then reads it exactly as it reads the
    baseline's.
    """
    where = {r: i for i, r in enumerate(sim.rows)}
    idx = np.array([where[r] for r in rows])
    norm = [dataclasses.replace(r, b_plant=PAPER.b, threshold=PAPER.cond_threshold, x0=PAPER.x0, xhat0=PAPER.x_hat0,
                                variant="wellposed" if r.variant == "literal" else r.variant) for r in rows]
    return SituationRun(
        rows=norm, t=sim.t, sums={m: v[idx] for m, v in sim.sums.items()},
        window_sums={m: v[idx] for m, v in sim.window_sums.items()}, n_window=sim.n_window,
        sup_dx3=sim.sup_dx3[idx], t_batch=sim.t_batch, theta_batch=sim.theta_batch[:, idx],
        log10_cond=sim.log10_cond[:, idx], rank=sim.rank[:, idx], diverged=sim.diverged[idx],
        diverged_step=sim.diverged_step[idx], b0=sim.b0)


#: simulations the sweep may read instead of simulating: (integrator, situation) -> SituationRun
_SIMULATED: dict = {}


def remember(sims: dict, integrator: str = PAPER.integrator) -> None:
    """Let :func:`evaluate` read its rows from these simulations (the main run's, keyed by situation)."""
    for key, sim in sims.items():
        _SIMULATED[(integrator, key)] = sim


def _simulated(key, rows, paper, horizon) -> SituationRun:
    sim = _SIMULATED.get((paper.integrator, key))
    if sim is None or not set(rows) <= set(sim.rows) or len(sim.t) != round(horizon / paper.h):
        sim = simulate_situation(SITUATIONS[key], rows, horizon, paper)
        _SIMULATED[(paper.integrator, key)] = sim
    return sim


_LIN: dict = {}


def _linear(eps_grid):
    if eps_grid not in _LIN:
        _LIN[eps_grid] = linear.analyse(PAPER, eps_grid)
    return _LIN[eps_grid]


def evaluate(params: dict) -> StudyResult:
    """One sensitivity evaluation: the primary cells and the claims under ``params``.

    Parameters
    ----------
    params : dict
        ``{"": Paper, "claims": Readings, "sweep": SweepSettings}``.

    Returns
    -------
    StudyResult
    """
    paper, readings, st = params[""], params["claims"], params["sweep"]
    an, horizons = st.analysis, dict(st.horizons)
    sims = {}
    for key in SITUATIONS:
        rows = base_rows(key, st.seeds, paper, readings, an.eps_grid)
        sims[key] = view(_simulated(key, rows, paper, horizons[key]), rows)
    result = StudyResult(StudyInfo("meso", "", "", ""))
    lin = _linear(tuple(an.eps_grid))
    record(result, sims, lin, quantities.eps_scaling(sims["s1"], an), horizons, an, paper, readings, extras=False)
    return result


def record(result: StudyResult, sims: dict, lin, sc: dict, horizons: dict, an: Analysis, paper: Paper = PAPER,
           readings: Readings = READINGS, extras: bool = True) -> dict:
    """Tables 2-3, Θ, the claims' quantities and the claim verdicts (the main run and every sweep evaluation).

    Returns
    -------
    dict
        :func:`.quantities.claim_quantities`'s run indices (for the findings).
    """
    quantities.linear_quantities(result, lin, sc)
    for key, sim in sims.items():
        quantities.table_quantities(result, key, sim, an, paper, literal=extras)
        quantities.theta_final(result, key, sim, horizons[key])
        quantities.theta_errors(result, key, sim)
    out = quantities.claim_quantities(result, sims, lin, horizons, readings, extras=extras)
    judge(result, readings)
    return out


def _v(result, qid):
    return result.get(qid).value


def _better(result, key):
    pairs = [(m, _v(result, f"{key}.meso.{m}"), _v(result, f"{key}.eso.{m}")) for m in METRICS]
    return [m for m, a, b in pairs if a is not None and b is not None and a < b], pairs


def judge(result: StudyResult, readings: Readings = READINGS) -> None:
    """Judge every claim of :data:`.paper.CLAIMS` from the recorded quantities."""
    for key in ("s1", "s2"):
        better, pairs = _better(result, key)
        n_runs = result.get(f"{key}.meso.est_x1").runs
        result.claim(_CLAIM[f"{key}-meso-better"], len(better) == 5,
                     evidence=[f"{key}.{o}.{m}" for o in ("meso", "eso") for m in METRICS],
                     note=f"{SITUATIONS[key].table}, noise on, mean over {n_runs} runs: the MESO is below the ESO in "
                          f"{len(better)}/5 columns (" + "; ".join(f"{m} {a:.3g} vs {b:.3g}" if a is not None and
                                                                  b is not None else f"{m} —" for m, a, b in pairs)
                          + ")")
    acc = readings.theta_accuracy
    e1b, e1e = _v(result, "s1.theta_rel_error.before_step"), _v(result, "s1.theta_rel_error.end")
    result.claim(_CLAIM["s1-theta-identified"], None if e1b is None or e1e is None else max(e1b, e1e) <= acc,
                 evidence=["s1.theta_rel_error.before_step", "s1.theta_rel_error.end", "s1.theta_final"],
                 note=f"relative error of the identified Θ (situation 1, noise on) {_f(e1b)} before the θ4 step and "
                      f"{_f(e1e)} at the end, against 'accurate' read as <= {acc:.0%}")
    e2 = _v(result, "s2.theta_rel_error.end")
    result.claim(_CLAIM["s2-theta-converges"], None if e2 is None else e2 <= acc,
                 evidence=["s2.theta_rel_error.end", "s2.theta_final"],
                 note=f"relative error of the identified Θ at the end of situation 2 {_f(e2)} (read: converged when "
                      f"<= {acc:.0%}); the closed loop's regressors x1, x2, u are collinear once it tracks, so the "
                      "LSM finds the trajectory-equivalent Θ_eq (see situation2-not-identifiable)")
    nc, wp = _v(result, "s1.no_const.theta_rel_error"), _v(result, "s1.nonoise.theta_rel_error")
    worse = [m for m in ("track_x1", "track_x2") if _v(result, f"s1.no_const.{m}") > _v(result, f"s1.nonoise.meso.{m}")]
    result.claim(_CLAIM["theta4-needed"], nc > acc and wp <= acc and len(worse) == 2,
                 evidence=["s1.no_const.theta_rel_error", "s1.nonoise.theta_rel_error", "s1.no_const.track_x1",
                           "s1.no_const.track_x2", "s1.nonoise.meso.track_x1", "s1.nonoise.meso.track_x2"],
                 note=f"situation 1, noise off: relative error of θ1, θ2 without θ4 {nc:.3g}, with θ4 {wp:.3g} "
                      f"(converged read as <= {acc:.0%}); tracking worse without θ4 in {len(worse)}/2 columns")
    e = readings.larger_eps
    ok = [m for m in METRICS if _v(result, f"s1.nonoise.meso_eps_larger.{m}") <= _v(result, f"s1.nonoise.eso.{m}")]
    ratio = np.asarray(_v(result, "s1.meso_eps_larger.noise_std_ratio"))
    result.claim(_CLAIM["larger-eps"], len(ok) == 5 and bool(np.all(ratio < 1)),
                 evidence=[f"s1.nonoise.meso_eps_larger.{m}" for m in METRICS] + [f"s1.nonoise.eso.{m}" for m in METRICS]
                 + ["s1.meso_eps_larger.noise_std_ratio"],
                 note=f"situation 1, noise off: the MESO at ε = {e:g} is at least as accurate as the ESO at "
                      f"ε = {PAPER.epsilon:g} in {len(ok)}/5 columns ({', '.join(ok) or 'none'}); its noise std is "
                      f"×{_vec(ratio)} (e1, e2, e3). The whole-run mean includes the first batch, where the MESO is "
                      "still the ESO at the larger ε")
    mn = [(k, _v(result, f"{k}.M_sup"), _v(result, f"{k}.N_sup")) for k in ("s1", "s2")]
    result.claim(_CLAIM["m-le-n"], all(m <= n for _, m, n in mn),
                 evidence=[f"{k}.{x}_sup" for k in ("s1", "s2") for x in ("M", "N")],
                 note="sup |dx3/dt| of each observer's true extended state, noise off: "
                      + "; ".join(f"situation {k[1]} M = {m:.3g}, N = {n:.3g}" for k, m, n in mn))
    law = (3, 2, 1)
    slopes = [_v(result, f"leso.eps_slope.x{i}") for i in (1, 2, 3)]
    tol = readings.exponent_tolerance
    result.claim(_CLAIM["eps-law"], all(abs(s / k - 1) <= tol for s, k in zip(slopes, law)),
                 evidence=[f"leso.eps_slope.x{i}" for i in (1, 2, 3)],
                 note=f"fitted log-log slopes of the ESO's mean |e_i| against ε: {_vec(slopes)} against the law "
                      f"{list(law)} (read as confirmed within {tol:.0%} of the exponent)")


def _f(v):
    return "—" if v is None else f"{v:.3g}"


def _vec(v):
    return "[" + ", ".join(f"{x:.3g}" for x in np.ravel(v)) + "]"
