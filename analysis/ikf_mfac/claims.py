"""Table 1's cells, the Fig. 2 and noise-level measures, and the paper's claims judged on them.

The same functions record the main run and every evaluation of the plausible box (:mod:`.evaluate`), so a
claim is judged by one piece of code whatever the runs.

The paper reads its claims off single runs (Fig. 2-6, and Table 1, whose numbers are one run's: the cells are
judged against the runs' spread, not their mean). A claim is therefore judged run by run, on the runs each scheme
shares (the same noise): it holds when more than half of the runs show it, and is untestable when that share
is within its noise floor, ``1/sqrt(runs)`` (two binomial standard errors at one half), of one half. A diverged run
has an infinite RMSE: it ranks last and shows no claim about its own scheme. A claim made of several parts (two
examples, several noise levels) holds when every part holds and fails when one part fails.
"""

from __future__ import annotations

import math

import numpy as np

from .paper import CLAIMS, SCHEME_LABELS, SCHEMES, TABLE1

__all__ = ["fig2_measures", "judge_claims", "noise_parts", "record_fig2", "record_noise_margin", "record_table1",
           "share_floor", "table1_cell"]

L = SCHEME_LABELS
_CLAIM = {c.id: c for c in CLAIMS}
_EXAMPLE = {"ex1": "Example 1", "ex2": "Example 2"}


def table1_cell(key: str, scheme: str, metric: str) -> str:
    """The paper cell a Table 1 quantity scores: ``"Table 1 / constant|varying / RMSE|SNR / <scheme>"``."""
    return f"Table 1 / {'constant' if key == 'ex1' else 'varying'} / {metric.upper()} / {SCHEME_LABELS[scheme]}"


def _pct(v, p) -> float:
    return float(100.0 * np.mean(v < p)) if v.size else float("nan")


def record_table1(result, key: str, per_run: dict, diverged_at: dict | None = None) -> None:
    """Quantities ``<key>.<scheme>.rmse`` (percentile policy over the healthy runs) and ``.snr`` (derived).

    Parameters
    ----------
    result : StudyResult
    key : {"ex1", "ex2"}
    per_run : dict
        ``{scheme: (rmse per run, snr per run)}``, NaN for a diverged run.
    diverged_at : dict, optional
        ``{scheme: ["run b at k = ..."]}`` for the note.
    """
    for s in SCHEMES:
        e, snr = (np.asarray(a, dtype=float) for a in per_run[s])
        ok = np.isfinite(e)
        n, bad = int(ok.sum()), int((~ok).sum())
        where = (diverged_at or {}).get(s, [])
        note = f"{bad} of {e.size} runs diverged and are excluded" + (f" ({'; '.join(where[:5])})" if where else "") \
            if bad else ""
        rid = f"{key}.{s}.rmse"
        cell = table1_cell(key, s, "rmse")
        result.quantity(rid, cell, float(np.mean(e[ok])) if n else None, paper=TABLE1[key]["rmse"][s],
                        std=float(np.std(e[ok], ddof=1)) if n > 1 else None, runs=int(e.size), runs_diverged=bad,
                        samples=e[ok] if n else None, unit="", cell=cell, primary=True, note=note)
        # SNR = 10 lg(mean y*²) − 20 lg RMSE run by run: it takes the RMSE cell's verdict
        p_snr = TABLE1[key]["snr"][s]
        own = (f"the printed SNR itself lies above {_pct(snr[ok], p_snr):.1f} % of the runs' SNR (Table 1's SNR and "
               "RMSE are not consistent with each other, see the checks)") if n else ""
        cell = table1_cell(key, s, "snr")
        result.quantity(f"{key}.{s}.snr", cell, float(np.mean(snr[ok])) if n else None, paper=p_snr,
                        std=float(np.std(snr[ok], ddof=1)) if n > 1 else None, runs=int(e.size), runs_diverged=bad,
                        derived_from=rid, unit="dB", cell=cell, primary=True,
                        note="; ".join(x for x in (note, "derived from the RMSE of the same runs", own) if x))


