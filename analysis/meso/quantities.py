"""Quantities of the study: the linear observer, Tables 2 and 3, Θ of Fig. 4 / 6 and the checked claims.

Every value is computed from a :class:`~.loops.SituationRun` or a :class:`~.linear.LinearAnalysis`;
table cells carry the paper's printed value, a tolerance and a unit. A quantity whose runs all
diverged has no value (``None``; the note says so).
"""

from __future__ import annotations

import numpy as np

from ctrl_analysis.metrics import mean_std
from ctrl_analysis.reporting.report import StudyResult
from ctrl_analysis.reporting.verdicts import digits_tolerance

from .identification import equivalent_theta
from .linear import noise_std
from .loops import SituationRun, pick
from .paper import (
    GATE_GRID,
    GATE_RERUNS,
    METRICS,
    PAPER,
    READINGS,
    SITUATIONS,
    TABLE_DECIMALS,
    TABLE_UNITS,
    TABLES,
    Analysis,
    Paper,
    Readings,
)

__all__ = [
    "claim_quantities",
    "eps_scaling",
    "first_divergence",
    "gate_passes",
    "linear_quantities",
    "meso_better",
    "noise_on",
    "plant_b",
    "table_cell",
    "table_quantities",
    "table_runs",
    "theta_errors",
    "theta_final",
    "theta_rel_error",
    "theta_truth",
]


def table_cell(key: str, observer: str, metric: str) -> str:
    """The paper cell (``"Table 2 / MESO / est_x1"``) a Table 2/3 quantity scores; ``est_x3_no_bu`` is a
    reading of the ``est_x3`` cell."""
    metric = "est_x3" if metric == "est_x3_no_bu" else metric
    return f"{SITUATIONS[key].table} / {observer.upper()} / {metric}"


def linear_quantities(result: StudyResult, lin, sc: dict) -> None:
    """ω_o, poles, error DC gains, ε-slopes of the closed-loop errors, noise std per ε.

    Parameters
    ----------
    result : StudyResult
        Receives the quantities.
    lin : LinearAnalysis
        From :func:`.linear.analyse`.
    sc : dict
        From :func:`eps_scaling`.
    """
    eps = PAPER.epsilon
    result.quantity("leso.omega_o", "LESO bandwidth ω_o: s³ + β₁/ε s² + β₂/ε² s + β₃/ε³ = (s + ω_o)³",
                    lin.omega_o, unit="rad/s",
                    note=f"exact (sympy): β = (3, 3, 1) = C(3, i)·1^i is a bandwidth form with ω_o = 1/ε; "
                         f"p(s) = {lin.char_poly}")
    result.quantity("leso.poles", "LESO poles (real parts; triple root)", lin.poles.real, unit="rad/s",
                    note=f"numerical roots of a triple root at -{lin.omega_o:g}; |imag| <= "
                         f"{np.max(np.abs(lin.poles.imag)):.1e}; python-control ss poles "
                         f"{np.sort(lin.observer.ss.poles().real).round(3).tolist()}")
    result.quantity("leso.error_dc_gains", "steady e_i per unit constant dx3/dt: (β_{i-1}/β₃) ε^(n+2-i)",
                    lin.error_dc_gains, unit="s³, s², s (e_i per unit of dx3/dt in 1/s³)",
                    note="DC gains of E_i(s)/H(s) (python-control); sympy gives ε³/β₃, β₁ε²/β₃, β₂ε/β₃ = "
                         f"{[eps**3, 3 * eps**2, 3 * eps]}")
    units = ("", "1/s", "1/s²")
    for i in range(3):
        result.quantity(f"leso.eps_slope.x{i + 1}",
                        f"log-log slope of mean |e_{i + 1}| vs ε (law (4)/(7): {lin.law[i]})",
                        float(sc["slope"][i]), unit="",
                        note=f"ESO in the noise-free situation-1 loop, ε ∈ {sc['eps'].tolist()}, mean over "
                             f"[{sc['window'][0]:g}, {sc['window'][1]:g}) s: "
                             f"{np.array2string(sc['err'][:, i], precision=3)}")
        result.quantity(f"leso.noise_std.x{i + 1}",
                        f"steady std of e_{i + 1} caused by the measurement noise, per ε {lin.eps.tolist()}",
                        lin.noise_std[:, i], unit=units[i],
                        note="linear error dynamics e' = (A − LC)e − Lv, ZOH at 3 ms, v ~ 0.002·U[−1, 1] per step "
                             "(control.dlyap); the same for ESO and MESO (§5's noise-sensitivity claim)")


