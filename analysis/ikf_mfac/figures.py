"""Figures of the study: data in, ``matplotlib.figure.Figure`` out (saving is the caller's job)."""

from __future__ import annotations

import numpy as np

from ctrl_analysis.reporting.report import new_figure

from .paper import SCHEME_LABELS, SCHEMES, TABLE1

__all__ = [
    "plot_errors",
    "plot_fig2",
    "plot_gain_sweep",
    "plot_noise_sweep",
    "plot_outputs",
    "plot_ratio_sweep",
    "plot_spread",
    "plot_td_scan",
    "td_scan_caption",
    "td_scan_lowest",
    "td_scan_text",
]

COLORS = {"mfac": "tab:gray", "td_mfac": "tab:orange", "d_mfac": "tab:green", "ikf_mfac": "tab:blue"}
#: Marker and size per scheme: drawn in this order, larger first, so equal values show as nested markers.
MARKERS = {"mfac": {"marker": "s", "ms": 9}, "td_mfac": {"marker": "o", "ms": 7}, "d_mfac": {"marker": "^", "ms": 6},
           "ikf_mfac": {"marker": "D", "ms": 4}}


def _legend(ax):
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)


#: A mean over fewer than this share of the runs is never drawn as an ordinary point.
HEALTHY = 0.8


def _plot_runs(ax, x, rows, color, label: str, short: str | None = None, **kw) -> str:
    """Mean per point: filled and joined where at least 80 % of the runs are healthy, hollow and annotated where
    fewer (but at least half), left out where at least half diverged; returns '<label> k/N at x, ...' ('' if none).

    ``rows`` holds ``(mean, std, healthy runs, diverged runs)`` per point.
    """
    x = np.asarray(x, dtype=float)
    mean = np.array([r[0] for r in rows], dtype=float)
    n_ok = np.array([r[2] for r in rows], dtype=float)
    bad = np.array([r[3] for r in rows], dtype=float)
    frac = np.where(n_ok + bad > 0, n_ok / np.maximum(n_ok + bad, 1), 0.0)
    ordinary = (frac >= HEALTHY) & np.isfinite(mean)
    hollow = (frac >= 0.5) & ~ordinary & np.isfinite(mean)
    kw = {"marker": "o", **kw}
    ax.plot(x, np.where(ordinary, mean, np.nan), color=color, label=label, **kw)
    if hollow.any():
        ax.plot(x[hollow], mean[hollow], kw["marker"], mfc="white", mec=color, mew=1.5, ms=kw.get("ms", 8) + 2,
                ls="none")
        for xi, mi, b, n in zip(x[hollow], mean[hollow], bad[hollow], (n_ok + bad)[hollow], strict=True):
            ax.annotate(f"{int(b)}/{int(n)} div.", (xi, mi), textcoords="offset points", xytext=(5, 4), fontsize=7,
                        color=color)
    parts = [f"{int(b)}/{int(n_ok[i] + b)} at {x[i]:g}" + ("" if ordinary[i] or hollow[i] else " (left out)")
             for i, b in enumerate(bad) if b]
    return f"{short or label} {', '.join(parts)}" if parts else ""


def _title_with_diverged(ax, title: str, notes: list) -> None:
    notes = [n for n in notes if n]
    ax.set_title(title + ("\ndiverged runs: " + "; ".join(notes) if notes else ""), fontsize=9 if notes else None)


_RULE = "filled: ≥ 80 % of runs healthy; hollow: 50-80 %; ≥ 50 % diverged: left out"


