"""Table 1's cells, the Fig. 2 and noise-level measures, and the paper's claims judged on them.

The same functions record the main run and every evaluation of the sensitivity sweep
(:mod:`.evaluate`), so a claim is judged by one piece of code whatever the runs.
"""

from __future__ import annotations

import itertools

import numpy as np

from .paper import CLAIMS, SCHEME_LABELS, SCHEMES, TABLE1

__all__ = ["fig2_measures", "judge_claims", "record_fig2", "record_noise_margin", "record_table1", "table1_cell"]

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
    """Per healthy run: the rejection measure (RMS of y − y* over ``steady``) and the rise (samples from k = 3
    until y first reaches ``rise_level``; NaN if it never does before the window ends).

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
        One value per healthy run.
    """
    ok = ~np.asarray(diverged, dtype=bool)
    a, b = steady
    yy = y[:, ok]
    with np.errstate(all="ignore"):
        fluct = np.sqrt(np.mean((yy[a - 1:b] - y_ref[a - 1:b, None]) ** 2, axis=0))
    seg = yy[2:b] >= rise_level                                        # k = 3 .. b
    rise = np.where(seg.any(axis=0), np.argmax(seg, axis=0), np.nan).astype(float)
    return fluct, rise


def record_fig2(result, R_grid, runs: int, measures: list, Q: float) -> None:
    """Quantities ``fig2.*`` of the Fig. 2 claim: per R, diverged runs, rejection and response-speed measures.

    ``measures`` holds, per R, ``(diverged runs, fluct samples, rise samples)``.
    """
    R = [float(r) for r in R_grid]
    div = [int(m[0]) for m in measures]
    fl = [float(np.mean(m[1])) if np.size(m[1]) else float("nan") for m in measures]
    rs = [float(np.nanmean(m[2])) if np.any(np.isfinite(m[2])) else float("nan") for m in measures]
    grid = ", ".join(f"{r:g}" for r in R)
    result.quantity("fig2.R", f"Fig. 2: R values tried at Q = {Q:g} (Example 1)", R, unit="")
    result.quantity("fig2.diverged_runs", f"Fig. 2: diverged runs of {runs} per R (R = {grid})", div, unit="runs",
                    runs=runs)
    result.quantity("fig2.rejection", f"Fig. 2: steady RMS of y − y* per R, healthy runs (R = {grid}); smaller = "
                    "stronger rejection", fl, unit="", runs=runs)
    result.quantity("fig2.rise", f"Fig. 2: start-up rise in samples per R, healthy runs (R = {grid}); larger = "
                    "slower response", rs, unit="samples", runs=runs)


