"""The paper's claims judged on computed quantities, and the evaluation of the plausible box.

:func:`record` records the primary cells (Tables 2-3), the quantities the claims rest on and the claim
verdicts; the main run (:func:`analysis.meso.run`) and every box evaluation (:func:`evaluate`, :func:`evaluate_many`)
call it, so the judging logic exists once.

A box point needs a few simulated runs per situation (:func:`base_rows`: the ESO and the MESO of the point's
algorithm, noise off, and at a noise-on point also with the box's seeds; situation 1 adds the claims' noise-free
runs). Each run is simulated once and kept (:class:`RunCache`): a run depends only on its own configuration
(observer, identification, seed, initial states, plant gain, ε, gate threshold, integrator), so points that share
it (e.g. every point with the same initial states and integrator shares its ESO runs) read it from the cache. The
gate threshold moves a run only through which batches pass it: a cached run is reused, exactly, for another
threshold that lets the same batches of that run pass. :func:`evaluate_many` evaluates many points at once: the runs
none of them finds in the cache are simulated together, on the batch axis of one loop per situation and integrator.
The noise runs of a box point are the main run's first ``Analysis.box_runs`` seeds (common random numbers).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ctrl_analysis.reporting.report import StudyInfo, StudyResult

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

__all__ = ["BoxSettings", "RunCache", "base_rows", "evaluate", "evaluate_many", "judge", "record", "remember"]

_CLAIM = {c.id: c for c in CLAIMS}
#: the identification without θ4 (Conclusion 3) under each algorithm
NO_CONST = {"wellposed": "no_const", "literal": "literal_no_const"}


@dataclass(frozen=True)
class BoxSettings:
    """What every box evaluation shares (not a reconstruction: never varied)."""

    seeds: tuple = ()
    horizons: tuple = (("s1", 60.0), ("s2", 210.0))
    analysis: Analysis = Analysis()


def base_rows(key: str, paper: Paper = PAPER, readings: Readings = READINGS, seeds=(), eps_grid=()) -> list:
    """The runs :func:`record` needs for situation ``key`` at one point of the box.

    The ESO and the MESO (the identification of the point's algorithm) noise-free, and with each of ``seeds``
    where the tables are read with the noise on; situation 1 also the ESO at the other ε of ``eps_grid`` (the
    ε-law), the MESO at ``readings.larger_eps`` (§5) and the MESO without θ4 (conclusion 3), all noise-free. The
    gate threshold is set only where it acts (situation 2's well-posed full regression), so runs it cannot move
    are shared by every threshold.
    """
    common = dict(b_plant=quantities.plant_b(key, paper), x0=tuple(paper.x0), xhat0=tuple(paper.x_hat0))
    v = paper.table_identification_variant
    gated = SITUATIONS[key].regression == "full" and v == "wellposed"
    gate = paper.cond_threshold if gated else PAPER.cond_threshold
    noise = list(seeds) if quantities.noise_on(paper) else []
    rows = [Row(o, var, s, threshold=gate if o == "meso" else PAPER.cond_threshold, **common)
            for o, var in (("eso", "none"), ("meso", v)) for s in noise + [None]]
    if key == "s1":
        rows += [Row("eso", "none", None, epsilon=e, **common) for e in eps_grid if e != PAPER.epsilon]
        rows += [Row("meso", v, None, epsilon=readings.larger_eps, **common),
                 Row("meso", NO_CONST[v], None, **common)]
    return rows


# ---------------------------------------------------------------------------------------------------------------
# the run cache

_PER_RUN = ("sup_dx3", "diverged", "diverged_step", "full_solved")


@dataclass
class _Situation:
    """The runs of one situation simulated with one integrator and horizon, each stored apart."""

    t: np.ndarray
    t_batch: np.ndarray
    n_window: int
    b0: float
    runs: dict = dataclasses.field(default_factory=dict)      # Row -> dict of its records


def _records(sim: SituationRun, b: int) -> dict:
    rec = {"sums": {m: v[b] for m, v in sim.sums.items()}, "window_sums": {m: v[b] for m, v in sim.window_sums.items()},
           "theta_batch": sim.theta_batch[:, b], "log10_cond": sim.log10_cond[:, b], "rank": sim.rank[:, b]}
    rec.update({f: getattr(sim, f)[b] for f in _PER_RUN})
    return rec


class RunCache:
    """Every simulated run of the box, by configuration; one per process (:data:`CACHE`).

    ``hits`` / ``simulated`` count the runs read and simulated (the box's cost, recorded in its note).
    """

    def __init__(self):
        self.store: dict = {}
        self.hits = 0
        self.simulated = 0

    def clear(self) -> None:
        self.store.clear()
        self.hits = self.simulated = 0

    def add(self, integrator: str, key: str, sim: SituationRun) -> None:
        """Keep every run of ``sim`` (situation ``key`` simulated with ``integrator``)."""
        st = self.store.setdefault((integrator, key, len(sim.t)),
                                   _Situation(sim.t, sim.t_batch, sim.n_window, sim.b0))
        for b, r in enumerate(sim.rows):
            st.runs.setdefault(r, _records(sim, b))

    def find(self, integrator: str, key: str, K: int, row: Row):
        """The records of ``row``: the run itself, or a run that differs only by a gate threshold passing the same
        batches (then bit for bit the same run); None if not simulated yet."""
        st = self.store.get((integrator, key, K))
        if st is None:
            return None
        rec = st.runs.get(row)
        if rec is not None or not (SITUATIONS[key].regression == "full" and row.variant == "wellposed"):
            return rec
        for other, rec in st.runs.items():
            if dataclasses.replace(other, threshold=row.threshold) == row and _same_gate(rec, other.threshold,
                                                                                         row.threshold):
                st.runs[row] = rec
                return rec
        return None

    def situation(self, integrator: str, key: str, K: int) -> _Situation:
        return self.store[(integrator, key, K)]


def _same_gate(rec, a: float, b: float) -> bool:
    """Whether thresholds ``a`` and ``b`` decide every batch of this run alike (it then runs identically with both)."""
    lc = rec["log10_cond"]
    ok = np.isfinite(lc) & (rec["rank"] == 4)
    c = 10.0 ** lc[ok]
    lo, hi = min(a, b), max(a, b)
    # no batch's condition number between the two (with a margin for the log10 round trip)
    return not np.any((c > lo * (1 - 1e-9)) & (c <= hi * (1 + 1e-9)))


#: the runs of this process (the main run's, then the box's)
CACHE = RunCache()


def remember(sims: dict, integrator: str = PAPER.integrator) -> None:
    """Keep the main run's simulations (keyed by situation) for the box evaluations."""
    for key, sim in sims.items():
        CACHE.add(integrator, key, sim)


def _simulate_missing(wanted: dict, horizons: dict) -> None:
    """Simulate the runs no cached run stands for: one batch per situation and integrator, repeated for runs a gate
    threshold may make equal to a run simulated in the same call (each round simulates one threshold per run)."""
    while wanted:
        nxt = {}
        for (integ, key), rows in wanted.items():
            K = round(horizons[key] / PAPER.h)
            missing = [r for r in dict.fromkeys(rows) if CACHE.find(integ, key, K, r) is None]
            if not missing:
                continue
            # of the runs that differ only by their threshold, simulate the lowest now; the others may then be found
            first, later = {}, []
            for r in sorted(missing, key=lambda r: r.threshold):
                k = dataclasses.replace(r, threshold=0.0)
                (later.append(r) if k in first else first.__setitem__(k, r))
            sim = simulate_situation(SITUATIONS[key], list(first.values()), horizons[key],
                                     dataclasses.replace(PAPER, integrator=integ))
            CACHE.simulated += len(first)
            CACHE.add(integ, key, sim)
            if later:
                nxt[(integ, key)] = later
        wanted = nxt


def _view(integ: str, key: str, K: int, rows) -> SituationRun:
    """The runs ``rows`` from the cache as one :class:`SituationRun`, relabelled with the paper's defaults.

    A run simulated with a reconstruction's alternative (another x0, plant gain, gate, the printed algorithm)
    is relabelled as the default row, so :func:`record` reads it exactly as it reads the chosen point's.
    """
    st = CACHE.situation(integ, key, K)
    recs = [CACHE.find(integ, key, K, r) for r in rows]
    CACHE.hits += len(recs)
    norm = [dataclasses.replace(r, b_plant=PAPER.b, threshold=PAPER.cond_threshold, x0=PAPER.x0, xhat0=PAPER.x_hat0,
                                variant={"literal": "wellposed", "literal_no_const": "no_const"}.get(r.variant,
                                                                                                     r.variant))
            for r in rows]
    sums = {m: np.array([rec["sums"][m] for rec in recs]) for m in recs[0]["sums"]}
    wsums = {m: np.array([rec["window_sums"][m] for rec in recs]) for m in recs[0]["window_sums"]}
    per = {f: np.array([rec[f] for rec in recs]) for f in _PER_RUN}
    return SituationRun(
        rows=norm, t=st.t, sums=sums, window_sums=wsums, n_window=st.n_window, t_batch=st.t_batch,
        theta_batch=np.stack([rec["theta_batch"] for rec in recs], axis=1),
        log10_cond=np.stack([rec["log10_cond"] for rec in recs], axis=1),
        rank=np.stack([rec["rank"] for rec in recs], axis=1), b0=st.b0, **per)


_LIN: dict = {}


def _linear(eps_grid):
    if eps_grid not in _LIN:
        _LIN[eps_grid] = linear.analyse(PAPER, eps_grid)
    return _LIN[eps_grid]


def evaluate_many(points: list) -> list:
    """Box evaluations of many points at once: the primary cells and the claims at each.

    The runs the points need and the cache does not hold are simulated together (one loop per situation and
    integrator, the runs on its batch axis); each point is then recorded from its runs.

    Parameters
    ----------
    points : list of dict
        ``{"": Paper, "claims": Readings, "box": BoxSettings}`` each.

    Returns
    -------
    list of StudyResult
    """
    wanted, plan = {}, []
    for params in points:
        paper, readings, st = params[""], params["claims"], params["box"]
        horizons = dict(st.horizons)
        rows = {key: base_rows(key, paper, readings, st.seeds, st.analysis.eps_grid) for key in SITUATIONS}
        for key, rs in rows.items():
            wanted.setdefault((paper.integrator, key), []).extend(rs)
        plan.append((paper, readings, st, horizons, rows))
    if plan:
        _simulate_missing(wanted, plan[0][3])
    out = []
    for paper, readings, st, horizons, rows in plan:
        sims = {key: _view(paper.integrator, key, round(horizons[key] / PAPER.h), rs) for key, rs in rows.items()}
        result = StudyResult(StudyInfo("meso", "", "", ""))
        an = st.analysis
        record(result, sims, _linear(tuple(an.eps_grid)), quantities.eps_scaling(sims["s1"], an), horizons, an,
               paper, readings, extras=False)
        out.append(result)
    return out


def evaluate(params: dict) -> StudyResult:
    """One box evaluation (:func:`evaluate_many` of one point).

    Parameters
    ----------
    params : dict
        ``{"": Paper, "claims": Readings, "box": BoxSettings}``.

    Returns
    -------
    StudyResult
    """
    return evaluate_many([params])[0]


# ---------------------------------------------------------------------------------------------------------------
# recording and judging


def record(result: StudyResult, sims: dict, lin, sc: dict, horizons: dict, an: Analysis, paper: Paper = PAPER,
           readings: Readings = READINGS, extras: bool = True) -> dict:
    """Tables 2-3, Θ, the claims' quantities and the claim verdicts (the main run and every box evaluation).

    Returns
    -------
    dict
        :func:`.quantities.claim_quantities`'s run indices (for the findings).
    """
    quantities.linear_quantities(result, lin, sc)
    per_run = {}
    for key, sim in sims.items():
        quantities.table_quantities(result, key, sim, paper, extras=extras)
        quantities.theta_final(result, key, sim, horizons[key], paper)
        per_run[key] = {"theta": quantities.theta_errors(result, key, sim, paper),
                        "better": quantities.meso_better(result, key, sim, paper),
                        "full": quantities.table_runs(sim, paper)["full"]}
    out = quantities.claim_quantities(result, sims, lin, horizons, readings, extras=extras)
    judge(result, paper, readings, per_run)
    return out


def _v(result, qid):
    return result.get(qid).value


def _share(ok) -> float | None:
    ok = np.asarray(ok, dtype=float)
    ok = ok[np.isfinite(ok)]
    return float(ok.mean()) if ok.size else None


def _per_run_note(share, n, paper) -> str:
    if not quantities.noise_on(paper):
        return "noise-free run (the tables' reading)"
    return f"noise on: holds in {share:.0%} of {n} runs (judged as holding when in at least half)"


def judge(result: StudyResult, paper: Paper = PAPER, readings: Readings = READINGS, per_run=None) -> None:
    """Judge every claim of :data:`.paper.CLAIMS` from the recorded quantities and the per-run measures.

    The claims on Tables 2-3 and Fig. 4/6 are judged under the noise reading ``paper.table_noise``: noise-free on
    the one deterministic run, noise on per run (the paper's table and figure are one run each) — a claim holds at
    the point when it holds in at least half the runs. In situation 2 a run whose MESO never solved the full
    regression (16) does not run the paper's identification: the claims are untestable on it.
    """
    alg = ("the corrected (well-posed) identification" if paper.table_identification_variant == "wellposed"
           else "the Table-1 literal identification")
    _judge_tables(result, paper, per_run, alg)
    _judge_theta(result, paper, readings, per_run, alg)
    _judge_observers(result, readings, alg)


def _judge_tables(result, paper, per_run, alg) -> None:
    """Tables 2-3: the MESO more accurate than the ESO (per run under noise, on the run when noise-free)."""
    for key in ("s1", "s2"):
        b = per_run[key]["better"]
        holds = None if b["share"] is None else b["share"] >= 0.5
        lower = [m for m, c in b["median_change"].items() if c is not None and c < 0]
        if quantities.noise_on(paper):
            head = ("the MESO is below the ESO in all five columns in "
                    + ("—" if b["share"] is None else f"{b['share']:.0%}") + f" of {b['runs']} noise runs (judged "
                    "as holding when in at least half); median MESO/ESO − 1: ")
        else:
            head = (f"noise-free run (the tables' reading): the MESO is below the ESO in {len(lower)}/5 columns; "
                    "MESO/ESO − 1: ")
        note = (f"{SITUATIONS[key].table}, {alg}: " + head
                + "; ".join(f"{m} {100 * c:+.0f} %" if c is not None else f"{m} —"
                            for m, c in b["median_change"].items()))
        if b["share"] is None:
            note += ("; untestable: the MESO never solved the full regression (16) — the gate rejected every batch, "
                     "so the paper's identification did not run")
        result.claim(_CLAIM[f"{key}-meso-better"], holds,
                     evidence=[f"{key}.meso_better.share"]
                     + [f"{key}.{o}.{m}" for o in ("meso", "eso") for m in METRICS],
                     note=note)


def _judge_theta(result, paper, readings, per_run, alg) -> None:
    """The identified parameters: accurate in situation 1, converging in situation 2, θ4 needed."""
    acc = readings.theta_accuracy
    th1 = per_run["s1"]["theta"]
    ok1 = np.where(np.isfinite(th1["before_step"]) & np.isfinite(th1["end"]),
                   (np.maximum(th1["before_step"], th1["end"]) <= acc).astype(float), 0.0)
    s1 = _share(ok1)
    e1b, e1e = _v(result, "s1.theta_rel_error.before_step"), _v(result, "s1.theta_rel_error.end")
    result.claim(_CLAIM["s1-theta-identified"], None if s1 is None else s1 >= 0.5,
                 evidence=["s1.theta_rel_error.before_step", "s1.theta_rel_error.end", "s1.theta_final"],
                 note=f"{alg}: relative error of the identified Θ (situation 1) {_f(e1b)} before the θ4 step and "
                      f"{_f(e1e)} at the end (mean over runs), against 'accurate' read as <= {acc:.0%}; "
                      + _per_run_note(s1 or 0.0, len(ok1), paper))
    th2 = per_run["s2"]["theta"]["end"]
    testable = per_run["s2"]["full"] > 0
    ok2 = np.where(np.isfinite(th2), (th2 <= acc).astype(float), 0.0)[testable]
    s2 = _share(ok2)
    e2 = _v(result, "s2.theta_rel_error.end")
    note = (f"{alg}: relative error of the identified Θ (θ3 included) at the end of situation 2 {_f(e2)} (read: "
            f"converged when <= {acc:.0%}); " + _per_run_note(s2 or 0.0, len(ok2), paper)
            + "; the closed loop's regressors x1, x2, u are collinear once it tracks, so the LSM finds at best the "
            "trajectory-equivalent Θ_eq (see situation2-not-identifiable)")
    if s2 is None:
        note += "; untestable: the MESO never solved the full regression (16), so θ3 was never identified"
    result.claim(_CLAIM["s2-theta-converges"], None if s2 is None else s2 >= 0.5,
                 evidence=["s2.theta_rel_error.end", "s2.theta_final", "s2.full_regression_batches"], note=note)
    nc, wp = _v(result, "s1.no_const.theta_rel_error"), _v(result, "s1.nonoise.theta_rel_error")
    worse = [m for m in ("track_x1", "track_x2") if _v(result, f"s1.no_const.{m}") > _v(result, f"s1.nonoise.meso.{m}")]
    result.claim(_CLAIM["theta4-needed"], nc > acc and wp <= acc and len(worse) == 2,
                 evidence=["s1.no_const.theta_rel_error", "s1.nonoise.theta_rel_error", "s1.no_const.track_x1",
                           "s1.no_const.track_x2", "s1.nonoise.meso.track_x1", "s1.nonoise.meso.track_x2"],
                 note=f"{alg}, situation 1, noise off: relative error of θ1, θ2 without θ4 {nc:.3g}, with θ4 {wp:.3g} "
                      f"(converged read as <= {acc:.0%}); tracking worse without θ4 in {len(worse)}/2 columns")


def _judge_observers(result, readings, alg) -> None:
    """The observers themselves: a larger ε for the MESO, M <= N, and the ε-law of the steady error."""
    e = readings.larger_eps
    ok = [m for m in METRICS if _v(result, f"s1.nonoise.meso_eps_larger.{m}") <= _v(result, f"s1.nonoise.eso.{m}")]
    ratio = np.asarray(_v(result, "s1.meso_eps_larger.noise_std_ratio"))
    result.claim(_CLAIM["larger-eps"], len(ok) == 5 and bool(np.all(ratio < 1)),
                 evidence=[f"s1.nonoise.meso_eps_larger.{m}" for m in METRICS]
                 + [f"s1.nonoise.eso.{m}" for m in METRICS] + ["s1.meso_eps_larger.noise_std_ratio"],
                 note=f"{alg}, situation 1, noise off: the MESO at ε = {e:g} is at least as accurate as the ESO at "
                      f"ε = {PAPER.epsilon:g} in {len(ok)}/5 columns ({', '.join(ok) or 'none'}); its noise std is "
                      f"×{_vec(ratio)} (e1, e2, e3). The whole-run mean includes the first batch, where the MESO is "
                      "still the ESO at the larger ε")
    mn = [(k, _v(result, f"{k}.M_sup"), _v(result, f"{k}.N_sup")) for k in ("s1", "s2")]
    result.claim(_CLAIM["m-le-n"], all(m is not None and m <= n for _, m, n in mn),
                 evidence=[f"{k}.{x}_sup" for k in ("s1", "s2") for x in ("M", "N")],
                 note=f"{alg}: sup |dx3/dt| of each observer's true extended state, noise off: "
                      + "; ".join(f"situation {k[1]} M = {_f(m)}{' (the MESO diverged)' if m is None else ''}, "
                                  f"N = {n:.3g}" for k, m, n in mn))
    law = (3, 2, 1)
    slopes = [_v(result, f"leso.eps_slope.x{i}") for i in (1, 2, 3)]
    tol = readings.exponent_tolerance
    result.claim(_CLAIM["eps-law"], all(abs(s / k - 1) <= tol for s, k in zip(slopes, law, strict=True)),
                 evidence=[f"leso.eps_slope.x{i}" for i in (1, 2, 3)],
                 note=f"fitted log-log slopes of the ESO's mean |e_i| against ε: {_vec(slopes)} against the law "
                      f"{list(law)} (read as confirmed within {tol:.0%} of the exponent)")


def _f(v):
    return "—" if v is None else f"{v:.3g}"


def _vec(v):
    return "[" + ", ".join(f"{x:.3g}" for x in np.ravel(v)) + "]"
