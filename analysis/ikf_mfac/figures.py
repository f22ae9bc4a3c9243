"""Figures of the study: data in, ``matplotlib.figure.Figure`` out (saving is the caller's job)."""

from __future__ import annotations

import numpy as np

from ctrl_analysis.report import new_figure

from .paper import SCHEME_LABELS, SCHEMES, TABLE1

__all__ = [
    "plot_errors",
    "plot_fig2",
    "plot_gain_sweep",
    "plot_noise_sweep",
    "plot_outputs",
    "plot_ratio_sweep",
    "plot_spread",
]

COLORS = {"mfac": "tab:gray", "td_mfac": "tab:orange", "d_mfac": "tab:green", "ikf_mfac": "tab:blue"}


def _legend(ax):
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)


def _mark_diverged(ax, x, rows, color, label: str) -> str:
    """Ring each sweep point whose mean excludes diverged runs; return '<label> n/N at x, ...' ('' if none)."""
    parts = []
    for xi, row in zip(x, rows):
        mean, _, ok, bad = row
        if not bad:
            continue
        parts.append(f"{bad}/{ok + bad} at {xi:g}" + ("" if ok and np.isfinite(mean) else " (no mean)"))
        if ok and np.isfinite(mean):
            ax.plot([xi], [mean], "o", ms=12, mfc="none", mec=color, mew=1.2)
    return f"{label} {', '.join(parts)}" if parts else ""


def _title_with_diverged(ax, title: str, notes: list) -> None:
    notes = [n for n in notes if n]
    ax.set_title(title + ("\ndiverged runs (ringed, excluded): " + "; ".join(notes) if notes else ""),
                 fontsize=10 if notes else None)


def plot_fig2(k, y_ref, outputs: dict, sweep: dict, Q: float, q_used: float):
    """Fig. 2: IKF-MFAC outputs for increasing R at fixed Q (one run), and mean RMSE and K∞ against Q/R."""
    fig, (a1, a2) = new_figure(1, 2, size=(12.0, 4.5),
                               title=f"Fig. 2 — Example 1: IKF-MFAC output for R increasing at Q = {Q:g}, "
                                     "and mean RMSE against Q/R")
    a1.plot(k, y_ref, "k--", lw=1, label="y*")
    lim = 2.5
    for R, y in outputs.items():
        peak = np.max(np.abs(y)) if np.all(np.isfinite(y)) else np.inf
        gone = ", diverges" if peak > 10.0 else (f", leaves the axes (max |y| = {peak:.2g})" if peak > lim else "")
        a1.plot(k, y, lw=0.9, label=f"R = {R:g} (Q/R = {Q / R:.3g})" + gone)
    a1.set(xlabel="sample k", ylabel="output y(k)", ylim=(-lim, lim))
    a1.legend(loc="lower left", fontsize=8)
    _ratio_axes(a2, sweep, "Example 1")
    a2.axvline(q_used, color="k", ls=":", lw=1)
    a2.set_title(f"Beyond the paper: mean RMSE against Q/R at the study's R (dotted: Q/R used, {q_used:.3g})",
                 fontsize=10)
    return fig


def _ratio_axes(ax, sweep: dict, label: str):
    q = np.asarray(sweep["q"])
    m = np.array([r[0] for r in sweep["rmse"]])
    s = np.array([r[1] for r in sweep["rmse"]])
    ax.errorbar(q, m, yerr=s, marker="o", capsize=3, color="tab:blue", label=f"{label}: mean RMSE ± std")
    for qi, mi, row in zip(q, m, sweep["rmse"]):
        if row[3]:
            ax.annotate(f"{row[3]} of {row[2] + row[3]} runs diverged", (qi, mi), textcoords="offset points",
                        xytext=(8, 0), fontsize=8)
    ax.set(xscale="log", xlabel="Q/R", ylabel="RMSE")
    tw = ax.twinx()
    tw.plot(q, sweep["k_inf"], "r:", marker=".", label="K∞(Q/R) (right axis)")
    tw.set_ylabel("steady-state gain K∞")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = tw.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, loc="upper center", fontsize=8)


def plot_outputs(fig_no: int, title: str, k, y_ref, ys: dict):
    """Fig. 3 / 5: reference and the true output of each scheme for one run."""
    fig, ax = new_figure(size=(10.0, 4.5), title=f"Fig. {fig_no} — {title}")
    ax.plot(k, y_ref, "k--", lw=1.2, label="y*(k)")
    for s in SCHEMES:
        ax.plot(k, ys[s], lw=0.8, color=COLORS[s], label=SCHEME_LABELS[s])
    ax.set(xlabel="sample k", ylabel="output y(k)")
    _legend(ax)
    return fig