def plot_fig2(k, y_ref, outputs: dict, R, runs: int, diverged, rejection, rise, Q: float, rise_level: float,
              steady: tuple):
    """Fig. 2: IKF-MFAC outputs for increasing R at fixed Q (one run), and the claim's measures against R."""
    fig, (a1, a2) = new_figure(1, 2, size=(13.0, 4.8),
                               title=f"Fig. 2 — Example 1: IKF-MFAC for R increasing at a fixed Q = {Q:g}")
    a1.plot(k, y_ref, "k--", lw=1, label="y*")
    lim = 2.5
    for Ri, y in outputs.items():
        peak = np.max(np.abs(y)) if np.all(np.isfinite(y)) else np.inf
        gone = ", diverges" if peak > 10.0 else (f", leaves the axes (max |y| = {peak:.2g})" if peak > lim else "")
        a1.plot(k, np.where(np.abs(y) <= 10 * lim, y, np.nan), lw=0.9, label=f"R = {Ri:g} (Q/R = {Q / Ri:.3g})" + gone)
    a1.set(xlabel="sample k", ylabel="output y(k)", ylim=(-lim, lim), title="one run (first seed)")
    a1.legend(loc="lower left", fontsize=8)
    R = np.asarray(R, dtype=float)
    div = np.asarray(diverged)
    rows_f = [(f, 0.0, runs - d, d) for f, d in zip(rejection, div, strict=True)]
    rows_r = [(r, 0.0, runs - d, d) for r, d in zip(rise, div, strict=True)]
    notes = [_plot_runs(a2, R, rows_f, "tab:blue",
                        f"rejection: steady RMS of y − y* (k = {steady[0]}..{steady[1]}), left axis",
                        short="per R")]
    a2.set(xscale="log", xlabel="R (measurement-noise variance of the IKF)", ylabel="steady RMS of y − y*")
    tw = a2.twinx()
    _plot_runs(tw, R, rows_r, "tab:red",
               f"response: start-up rise to y = {rise_level:g} (samples from k = 3), right axis",
               ls="--")
    tw.set_ylabel("start-up rise (samples)")
    for Ri, d in zip(R, div, strict=True):
        if 2 * d >= runs:
            a2.axvspan(Ri / 1.3, Ri * 1.3, color="0.85")
            a2.text(Ri, 0.5, f"{d} of {runs}\nruns diverged", transform=a2.get_xaxis_transform(), ha="center",
                    fontsize=8)
    h1, l1 = a2.get_legend_handles_labels()
    h2, l2 = tw.get_legend_handles_labels()
    a2.legend(h1 + h2, l1 + l2, loc="upper left", fontsize=7)
    _title_with_diverged(a2, f"the claim's measures over {runs} runs per R (mean of the healthy runs)", notes)
    return fig


def _ratio_axes(ax, sweep: dict, label: str):
    q = np.asarray(sweep["q"])
    note = _plot_runs(ax, q, sweep["rmse"], "tab:blue", f"{label}: mean RMSE", short="IKF-MFAC")
    ax.set(xscale="log", xlabel="Q/R", ylabel="RMSE")
    tw = ax.twinx()
    tw.plot(q, sweep["k_inf"], "r:", marker=".", label="K∞(Q/R) (right axis)")
    tw.set_ylabel("steady-state gain K∞")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = tw.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, loc="upper center", fontsize=8)
    return note


def plot_outputs(fig_no: int, title: str, k, y_ref, ys: dict):
    """Fig. 3 / 5: reference and the true output of each scheme for one run, one panel per scheme (same axes)."""
    fig, axes = new_figure(len(SCHEMES), 1, size=(10.0, 8.0), sharex=True, sharey=True,
                           title=f"Fig. {fig_no} — {title}")
    for ax, s in zip(axes, SCHEMES, strict=True):
        ax.plot(k, y_ref, "k--", lw=1.0, label="y*(k)")
        ax.plot(k, ys[s], lw=0.8, color=COLORS[s], label=f"{SCHEME_LABELS[s]} y(k)")
        ax.set_ylabel("y(k)")
        _legend(ax)
    axes[-1].set_xlabel("sample k")
    return fig


def plot_errors(fig_no: int, title: str, k, y_ref, ys: dict):
    """Fig. 4 / 6: |y*(k) − y(k)| of each scheme for one run, one panel per scheme."""
    fig, axes = new_figure(len(SCHEMES), 1, size=(10.0, 7.0), sharex=True, sharey=True,
                           title=f"Fig. {fig_no} — {title}")
    for ax, s in zip(axes, SCHEMES, strict=True):
        ax.plot(k, np.abs(y_ref - ys[s]), lw=0.7, color=COLORS[s], label=SCHEME_LABELS[s])
        ax.set_ylabel("|e*(k)|")
        _legend(ax)
    axes[-1].set_xlabel("sample k")
    return fig


def plot_spread(per_run: dict, runs: int):
    """Monte Carlo spread of RMSE per scheme (violins), Table 1's values as red marks."""
    fig, axes = new_figure(1, 2, size=(11.0, 4.5),
                           title=f"Table 1 — RMSE per scheme over {runs} seeded runs (violins), paper's value (red ×)")
    for ax, key, name in zip(axes, ("ex1", "ex2"), ("Example 1 (constant y*)", "Example 2 (varying y*)"), strict=True):
        data = [per_run[key][s][0][np.isfinite(per_run[key][s][0])] for s in SCHEMES]
        pos = np.arange(1, len(SCHEMES) + 1)
        ax.violinplot([d if d.size else [np.nan] for d in data], positions=pos, showmedians=True)
        ax.plot(pos, [TABLE1[key]["rmse"][s] for s in SCHEMES], "rx", ms=9, mew=2, label="Table 1")
        ax.set_xticks(pos, [SCHEME_LABELS[s] for s in SCHEMES])
        ax.set(title=name, ylabel="RMSE")
        ax.legend(loc="upper right", fontsize=8)
    return fig