def record_noise_margin(result, key: str, levels, rows: dict) -> None:
    """Quantity ``<key>.noise.ikf_ratio``: IKF-MFAC's mean RMSE over the best other scheme's, per noise std.

    ``rows`` is ``{scheme: [(mean, std, healthy runs, diverged runs) per level]}``; a scheme with at least
    half its runs diverged at a level is no competitor there (and IKF-MFAC diverging is a ratio of inf).
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
    result.quantity(f"{key}.noise.ikf_ratio", f"{_EXAMPLE[key]}: IKF-MFAC's mean RMSE ÷ the best other scheme's, "
                    f"per noise std σ_v = {', '.join(f'{v:g}' for v in levels)}", ratio, unit="", runs=runs,
                    note="best other scheme per level: " + ", ".join(L[b] for b in best)
                    + ("; " + "; ".join(notes) if notes else ""))


def _rmse(result, key: str, s: str) -> float:
    """Mean RMSE of a Table 1 cell; inf when it diverged (a diverged scheme ranks last)."""
    q = result.get(f"{key}.{s}.rmse")
    return float("inf") if q.is_diverged or q.value is None else float(q.value)


def _fmt(x: float) -> str:
    return "diverged" if not np.isfinite(x) else f"{x:.4f}"


def _best(result, key: str) -> None:
    cid = "ikf-best-constant" if key == "ex1" else "ikf-best-varying"
    m = {s: _rmse(result, key, s) for s in SCHEMES}
    others = {s: v for s, v in m.items() if s != "ikf_mfac"}
    b = min(others, key=others.get)
    holds = m["ikf_mfac"] < others[b]
    result.claim(_CLAIM[cid], holds, evidence=[f"{key}.{s}.rmse" for s in SCHEMES],
                 note=f"{_EXAMPLE[key]}: IKF-MFAC's mean RMSE {_fmt(m['ikf_mfac'])} against {L[b]}'s "
                      f"{_fmt(others[b])}, the lowest of the other three (Table 1: "
                      f"{TABLE1[key]['rmse']['ikf_mfac']} against {min(TABLE1[key]['rmse'][s] for s in others)}); "
                      "SNR is a decreasing function of RMSE on the same reference, so it ranks the same way.")


def _fig2(result) -> None:
    R = result.get("fig2.R").value
    div = result.get("fig2.diverged_runs")
    runs = div.runs
    fl, rs = result.get("fig2.rejection").value, result.get("fig2.rise").value
    healthy = [i for i, d in enumerate(div.value) if 2 * d < runs and np.isfinite(fl[i])]
    lost = [f"{R[i]:g} ({d} of {runs})" for i, d in enumerate(div.value) if 2 * d >= runs]
    f, r = [fl[i] for i in healthy], [rs[i] for i in healthy]
    stronger = len(f) >= 2 and all(b < a for a, b in itertools.pairwise(f))
    slower = len(r) >= 2 and all(b >= a for a, b in itertools.pairwise(r)) and r[-1] > r[0]
    holds = stronger and slower and not lost
    pts = "; ".join(f"R = {R[i]:g}: RMS {fl[i]:.4f}, rise {rs[i]:.1f}" + (f", {div.value[i]} diverged"
                                                                            if div.value[i] else "")
                    for i in healthy)
    result.claim(_CLAIM["fig2-larger-r"], holds, evidence=["fig2.R", "fig2.diverged_runs", "fig2.rejection", "fig2.rise"],
                 note=f"Over the R values with most runs healthy ({pts}) the steady RMS of y − y* "
                      f"{'falls' if stronger else 'does not fall'} at every step up in R and the start-up rise "
                      f"{'lengthens' if slower else 'does not lengthen'}"
                      + (f"; but at R = {', '.join(lost)} runs diverged: rejection does not keep growing with R, the "
                         "loop is lost" if lost else "; no R of the grid loses half its runs") + ".")


def _noise(result) -> None:
    parts, ok = [], True
    for key in ("ex1", "ex2"):
        q = result.get(f"{key}.noise.ikf_ratio")
        worst = int(np.argmax(q.value))
        ok &= all(v < 1 for v in q.value)
        lv = q.label.split("σ_v = ")[-1].split(", ")
        lose = [f"{lv[i]}" for i, v in enumerate(q.value) if not v < 1]
        parts.append(f"{_EXAMPLE[key]}: ratio {min(q.value):.3f} to {max(q.value):.3f} (largest at σ_v = {lv[worst]})"
                     + (f", not the lowest at σ_v = {', '.join(lose)}" if lose else ", the lowest at every level"))
    result.claim(_CLAIM["ikf-best-every-noise"], ok, evidence=["ex1.noise.ikf_ratio", "ex2.noise.ikf_ratio"],
                 note="IKF-MFAC's mean RMSE over the best other scheme's across the noise levels: " + "; ".join(parts)
                      + ".")


def judge_claims(result) -> None:
    """Judge every claim of :data:`~.paper.CLAIMS` on the recorded quantities (main run and sensitivity sweep)."""
    _best(result, "ex1")
    _best(result, "ex2")
    r = {(k, s): _rmse(result, k, s) for k in ("ex1", "ex2") for s in SCHEMES}
    td = [r[(k, "td_mfac")] < r[(k, "mfac")] for k in ("ex1", "ex2")]
    result.claim(_CLAIM["td-beats-mfac"], all(td), evidence=[f"{k}.{s}.rmse" for k in ("ex1", "ex2")
                                                             for s in ("mfac", "td_mfac")],
                 note="; ".join(f"{_EXAMPLE[k]}: TD-MFAC {_fmt(r[(k, 'td_mfac')])} against MFAC {_fmt(r[(k, 'mfac')])}"
                                for k in ("ex1", "ex2")) + " (mean RMSE).")
    worst2 = max(SCHEMES, key=lambda s: r[("ex2", s)])
    d_ok = r[("ex1", "d_mfac")] < r[("ex1", "mfac")] and worst2 == "d_mfac"
    result.claim(_CLAIM["d-mfac-constant-only"], d_ok,
                 evidence=[f"{k}.{s}.rmse" for k in ("ex1", "ex2") for s in SCHEMES],
                 note=f"Example 1: D-MFAC {_fmt(r[('ex1', 'd_mfac')])} against MFAC {_fmt(r[('ex1', 'mfac')])}; "
                      f"Example 2: the largest mean RMSE is {L[worst2]}'s ({_fmt(r[('ex2', worst2)])}; D-MFAC "
                      f"{_fmt(r[('ex2', 'd_mfac')])}).")
    f_ok = r[("ex2", "td_mfac")] < r[("ex2", "d_mfac")] and r[("ex2", "ikf_mfac")] < r[("ex2", "d_mfac")]
    result.claim(_CLAIM["filters-beat-d-mfac-varying"], f_ok,
                 evidence=["ex2.td_mfac.rmse", "ex2.ikf_mfac.rmse", "ex2.d_mfac.rmse"],
                 note=f"Example 2 mean RMSE: TD-MFAC {_fmt(r[('ex2', 'td_mfac')])}, IKF-MFAC "
                      f"{_fmt(r[('ex2', 'ikf_mfac')])}, D-MFAC {_fmt(r[('ex2', 'd_mfac')])}.")
    _fig2(result)
    _noise(result)
