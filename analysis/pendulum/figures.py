"""Figures of the `pendulum` study: each function takes data and returns a matplotlib Figure."""

from __future__ import annotations

import numpy as np

from ctrl_analysis.reporting.report import new_figure

from .regimes import phi_band

__all__ = [
    "plot_beyond",
    "plot_control_surface",
    "plot_fig3_states",
    "plot_fig4_output",
    "plot_filter_bode",
    "plot_gain_interpretations",
    "plot_per_run_changes",
    "plot_qr_sweep",
    "plot_riccati_convergence",
    "plot_saturation",
]


def _drop_log_minor_ticks(fig) -> None:
    """No minor ticks on log axes (they slow rendering and clutter many-decade axes)."""
    from matplotlib.ticker import NullLocator

    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            if axis.get_scale() == "log":
                axis.set_minor_locator(NullLocator())


def plot_riccati_convergence(t, trajectories: dict, P_bar, a21: float, Q: float, R: float):
    """Entries of P(t) from several P(0), with P̄ dashed, and the relative distance to P̄."""
    fig, axes = new_figure(2, 2, size=(10.0, 7.0),
                           title=f"§2/§4 Riccati ODE Ṗ = AP + PAᵀ − PCᵀR⁻¹CP + ΓQΓᵀ: P(t) from four P(0), and the ARE "
                                 f"solution P̄; a21 = {a21:.4g} s⁻², Q = {Q:g}, R = {R:g}")
    entries = [((0, 0), "p11 = var φ̃  (rad²)"), ((0, 1), "p12 = cov(φ̃, φ̃')  (rad²/s)"),
               ((1, 1), "p22 = var φ̃'  (rad²/s²)")]
    colors = [f"C{k}" for k in range(len(trajectories))]
    for ax, ((r, c), label) in zip(axes.ravel()[:3], entries, strict=True):
        for color, (name, P) in zip(colors, trajectories.items(), strict=True):
            ax.plot(t, P[:, r, c], color=color, label=name)
        ax.axhline(P_bar[r, c], color="k", ls="--", lw=1.2, label=f"P̄ = {P_bar[r, c]:.5g}")
        ax.set_xlabel("t (s)")
        ax.set_ylabel(label + ", log scale")
        ax.set_yscale("log", nonpositive="mask")
        ax.set_ylim(bottom=1.0)
        ax.legend(fontsize=7, loc="lower right")
    ax = axes.ravel()[3]
    for color, (name, P) in zip(colors, trajectories.items(), strict=True):
        err = np.linalg.norm(P - P_bar, axis=(1, 2)) / np.linalg.norm(P_bar)
        ax.semilogy(t, np.maximum(err, 1e-16), color=color, label=name)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("‖P(t) − P̄‖ / ‖P̄‖  (Frobenius norm, –)")
    ax.set_title("relative distance to P̄", fontsize=10)
    ax.legend(fontsize=7, loc="best")
    _drop_log_minor_ticks(fig)
    return fig


def plot_filter_bode(filters: dict, omega, plant_poles=None):
    """Bode magnitude/phase of the steady-state filters y → (φ̂, φ̂') (python-control frequency_response).

    ``plant_poles``, if given, holds one frequency (rad/s) per filter, in the order of ``filters``: the
    pendulum's unstable open-loop pole √a21, drawn as a dotted vertical line in the filter's colour.
    """
    import control as ct

    fig, axes = new_figure(2, 2, size=(10.0, 6.5), sharex=True,
                           title="Beyond the paper (§4 gives no frequency response): what the correct steady-state "
                                 "filter passes\n"
                                 "Bode of the Kalman–Bucy filter x̂' = (A − KC) x̂ + K y (u = 0), y → x̂, K computed here")
    for k, (name, sys) in enumerate(filters.items()):
        resp = ct.frequency_response(sys, omega, squeeze=False)
        for out, (unit, col) in enumerate((("φ̂/y (–)", 0), ("φ̂'/y (1/s)", 1))):
            mag_db = 20 * np.log10(resp.magnitude[out, 0, :])
            phase = np.degrees(np.unwrap(resp.phase[out, 0, :]))
            axes[0, col].semilogx(omega, mag_db, color=f"C{k}", ls="-" if k == 0 else "--", label=name)
            axes[1, col].semilogx(omega, phase, color=f"C{k}", ls="-" if k == 0 else "--", label=name)
            axes[0, col].set_title(unit, fontsize=10)
            axes[0, col].set_ylabel("magnitude (dB)")
            axes[1, col].set_ylabel("phase (deg)")
            axes[1, col].set_xlabel("ω (rad/s)")
    if plant_poles is not None:
        for k, w in enumerate(plant_poles):
            for ax in axes.ravel():
                top = ax is axes[0, 0] or ax is axes[0, 1]
                ax.axvline(w, color=f"C{k}", ls=":", lw=1.0,
                           label=f"pendulum pole √a21 = {w:.3g} rad/s" if top else None)
    for ax in axes[0]:
        ax.legend(fontsize=7, loc="lower left")
    _drop_log_minor_ticks(fig)
    return fig