def eps_scaling(sim: SituationRun, analysis: Analysis) -> dict:
    """Mean |e_i| of the noise-free ESO over the analysis window, for each ε of the grid (situation 1).

    Parameters
    ----------
    sim : SituationRun
        Situation 1 (its rows include the ESO at every ε of ``analysis.eps_grid``, noise off).
    analysis : Analysis

    Returns
    -------
    dict
        ``eps``, ``err`` (len(eps), 3), the log-log ``slope`` (3,) and the ``window``.
    """
    eps = np.asarray(analysis.eps_grid, dtype=float)
    idx = [pick(sim.rows, "eso", "none", False, epsilon=e)[0] for e in eps]
    err = np.stack([sim.window_sums[m][idx] / sim.n_window for m in ("est_x1", "est_x2", "est_x3")], axis=1)
    slope = np.array([np.polyfit(np.log(eps), np.log(err[:, i]), 1)[0] for i in range(3)])
    return {"eps": eps, "err": err, "slope": slope, "window": analysis.eps_window}


def first_divergence(sim: SituationRun, idx) -> float | None:
    """Time of the earliest divergence among runs ``idx``.

    Parameters
    ----------
    sim : SituationRun
    idx : sequence of int

    Returns
    -------
    float or None
        None if none of the runs diverged.
    """
    bad = [i for i in idx if sim.diverged[i]]
    if not bad:
        return None
    return float(sim.t[min(sim.diverged_step[i] for i in bad) - 1] + (sim.t[1] - sim.t[0]))


def _table_cell(result, key, sim, idx, metric, qid, what, noise, paper=PAPER, primary=False, with_paper=True):
    """One Table 2/3 cell (or its other-reading / literal twin) as a quantity.

    Noise on: the percentile policy (the paper's value from one noisy run against the central 95 % of the
    healthy runs, ``samples``). Noise off: one deterministic run, judged at the paper's printed digits (half a
    unit of the last printed decimal, :data:`.paper.TABLE_DECIMALS`) — the same rule as every deterministic number.
    """
    sit = SITUATIONS[key]
    K = len(sim.t)
    ok = ~sim.diverged[idx]
    # the x3 column follows the reconstruction true_x3 (both readings are always summed)
    source = "est_x3_no_bu" if metric == "est_x3" and paper.true_x3 == "without (b - b0)u" else metric
    per_run = sim.sums[source][idx] / K
    mean, std, n_ok = mean_std(per_run, ok)
    o = "eso" if what == "ESO" else "meso"
    col = METRICS.index("est_x3" if metric == "est_x3_no_bu" else metric)
    paper_v = TABLES[key][o][col]
    note = f"noise {'on' if noise else 'off'}; {what}"
    if source == "est_x3":
        note += "; true x3 = x2' − b0 u − XᵀΘ_used (with the (b − b0)u part)"
    if source == "est_x3_no_bu":
        note += "; true x3 taken as the printed d(t) minus 0.95u (i.e. 1.3x1 − 1.6x2 + θ4) minus XᵀΘ_used"
    t_div = first_divergence(sim, idx)
    if t_div is not None:
        note += f"; {len(idx) - n_ok}/{len(idx)} runs diverged (first at t = {t_div:.2f} s)"
    if n_ok == 0:
        note += "; all runs diverged: no value"
    label_m = "est_x3 against x3 without (b − b0)u" if metric == "est_x3_no_bu" else metric
    samples = per_run[ok] if noise and len(idx) > 1 and n_ok > 1 else None
    tol = None
    if samples is None:
        decimals = TABLE_DECIMALS[key][o][col]
        tol = digits_tolerance(paper_v, decimals)
        note += f"; one deterministic run judged at the printed digits ({decimals} decimals: ±{tol:.2%})"
    cell = {"paper": paper_v, "tolerance": tol, "samples": samples, "cell": table_cell(key, o, metric),
            "primary": primary}
    result.quantity(qid, f"{sit.table}, {what}, mean |e| {label_m}, noise {'on' if noise else 'off'}",
                    None if n_ok == 0 else float(mean), std=None if n_ok == 0 else float(std), runs=len(idx),
                    runs_diverged=len(idx) - int(n_ok), diverged=n_ok == 0, unit=TABLE_UNITS[metric], note=note,
                    **(cell if with_paper else {}))