def plot_noise_sweep(levels, sweeps: dict, paper_levels: dict):
    """RMSE per scheme against the measurement-noise std (beyond the paper), one panel per example."""
    fig, axes = new_figure(1, 2, size=(12.0, 4.8), title="RMSE of the four schemes against the noise std σ_v "
                                                           f"(mean of the healthy seeded runs; {_RULE})")
    for ax, key in zip(axes, ("ex1", "ex2"), strict=True):
        notes = [_plot_runs(ax, levels[key], sweeps[key][s]["noise"], COLORS[s], SCHEME_LABELS[s], **MARKERS[s])
                 for s in SCHEMES]
        ax.axvline(paper_levels[key], color="k", ls=":", lw=1, label="paper's σ_v")
        ax.set(xlabel="measurement-noise std σ_v", ylabel="RMSE (log scale)", yscale="log")
        _title_with_diverged(ax, "Example 1" if key == "ex1" else "Example 2", notes)
    _legend(axes[-1])
    return fig


def plot_ratio_sweep(sweeps: dict, paper_q: dict):
    """IKF-MFAC RMSE and K∞ against Q/R (beyond the paper), one panel per example."""
    fig, axes = new_figure(1, 2, size=(12.0, 4.8),
                           title=f"IKF-MFAC: mean RMSE and steady gain K∞ against Q/R ({_RULE})")
    for ax, key in zip(axes, ("ex1", "ex2"), strict=True):
        name = "Example 1" if key == "ex1" else "Example 2"
        note = _ratio_axes(ax, sweeps[key], name)
        ax.axvline(paper_q[key], color="k", ls=":", lw=1)
        _title_with_diverged(ax, name + f" (dotted: Q/R used, {paper_q[key]:.3g})", [note])
    return fig


def plot_gain_sweep(values: dict, sweeps: dict, used: dict):
    """RMSE per scheme against ρ and λ (beyond the paper): rows examples, columns parameters."""
    fig, axes = new_figure(2, 2, size=(12.0, 8.0), title="RMSE of the four schemes against the step size ρ and the "
                                                           f"weight λ (mean of the healthy seeded runs;\n{_RULE})")
    for i, key in enumerate(("ex1", "ex2")):
        for j, (name, sym) in enumerate((("rho", "ρ"), ("lam", "λ"))):
            ax = axes[i, j]
            notes = [_plot_runs(ax, values[name], sweeps[key][s][name], COLORS[s], SCHEME_LABELS[s], **MARKERS[s])
                     for s in SCHEMES]
            ax.axvline(used[name], color="k", ls=":", lw=1, label="Example 1's value")
            ax.set(xlabel=sym, ylabel="RMSE")
            _title_with_diverged(ax, ("Example 1" if key == "ex1" else "Example 2") + f", RMSE vs {sym}", notes)
    _legend(axes[0, 1])
    return fig


#: TD-MFAC's mean RMSE within this relative distance of plain MFAC's counts as equal to it (at 48 and more steps
#: per sample x1 has settled within the sample and the two differ by 1e-3 % or less).
EQUAL = 5e-4


def td_scan_lowest(d: dict, mfac: float) -> dict:
    """TD-MFAC's lowest mean RMSE over the step counts with no diverged run, and where it is below or equal to MFAC.

    Parameters
    ----------
    d : dict
        ``{"counts", "rmse", "diverged", "runs"}`` of one example (:func:`~.findings.record_td_scan`).
    mfac : float
        Plain MFAC's mean RMSE on the same runs.

    Returns
    -------
    dict
        ``count``, ``rmse``, ``change`` (relative to MFAC, %) of the lowest clean count (None without one);
        ``below``: the clean counts more than :data:`EQUAL` below MFAC; ``equal``: those within it.
    """
    clean = [(n, m) for n, m, b in zip(d["counts"], d["rmse"], d["diverged"], strict=True) if not b and np.isfinite(m)]
    if not clean:
        return {"count": None, "rmse": None, "change": None, "below": [], "equal": []}
    n, m = min(clean, key=lambda t: t[1])
    return {"count": n, "rmse": m, "change": 100.0 * (m / mfac - 1.0),
            "below": [c for c, v in clean if v < mfac * (1 - EQUAL)],
            "equal": [c for c, v in clean if abs(v / mfac - 1) <= EQUAL]}


def _change(low: dict) -> str:
    return (f"equal to plain MFAC within {100 * EQUAL:g} %" if abs(low["change"]) <= 100 * EQUAL
            else f"{low['change']:+.1f} % against plain MFAC")