def fig2_measures(y: np.ndarray, y_ref: np.ndarray, diverged: np.ndarray, rise_level: float, steady: tuple):
    """Per run: the rejection measure (RMS of y − y* over ``steady``) and the rise (samples from k = 3 until y
    first reaches ``rise_level``; NaN if it never does before the window ends); both NaN for a diverged run.

    Parameters
    ----------
    y : numpy.ndarray
        True outputs, shape ``(N, B)``, row ``k − 1``.
    y_ref : numpy.ndarray
        ``y*(k)``, shape ``(N,)``.
    diverged : numpy.ndarray
        Shape ``(B,)``.
    rise_level : float
        Threshold of the start-up rise (y(3) = 0.5 towards y* = 1).
    steady : (int, int)
        First and last sample of the steady window.

    Returns
    -------
    fluct, rise : numpy.ndarray
        One value per run, shape ``(B,)``.
    """
    bad = np.asarray(diverged, dtype=bool)
    a, b = steady
    with np.errstate(all="ignore"):
        fluct = np.sqrt(np.mean((y[a - 1:b] - y_ref[a - 1:b, None]) ** 2, axis=0))
    seg = y[2:b] >= rise_level                                        # k = 3 .. b
    rise = np.where(seg.any(axis=0), np.argmax(seg, axis=0), np.nan).astype(float)
    return np.where(bad, np.nan, fluct), np.where(bad, np.nan, rise)


def record_fig2(result, R_grid, runs: int, measures: list, Q: float) -> None:
    """Quantities ``fig2.*`` of the Fig. 2 claim: per R, diverged runs, rejection and response-speed measures.

    ``measures`` holds, per R, ``(diverged per run, fluct per run, rise per run)`` (:func:`fig2_measures`); the
    quantities are the means over the healthy runs.
    """
    R = [float(r) for r in R_grid]
    div = [int(np.sum(m[0])) for m in measures]
    fl = [float(np.nanmean(m[1])) if np.any(np.isfinite(m[1])) else float("nan") for m in measures]
    rs = [float(np.nanmean(m[2])) if np.any(np.isfinite(m[2])) else float("nan") for m in measures]
    grid = ", ".join(f"{r:g}" for r in R)
    result.quantity("fig2.R", f"Fig. 2: R values tried at Q = {Q:g} (Example 1)", R, unit="")
    result.quantity("fig2.diverged_runs", f"Fig. 2: diverged runs of {runs} per R (R = {grid})", div, unit="runs",
                    runs=runs)
    result.quantity("fig2.rejection", f"Fig. 2: steady RMS of y − y* per R, healthy runs (R = {grid}); smaller = "
                    "stronger rejection", fl, unit="", runs=runs)
    result.quantity("fig2.rise", f"Fig. 2: start-up rise in samples per R, healthy runs (R = {grid}); larger = "
                    "slower response", rs, unit="samples", runs=runs)


def _lowest(rows: dict, scheme: str) -> np.ndarray:
    """Per run: ``scheme``'s RMSE below every other scheme's in ``rows`` (a diverged run ranks last)."""
    r = {s: _inf(e) for s, e in rows.items()}
    others = [v for s, v in r.items() if s != scheme]
    return np.all([r[scheme] < v for v in others], axis=0) if others else np.isfinite(r[scheme])