def noise_on(paper: Paper) -> bool:
    """Whether the tables and Fig. 3-6 are read with the measurement noise of (27) (reconstruction table_noise)."""
    return paper.table_noise == "noise on"


def table_quantities(result: StudyResult, key: str, sim: SituationRun, paper: Paper = PAPER,
                     extras: bool = True) -> None:
    """Tables 2/3: the primary cells under the noise reading; with ``extras`` both readings and the literal rule.

    The primary cell ``{key}.{observer}.{metric}`` is the ESO or the MESO (the identification of the point's
    algorithm) under the reconstruction ``table_noise``: noise on, the runs' mean with the central 95 % of the
    runs as its band; noise-free, the one deterministic run at the printed digits.

    Parameters
    ----------
    result : StudyResult
    key : {"s1", "s2"}
    sim : SituationRun
    paper : Paper
        Its ``table_noise`` chooses the primary reading, its ``true_x3`` the reading of the x3 column.
    extras : bool
        Also record both readings (``{key}.noise.*``, ``{key}.nonoise.*``) and the Table-1 literal rule with noise
        on (``{key}.literal.meso.*``), none of them primary (the main run; the box records the primary cells only).
    """
    rows = sim.rows
    whats = {"meso": "MESO (well-posed identification)", "eso": "ESO", "literal": "MESO, Table-1 literal accumulation"}
    if paper.table_identification_variant == "literal":
        whats["meso"] = whats["literal"]
    on = noise_on(paper)
    for o, v in (("meso", "wellposed"), ("eso", "none")):
        idx = pick(rows, o, v, on)
        for m in METRICS:
            _table_cell(result, key, sim, idx, m, f"{key}.{o}.{m}", whats[o], on, paper, primary=True)
    # the noise-free runs (the claims of §5 and conclusion 3 compare situation 1's); in the box without the paper's
    # value, so that only the primary cells are searched
    for o, v in (("meso", "wellposed"), ("eso", "none")) if extras or key == "s1" else ():
        for m in METRICS:
            _table_cell(result, key, sim, pick(rows, o, v, False), m, f"{key}.nonoise.{o}.{m}", whats[o], False,
                        paper, with_paper=extras)
    if not extras:
        return
    for name, o, v in (("meso", "meso", "wellposed"), ("eso", "eso", "none"), ("literal", "meso", "literal")):
        idx = pick(rows, o, v, True)
        for m in METRICS:
            qid = f"{key}.literal.meso.{m}" if name == "literal" else f"{key}.noise.{o}.{m}"
            _table_cell(result, key, sim, idx, m, qid, whats[name], True, paper)
    if key == "s2":
        for noise in (True, False):
            tag = f"{key}.noise." if noise else f"{key}.nonoise."
            for o, v in (("eso", "none"), ("meso", "wellposed")):
                _table_cell(result, key, sim, pick(rows, o, v, noise), "est_x3_no_bu", f"{tag}{o}.est_x3_no_bu",
                            whats[o], noise, paper)