def plot_gain_interpretations(rows: list, K_paper, closest, a21_printed: float):
    """(α, β) of every interpretation, in three panels by the units of the gains, with the printed K in each.

    (a) continuous gains K = [k1 (1/s), k2 (1/s²)]; (b) discrete filter/predictor gains with β = k2
    (α dimensionless, k2 in 1/s); (c) discrete dimensionless α and β = T·k2 with Kalata's locus.
    """
    fig, axes = new_figure(1, 3, size=(16.0, 5.8),
                           title="§4 printed K = [α, β]ᵀ = [0.950, 0.863]ᵀ (red star) vs the steady-state gains of "
                                 "every interpretation tried, by units of the gains")
    panels = (
        (axes[0], lambda g: g.kind != "discrete", "(a) continuous ARE: K = [k1, k2]",
         "k1  (1/s)", "k2  (1/s²)"),
        (axes[1], lambda g: g.kind == "discrete" and g.beta_rule == "beta = k2",
         "(b) discrete, K = [α, k2]: α dimensionless, k2 in 1/s", "α = k1  (–)", "k2  (1/s)"),
        (axes[2], lambda g: g.kind == "discrete" and g.beta_rule == "beta = T k2",
         "(c) discrete, dimensionless α and β = T·k2 (Kalata)", "α = k1  (–)", "β = T·k2  (–)"),
    )
    styles = {"continuous": ("s", "C0", "continuous filter ARE"),
              "printed ARE (literal)": ("D", "C1", "printed ARE literally"),
              "filter": ("o", "C2", "filter form K"), "predictor": ("^", "C4", "predictor form L = FK")}
    for ax, sel, title, xlabel, ylabel in panels:
        sub = [g for g in rows if sel(g)]
        for key, (marker, color, label) in styles.items():
            for printed_a21 in (False, True):
                pts = [g for g in sub if (g.kind == key or g.form == key)
                       and (abs(g.a21 - a21_printed) < 1e-9) == printed_a21]
                if pts:
                    ax.scatter([g.alpha for g in pts], [g.beta for g in pts], s=24, marker=marker, alpha=0.8,
                               facecolors="none" if printed_a21 else color, edgecolors=color,
                               label=label + (", a21 = 2.6149" if printed_a21 else ", a21 = g·B"))
        if sub and closest in sub:
            ax.scatter([closest.alpha], [closest.beta], s=170, facecolors="none", edgecolors="k", lw=1.5,
                       label=f"closest ({closest.error:.0%} max rel. error)")
        if "Kalata" in title:
            a = np.linspace(1e-4, 0.9999, 400)
            ax.plot(a, 2 * (2 - a) - 4 * np.sqrt(1 - a), "k-", lw=1, label="Kalata locus β = 2(2−α) − 4√(1−α)")
        ax.scatter([K_paper[0]], [K_paper[1]], s=240, marker="*", color="red", zorder=5,
                   label="paper (0.950, 0.863) in these units")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=10)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
    _drop_log_minor_ticks(fig)
    return fig