def record_noise_margin(result, key: str, levels, rows: dict, per_run: dict | None = None) -> None:
    """Quantities ``<key>.noise.ikf_ratio`` (IKF-MFAC's mean RMSE over the best other scheme's, per noise std)
    and, given the runs, ``<key>.noise.ikf_lowest_share`` (the share of runs in which IKF-MFAC's RMSE is the lowest).

    ``rows`` is ``{scheme: [(mean, std, healthy runs, diverged runs) per level]}``; a scheme with at least
    half its runs diverged at a level is no competitor for the mean (and IKF-MFAC diverging is a ratio of inf).
    ``per_run`` is ``{scheme: [RMSE per run (NaN: diverged) per level]}``.
    """
    ratio, best, notes = [], [], []
    def mean(row):
        m, _, ok, bad = row
        return float(m) if ok and 2 * bad < ok + bad and np.isfinite(m) else float("inf")

    for i, lv in enumerate(levels):
        others = {s: mean(rows[s][i]) for s in SCHEMES if s != "ikf_mfac"}
        b = min(others, key=others.get)
        ratio.append(mean(rows["ikf_mfac"][i]) / others[b])
        best.append(b)
        div = [f"{L[s]} {rows[s][i][3]}/{rows[s][i][2] + rows[s][i][3]}" for s in SCHEMES if rows[s][i][3]]
        if div:
            notes.append(f"σ_v = {lv:g}: diverged {', '.join(div)}")
    runs = rows["ikf_mfac"][0][2] + rows["ikf_mfac"][0][3]
    lv = ", ".join(f"{v:g}" for v in levels)
    result.quantity(f"{key}.noise.ikf_ratio", f"{_EXAMPLE[key]}: IKF-MFAC's mean RMSE ÷ the best other scheme's, "
                    f"per noise std σ_v = {lv}", ratio, unit="", runs=runs,
                    note="best other scheme per level: " + ", ".join(L[b] for b in best)
                    + ("; " + "; ".join(notes) if notes else ""))
    if per_run is not None:
        share = [float(np.mean(_lowest({s: per_run[s][i] for s in SCHEMES}, "ikf_mfac"))) for i in range(len(levels))]
        result.quantity(f"{key}.noise.ikf_lowest_share", f"{_EXAMPLE[key]}: share of runs in which IKF-MFAC's RMSE "
                        f"is the lowest of the four, per noise std σ_v = {lv}", share, unit="", runs=runs)


# ---------------------------------------------------------------------------------------------------------------
# the claims, run by run


def share_floor(runs: int) -> float:
    """The noise floor of a share of ``runs`` runs against one half: two binomial standard errors, ``1/sqrt(runs)``."""
    return 1.0 / math.sqrt(max(int(runs), 1))


def _inf(e) -> np.ndarray:
    e = np.asarray(e, dtype=float)
    return np.where(np.isfinite(e), e, np.inf)


def _judge(result, cid: str, parts: list, evidence, note: str) -> None:
    """Judge claim ``cid`` on its parts ``[(label, per-run bool)]``: every part's share of runs above one half."""
    shares = [(label, float(np.mean(ok)), int(np.size(ok))) for label, ok in parts]
    n = min(k for _, _, k in shares)
    margin = min(s - 0.5 for _, s, _ in shares)
    holds = all(s > 0.5 for _, s, _ in shares)
    text = "; ".join(f"{label} in {100 * s:.0f} % of {k} runs" for label, s, k in shares)
    result.claim(_CLAIM[cid], holds, evidence=evidence, measure=margin, noise_floor=share_floor(n),
                 note=f"Run by run (the same noise for every scheme): {text}. {note}".strip()
                      + (f" The measure is the smallest share minus one half; its noise floor 1/sqrt({n})."
                         if abs(margin) < share_floor(n) else ""))


def _rmse(result, key: str, s: str) -> float:
    """Mean RMSE of a Table 1 cell; inf when it diverged."""
    q = result.get(f"{key}.{s}.rmse")
    return float("inf") if q.is_diverged or q.value is None else float(q.value)


def _fmt(x: float) -> str:
    return "diverged" if not np.isfinite(x) else f"{x:.4f}"


def _best(result, key: str, table: dict) -> None:
    cid = "ikf-best-constant" if key == "ex1" else "ikf-best-varying"
    m = {s: _rmse(result, key, s) for s in SCHEMES}
    others = {s: v for s, v in m.items() if s != "ikf_mfac"}
    b = min(others, key=others.get)
    beats = {s: float(np.mean(_inf(table[key]["ikf_mfac"]) < _inf(table[key][s]))) for s in others}
    _judge(result, cid, [("IKF-MFAC has the lowest RMSE of the four", _lowest(table[key], "ikf_mfac"))],
           [f"{key}.{s}.rmse" for s in SCHEMES],
           f"{_EXAMPLE[key]}: IKF-MFAC's RMSE is below " + ", ".join(f"{L[s]}'s in {100 * v:.0f} %"
                                                                     for s, v in beats.items())
           + f" of the runs; mean RMSE {_fmt(m['ikf_mfac'])} against {L[b]}'s {_fmt(others[b])}, the lowest of the "
           f"other three (Table 1: {TABLE1[key]['rmse']['ikf_mfac']} against "
           f"{min(TABLE1[key]['rmse'][s] for s in others)}). SNR is a decreasing function of RMSE on the same "
           "reference, run by run, so it ranks the same way.")