def plant_b(key: str, paper: Paper = PAPER) -> float:
    """Input gain of the simulated plant: situation 2 read with 0.95 u as an extra term has b = 3.95 + 0.95."""
    return paper.b + 0.95 if key == "s2" and paper.situation2_plant == "extra term" else paper.b


def theta_truth(key: str, t, paper: Paper = PAPER) -> np.ndarray:
    """True Θ = [θ1, θ2, θ3, θ4] of situation ``key`` at the times ``t`` ((31)/(32); θ4 from t_step on).

    θ3 is the u-part of the extended state, b − b0 of the simulated plant: 0 in situation 1, 0.95 in situation 2
    (1.9 where 0.95 u is read as a term on top of b u, reconstruction situation2_plant).

    Parameters
    ----------
    key : {"s1", "s2"}
    t : array_like, shape (n,)
    paper : Paper

    Returns
    -------
    ndarray, shape (n, 4)
    """
    th3 = plant_b(key, paper) - SITUATIONS[key].b0 if SITUATIONS[key].regression == "full" else 0.0
    before = np.array([paper.theta1, paper.theta2, th3, 0.0])
    after = np.array([paper.theta1, paper.theta2, th3, paper.step])
    return np.where((np.asarray(t) >= paper.t_step - 0.5 * paper.h)[:, None], after, before)


def theta_final(result: StudyResult, key: str, sim: SituationRun, horizon: float, paper: Paper = PAPER) -> None:
    """Θ after the last batch (the point's identification and noise reading): what Fig. 4 / Fig. 6 show converging.

    Parameters
    ----------
    result : StudyResult
    key : {"s1", "s2"}
    sim : SituationRun
    horizon : float
        End of the run (s), for the truth at that time.
    paper : Paper
        Its ``table_noise`` chooses the runs.
    """
    on = noise_on(paper)
    idx = pick(sim.rows, "meso", "wellposed", on)
    mean, std, n_ok = mean_std(sim.theta_batch[-1, idx], ~sim.diverged[idx])
    true_end = theta_truth(key, [horizon], paper)[0]
    note = (f"Fig. {4 if key == 's1' else 6} plots Θ converging to the truth; the paper prints no value. "
            f"Truth Θ = {np.round(true_end, 6).tolist()} (at t = {horizon:g} s)")
    if key == "s2":
        note += (f"; trajectory-equivalent Θ_eq = {equivalent_theta(true_end, plant_b(key, paper)).round(4).tolist()} "
                 "(θ3 not identifiable in closed loop)")
    result.quantity(f"{key}.theta_final", f"Fig. {4 if key == 's1' else 6}: identified Θ after the last LSM "
                    f"batch (noise {'on' if on else 'off'})", None if n_ok == 0 else np.asarray(mean),
                    std=None if n_ok == 0 else np.asarray(std), runs=len(idx), runs_diverged=len(idx) - int(n_ok),
                    unit="[1/s², 1/s, 1, 1/s²]", note=note)


def theta_rel_error(theta, truth, cols=(0, 1, 2, 3)) -> np.ndarray:
    """Relative error |Θ − Θ_true| / |Θ_true| over the parameters ``cols`` (per run for a (B, 4) ``theta``).

    Parameters
    ----------
    theta : array_like, shape (4,) or (B, 4)
    truth : array_like, shape (4,)
    cols : sequence of int

    Returns
    -------
    float or ndarray
    """
    c = list(cols)
    th, tr = np.asarray(theta, dtype=float)[..., c], np.asarray(truth, dtype=float)[c]
    return np.linalg.norm(th - tr, axis=-1) / np.linalg.norm(tr)