def plot_control_surface(E, EC, U, Ku: float, Ke: float, Kec: float):
    """The fuzzy controller's control surface U(E, EC) (query table) and three slices, in physical units."""
    fig, axes = new_figure(1, 2, size=(13.0, 5.0), gridspec_kw={"wspace": 0.12},
                           title="§3.2 fuzzy controller: control surface u = Ku·U(Ke·e, Kec·ec) "
                                 "(7 triangular terms, U = sat(E + EC, ±3), min–max, centroid)")
    ax = axes[0]
    cs = ax.contourf(E / Ke, EC / Kec, (Ku * U).T, levels=29, cmap="RdBu_r")
    fig.colorbar(cs, ax=ax, label="u  (m/s²)")
    ax.set_xlabel("e = r − φ  (rad)")
    ax.set_ylabel("ec = ė  (rad/s)")
    ax.set_title("u(e, ec) on the quantised universes [−6, 6]²", fontsize=10)
    ax = axes[1]
    for k, ec_q in enumerate((-3.0, 0.0, 3.0)):
        j = int(np.argmin(np.abs(EC - ec_q)))
        ax.plot(E / Ke, Ku * U[:, j], color=f"C{k}", label=f"ec = {EC[j] / Kec:.2g} rad/s (EC = {EC[j]:.2g})")
    ax.set_xticks(np.linspace(-0.08, 0.08, 5))
    ax.set_xlabel("e  (rad)")
    ax.set_ylabel("u  (m/s²)")
    ax.set_title("slices at fixed ec", fontsize=10)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    return fig


def plot_fig3_states(cases: dict, run: int = 0):
    """Fig. 3: states before filtering (measured y, its backward difference) and after (the estimate), with the true
    states, and the errors before and after in separate panels (so neither hides the other).

    ``cases`` maps a column title to a :class:`~.loops.ClosedLoopRun` with a filter (``phi_hat``).
    """
    n = len(cases)
    fig, axes = new_figure(6, n, size=(5.6 * n, 13.5), sharex=True,
                           gridspec_kw={"height_ratios": [1.4, 1, 1, 1.4, 1, 1]})
    axes = np.asarray(axes).reshape(6, n)
    fig.suptitle(f"Fig. 3: pendulum states before and after filtering (closed loop, 0.1 rad step, run {run}); "
                 "before = measured y and its backward difference, after = filter estimate", fontsize=11)
    for c, (title, r) in enumerate(cases.items()):
        t, T = r.t, r.t[1] - r.t[0]
        dy = np.concatenate([[np.nan], np.diff(r.y[:, run]) / T])
        rows = ((r.y[:, run], r.phi_hat[:, run], r.phi[:, run], "φ", "rad", "measured y"),
                (dy, r.dphi_hat[:, run], r.dphi[:, run], "φ'", "rad/s", "backward difference Δy/T"))
        for k, (raw, est, true, sym, unit, rawlabel) in enumerate(rows):
            ax, eb, ea = axes[3 * k, c], axes[3 * k + 1, c], axes[3 * k + 2, c]
            ax.plot(t, est, color="C0", lw=1.1, label="after: filter estimate (line)", zorder=2)
            ax.plot(t, raw, ".", color="0.3", ms=1.6, label=f"before: {rawlabel} (dots)", zorder=3)
            ax.plot(t, true, color="k", lw=1.0, ls="--", label="true state (dashed)")
            ax.set_ylabel(f"{sym}  ({unit})")
            lo, hi = np.nanpercentile(np.concatenate([raw, est, true]), [0.5, 99.5])
            ax.set_ylim(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo))
            before, after = raw - true, est - true
            lim = 1.1 * np.nanmax(np.abs(np.concatenate([before, after])))
            eb.plot(t, before, color="0.45", lw=0.6)
            ea.plot(t, after, color="C0", lw=0.6)
            for a, err, name in ((eb, before, "before"), (ea, after, "after")):
                a.set_ylim(-lim, lim)
                a.set_ylabel(f"{name}: error\n({unit})", fontsize=8)
                a.text(0.99, 0.95, f"{name}: RMS {np.sqrt(np.nanmean(err ** 2)):.3g} {unit}", transform=a.transAxes,
                       ha="right", va="top", fontsize=8, bbox={"fc": "white", "ec": "none", "alpha": 0.8})
            if c == 0:
                ax.legend(fontsize=7, loc="lower right", markerscale=4)
        axes[0, c].set_title(title, fontsize=9)
        axes[-1, c].set_xlabel("t (s)")
    return fig


