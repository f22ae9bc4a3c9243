"""Findings of the study: every sentence is generated from computed quantities, never typed as a number."""

from __future__ import annotations

import numpy as np

from ctrl_analysis.reporting.report import StudyResult

from .identification import equivalent_theta
from .loops import SituationRun, pick
from .paper import METRICS, PAPER
from .quantities import first_divergence, theta_truth

__all__ = ["add_findings", "missing"]


def _fmt(v, none="—"):
    return none if v is None else f"{v:.4g}"


def _summary(a) -> str:
    """min / median / max of an array (finite entries), for findings that would quote long arrays."""
    a = np.asarray(a, dtype=float)
    a = a[np.isfinite(a)]
    return "no finite value" if a.size == 0 else f"min {a.min():.3g}, median {np.median(a):.3g}, max {a.max():.3g}"


def _theta_error(sim: SituationRun, i: int, key: str) -> np.ndarray:
    # the batch ending at t_batch identifies the system of that batch (the θ4 step at 30 s starts the next one)
    return np.linalg.norm(sim.theta_batch[:, i] - theta_truth(key, sim.t_batch), axis=1)


def _vec(v) -> str:
    return "[" + ", ".join(f"{x:.3g}" for x in v) + "]"


def _rank_text(ranks, cond, t_batch) -> str:
    """How long the numerical rank test of Theorem 1 passes, against the condition number."""
    full = ranks == ranks.max()
    if full.all():
        return f"numerical rank {ranks.max()} in every batch: the rank test of Theorem 1 always passes"
    k = int(np.argmin(full))
    return (f"numerical rank {ranks.max()} (the rank test of Theorem 1 passes) up to the batch ending at "
            f"t = {t_batch[k - 1] if k else t_batch[0]:.0f} s, where the condition number is already "
            f"{cond[k - 1] if k else cond[0]:.3g}; rank {ranks[k:].min()} after")


def _div_text(sim, i, what) -> str:
    t = first_divergence(sim, [i])
    return f"{what}: diverges at t = {t:.2f} s" if t is not None else f"{what}: no divergence within the run"


def noise_free_counts(result: StudyResult) -> dict:
    """ESO cells closer to the noise-free run than to the noisy runs' mean, and the median deviations of each reading.

    x3 of Table 3 is read against the paper's own reference (without (b − b0)u). Each ESO cell's deviation is
    ``|value / paper − 1|``; no allowance decides anything here.
    """
    off, on, closer = [], [], 0
    for key in ("s1", "s2"):
        for m in METRICS:
            mm = "est_x3_no_bu" if key == "s2" and m == "est_x3" else m
            a, b = result.get(f"{key}.nonoise.eso.{mm}"), result.get(f"{key}.noise.eso.{mm}")
            d_off, d_on = abs(a.value / a.paper - 1), abs(b.value / b.paper - 1)
            off.append(d_off)
            on.append(d_on)
            closer += d_off < d_on
    return {"closer_off": int(closer), "cells": len(off), "median_off": float(np.median(off)),
            "median_on": float(np.median(on)), "max_off": float(np.max(off))}


def _tables_noise(result) -> dict:
    n = noise_free_counts(result)
    lines = []
    for key in ("s1", "s2"):
        for m in METRICS:
            mm = "est_x3_no_bu" if key == "s2" and m == "est_x3" else m
            on, off = result.get(f"{key}.noise.eso.{mm}"), result.get(f"{key}.nonoise.eso.{mm}")
            pct = "" if on.percentile is None else f", the paper at the {on.percentile:.0f}th percentile of the runs"
            lines.append(f"{key} ESO {m}: paper {on.paper:.4g}, noise off {_fmt(off.value)} "
                         f"({100 * (off.value / off.paper - 1):+.1f} %), noise on {_fmt(on.value)}{pct}")
    result.finding(
        "tables-are-noise-free",
        ("The ESO rows of Tables 2 and 3 match the noise-free simulation, not the one with the stated 0.002·U[-1,1] "
         "measurement noise" if n["closer_off"] > n["cells"] / 2 else "The ESO rows of Tables 2 and 3 do not match "
         "the noise-free simulation better than the noisy one")
        + f": the ESO has no identification, so only the initial states and the integrator are reconstructed; "
        f"{n['closer_off']} of its {n['cells']} cells lie closer to the noise-free run (median deviation "
        f"{100 * n['median_off']:.1f} %, at most {100 * n['max_off']:.0f} %) than to the noisy runs' mean (median "
        f"deviation {100 * n['median_on']:.0f} %; x3 of Table 3 against the paper's own reference, see "
        "table3-x3-reference). The study therefore reads the tables as noise-free (reconstruction table_noise, the "
        "noise-on reading is the other value of its box); a deterministic cell is judged at its printed digits, so a "
        "cell a few per cent off differs unless some plausible point lands on it. Per cell: " + "; ".join(lines) + ".",
        evidence=lines)
    return n