def theta_errors(result: StudyResult, key: str, sim: SituationRun, paper: Paper = PAPER) -> dict:
    """Relative Θ error of the MESO at the last batch before the θ4 step and at the end, per run.

    The claims of Fig. 4 / Fig. 6 are judged on these (``{key}.theta_rel_error.before_step`` / ``.end``: the
    mean over the runs; the per-run values are returned), under the noise reading of ``paper``.

    Parameters
    ----------
    result : StudyResult
    key : {"s1", "s2"}
    sim : SituationRun
    paper : Paper

    Returns
    -------
    dict
        ``{"before_step": (runs,), "end": (runs,)}`` per-run relative errors (NaN for a diverged run).
    """
    on = noise_on(paper)
    idx = pick(sim.rows, "meso", "wellposed", on)
    ok = ~sim.diverged[idx]
    before = np.flatnonzero(sim.t_batch < PAPER.t_step - 0.5 * PAPER.h)
    cols = (0, 1, 3) if SITUATIONS[key].regression == "reduced" else (0, 1, 2, 3)
    names = "θ1, θ2, θ4" if len(cols) == 3 else "θ1..θ4"
    out = {}
    for tag, k, when in (("before_step", before[-1] if before.size else 0, "last batch before the θ4 step"),
                         ("end", len(sim.t_batch) - 1, "last batch")):
        truth = theta_truth(key, [sim.t_batch[k]], paper)[0]
        per_run = theta_rel_error(sim.theta_batch[k, idx], truth, cols)
        per_run = np.where(ok, per_run, np.nan)
        out[tag] = per_run
        mean, std, n_ok = mean_std(per_run, ok & np.isfinite(per_run))
        note = (f"{when}, ending at t = {sim.t_batch[k] + PAPER.h:.0f} s; relative error over {names} against the "
                f"truth {np.round(truth[list(cols)], 6).tolist()}; noise {'on' if on else 'off'}")
        if key == "s2":
            eq = equivalent_theta(truth, plant_b(key, paper))
            e_eq = theta_rel_error(sim.theta_batch[k, idx], eq, cols)
            e_eq = e_eq[np.isfinite(e_eq)]
            note += (f"; against the trajectory-equivalent Θ_eq = {eq.round(4).tolist()}: "
                     + (f"{float(np.mean(e_eq)):.3g}" if e_eq.size else "no healthy run"))
        result.quantity(f"{key}.theta_rel_error.{tag}", f"situation {key[1]}: relative error of the identified Θ, "
                        f"{when}", None if n_ok == 0 else float(mean),
                        std=None if n_ok == 0 else float(std), runs=len(idx), runs_diverged=len(idx) - int(n_ok),
                        unit="", note=note)
    return out


def table_runs(sim: SituationRun, paper: Paper = PAPER) -> dict:
    """Per-run table metrics of the ESO and the MESO under the noise reading, paired by seed.

    Returns
    -------
    dict
        ``{"meso": {metric: (runs,)}, "eso": {...}, "diverged": (runs,) (the MESO run), "full": (runs,)}``;
        ``full`` is the number of batches in which the MESO solved situation 2's full regression (16).
    """
    on = noise_on(paper)
    K = len(sim.t)
    im, ie = pick(sim.rows, "meso", "wellposed", on), pick(sim.rows, "eso", "none", on)
    if [sim.rows[i].seed for i in im] != [sim.rows[i].seed for i in ie]:
        raise ValueError("the MESO and ESO runs must pair by seed")
    out = {}
    for o, idx in (("meso", im), ("eso", ie)):
        out[o] = {}
        for m in METRICS:
            src = "est_x3_no_bu" if m == "est_x3" and paper.true_x3 == "without (b - b0)u" else m
            v = sim.sums[src][idx] / K
            out[o][m] = np.where(sim.diverged[idx], np.nan, v)
    out["diverged"] = sim.diverged[im]
    out["full"] = sim.full_solved[im]
    return out