def td_scan_text(low: dict, mfac: float) -> str:
    """Where TD-MFAC's mean RMSE over the clean step counts lies against plain MFAC's, in words (caption, finding)."""
    if low["count"] is None:
        return "every count scanned loses runs"
    where = (f"below plain MFAC's {mfac:.4f} at {', '.join(map(str, low['below']))} steps" if low["below"] else
             f"never below plain MFAC's {mfac:.4f} by more than {100 * EQUAL:g} %")
    if low["equal"]:
        where += f", equal to it within {100 * EQUAL:g} % at {', '.join(map(str, low['equal']))} steps"
    return (f"its lowest mean RMSE over the counts with no diverged run is {low['rmse']:.4f} at {low['count']} steps "
            f"({_change(low)}): {where}")


def td_scan_caption(scan: dict, mfac: dict) -> str:
    """The caption of :func:`plot_td_scan`, its words from the numbers it describes."""
    parts = [f"in {name} " + td_scan_text(td_scan_lowest(scan[key], mfac[key]), mfac[key])
             for key, name in (("ex1", "Example 1"), ("ex2", "Example 2"))]
    return ("TD-MFAC's mean RMSE (left axis) and its diverged runs (bars, right axis) against the number of TD steps "
            "per control sample, which the paper does not print, on Table 1's seeds; the count used (dashed), plain "
            "MFAC's RMSE, Table 1's TD-MFAC value and the lowest clean count (star) are marked. Too few steps lose "
            "runs; more steps bring TD-MFAC to plain MFAC: " + "; ".join(parts) + " (finding td-steps-per-sample).")


def plot_td_scan(scan: dict, chosen: dict, mfac: dict):
    """TD-MFAC's mean RMSE and diverged runs against the TD step count per sample, one panel per example."""
    fig, axes = new_figure(1, 2, size=(12.5, 5.4), title="TD-MFAC against the TD steps per control sample (not printed)"
                                                           f" on Table 1's seeds\n({_RULE}; a mean off the top is "
                                                           "printed at the edge)")
    for ax, key in zip(axes, ("ex1", "ex2"), strict=True):
        d = scan[key]
        n, runs = np.asarray(d["counts"]), d["runs"]
        rows = [(m, 0.0, runs - b, b) for m, b in zip(d["rmse"], d["diverged"], strict=True)]
        _plot_runs(ax, n, rows, "tab:orange", "TD-MFAC mean RMSE (left axis)")
        ax.axhline(mfac[key], color="tab:gray", ls="-", lw=1, label=f"plain MFAC {mfac[key]:.4f}")
        ax.axhline(TABLE1[key]["rmse"]["td_mfac"], color="tab:red", ls=":", lw=1.2,
                   label=f"Table 1 TD-MFAC {TABLE1[key]['rmse']['td_mfac']}")
        ax.axvline(chosen[key], color="k", ls="--", lw=1, label=f"count used: {chosen[key]}")
        low = td_scan_lowest(d, mfac[key])
        if low["count"] is not None:
            ax.plot([low["count"]], [low["rmse"]], marker="*", ms=13, color="tab:red", ls="none", zorder=5,
                    label=f"lowest with no diverged run: {low['rmse']:.4f} at {low['count']} "
                          + ("(= MFAC within 0.05 %)" if abs(low["change"]) <= 100 * EQUAL else
                             f"({low['change']:+.1f} % vs MFAC)"))
        ok = np.isfinite(d["rmse"]) & (np.asarray(d["diverged"]) < 0.5 * runs)
        top = max(1.5 * mfac[key], TABLE1[key]["rmse"]["td_mfac"])
        ax.set(xscale="log", xlabel="TD steps per sample (log scale)", ylabel="mean RMSE",
               ylim=(0.9 * min(np.nanmin(np.asarray(d["rmse"])[ok]) if ok.any() else mfac[key],
                               TABLE1[key]["rmse"]["td_mfac"]), top))
        for ni, m in zip(n[ok], np.asarray(d["rmse"])[ok], strict=True):
            if m > top:
                ax.annotate(f"{m:.3g} ↑", (ni, top), textcoords="offset points", xytext=(0, -12), ha="center",
                            fontsize=7, color="tab:orange")
        tw = ax.twinx()
        tw.bar(n, d["diverged"], width=n * 0.08, color="tab:purple", alpha=0.35, label="diverged runs (right axis)")
        tw.set(ylabel=f"diverged runs of {runs}", ylim=(0, runs * 1.05))
        h1, l1 = ax.get_legend_handles_labels()
        h2, l2 = tw.get_legend_handles_labels()
        ax.legend(h1 + h2, l1 + l2, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=7)
        ax.set_title("Example 1" if key == "ex1" else "Example 2")
    return fig
