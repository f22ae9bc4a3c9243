"""Figures of the arena: Pareto fronts per signal class, ratio-to-bound heat map, best estimators on one signal, and
the start-up window."""

from __future__ import annotations

import numpy as np

from ..reporting.report import new_figure
from .interface import estimate, family
from .tuning import case_records, pareto_front

__all__ = ["PARETO_CAPTION", "save_all", "save_pareto"]


#: f̂' in matplotlib's mathtext (a combining circumflex does not render in the figures' font)
FHAT = r"$\hat{f}{}'$"


def _pareto(s, cases, tuned):
    noise = s.noises[0]
    eps = s.eps[len(s.eps) // 2]
    n = len(s.signals)
    ncols = min(n, 4)
    nrows = -(-n // ncols)
    fig, axes = new_figure(nrows, ncols, title=f"Pareto fronts: lag vs noise-induced error of {FHAT} ({noise} noise, "
                                               f"ε = {eps:g})", size=(3.6 * ncols + 1.6, 3.3 * nrows + 0.5))
    axes = np.array(axes).reshape(nrows, ncols)
    for j, sig in enumerate(s.signals):
        ax = axes.flat[j]
        ci = next(i for i, c in enumerate(cases) if c.signal == sig and c.noise == noise and c.eps == eps)
        for name, r in tuned.items():
            pts = np.array([[m[2], m[3]] for _, m in r["evaluated"][ci]])
            pts = pts[np.all(np.isfinite(pts), axis=1)]
            idx = pareto_front(pts)
            ax.loglog(pts[idx, 0], pts[idx, 1], ".-", label=name)
        ax.set_title(sig)
        if j + ncols >= n:  # no panel below
            ax.set_xlabel(f"lag: worst |{FHAT} - f'| without noise (1/s)")
        if j % ncols == 0:
            ax.set_ylabel(f"noise-induced RMS error of {FHAT} (1/s)")
        ax.grid(True, which="both", alpha=0.3)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    axes.flat[ncols - 1].legend(loc="center left", bbox_to_anchor=(1.02, 0.5), fontsize=8)
    return fig


def _heat(cases, table):
    fams = list(table)
    M = np.array([[table[n][c.key]["ratio"] for c in cases] for n in fams])
    A = np.array([[table[n][c.key]["adv_ratio"] for c in cases] for n in fams])
    fig, axes = new_figure(2, 1, title=f"Tuned worst-case error of {FHAT} / 2√(εL)",
                           size=(max(8, len(cases) / 3.5 + 3), 7.5))
    axes = np.array(axes).reshape(2, 1)
    adv = (f"adversarial pair of the bound's proof: {A.min():.3f}..{A.max():.3f}\n"
           "(≥ 1 for any causal estimator: a causality check, not a ranking)")
    for ax, data, what in ((axes[0, 0], M, "random records (seeded signals and noise)"), (axes[1, 0], A, adv)):
        im = ax.imshow(np.log10(data), aspect="auto", cmap="viridis")
        ax.set_yticks(range(len(fams)), fams)
        ax.set_title(what)
        cb = ax.figure.colorbar(im, ax=ax)
        cb.set_label("log10(ratio)")
    axes[1, 0].set_xticks(range(len(cases)), [c.key for c in cases], rotation=90, fontsize=6)
    axes[0, 0].set_xticks([])
    return fig


def _sample(s, cases, table):
    ci = len(s.eps) // 2
    case = cases[ci]
    setup = s.setup
    d1, y, _ = case_records(case, setup)
    fams = sorted(table, key=lambda n: table[n][case.key]["worst"])[:3]
    t = setup.dt * np.arange(setup.n)
    k = setup.k_from  # the scored window only (the start-up peaking is not scored and would hide it)
    t, d1 = t[k:], d1[k:]
    fig, axes = new_figure(2, 1,
                           title=f"Best 3 estimators of f' on one {case.signal} record ({case.noise}, ε = "
                           f"{case.eps:g}), "
                                       f"after the {setup.transient:g} s transient",
                           size=(9, 6), sharex=True)
    axes = np.array(axes).reshape(2, 1)
    axes[0, 0].plot(t, d1[:, 0], "k", lw=2, label="true f'")
    for name in fams:
        est = estimate(family(name), np.array([table[name][case.key]["params"]]), y[:, :1], setup.dt,
                       init=setup.init)[k:, 0, 1]
        axes[0, 0].plot(t, est, lw=1, label=name)
        axes[1, 0].plot(t, est - d1[:, 0], lw=1, label=name)
    for ax in axes[:, 0]:
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)
        ax.grid(True, alpha=0.3)
    axes[0, 0].set_ylabel("f' (1/s)")
    axes[1, 0].set_ylabel(f"{FHAT} - f' (1/s)")
    axes[1, 0].set_xlabel("time (s)")
    return fig


def _startup(s, cases, table):
    """One record's start-up (the best 3 families, at rest on the first sample and from zero), and every family's
    start-up error over all cases."""
    from dataclasses import replace

    case = cases[len(s.eps) // 2]
    setup = replace(s.setup, n=min(s.setup.n, s.setup.k_from + max(1, s.setup.k_from // 4)))
    d1, y, _ = case_records(case, s.setup)
    peak = float(np.max(np.abs(d1)))
    fams = sorted(table, key=lambda n: table[n][case.key]["worst"])[:3]
    t = setup.dt * np.arange(setup.n)
    fig, (ax, bx) = new_figure(2, 1, title=f"The start-up window (first {setup.transient:g} s), scored apart",
                               size=(9, 8))
    for i, name in enumerate(fams):
        P = np.array([table[name][case.key]["params"]])
        for init, ls in (("first", "-"), ("zero", ":")):
            est = estimate(family(name), P, y[:setup.n, :1], setup.dt, init=init)[:, 0, 1]
            ax.plot(t, (est - d1[:setup.n, 0]) / peak, ls, color=f"C{i}", lw=1.2 if ls == "-" else 1.0,
                    label=f"{name}, " + ("at rest on y0" if init == "first" else "from the zero state"))
    ax.axvline(setup.transient, color="k", lw=0.8)
    ax.set_yscale("symlog", linthresh=1.0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"({FHAT} - f') / max|f'|")
    ax.set_title(f"best 3 on one {case.signal} record ({case.noise}, ε = {case.eps:g}); scoring starts at the line",
                 fontsize=9)
    ax.legend(fontsize=7, ncol=2, loc="lower right")
    names = list(table)
    first = [max(table[n][c.key]["startup"] for c in cases) for n in names]
    zero = [max(table[n][c.key]["startup_zero"] for c in cases) for n in names]
    pos = np.arange(len(names))
    bx.barh(pos + 0.2, first, height=0.4, color="tab:blue", label="started at rest on the first sample")
    bx.barh(pos - 0.2, zero, height=0.4, color="tab:gray", label="started from the zero state")
    bx.set_yticks(pos, names)
    bx.set_xscale("log")
    bx.axvline(1.0, color="k", ls="--", lw=0.8)
    bx.set_xlabel(f"worst |{FHAT} - f'| in the start-up window / max|f'|, worst over {len(cases)} cases")
    bx.legend(fontsize=8)
    for a in (ax, bx):
        a.grid(True, which="both", alpha=0.3)
    return fig


#: The Pareto figure's caption.
PARETO_CAPTION = ("Per signal class, each family's Pareto front over every configuration evaluated: lag (worst "
                  "derivative error on the noise-free records) against noise-induced RMS error.")


def save_pareto(ctx, result, s, cases, tuned) -> None:
    """Draw and save the Pareto figure (sent first: it takes the longest to render).

    Parameters
    ----------
    ctx : StudyContext
    result : StudyResult
    s : ArenaSettings
    cases : list of Case
    tuned : dict
        :func:`~ctrl_analysis.arena.tuning.tune_family` output per family.
    """
    ctx.save_figure(result, _pareto(s, cases, tuned), "arena_pareto.png", dpi=120, caption=PARETO_CAPTION)


def save_all(ctx, result, s, cases, table) -> None:
    """Draw and save the other three arena figures with captions (after :func:`save_pareto`).

    Parameters
    ----------
    ctx : StudyContext
    result : StudyResult
    s : ArenaSettings
    cases : list of Case
    table : dict
    """
    # one after another: in a pool the heat map renders while the sample figure is drawn
    ctx.save_figure(result, _heat(cases, table), "arena_ratio_heatmap.png", caption=(
        "Each family's worst-case-tuned derivative error divided by the bound 2√(εL), per case (signal/noise/ε), on "
        "the random records (top) and on the bound's adversarial pair (bottom: at least 1 for any causal estimator, "
        "so a check of the construction and of causality, not a ranking)."))
    ctx.save_figure(result, _sample(s, cases, table), "arena_best_on_one_signal.png", caption=(
        "The three best-ranked families (worst-case tuning) on one record, over the scored window (after the "
        "transient): the derivative estimates and their errors."))
    ctx.save_figure(result, _startup(s, cases, table), "arena_startup.png", caption=(
        "The start-up window, which no tuning cost counts. Top: the derivative error of the three best-ranked "
        "families on one record, started at rest on the first sample (solid, the arena's start) and from the zero "
        "state (dotted), relative to max|f'| (log scale beyond ±1). Bottom: every family's worst start-up error over "
        "all cases, at its worst-case tuning, both ways (dashed: max|f'|)."))