def plot_errors(fig_no: int, title: str, k, y_ref, ys: dict):
    """Fig. 4 / 6: |y*(k) − y(k)| of each scheme for one run, one panel per scheme."""
    fig, axes = new_figure(len(SCHEMES), 1, size=(10.0, 7.0), sharex=True, sharey=True,
                           title=f"Fig. {fig_no} — {title}")
    for ax, s in zip(axes, SCHEMES):
        ax.plot(k, np.abs(y_ref - ys[s]), lw=0.7, color=COLORS[s], label=SCHEME_LABELS[s])
        ax.set_ylabel("|e*(k)|")
        _legend(ax)
    axes[-1].set_xlabel("sample k")
    return fig


def plot_spread(per_run: dict, runs: int):
    """Monte Carlo spread of RMSE per scheme (violins), Table 1's values as red marks."""
    fig, axes = new_figure(1, 2, size=(11.0, 4.5),
                           title=f"Table 1 — RMSE per scheme over {runs} seeded runs (violins), paper's value (red ×)")
    for ax, key, name in zip(axes, ("ex1", "ex2"), ("Example 1 (constant y*)", "Example 2 (varying y*)")):
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
    fig, axes = new_figure(1, 2, size=(12.0, 4.5), title="RMSE of the four schemes against the noise std σ_v "
                                                           "(mean over the non-diverged seeded runs)")
    for ax, key in zip(axes, ("ex1", "ex2")):
        notes = []
        for s in SCHEMES:
            m = [row[0] for row in sweeps[key][s]["noise"]]
            ax.plot(levels[key], m, marker="o", color=COLORS[s], label=SCHEME_LABELS[s])
            notes.append(_mark_diverged(ax, levels[key], sweeps[key][s]["noise"], COLORS[s], SCHEME_LABELS[s]))
        ax.axvline(paper_levels[key], color="k", ls=":", lw=1, label="paper's σ_v")
        ax.set(xlabel="measurement-noise std σ_v", ylabel="RMSE (log scale)", yscale="log")
        _title_with_diverged(ax, "Example 1" if key == "ex1" else "Example 2", notes)
    _legend(axes[-1])
    return fig


def plot_ratio_sweep(sweeps: dict, paper_q: dict):
    """IKF-MFAC RMSE and K∞ against Q/R (beyond the paper), one panel per example."""
    fig, axes = new_figure(1, 2, size=(12.0, 4.5), title="IKF-MFAC: mean RMSE and steady gain K∞ against Q/R")
    for ax, key in zip(axes, ("ex1", "ex2")):
        _ratio_axes(ax, sweeps[key], "Example 1" if key == "ex1" else "Example 2")
        ax.axvline(paper_q[key], color="k", ls=":", lw=1)
        ax.set_title(("Example 1" if key == "ex1" else "Example 2") + f" (dotted: Q/R used, {paper_q[key]:.3g})")
    return fig


def plot_gain_sweep(values: dict, sweeps: dict, used: dict):
    """RMSE per scheme against ρ and λ (beyond the paper): rows examples, columns parameters."""
    fig, axes = new_figure(2, 2, size=(12.0, 7.5), title="RMSE of the four schemes against the step size ρ "
                                                           "and the weight λ (mean over the non-diverged seeded runs)")
    for i, key in enumerate(("ex1", "ex2")):
        for j, (name, sym) in enumerate((("rho", "ρ"), ("lam", "λ"))):
            ax = axes[i, j]
            notes = []
            for s in SCHEMES:
                ax.plot(values[name], [row[0] for row in sweeps[key][s][name]], marker="o", color=COLORS[s],
                        label=SCHEME_LABELS[s])
                notes.append(_mark_diverged(ax, values[name], sweeps[key][s][name], COLORS[s], SCHEME_LABELS[s]))
            ax.axvline(used[name], color="k", ls=":", lw=1, label="paper's value")
            ax.set(xlabel=sym, ylabel="RMSE")
            _title_with_diverged(ax, ("Example 1" if key == "ex1" else "Example 2") + f", RMSE vs {sym}", notes)
    _legend(axes[0, 1])
    return fig