def plot_fig4_output(regimes: dict, step: float, run: int = 0):
    """Fig. 4: the closed-loop angle per case and regime: one run, the mean ± std band over runs, and noise-free.

    ``regimes`` maps a row title to ``{column title: CaseRuns}``; each regime gets a full-scale row and a zoom
    around the reference (where the noise and the filters' differences are visible).
    """
    nr, nc = 2 * len(regimes), max(len(v) for v in regimes.values())
    fig, axes = new_figure(nr, nc, size=(5.0 * nc, 3.0 * nr + 1.0), sharex=True)
    axes = np.asarray(axes).reshape(nr, nc)
    fig.suptitle("Fig. 4: pendulum angle φ(t) without and with filtering after the 0.1 rad step, per noise regime "
                 "(each regime: full scale, then zoomed around r)")
    for i, (row, cases) in enumerate(regimes.items()):
        dev = 0.0
        for c, (title, cr) in enumerate(cases.items()):
            r = cr.noisy
            mean, std, n_ok = phi_band(r)
            late = r.t >= 0.5
            dev = max(dev, float(np.max(np.abs(r.phi[late, run] - step))))
            for ax in axes[2 * i:2 * i + 2, c]:
                ax.fill_between(r.t, mean - std, mean + std, color="C0", alpha=0.25, label="± 1 std over runs")
                ax.plot(r.t, r.phi[:, run], color="C1", lw=0.6, label=f"run {run}")
                ax.plot(r.t, mean, color="C0", lw=1.6, label=f"mean over {n_ok} runs")
                ax.plot(cr.quiet.t, cr.quiet.phi[:, 0], color="k", lw=1.0, ls="--", label="noise-free")
                ax.axhline(step, color="0.3", ls=":", lw=0.8, label="reference r = 0.1 rad")
            if i == 0:
                axes[0, c].set_title(title, fontsize=10)
        for ax in axes[2 * i + 1]:
            ax.set_ylim(step - 1.15 * dev, step + 1.15 * dev)
        axes[2 * i, 0].set_ylabel(f"{row}\nφ  (rad)", fontsize=8)
        axes[2 * i + 1, 0].set_ylabel("zoom around r\nφ  (rad)", fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=5, fontsize=8, bbox_to_anchor=(0.5, 0.0))
    return fig


