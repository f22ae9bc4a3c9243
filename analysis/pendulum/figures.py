"""Figures of the `pendulum` study: each function takes data and returns a matplotlib Figure."""

from __future__ import annotations

import numpy as np

from ctrl_analysis.report import new_figure

__all__ = [
    "plot_beyond",
    "plot_control_surface",
    "plot_fig3_states",
    "plot_fig4_output",
    "plot_filter_bode",
    "plot_gain_interpretations",
    "plot_riccati_convergence",
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
                           title=f"§2/§4 Riccati ODE Ṗ = AP + PAᵀ − PCᵀR⁻¹CP + ΓQΓᵀ: P(t) from four P(0), and the ARE solution P̄; "
                                 f"a21 = {a21:.4g} s⁻², Q = {Q:g}, R = {R:g}")
    entries = [((0, 0), "p11 = var φ̃  (rad²)"), ((0, 1), "p12 = cov(φ̃, φ̃')  (rad²/s)"),
               ((1, 1), "p22 = var φ̃'  (rad²/s²)")]
    colors = [f"C{k}" for k in range(len(trajectories))]
    for ax, ((r, c), label) in zip(axes.ravel()[:3], entries):
        for color, (name, P) in zip(colors, trajectories.items()):
            ax.plot(t, P[:, r, c], color=color, label=name)
        ax.axhline(P_bar[r, c], color="k", ls="--", lw=1.2, label=f"P̄ = {P_bar[r, c]:.5g}")
        ax.set_xlabel("t (s)")
        ax.set_ylabel(label + ", log scale")
        ax.set_yscale("log", nonpositive="mask")
        ax.set_ylim(bottom=1.0)
        ax.legend(fontsize=7, loc="lower right")
    ax = axes.ravel()[3]
    for color, (name, P) in zip(colors, trajectories.items()):
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
                           title="Beyond the paper (§4 gives no frequency response): what the correct steady-state filter passes\n"
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
                ax.axvline(w, color=f"C{k}", ls=":", lw=1.0,
                           label=f"pendulum pole √a21 = {w:.3g} rad/s" if ax is axes[0, 0] or ax is axes[0, 1] else None)
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
    styles = {"continuous": ("s", "C0", "continuous filter ARE"), "printed ARE (literal)": ("D", "C1", "printed ARE literally"),
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


def plot_fig3_states(cases: dict, T: float, run: int = 0):
    """Fig. 3: states before filtering (measured y and its backward difference) and after, with the true states.

    ``cases`` maps a title to a :class:`~.loops.ClosedLoopRun` with a filter (``phi_hat``).
    """
    fig, axes = new_figure(2, len(cases), size=(6.0 * len(cases), 7.5), sharex=True)
    axes = np.asarray(axes).reshape(2, len(cases))
    fig.suptitle(f"Fig. 3: pendulum states before and after filtering (closed loop, 0.1 rad step, run {run})")
    for c, (title, r) in enumerate(cases.items()):
        t = r.t
        dy = np.concatenate([[0.0], np.diff(r.y[:, run]) / T])
        rows = ((r.y[:, run], r.phi_hat[:, run], r.phi[:, run], "φ  (rad)", "measured y = φ + v"),
                (dy, r.dphi_hat[:, run], r.dphi[:, run], "φ'  (rad/s)", "backward difference of y"))
        for k, (raw, est, true, ylabel, rawlabel) in enumerate(rows):
            ax = axes[k, c]
            # the estimate under the raw signal, so that a raw trace equal to the estimate stays visible
            ax.plot(t, est, color="C0", lw=1.4, label="after: filter estimate", zorder=2)
            ax.plot(t, raw, color="0.35", lw=0.5, alpha=0.8, label=f"before: {rawlabel}", zorder=3)
            ax.plot(t, true, color="k", lw=1.0, ls="--", label="true state", zorder=4)
            ax.set_ylabel(ylabel)
            if k == 0:
                ax.set_title(title, fontsize=10)
            if k == 1:  # one legend per column, below the data
                ax.legend(handles=ax.get_lines()[:3],
                          labels=["after: filter estimate",
                                  "before: measured y = φ + v (top), its backward difference (bottom)",
                                  "true state"],
                          fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
        axes[1, c].set_xlabel("t (s)")
        lim = max(float(np.nanmax(np.abs(x))) for x in rows[1][:3])  # whole range: nothing clipped
        axes[1, c].set_ylim(-1.05 * lim, 1.05 * lim)
    return fig


def plot_fig4_output(cases: dict, step: float, run: int = 0):
    """Fig. 4: the closed-loop angle without and with filtering: one run and the mean ± std band over runs."""
    fig, axes = new_figure(1, len(cases), size=(5.0 * len(cases), 4.8), sharey=True)
    axes = np.asarray(axes).reshape(1, len(cases))
    fig.suptitle("Fig. 4: pendulum angle φ(t) before (no filter) and after filtering, 0.1 rad step")
    for c, (title, r) in enumerate(cases.items()):
        ax = axes[0, c]
        ok = ~r.diverged
        mean, std = np.mean(r.phi[:, ok], axis=1), np.std(r.phi[:, ok], axis=1)
        ax.plot(r.t, r.phi[:, run], color="C1", lw=0.7, label=f"run {run}")
        ax.plot(r.t, mean, color="C0", lw=1.4, label=f"mean over {int(ok.sum())} runs")
        ax.fill_between(r.t, mean - std, mean + std, color="C0", alpha=0.25, label="± 1 std")
        ax.axhline(step, color="k", ls="--", lw=0.8, label="reference r = 0.1 rad")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("t (s)")
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
    axes[0, 0].set_ylabel("φ  (rad)")
    return fig


def plot_beyond(est_cases: dict, angles, final: dict, T: float, run: int = 0):
    """Beyond the paper: estimation error of each filter in the loop, and recovery from initial angles."""
    fig, axes = new_figure(1, 2, size=(13.0, 5.0),
                           title="Beyond the paper: angle estimation error φ − φ̂ of each filter in the loop "
                                 f"(run {run}) and largest recoverable initial angle")
    ax = axes[0]
    for k, (name, r) in enumerate(est_cases.items()):
        err = r.phi[:, run] - r.phi_hat[:, run]
        stop = r.diverged_step[run] if r.diverged[run] else err.size
        ax.plot(r.t[:stop], err[:stop], color=f"C{k}", lw=0.8, label=name + (" (diverged)" if r.diverged[run] else ""))
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