def _fig2(result, fig2: list) -> None:
    """Fig. 2's claim run by run: over the whole R grid, the run stays healthy, its rejection measure falls at every
    step up in R and its rise never shortens and ends longer than it started."""
    R = result.get("fig2.R").value
    div = result.get("fig2.diverged_runs")
    runs = div.runs
    fl, rs = result.get("fig2.rejection").value, result.get("fig2.rise").value
    bad = np.any([m[0] for m in fig2], axis=0)
    f = np.array([m[1] for m in fig2])                                  # (R, runs), NaN where diverged
    r = np.array([np.where(np.isnan(m[2]) & ~m[0], np.inf, m[2]) for m in fig2])   # never reached: slowest
    with np.errstate(invalid="ignore"):
        stronger = ~bad & np.all(np.diff(f, axis=0) < 0, axis=0)
        slower = ~bad & np.all(np.diff(r, axis=0) >= 0, axis=0) & (r[-1] > r[0])
        # the same over the R values where each run stays healthy (what the trends are short of the lost runs)
        ok = [np.isfinite(f[:, b]) for b in range(f.shape[1])]
        f_ok = [np.all(np.diff(f[k, b]) < 0) for b, k in enumerate(ok) if k.sum() >= 2]
        r_ok = [np.all(np.diff(r[k, b]) >= 0) and r[k, b][-1] > r[k, b][0] for b, k in enumerate(ok) if k.sum() >= 2]
    lost = [f"{R[i]:g} ({d} of {runs})" for i, d in enumerate(div.value) if 2 * d >= runs]
    pts = "; ".join(f"R = {R[i]:g}: " + (f"all {d} runs diverged" if d == runs else
                                         f"RMS {fl[i]:.4f}, rise {rs[i]:.1f}" + (f", {d} diverged" if d else ""))
                    for i, d in enumerate(div.value))
    shows = "the rejection measure falls at every step up in R and the rise lengthens (no run lost at any R)"
    _judge(result, "fig2-larger-r", [(shows, stronger & slower)],
           ["fig2.R", "fig2.diverged_runs", "fig2.rejection", "fig2.rise"],
           f"Over the R values where the run stays healthy, the rejection measure falls in "
           f"{100 * np.mean(f_ok) if f_ok else 0:.0f} % and the rise lengthens in "
           f"{100 * np.mean(r_ok) if r_ok else 0:.0f} "
           f"% of the {len(f_ok)} runs healthy at two R or more. Means over the healthy runs: {pts}"
           + (f"; at R = {', '.join(lost)} runs diverged: rejection does not keep growing with R, the loop is lost"
              if lost else "") + ".")


def noise_parts(levels: dict, rows: dict) -> list:
    """The noise claim's parts: per example and noise std, the runs in which IKF-MFAC's RMSE is the lowest.

    ``levels`` is ``{key: noise stds}``; ``rows`` is ``{key: {scheme: [RMSE per run or None per level]}}``: a
    scheme not run at a level (None) is left out there, which can only raise IKF-MFAC's share (a level without
    IKF-MFAC's runs is no part yet).
    """
    parts = []
    for key, lv in levels.items():
        for i, v in enumerate(lv):
            here = {s: r[i] for s, r in rows[key].items() if r[i] is not None}
            if "ikf_mfac" not in here:
                continue
            parts.append((f"{_EXAMPLE[key]} σ_v = {v:g}", _lowest(here, "ikf_mfac")))
    return parts


def _has(result, qid: str) -> bool:
    return any(q.id == qid for q in result.quantities)


def _noise(result, levels: dict, rows: dict, skipped: str = "") -> None:
    parts = []
    for key in ("ex1", "ex2"):
        if not _has(result, f"{key}.noise.ikf_ratio"):
            continue
        q = result.get(f"{key}.noise.ikf_ratio")
        worst = int(np.argmax(q.value))
        lv = q.label.split("σ_v = ")[-1].split(", ")
        parts.append(f"{_EXAMPLE[key]}: mean-RMSE ratio {min(q.value):.3f} to {max(q.value):.3f} (largest at "
                     f"σ_v = {lv[worst]})")
    _judge(result, "ikf-best-every-noise", noise_parts(levels, rows),
           [f"{k}.noise.{m}" for k in ("ex1", "ex2") for m in ("ikf_ratio", "ikf_lowest_share")
            if _has(result, f"{k}.noise.{m}")],
           " ".join(x for x in ("IKF-MFAC's mean RMSE over the best other scheme's: " + "; ".join(parts) + "."
                                if parts else "", skipped) if x))