def plot_saturation(stats: dict, labels: dict):
    """Beyond the paper: per case and regime, the fraction of steady samples with each fuzzy input saturated, and the
    acceleration RMS. ``stats`` = ``{regime title: {case: {metric: (value, std, n)}}}``."""
    fig, axes = new_figure(1, 3, size=(16.0, 5.2), gridspec_kw={"wspace": 0.35},
                           title="Fuzzy inputs saturated by noise (steady-state window) and cart acceleration RMS, "
                                 "per case and noise regime")
    for k, (reg, st) in enumerate(stats.items()):
        ax = axes[k]
        names = list(st)
        y = np.arange(len(names))
        for j, (m, col, lab) in enumerate((("sat_e", "C2", "e (angle error) saturated"),
                                           ("sat_ec", "C3", "ec (rate) saturated"))):
            v = [np.nan if st[n][m][0] is None else 100 * st[n][m][0] for n in names]
            ax.barh(y + (0.2 if j == 0 else -0.2), v, height=0.38, color=col, label=lab)
            for yi, vi in zip(y, v, strict=True):
                ax.text(0 if np.isnan(vi) else vi, yi + (0.2 if j == 0 else -0.2),
                        " diverged" if np.isnan(vi) else f" {vi:.2g} %", va="center", fontsize=7)
        ax.set_yticks(y, [labels.get(n, n) for n in names], fontsize=8)
        ax.invert_yaxis()
        ax.set_xlim(0, 100)
        ax.set_xlabel("steady-state samples saturated (%)")
        ax.set_title(reg, fontsize=9)
        ax.legend(fontsize=7, loc="lower right")
    ax = axes[2]
    regs = list(stats)
    names = list(dict.fromkeys(n for st in stats.values() for n in st))
    y = np.arange(len(names))
    for j, reg in enumerate(regs):
        v = [stats[reg].get(n, {}).get("accel_rms", (None,))[0] for n in names]
        v = [np.nan if x is None else x for x in v]
        ax.barh(y + (0.2 if j == 0 else -0.2), v, height=0.38, color=f"C{j}", label=reg.split(" (")[0])
    ax.set_xscale("log")
    ax.set_yticks(y, [labels.get(n, n) for n in names], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("steady-state RMS of the cart acceleration u (m/s², log)")
    ax.set_title("acceleration RMS (missing bar: not simulated or diverged)", fontsize=9)
    ax.legend(fontsize=7, loc="lower right")
    _drop_log_minor_ticks(fig)
    return fig


def plot_qr_sweep(qr: dict, paper_ratio: float, main_ratio: float, alpha_paper: float):
    """Beyond the paper: angle-estimate error and closed-loop angle RMS against σ_w/σ_v, and the optimal α."""
    few = any(np.any(np.asarray(v) < 0.8) for v in qr["healthy"].values())
    fig, axes = new_figure(1, 3, size=(16.0, 5.0), gridspec_kw={"wspace": 0.3},
                           title="σ_w/σ_v swept independently (main σ_v and T): where the paper's K is, and is not, "
                                 "the best constant gain" + ("\n(hollow marker: mean over < 80 % of the runs; no "
                                                             "marker: every run fell)" if few else ""))
    r = qr["ratios"]
    names = {"nofilter": ("no filter", "C7", "s"), "filter": ("paper's K", "C3", "o"),
             "kf_ss": ("optimal steady-state gain for the ratio", "C0", "^")}
    for ax, key, ylabel in ((axes[0], "est", "steady RMS of φ_in − φ  (rad, log)"),
                            (axes[1], "angle", "steady RMS of φ − r  (rad, log)")):
        for n, (lab, col, mk) in names.items():
            few = np.asarray(qr["healthy"][n]) < 0.8  # a mean over < 80 % of the runs: hollow marker
            ax.loglog(r, qr[key][n], color=col, label=lab, lw=1.2)
            ax.plot(r[~few], np.asarray(qr[key][n])[~few], mk, color=col)
            if few.any():
                ax.plot(r[few], np.asarray(qr[key][n])[few], mk, mfc="none", color=col, ms=8)
        ax.set_ylabel(ylabel)
    axes[0].set_title("error of the angle the controller receives", fontsize=9)
    axes[1].set_title("closed-loop angle error", fontsize=9)
    axes[2].semilogx(r, qr["alpha_opt"], "o-", color="C0", label="optimal steady-state α")
    axes[2].axhline(alpha_paper, color="C3", ls="--", label=f"paper's α = {alpha_paper}")
    axes[2].set_ylabel("α  (–)")
    axes[2].set_title("optimal α against the paper's", fontsize=9)
    for ax in axes:
        ax.axvline(paper_ratio, color="k", ls=":", lw=1, label=f"paper's √(Q/R) = {paper_ratio:.3g}")
        ax.axvline(main_ratio, color="C2", ls="-.", lw=1, label=f"main regime {main_ratio:.3g}")
        ax.set_xlabel("σ_w/σ_v  (s⁻², log)")
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    _drop_log_minor_ticks(fig)
    return fig


def plot_beyond(est_cases: dict, angles, final: dict, T: float, run: int = 0):
    """Beyond the paper: estimation error of each filter in the loop, and recovery from initial angles."""
    fig, axes = new_figure(1, 2, size=(13.0, 5.0),
                           title="Beyond the paper: angle estimation error φ − φ̂ of each filter in the loop "
                                 f"(run {run}) and largest recoverable initial angle")
    ax = axes[0]
    styles = ("-", (0, (4, 2)), "-", "-")  # the time-varying KF dashed: after its transient it equals the steady gain
    for k, (name, r) in enumerate(est_cases.items()):
        err = r.phi[:, run] - r.phi_hat[:, run]
        stop = r.diverged_step[run] if r.diverged[run] else err.size
        # the steady-state gain (k = 2) wide and pale, the time-varying KF (k = 1) dashed on top of it
        ax.plot(r.t[:stop], err[:stop], color=f"C{k}", lw={1: 0.9, 2: 2.6}.get(k, 0.8), ls=styles[k % len(styles)],
                alpha=0.55 if k == 2 else 1.0, zorder=3 if k == 1 else 2,
                label=name + (f" (diverged/fell at t = {r.t[stop]:.2g} s)" if r.diverged[run] else ""))
    ax.set_yscale("symlog", linthresh=1e-3)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("φ − φ̂  (rad, symlog)")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
    ax = axes[1]
    for k, (name, ok) in enumerate(final.items()):
        ax.plot(angles, np.where(ok, 1.0, 0.0) + 0.03 * k, marker="o", ms=3, color=f"C{k}", label=name)
    ax.set_yticks([0, 1], ["falls / not settled", "recovers"])
    ax.set_xlabel("initial angle φ(0)  (rad)")
    ax.set_title("noise-free regulation to r = 0 from rest", fontsize=10)
    ax.legend(fontsize=8, loc="center left")
    return fig


def plot_per_run_changes(regimes: dict, thresholds: dict):
    """§5/abstract claims, per run: each run's change against no filter (same noise), per measure and filter.

    ``regimes`` = ``{row title: {measure: {filter label: per-run relative changes}}}``; ``thresholds`` =
    ``{measure: (value, label)}``, the change each claim asks for (drawn as a dashed line).
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    rows = list(regimes)
    fig, axes = new_figure(len(rows), 1, size=(13.0, 4.3 * len(rows) + 0.4),
                           title="§5 / abstract claims per run: change with a filter against no filter, same noise "
                                 "(boxes: quartiles, whiskers 5-95 %, dots: runs)")
    axes = np.atleast_1d(axes)
    colors = ("C0", "C2")
    for ax, row in zip(axes, rows, strict=True):
        measures = list(regimes[row])
        labels = list(dict.fromkeys(lab for m in measures for lab in regimes[row][m]))
        width = 0.8 / len(labels)
        rng = np.random.default_rng(0)
        low = -100.0
        for i, m in enumerate(measures):
            for j, lab in enumerate(labels):
                v = 100 * np.asarray(regimes[row][m].get(lab, []), dtype=float)
                v = v[np.isfinite(v)]
                if not v.size:
                    continue
                low = min(low, float(np.min(v)))
                x = i + (j - (len(labels) - 1) / 2) * width
                ax.boxplot([v], positions=[x], widths=0.8 * width, whis=(5, 95), showfliers=False,
                           patch_artist=True, boxprops={"facecolor": colors[j % 2], "alpha": 0.35},
                           medianprops={"color": "k"})
                ax.plot(x + rng.uniform(-0.25, 0.25, v.size) * width, v, ".", ms=2.5, color=colors[j % 2], alpha=0.6)
                ax.annotate(f"lower in {np.mean(v < 0):.0%}\nmedian {np.median(v):+.0f} %", (x, 0.99),
                            xycoords=("data", "axes fraction"), ha="center", va="top", fontsize=7)
            if m in thresholds:
                val, tlab = thresholds[m]
                ax.hlines(100 * val, i - 0.45, i + 0.45, colors="C3", linestyles="--", lw=1.2)
                ax.annotate(tlab, (i + 0.45, 100 * val), ha="right", va="bottom", fontsize=7, color="C3")
        ax.axhline(0.0, color="0.3", lw=0.8)
        ax.set_xticks(range(len(measures)), measures, fontsize=8)
        ax.set_ylabel("change against no filter\n(% of the no-filter median)")
        ax.set_title(row, fontsize=9)
        ax.set_ylim(low - 10, max(60, ax.get_ylim()[1]))
        handles = [Patch(color=colors[j % 2], alpha=0.5, label=lab) for j, lab in enumerate(labels)]
    fig.legend(handles=handles + [Line2D([], [], color="C3", ls="--", label="the change the claim asks for (chosen "
                                         "reading of its words)")], fontsize=8, loc="outside lower center", ncol=3)
    return fig