def _literal(result, s1, s2) -> None:
    il, iw = pick(s1.rows, "meso", "literal", False)[0], pick(s1.rows, "meso", "wellposed", False)[0]
    norm_l, norm_w = _theta_error(s1, il, "s1"), _theta_error(s1, iw, "s1")
    t_div2 = first_divergence(s2, pick(s2.rows, "meso", "literal", True) + pick(s2.rows, "meso", "literal", False))
    result.finding(
        "table1-accumulation-diverges",
        "The literal Table-1 rule (Θ = Σ Θ̂_i, each Θ̂_i fitted to the MESO's residual x̂3) does not converge once the "
        f"identified parameters pass through W(s) = {PAPER.omega_f:g}²/(s+{PAPER.omega_f:g})² before entering the "
        f"observer: W(s) needs ≈2/ω_f = {2 / PAPER.omega_f:.1f} s to settle, so Θ_used changes during each batch and "
        "the residual regression no longer returns Θ_true − Θ_previous. Situation 1, noise off, |Θ_cum − Θ_true| per "
        f"batch: literal first {norm_l[0]:.3g}, last {norm_l[-1]:.3g} ({_summary(norm_l)}); well-posed (re-identify "
        f"x̂3 + XᵀΘ_used every batch) first {norm_w[0]:.3g}, last {norm_w[-1]:.3g}. Situation 2: "
        + (f"literal runs diverge (first at t = {t_div2:.2f} s)." if t_div2 is not None else
           "no literal run diverges within the simulated horizon."),
        evidence={"s1_literal_error_norm": norm_l, "s1_wellposed_error_norm": norm_w})
    parts, ev = [], {}
    for key, sim in (("s1", s1), ("s2", s2)):
        i = pick(sim.rows, "meso", "literal", False, bypass_w=True)[0]
        err = _theta_error(sim, i, key)
        ev[f"{key}_literal_noW_error_norm"] = err
        t_div = first_divergence(sim, [i])
        parts.append(f"situation {key[1]}: " + (f"diverges at t = {t_div:.2f} s" if t_div is not None else
                     f"|Θ_cum − Θ_true| first {err[0]:.3g}, last {err[-1]:.3g} ({_summary(err)}), track_x1 "
                     f"{_fmt(result.get(f'{key}.literal_noW.track_x1').value)}"))
    result.finding(
        "literal-without-W",
        "The literal Table-1 rule run without W(s) (each batch's Θ̂_i added directly, Θ constant within a batch, as "
        "the derivation of (13)-(14) assumes), noise off: " + "; ".join(parts) + ". Compare the literal rule with "
        "W(s) in table1-accumulation-diverges.", evidence=ev)