def meso_better(result: StudyResult, key: str, sim: SituationRun, paper: Paper = PAPER) -> dict:
    """Tables 2/3's comparison per run: in how many runs the MESO is below the ESO in all five columns.

    The paper's table is one run; with the noise on, each reproduced run is one possible table, so the measure is
    the share of runs in which the MESO wins every column (a diverged MESO run loses), with the median change per
    column. In situation 2 a run whose MESO never solved the full regression (16) (the corrected algorithm's gate
    rejected every batch) does not run the paper's identification and is left out (untestable).

    Returns
    -------
    dict
        ``share`` (None when no run is testable), ``runs`` (testable), ``median_change`` {metric: MESO/ESO − 1}.
    """
    tr = table_runs(sim, paper)
    testable = np.ones(len(tr["diverged"]), dtype=bool)
    if SITUATIONS[key].regression == "full":
        testable = tr["full"] > 0
    wins = np.ones(len(testable), dtype=bool)
    change = {}
    for m in METRICS:
        a, b = tr["meso"][m], tr["eso"][m]
        with np.errstate(invalid="ignore"):
            wins &= np.isfinite(a) & (a < b)
        r = a[testable] / b[testable] - 1
        r = r[np.isfinite(r)]
        change[m] = float(np.median(r)) if r.size else None
    n = int(testable.sum())
    share = float(wins[testable].mean()) if n else None
    ch = "; ".join(f"{m} {100 * c:+.0f} %" if c is not None else f"{m} —" for m, c in change.items())
    note = (f"runs in which the MESO is below the ESO in all five columns of {SITUATIONS[key].table} "
            f"({'noise on, ' + str(n) + ' runs' if noise_on(paper) else 'noise-free, one run'}); median change "
            f"MESO/ESO − 1 per column: {ch}")
    if SITUATIONS[key].regression == "full":
        note += (f"; {int((~testable).sum())} of {len(testable)} runs never solved the full regression (16) (left out: "
                 "without it the MESO does not run the paper's identification)")
    result.quantity(f"{key}.meso_better.share", f"situation {key[1]}: share of runs with the MESO below the ESO in "
                    "every table column", share, unit="", runs=n or None, note=note)
    return {"share": share, "runs": n, "median_change": change, "testable": testable}


def _one(sim, i, metric):
    return float(sim.sums[metric][i] / len(sim.t))


def claim_quantities(result: StudyResult, sims: dict, lin, horizons: dict, readings: Readings = READINGS,
                     extras: bool = True) -> dict:
    """Quantities of the claims the tables do not show (Conclusion 3, (5)/(8) M <= N, §5 ε, W(s), gate).

    Parameters
    ----------
    result : StudyResult
    sims : dict of str -> SituationRun
    lin : LinearAnalysis
    horizons : dict of str -> float
    readings : Readings
        Its ``larger_eps`` is the ε at which the MESO is compared with the ESO (§5).
    extras : bool
        Also the quantities only the findings use (literal rule without W(s), the gate's sensitivity).

    Returns
    -------
    dict
        Run indices and gate counts the findings reuse (``no_const``, ``gate``).
    """
    s1, s2 = sims["s1"], sims["s2"]
    out = {"no_const": _conclusion3(result, s1, horizons)}
    _m_and_n(result, sims, s2)
    _larger_eps(result, s1, readings)
    if not extras:
        return out
    # the literal rule without W(s)
    for key, sim in sims.items():
        i = pick(sim.rows, "meso", "literal", False, bypass_w=True)[0]
        t_div = first_divergence(sim, [i])
        for m in ("track_x1", "est_x3"):
            result.quantity(f"{key}.literal_noW.{m}", f"situation {key[1]}, Table-1 literal rule without W(s), "
                            f"mean |e| {m}, noise off", None if sim.diverged[i] else _one(sim, i, m),
                            diverged=bool(sim.diverged[i]), runs=1, unit=TABLE_UNITS[m],
                            note=f"diverged at t = {t_div:.2f} s: no value" if t_div else "")
    out["gate"] = _gate_quantities(result, s2)
    return out