def judge_claims(result, table: dict, noise: dict, fig2: list, skipped: str = "") -> None:
    """Judge every claim of :data:`~.paper.CLAIMS` run by run (main run and every evaluation of the box).

    Parameters
    ----------
    result : StudyResult
        With Table 1's cells, ``fig2.*`` and (if recorded) ``<key>.noise.*``.
    table : dict
        ``{key: {scheme: RMSE per run}}`` (NaN: diverged), Table 1's runs.
    noise : dict
        ``{"levels": {key: noise stds}, "rows": {key: {scheme: [RMSE per run or None per level]}}}``.
    fig2 : list
        Per R, ``(diverged per run, fluct per run, rise per run)``.
    skipped : str
        What the noise claim's evaluation left out, for its note.
    """
    _best(result, "ex1", table)
    _best(result, "ex2", table)
    t = {(k, s): _inf(table[k][s]) for k in ("ex1", "ex2") for s in SCHEMES}
    r = {(k, s): _rmse(result, k, s) for k in ("ex1", "ex2") for s in SCHEMES}
    _judge(result, "td-beats-mfac", [(f"{_EXAMPLE[k]}: TD-MFAC below MFAC", t[(k, "td_mfac")] < t[(k, "mfac")])
                                     for k in ("ex1", "ex2")],
           [f"{k}.{s}.rmse" for k in ("ex1", "ex2") for s in ("mfac", "td_mfac")],
           "Mean RMSE: " + "; ".join(f"{_EXAMPLE[k]}: TD-MFAC {_fmt(r[(k, 'td_mfac')])} against MFAC "
                                     f"{_fmt(r[(k, 'mfac')])}" for k in ("ex1", "ex2")) + ".")
    worst2 = max(SCHEMES, key=lambda s: r[("ex2", s)])
    largest = np.all([t[("ex2", "d_mfac")] > t[("ex2", s)] for s in SCHEMES if s != "d_mfac"], axis=0)
    _judge(result, "d-mfac-constant-only", [("Example 1: D-MFAC below MFAC", t[("ex1", "d_mfac")] < t[("ex1", "mfac")]),
                                            ("Example 2: D-MFAC the largest of the four", largest)],
           [f"{k}.{s}.rmse" for k in ("ex1", "ex2") for s in SCHEMES],
           f"Mean RMSE: Example 1 D-MFAC {_fmt(r[('ex1', 'd_mfac')])} against MFAC {_fmt(r[('ex1', 'mfac')])}; "
           f"Example 2: the largest is {L[worst2]}'s ({_fmt(r[('ex2', worst2)])}"
           + (")." if worst2 == "d_mfac" else f"; D-MFAC {_fmt(r[('ex2', 'd_mfac')])})."))
    both = (t[("ex2", "td_mfac")] < t[("ex2", "d_mfac")]) & (t[("ex2", "ikf_mfac")] < t[("ex2", "d_mfac")])
    _judge(result, "filters-beat-d-mfac-varying", [("Example 2: TD-MFAC and IKF-MFAC both below D-MFAC", both)],
           ["ex2.td_mfac.rmse", "ex2.ikf_mfac.rmse", "ex2.d_mfac.rmse"],
           f"TD-MFAC alone in {100 * np.mean(t[('ex2', 'td_mfac')] < t[('ex2', 'd_mfac')]):.0f} %, IKF-MFAC alone in "
           f"{100 * np.mean(t[('ex2', 'ikf_mfac')] < t[('ex2', 'd_mfac')]):.0f} %. Mean RMSE: TD-MFAC "
           f"{_fmt(r[('ex2', 'td_mfac')])}, IKF-MFAC {_fmt(r[('ex2', 'ikf_mfac')])}, D-MFAC "
           f"{_fmt(r[('ex2', 'd_mfac')])}.")
    _fig2(result, fig2)
    _noise(result, noise["levels"], noise["rows"], skipped)