def _identifiability(result, s1, s2, horizons, gate) -> None:
    iw_on = pick(s2.rows, "meso", "wellposed", True)
    iw_off = pick(s2.rows, "meso", "wellposed", False)[0]
    idir, idir_off = pick(s2.rows, "meso", "direct", True)[0], pick(s2.rows, "meso", "direct", False)[0]
    c_off, ranks = s2.exact_cond[iw_off], s2.exact_rank[iw_off]
    c_on = 10.0 ** s2.log10_cond[1:, iw_on]
    c1 = 10.0 ** s1.log10_cond[:, pick(s1.rows, "meso", "wellposed", True)]
    th_fin = np.nanmean(s2.theta_batch[-1, iw_on], axis=0)
    true_end = theta_truth("s2", [horizons["s2"]])[0]
    eq = equivalent_theta(true_end, PAPER.b)
    dir_th = s2.theta_batch[:, idir, 2]
    dir_th = dir_th[np.isfinite(dir_th)]
    passes = dict(zip(gate["grid"], gate["passes"], strict=True))
    result.finding(
        "situation2-not-identifiable",
        "Situation 2's full parameter vector is not identifiable from closed-loop data with ξ = sin t, contrary to the "
        "paper's Fig. 6 and its claim that Theorem 1 removes the need for excitation: once the loop tracks, x1 ≈ sin "
        "t, "
        "x2 ≈ cos t and u = −((1+θ1)x1 + θ2x2 + θ4)/b all lie in span{sin t, cos t, 1}, so the 4-column regression has "
        "rank 3 up to transients and noise. Column-scaled condition numbers per batch: situation 1 (3 columns, noise "
        f"on) {_summary(c1)}; situation 2 (16), noise off (exact, from the raw batch) first {c_off[0]:.3g}, last "
        f"{c_off[-1]:.3g} ({_summary(c_off)}; {_rank_text(ranks, c_off, s2.t_batch)}); noise on after the first "
        f"batch {_summary(c_on)}. "
        f"The well-posed identification therefore converges to the trajectory-equivalent Θ_eq = {eq.round(3).tolist()} "
        f"(θ3·u folded into x1, x2, 1), reached: {np.round(th_fin, 3).tolist()} (mean of {len(iw_on)} noise runs), not "
        f"to the true {np.round(true_end, 6).tolist()}; {passes[PAPER.cond_threshold]} of {gate['total']} situation-2 "
        f"batches "
        f"passed the identifiability gate (cond <= {PAPER.cond_threshold:g}"
        + (": one per run, the start-up batch" if passes[PAPER.cond_threshold] == len(iw_on) + 1
           and np.all(s2.full_solved[iw_on] == 1) else "")
        + f"), θ3 held otherwise (mean final value {th_fin[2]:.3g}; see identifiability-threshold). The direct "
        "regression (10) on [x̂1 x̂2 u 1] is well conditioned only because of the noise, and biased by it (u carries "
        f"−x̂3/b0, the same noise as the regressand): θ3 goes {np.array2string(dir_th, precision=2)} per batch; "
        f"{_div_text(s2, idir, 'noise on')}, {_div_text(s2, idir_off, 'noise off')}.",
        evidence={"s2_cond_noise_off": c_off, "s2_rank_noise_off": ranks, "s2_cond_noise_on": _summary(c_on),
                  "s1_cond_noise_on": _summary(c1), "theta_final": th_fin, "theta_equivalent": eq})


def _gate(result, s2, gate) -> None:
    grid, passes = gate["grid"], gate["passes"]
    on = pick(s2.rows, "meso", "wellposed", True)
    base = pick(s2.rows, "meso", "wellposed", False)[0]
    first = np.concatenate([10.0 ** s2.log10_cond[0, on], s2.exact_cond[base][:1]])
    later = np.concatenate([10.0 ** s2.log10_cond[1:, on].ravel(), s2.exact_cond[base][1:]])
    first, later = first[np.isfinite(first)], later[np.isfinite(later)]
    reruns = []
    for g, i in gate["reruns"].items():
        th = s2.theta_batch[-1, i]
        reruns.append(f"threshold {g:g}: (16) solved in {int(s2.full_solved[i])} batches, " + (
            f"diverges at t = {first_divergence(s2, [i]):.2f} s" if s2.diverged[i] else
            f"Θ_final = {np.round(th, 3).tolist()}, track_x1 {_fmt(result.get(f's2.gate{g:g}.track_x1').value)}"))
    result.finding(
        "identifiability-threshold",
        "The identifiability gate decides whether situation 2 runs the paper's identification at all. Column-scaled "
        f"condition numbers of the full regression (16) (well-posed runs at the chosen threshold, noise on and off): "
        f"the start-up batch {_summary(first)}, every later batch {_summary(later)} — the later batches are "
        f"near-collinear (situation2-not-identifiable). Thresholds {list(grid)} let "
        f"{', '.join(str(int(p)) for p in passes)} of {gate['total']} batches through. At the chosen "
        f"{PAPER.cond_threshold:g}, (16) is solved in "
        + ("the start-up batch only" if s2.full_solved[base] == 1 else f"{int(s2.full_solved[base])} batches")
        + f" (noise off; Θ_final = {np.round(s2.theta_batch[-1, base], 3).tolist()}). Noise-free "
        "reruns: " + "; ".join(reruns) + f". So below ≈ {np.min(first):.4g} the paper's identification never runs "
        "(the box judges the situation-2 claims untestable there)" + "".join(
            f"; the rerun at {g:g}, which admits later batches, diverges" for g, i in gate["reruns"].items()
            if s2.diverged[i] and s2.full_solved[i] > 1) + ".",
        evidence={"thresholds": list(grid), "passes": passes, "cond_first": _summary(first),
                  "cond_later": _summary(later)})