def _conclusion3(result, s1, horizons) -> tuple:
    """Conclusion 3: the well-posed MESO without θ4 (noise off); returns the two runs' indices."""
    i_nc, i_wp = pick(s1.rows, "meso", "no_const", False)[0], pick(s1.rows, "meso", "wellposed", False)[0]
    for m in ("track_x1", "track_x2", "est_x3"):
        result.quantity(f"s1.no_const.{m}", f"Situation 1, MESO without θ4 (Conclusion 3), mean |e| {m}, noise off",
                        _one(s1, i_nc, m), unit=TABLE_UNITS[m],
                        note=f"with θ4 (well-posed, noise off): {_one(s1, i_wp, m):.4g}")
    t_end = [s1.t_batch[-1]]
    for qid, i, what in (("s1.no_const.theta_rel_error", i_nc, "without θ4"),
                         ("s1.nonoise.theta_rel_error", i_wp, "with θ4")):
        result.quantity(qid, f"Situation 1, MESO {what}: relative error of θ1, θ2 after the last batch, noise off",
                        float(theta_rel_error(s1.theta_batch[-1, i], theta_truth("s1", t_end)[0], (0, 1))), unit="",
                        note="the model-class parameters (conclusion 3's 'other parameters'); θ3 is not identified "
                             "in situation 1")
    result.quantity("s1.no_const.theta_final", "Situation 1, MESO without θ4: Θ after the last batch, noise off",
                    s1.theta_batch[-1, i_nc], unit="[1/s², 1/s, 1, 1/s²]",
                    note=f"truth {theta_truth('s1', [horizons['s1']])[0].tolist()}; with θ4: "
                         f"{np.round(s1.theta_batch[-1, i_wp], 4).tolist()}")
    return i_nc, i_wp


def _m_and_n(result, sims, s2) -> None:
    """(5)/(8): M = sup|d x3/dt| of the MESO's extended state, N that of the ESO's (noise off); situation 2's full
    regressions."""
    for key, sim in sims.items():
        i_m, i_e = pick(sim.rows, "meso", "wellposed", False)[0], pick(sim.rows, "eso", "none", False)[0]
        result.quantity(f"{key}.M_sup", f"situation {key[1]}: M of (5), sup |dx3/dt| of the MESO's extended "
                        "state (noise off)", None if sim.diverged[i_m] else float(sim.sup_dx3[i_m]), unit="1/s³",
                        diverged=bool(sim.diverged[i_m]), runs=1,
                        note=f"N of (8) (ESO): {sim.sup_dx3[i_e]:.4g}; finite differences of the true x3 at the "
                             f"3-ms samples from t = {2 * SITUATIONS[key].N * PAPER.h:g} s on (after the start-up, "
                             "identical for both observers until the first batch), the θ4 step at 30 s excluded")
        result.quantity(f"{key}.N_sup", f"situation {key[1]}: N of (8), sup |dx3/dt| of the ESO's extended state "
                        "(noise off)", float(sim.sup_dx3[i_e]), unit="1/s³", note="see M_sup")
    # situation 2: batches in which the MESO solved the full regression (16) (the paper's identification)
    i_m = pick(s2.rows, "meso", "wellposed", False)[0]
    result.quantity("s2.full_regression_batches", "situation 2: batches in which the MESO solved the full regression "
                    "(16)-(20), noise off", int(s2.full_solved[i_m]), unit="batches",
                    note=f"of {len(s2.t_batch)}; the corrected algorithm solves (16) only when it passes the "
                         "identifiability gate (cond_threshold), else (22) with θ3 held; the Table-1 literal rule "
                         "solves it every batch")