def _x3_reference(result, s2) -> None:
    a, b_ = result.get("s2.nonoise.eso.est_x3"), result.get("s2.nonoise.eso.est_x3_no_bu")
    am, bm = result.get("s2.nonoise.meso.est_x3"), result.get("s2.nonoise.meso.est_x3_no_bu")
    iB = pick(s2.rows, "eso", "none", False, b_plant=PAPER.b + 0.95)[0]
    K = len(s2.t)
    result.finding(
        "table3-x3-reference",
        "Table 3's x3 errors are explained by a reference that omits the (b − b0)u = 0.95u part of the extended "
        f"state: ESO (noise off) {_fmt(b_.value)} against 1.3x1 − 1.6x2 + θ4 versus paper {a.paper}, but "
        f"{_fmt(a.value)} against the true extended state d + (b − b0)u; MESO {_fmt(bm.value)} vs {_fmt(am.value)} "
        f"(paper {am.paper}). The large, nearly equal x3 errors of both observers in Table 3 are therefore the omitted "
        f"0.95|u|, not estimation error. Reading 0.95u as an extra term on top of b = {PAPER.b:g} (total gain "
        f"{PAPER.b + 0.95:g}) fits worse: ESO est_x3 {s2.sums['est_x3'][iB] / K:.4g} against its true extended state, "
        f"{s2.sums['est_x3_no_bu'][iB] / K:.4g} against the reference without 0.95u, track_x1 "
        f"{s2.sums['track_x1'][iB] / K:.4g} (paper {result.get('s2.eso.track_x1').paper}, same-plant reading "
        f"{_fmt(result.get('s2.nonoise.eso.track_x1').value)}).")


def _eps(result, sc, lin, s1) -> None:
    law = list(lin.law)
    result.finding(
        "eps-scaling",
        f"The steady estimation errors scale as ε^(n+2−i): fitted log-log slopes over ε ∈ {sc['eps'].tolist()} are "
        f"{np.array2string(sc['slope'], precision=2)} against the law {law} (exact for the DC gains of E_i(s)/H(s), "
        "derived in sympy: ε³/β3, β1ε²/β3, β2ε/β3).")


def _conclusion3_and_mn(result, sims, out) -> None:
    i_nc, i_wp = out["no_const"]
    s1 = sims["s1"]
    err_nc, err_wp = _theta_error(s1, i_nc, "s1"), _theta_error(s1, i_wp, "s1")
    before = s1.t_batch < PAPER.t_step
    tr = [result.get(f"s1.no_const.{m}") for m in ("track_x1", "track_x2")]
    worse_track = sum(q.value > result.get(f"s1.nonoise.meso.{q.id.split('.')[-1]}").value for q in tr)
    has_after = bool(np.any(~before))
    diverge = has_after and err_nc[-1] > 2 * err_wp[-1]
    text = ("Conclusion 3 (without the non-model-class term θ_{n+2} the other parameters do not converge and control "
            "degrades), checked with the well-posed MESO in situation 1, noise off: without θ4, |Θ − Θ_true| at the "
            f"last batch before the step at {PAPER.t_step:g} s is {err_nc[before][-1]:.3g} (with θ4: "
            f"{err_wp[before][-1]:.3g})")
    if has_after:
        text += f", at the end {err_nc[-1]:.3g} (with θ4: {err_wp[-1]:.3g})"
    text += (f"; Θ without θ4 at the end {np.round(s1.theta_batch[-1, i_nc], 3).tolist()}. Tracking: "
             + "; ".join(f"{q.id.split('.')[-1]} {q.value:.4g} ({q.note})" for q in tr) + ". ")
    if not has_after:
        text += "The run ends before the step, so θ4 = 0 throughout and the claim is not tested."
    else:
        text += ("Parameters: the claim holds (the error without θ4 stays more than twice that with it after the "
                 "step). " if diverge else "Parameters: the claim does not hold here (the error without θ4 is not "
                 "more than twice that with it). ")
        text += f"Tracking is worse without θ4 in {worse_track}/2 metrics."
    result.finding("conclusion3-theta4", text, evidence={"error_no_theta4": err_nc, "error_with_theta4": err_wp})
    parts = []
    for key in ("s1", "s2"):
        M, N = result.get(f"{key}.M_sup").value, result.get(f"{key}.N_sup").value
        parts.append(f"situation {key[1]}: M = {M:.4g}, N = {N:.4g} ({'M <= N' if M <= N else 'M > N'})")
    result.finding(
        "m-le-n",
        "(5)/(8) assert M <= N (the MESO's extended state varies no faster than the ESO's), whence the MESO's error "
        "bound (4) is below the ESO's (7). Measured as sup |dx3/dt| of each observer's true extended state, noise off: "
        + "; ".join(parts) + " (from the third batch on, the θ4 step excluded). The inequality is not implied by "
        "(5)/(8) in general: the MESO's extended state also contains the identification error (Θ_true − Θ_used)ᵀX, "
        "which changes whenever W(s) moves Θ_used.")


def _summary_findings(result, sims) -> None:
    def better(tag, key):
        return [m for m in METRICS if (result.get(f"{key}.{tag}meso.{m}").value or np.inf)
                < (result.get(f"{key}.{tag}eso.{m}").value or 0)]

    off = {k: better("nonoise.", k) for k in ("s1", "s2")}
    on = {k: better("noise.", k) for k in ("s1", "s2")}
    runs = result.get("s1.noise.eso.est_x1").runs
    result.finding(
        "meso-better-than-eso",
        f"Without measurement noise (the tables' reading) the MESO (well-posed identification) beats the ESO at equal "
        f"ε in {len(off['s1'])}/5 columns of Table 2 and {len(off['s2'])}/5 of Table 3; with the noise on (means over "
        f"{runs} runs) in {len(on['s1'])}/5 and {len(on['s2'])}/5 (claims s1-meso-better, s2-meso-better judge it per "
        f"run over the whole box). Noise-free, situation 1: {', '.join(off['s1']) or 'none'}; situation 2: "
        f"{', '.join(off['s2']) or 'none'}; in situation 2 this needs only the trajectory-equivalent model, not the "
        "true Θ.")
    div = []
    for key, sim in sims.items():
        labels = {}
        for i in np.flatnonzero(sim.diverged):
            lab = sim.rows[i].label.split("/seed")[0] + ("/noise" if sim.rows[i].seed is not None else "")
            labels.setdefault(lab, []).append(float(sim.t[min(sim.diverged_step[i], len(sim.t) - 1)]))
        for lab, ts in labels.items():
            div.append(f"{key} {lab}: " + (f"1 run, t = {ts[0]:.2f} s" if len(ts) == 1 else
                                            f"{len(ts)} runs, t = {min(ts):.2f}–{max(ts):.2f} s"))
    if div:
        result.finding("diverged-runs", "Runs flagged as diverged (a state beyond 1e6 — the plant, the observer, "
                       "or the identification's Gram entries, i.e. |u| or |x̂3| beyond ~1e3 — excluded from every "
                       "mean): "
                       + "; ".join(div) + ".")


def add_findings(result: StudyResult, sims: dict, lin, sc: dict, claims: dict, horizons: dict) -> None:
    """Every finding of the study, in reading order; every number in them comes from the arguments.

    Parameters
    ----------
    result : StudyResult
        Holds the quantities (read) and receives the findings.
    sims : dict of str -> SituationRun
    lin : LinearAnalysis
    sc : dict
        ε-scaling (:func:`.quantities.eps_scaling`).
    claims : dict
        From :func:`.quantities.claim_quantities`.
    horizons : dict of str -> float
    """
    s1, s2 = sims["s1"], sims["s2"]
    _tables_noise(result)
    _literal(result, s1, s2)
    _identifiability(result, s1, s2, horizons, claims["gate"])
    _gate(result, s2, claims["gate"])
    _x3_reference(result, s2)
    _eps(result, sc, lin, s1)
    _conclusion3_and_mn(result, sims, claims)
    _summary_findings(result, sims)


def differing_cells(result: StudyResult) -> list:
    """The primary Table 2/3 cells whose verdict is ``differs`` or ``diverged`` (what the report counts)."""
    return [q for q in result.quantities if q.primary and q.paper is not None and q.kind == "reproduction"
            and q.verdict in ("differs", "diverged")]


def missing(result: StudyResult) -> list:
    """What the reproduction does not reach beyond the differing cells: the paper's figures and rules (not cells).

    The report lists every differing cell itself, from its verdict and percentile (so the list adds up to
    its count); the noise-free twin of each cell is in the findings.

    Parameters
    ----------
    result : StudyResult

    Returns
    -------
    list of str
    """
    out = []
    out.append("Fig. 6 (not a cell): convergence of θ3 to 0.95 in situation 2 — not identifiable in closed loop "
               "(situation2-not-identifiable)")
    out.append("Table 1's literal accumulation with W(s) (not a cell): does not converge in situation 1 and diverges "
               "in situation 2; the tables use the well-posed variant (table1-accumulation-diverges)")
    return out