def _larger_eps(result, s1, readings) -> None:
    """§5: the MESO at a larger ε against the ESO at the paper's, and the noise std ratio."""
    e = readings.larger_eps
    i_m01 = pick(s1.rows, "meso", "wellposed", False, epsilon=e)[0]
    for m in METRICS:
        result.quantity(f"s1.nonoise.meso_eps_larger.{m}", f"Situation 1, MESO (well-posed) with the larger ε = {e:g}, "
                        f"mean |e| {m}, noise off", _one(s1, i_m01, m), unit=TABLE_UNITS[m],
                        note=f"ESO with the paper's ε = {PAPER.epsilon:g}: "
                             f"{_one(s1, pick(s1.rows, 'eso', 'none', False)[0], m):.4g}")
    ratio = noise_std(PAPER, e) / noise_std(PAPER, PAPER.epsilon)
    result.quantity("s1.meso_eps_larger.noise_std_ratio", f"steady noise std of e1, e2, e3 at ε = {e:g} relative to "
                    f"ε = {PAPER.epsilon:g}", ratio, unit="",
                    note="linear error dynamics driven by the measurement noise (control.dlyap), the same for ESO and "
                         "MESO")


def gate_passes(sim: SituationRun, thresholds) -> tuple:
    """Situation-2 batches whose full regression passes the gate, per threshold (well-posed runs, noise on + off).

    Noise-off runs use the exact condition number of the raw batch, noise-on runs the block's Gram value.

    Parameters
    ----------
    sim : SituationRun
        Situation 2.
    thresholds : sequence of float

    Returns
    -------
    passes : ndarray of int
        Batches at or below each threshold.
    total : int
        Batches counted.
    cond : ndarray
        Their condition numbers.
    """
    on = pick(sim.rows, "meso", "wellposed", True)
    off = pick(sim.rows, "meso", "wellposed", False)[0]
    cond = np.concatenate([10.0 ** sim.log10_cond[:, on].T.ravel(), sim.exact_cond[off]])
    cond = cond[np.isfinite(cond)]
    return np.array([int(np.sum(cond <= g)) for g in thresholds]), int(cond.size), cond


def _gate_quantities(result, s2) -> dict:
    """Sensitivity of situation 2's identifiability gate: batches passing per threshold, reruns at other thresholds."""
    grid = GATE_GRID
    passes, total, cond = gate_passes(s2, grid)
    result.quantity("s2.gate_passes",
                    f"situation 2: batches passing the identifiability gate for thresholds {list(grid)} "
                    f"(of {total})", passes, unit="batches",
                    note=f"the study's threshold is {PAPER.cond_threshold:g}; well-posed runs, noise on and off; "
                    f"column-scaled cond of "
                         f"(16); lowest cond seen {np.min(cond):.4g}")
    base = pick(s2.rows, "meso", "wellposed", False)[0]
    out = {"grid": grid, "passes": passes, "total": total, "cond": cond, "reruns": {}}
    for g in GATE_RERUNS:
        i = pick(s2.rows, "meso", "wellposed", False, threshold=g)[0]
        out["reruns"][g] = i
        result.quantity(f"s2.gate{g:g}.theta_final", f"situation 2, well-posed MESO with gate threshold {g:g}: Θ after "
                        "the last batch, noise off", None if s2.diverged[i] else s2.theta_batch[-1, i],
                        diverged=bool(s2.diverged[i]), runs=1, unit="[1/s², 1/s, 1, 1/s²]",
                        note=f"threshold {PAPER.cond_threshold:g}: {np.round(s2.theta_batch[-1, base], 4).tolist()}"
                             + (f"; diverged at t = {first_divergence(s2, [i]):.2f} s: no value"
                                if s2.diverged[i] else ""))
        result.quantity(f"s2.gate{g:g}.track_x1", f"situation 2, well-posed MESO with gate threshold {g:g}: mean "
                        "|e| track_x1, noise off", None if s2.diverged[i] else _one(s2, i, "track_x1"),
                        diverged=bool(s2.diverged[i]), runs=1, unit="",
                        note=f"threshold {PAPER.cond_threshold:g}: {_one(s2, base, 'track_x1'):.4g}"
                             + (f"; diverged at t = {first_divergence(s2, [i]):.2f} s: no value"
                                if s2.diverged[i] else ""))
    return out
