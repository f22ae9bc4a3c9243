"""Figures of the study: functions that take data and return a ``matplotlib.figure.Figure`` (saving is the caller's)."""

from __future__ import annotations

import control as ct
import numpy as np

from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.reporting.report import new_figure

from .linear_checks import min_stable_gain, peak

__all__ = ["plot_root_locus", "plot_bode", "plot_normalised_magnitude", "plot_x2", "plot_tradeoff", "plot_fig5",
           "plot_literal", "plot_stability_map", "BODE_OMEGA"]

BODE_OMEGA = np.logspace(-1, 4, 2000)  # rad/s, Fig. 2


def plot_root_locus(est: DifferentialEstimator, *, printed_K: float | None = None, printed_n=None,
                    title: str = ""):
    """Root locus of G(s) = K (s+a)^(n0-1)/s^n0 over K > 0, design poles "x", breakaway annotated.

    Left panel: overview with the breakaway point; right panel: zoom on the origin, where the
    branches leave the n0-fold pole (some into the right half-plane) and the slow design poles sit.
    """
    n0, a, k_design = est.n0, est.a, est.K
    g_unit = est.open_loop_tf / k_design  # (s + a)^(n0-1) / s^n0
    gains = np.unique(np.concatenate([
        [0.0],
        np.logspace(-16, 4, 1000) * k_design,
        np.linspace(0.95, 1.05, 101) * k_design,
        [k_design],
    ]))
    loci = ct.root_locus_map(g_unit, gains).loci
    s_b = est.breakaway_point
    design = est.poles

    fig, axes = new_figure(1, 2, title=title, size=(12.0, 5.2), width_ratios=[1.6, 1.0])
    k_min = min_stable_gain(n0, a)
    p_min = DifferentialEstimator(n0, a, k_min, allow_unstable=True).poles if k_min > 0 else np.array([])
    crossing = p_min[np.abs(p_min.real) < 1e-6 * max(1.0, a)]
    views = [((2.5 * s_b, -0.3 * s_b), (1.2 * s_b, -1.2 * s_b)), ((-1.9 * a, 0.8 * a), (-1.5 * a, 1.5 * a))]
    for _panel, (ax, (xlim, ylim)) in enumerate(zip(axes, views, strict=True)):
        for j in range(loci.shape[1]):
            ax.plot(loci[:, j].real, loci[:, j].imag, color="C0", lw=1.3,
                    label="root locus, K from 0 to ∞" if j == 0 else None)
        ax.plot([0], [0], "s", mfc="none", mec="k", ms=9, label=f"open-loop poles (×{n0} at 0)")
        ax.plot([-a], [0], "o", mfc="none", mec="k", ms=9, label=f"open-loop zeros (×{n0 - 1} at −a = {-a:g})")
        ax.plot(design.real, design.imag, "x", color="C3", ms=11, mew=2.2,
                label=f"closed-loop poles at K = {k_design:.4g} (design)")
        if printed_K is not None:
            p_pr = DifferentialEstimator(n0, a, printed_K, allow_unstable=True).poles
            ax.plot(p_pr.real, p_pr.imag, "+", color="C1", ms=11, mew=2.0,
                    label=f"closed-loop poles at printed eq. (9), n = {printed_n}: K = {printed_K:.4g}")
        if crossing.size:
            ax.plot(crossing.real, crossing.imag, "D", color="C4", ms=6,
                    label=f"imaginary-axis crossing, K = {k_min:.4g} (Σ stable only for K > {k_min:.4g})")
        ax.axhline(0, color="0.5", lw=0.6)
        ax.axvline(0, color="0.5", lw=0.6)
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_xlabel("Re s  [1/s]")
        ax.set_ylabel("Im s  [1/s]")
    ax0, ax1 = axes
    ax0.annotate(
        f"breakaway (break-in) point s = −n0·a = {s_b:g}\n(double pole at K = n0^n0·a/(n0−1)^(n0−1) = {k_design:.4g})",
        xy=(s_b, 0), xytext=(1.65 * s_b, 0.8 * abs(s_b)),
        arrowprops=dict(arrowstyle="->", color="C3"), ha="center", fontsize=9, color="C3",
    )
    ax0.set_title("overview")
    ax1.set_title("zoom near the origin")
    ax0.legend(loc="lower left", fontsize=8, framealpha=0.9)
    return fig


def plot_bode(est: DifferentialEstimator, omega=BODE_OMEGA, *, title: str = ""):
    """Bode magnitude (dB) and phase (deg) of Φ(s), −3 dB line, bandwidth, peak, hf asymptote."""
    phi = est.tf
    resp = ct.frequency_response(phi, omega)
    mag_db = 20 * np.log10(np.abs(resp.magnitude))
    phase_deg = np.degrees(np.unwrap(resp.phase))
    bw = float(ct.bandwidth(phi))
    peak_db, w_peak = peak(est)

    fig, (axm, axp) = new_figure(2, 1, title=title, size=(8.0, 6.5), sharex=True)
    axm.semilogx(omega, mag_db, color="C0", lw=2.2, label="|Φ(jω)|", zorder=3)
    axm.semilogx(omega, 20 * np.log10(est.a_coeffs[0] / omega), "--", color="0.3", lw=0.9, zorder=4,
                 label=f"high-frequency asymptote a₁/ω (−20 dB/dec), a₁ = K = {est.K:.4g}")
    axm.axhline(-3, color="C3", ls=":", lw=1.2, label="−3 dB")
    axm.axvline(bw, color="C3", ls=":", lw=1.2)
    axm.plot([bw], [-3], "o", color="C3", label=f"bandwidth ω_b = {bw:.4g} rad/s")
    axm.plot([w_peak], [peak_db], "^", color="C2", label=f"resonance peak {peak_db:.3g} dB at {w_peak:.4g} rad/s")
    axm.set_ylim(max(mag_db.min(), -60) - 5, peak_db + 5)
    axm.set_ylabel("magnitude [dB]")
    axm.legend(loc="lower left", fontsize=8)
    axp.semilogx(omega, phase_deg, color="C0", lw=1.8)
    axp.axvline(bw, color="C3", ls=":", lw=1.2)
    axp.set_ylabel("phase [deg]")
    axp.set_xlabel("frequency ω [rad/s]")
    axp.set_yticks(np.arange(-180, 91, 45))
    axp.set_ylim(min(-100, phase_deg.min() - 10), max(10, phase_deg.max() + 10))
    return fig


def plot_normalised_magnitude(n0_values, *, title: str = ""):
    """|Φ(jω)| against ω/a for several n0 (Φ depends on a only through ω/a)."""
    fig, ax = new_figure(title=title, size=(8.0, 4.8))
    w_over_a = np.logspace(-2, 3, 1500)
    for k, n0 in enumerate(n0_values):
        phi = DifferentialEstimator(n0, 1.0).tf
        ax.semilogx(w_over_a, 20 * np.log10(np.abs(phi(1j * w_over_a))), color=f"C{k}", label=f"n0 = {n0}")
    ax.axhline(-3, color="k", ls=":", lw=1, label="−3 dB")
    ax.set_xlabel("normalised frequency ω / a  [–]")
    ax.set_ylabel("|Φ(jω)|  [dB]")
    ax.set_ylim(-40, 6)
    ax.legend(fontsize=8, ncol=2)
    return fig


def plot_x2(t, x2, x2_hat, title: str, label: str, zoom=(10.0, 10.5)):
    """True x2 and an estimate (top), the error (middle), both over a short window ``zoom`` (bottom, s).

    The zoom shows the estimate's waveform where, over the whole run, high-frequency noise
    fills the trace into a solid band. A run that ends before ``zoom`` (``--quick``) is zoomed over its
    last stretch of the same length instead.
    """
    if zoom[1] > t[-1]:
        zoom = (max(t[0], t[-1] - (zoom[1] - zoom[0])), t[-1])
    fig, (ax, ax_e, ax_z) = new_figure(3, 1, title=title, size=(8.0, 7.0),
                                       gridspec_kw={"height_ratios": [2, 1, 1.3]})
    ax.plot(t, x2_hat, color="tab:red", lw=0.6, alpha=0.85, label=label)
    ax.plot(t, x2, color="k", lw=1.3, label=r"$x_2$ (true)")  # on top of a noisy estimate
    ax.axvspan(*zoom, color="0.6", alpha=0.35, lw=0, label="zoom (bottom)")
    ax.set_ylabel(r"$x_2 = \dot x_1$ (1/s)")
    ax.set_xlabel("t (s)")
    ax.set_xlim(t[0], t[-1])
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax_e.plot(t, x2 - x2_hat, color="tab:blue", lw=0.6)
    ax_e.set_ylabel(r"$x_2 - \hat x_2$ (1/s)")
    ax_e.set_xlabel("t (s)")
    ax_e.set_xlim(t[0], t[-1])
    w = (t >= zoom[0]) & (t <= zoom[1])
    ax_z.plot(t[w], x2_hat[w], color="tab:red", lw=0.8, label=label)
    ax_z.plot(t[w], x2[w], color="k", lw=1.3, label=r"$x_2$ (true)")
    ax_z.set_xlim(*zoom)
    ax_z.set_ylabel(r"$x_2,\ \hat x_2$ (1/s)")
    ax_z.set_xlabel(f"t (s), zoom {zoom[0]:g}-{zoom[1]:g} s")
    return fig


def plot_tradeoff(trade: dict, sigma_point, title: str):
    """x2 error against x1 error over the bandwidth grid: Σ, linear ESO, Han's fal ESO points.

    Left: every point (Σ filled circles under the linear ESO's hollow squares, so coincident points
    both show; each bandwidth labelled once, left of its Σ point). Right: a zoom on the low-bandwidth
    corner where Σ as in the paper, the fal ESO at Σ's bandwidth and the neighbouring sweep points
    crowd, each labelled with an arrow.
    """
    from matplotlib.patches import Rectangle
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    bws, curves, fal = trade["bws"], trade["curves"], trade["fal"]
    bw_s = trade["fal_bw"]["equal_bw"]
    fig, (ax, az) = new_figure(1, 2, title=title, size=(13.0, 5.8), width_ratios=[1.25, 1.0])
    near = (bws >= bw_s / 2) & (bws <= 2.5 * bw_s)
    pts = np.vstack([curves["sigma"][near], curves["leso"][near], fal["equal_bw"][None], np.asarray(sigma_point)[None]])
    lo, hi = pts.min(axis=0) / 1.12, pts.max(axis=0) * 1.15
    fal_style = {"textbook": ("^",
                              "Han's fal ESO, step-size gains for h' = 1 ms (the paper's tuning as reconstructed)"),
                 "equal_bw": ("v", "Han's fal ESO tuned to Σ's bandwidth")}
    for axis, zoom in ((ax, False), (az, True)):
        axis.loglog(curves["sigma"][:, 0], curves["sigma"][:, 1], "o-", color="C0", ms=6, zorder=3,
                    label="Σ (n0 = 5), a swept")
        axis.loglog(curves["leso"][:, 0], curves["leso"][:, 1], "s--", color="C1", ms=10, mfc="none", mew=1.5,
                    zorder=4, label="linear ESO, ω_o swept (hollow)")
        for k, (mk, name) in fal_style.items():
            e = fal[k]
            axis.loglog([e[0]], [e[1]], mk, color="C3", ms=10, mfc="none", mew=2, zorder=5,
                        label=f"{name}: {trade['fal_bw'][k]:.0f} rad/s")
        axis.loglog([sigma_point[0]], [sigma_point[1]], "*", color="k", ms=17, mfc="none", mew=1.3, zorder=2,
                    label=f"Σ as in the paper (a = 7): {bw_s:.0f} rad/s")
        box = dict(boxstyle="round,pad=0.15", fc="w", ec="none", alpha=0.85)
        for bw, (e1, e2), inside in zip(bws, curves["sigma"], near, strict=True):
            if inside == zoom:
                axis.annotate(f"{bw:.0f}", (e1, e2), textcoords="offset points", xytext=(-8, 6), ha="right",
                              fontsize=8, color="C0", bbox=box, zorder=6)
        axis.set_xlabel("mean |x1 − x̂1|  [–]")
        axis.set_ylabel("mean |x2 − x̂2|  [1/s]")
        fmt = FuncFormatter(lambda v, _: f"{v:.1e}".replace("e-0", "e-"))
        subs = (1.2, 1.4, 1.6, 1.8, 2.0) if zoom else (2.0, 5.0)
        axis.xaxis.set_minor_locator(LogLocator(base=10.0, subs=subs))
        axis.xaxis.set_minor_formatter(fmt)
        axis.xaxis.set_major_formatter(fmt)
        if zoom:
            axis.yaxis.set_minor_locator(LogLocator(base=10.0, subs=(5.0, 6.0, 8.0, 10.0, 12.0, 15.0)))
            axis.yaxis.set_minor_formatter(fmt)
        else:
            axis.yaxis.set_minor_formatter(NullFormatter())
    ax.add_patch(Rectangle((lo[0], lo[1]), hi[0] - lo[0], hi[1] - lo[1], fill=False, ec="0.4", ls=":", lw=1.0,
                           zorder=1))
    ax.set_title("all bandwidths (labels: −3 dB bandwidth, rad/s; dotted box: zoom, right)", fontsize=9)
    az.set_xlim(lo[0], hi[0])
    az.set_ylim(lo[1], hi[1])
    az.set_title(f"zoom: bandwidths {bw_s / 2:.0f}-{2.5 * bw_s:.0f} rad/s around Σ's {bw_s:.0f} rad/s", fontsize=9)
    for e, text, off in ((fal["equal_bw"], "fal ESO at Σ's bandwidth", (40, 16)),
                         (sigma_point, "Σ as in the paper (a = 7)", (36, -26))):
        az.annotate(text, (e[0], e[1]), textcoords="offset points", xytext=off, fontsize=8, color="0.15",
                    arrowprops=dict(arrowstyle="->", color="0.3", lw=0.8), bbox=dict(boxstyle="round,pad=0.2",
                                                                                    fc="w", ec="0.6"), zorder=7)
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=2, fontsize=8,
               title="lower left is better; points at the same bandwidth compare the observers fairly",
               title_fontsize=8)
    return fig


def plot_fig5(t, r, v, runs, title: str):
    """Fig. 5 side by side: per preset, v and x1 (top), x1 − v (middle), x2 and its estimate x̂2 (bottom)."""
    fig, axes = new_figure(3, len(runs), size=(7.0 * len(runs), 8.0), sharex=True, title=title,
                           gridspec_kw={"height_ratios": [3, 1.5, 2]})
    axes = np.atleast_2d(axes).reshape(3, len(runs))
    for j, (label, d) in enumerate(runs):
        ax, ax_e, ax_x = axes[:, j]
        ax.plot(t, r, color="0.6", lw=0.8, ls=":", label=r"$r = \mathrm{sign}(\cos 0.15t)$")
        ax.plot(t, v, color="k", lw=1.4, label="setpoint v (softened r)")
        ax.plot(t, d["x[0]"], color="tab:red", lw=0.9, ls="--", label=r"output $x_1$")
        ax.plot(t, d["xhat[0]"], color="tab:green", lw=0.6, alpha=0.8, label=r"estimate $\hat x_1 = z_1$")
        ax.set_title(label, fontsize=10)
        ax.set_ylabel(r"$v$, $x_1$")
        ax_e.plot(t, d["x[0]"] - v, color="tab:red", lw=0.6)
        ax_e.set_ylabel(r"$x_1 - v$")
        ax_x.plot(t, d["xhat[1]"], color="tab:green", lw=0.6, alpha=0.7, label=r"$\hat x_2 = z_2$")
        ax_x.plot(t, d["x[1]"], color="k", lw=1.0, label=r"$x_2$", zorder=3)
        ax_x.set_ylabel(r"$x_2$, $\hat x_2$ (1/s)")
        ax_x.set_xlabel("t (s)")
        ax_x.set_xlim(t[0], t[-1])
    axes[0, -1].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    axes[2, -1].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    return fig


def plot_literal(t, v, x1, u, zoom, title: str, subtitle: str):
    """The printed loop: v and x1 over the horizon, x1 − v and u in a zoom window."""
    fig, (ax, ax_e, ax_u) = new_figure(3, 1, size=(8.0, 7.5), gridspec_kw={"height_ratios": [3, 2, 2]}, title=title)
    ax.plot(t, v, color="k", lw=1.4, label="setpoint v")
    ax.plot(t, x1, color="tab:red", lw=0.7, label=r"output $x_1$")
    ax.axvspan(t[zoom][0], t[zoom][-1], color="0.85", label="zoom below")
    ax.set_ylabel(r"$v$, $x_1$")
    ax.set_xlabel("t (s)")
    ax.set_xlim(t[0], t[-1])
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax_e.plot(t[zoom], x1[zoom] - v[zoom], color="tab:red", lw=0.9)
    ax_e.set_ylabel(r"$x_1 - v$")
    ax_e.set_title(subtitle, fontsize=9)
    ax_u.plot(t[zoom], u[zoom], color="tab:blue", lw=0.9)
    ax_u.set_ylabel("control u")
    ax_u.set_xlabel("t (s)")
    for a_ in (ax_e, ax_u):
        a_.set_xlim(t[zoom][0], t[zoom][-1])
    return fig


#: Simulated outcome of a grid point (0, 1, 2) → marker, face colour, legend label.
OUTCOMES = ((0, "o", "w", "settles (ripple of x1 − v below the tolerance)"),
            (1, "^", "tab:orange", "oscillates (bounded, ripple above the tolerance)"),
            (2, "X", "k", "diverges"))


def plot_stability_map(b1s, b2s, b3s, maps, title: str):
    """Per preset: linearised max Re over (b1, b2) as colour, simulated outcome per b3 as markers.

    ``maps`` holds ``(label, outcome, lin)`` per preset, ``outcome[i1, i2, i3]`` in {0 settles,
    1 oscillates, 2 diverges} (:data:`OUTCOMES`); every outcome has a legend entry with its count.
    """
    from matplotlib.colors import TwoSlopeNorm
    from matplotlib.lines import Line2D

    nr = len(maps)
    fig, axes = new_figure(nr, 1, size=(8.0, 3.6 * nr + 1.0), title=title)
    axes = np.atleast_1d(axes)
    lim = max(float(np.max(np.abs(m[2]))) for m in maps)
    norm = TwoSlopeNorm(vmin=-lim, vcenter=0.0, vmax=lim)
    i1, i2 = np.meshgrid(np.arange(len(b1s)), np.arange(len(b2s)), indexing="ij")
    offsets = np.linspace(-0.25, 0.25, len(b3s))
    counts = np.zeros(len(OUTCOMES), dtype=int)
    for ax, (label, outcome, lin) in zip(axes, maps, strict=True):
        ax.grid(False)
        im = ax.imshow(lin.T, origin="lower", cmap="RdBu_r", norm=norm, aspect="auto",
                       extent=(-0.5, len(b1s) - 0.5, -0.5, len(b2s) - 0.5))
        n_here = []
        for k in range(len(b3s)):
            for code, marker, face, _ in OUTCOMES:
                s = outcome[:, :, k] == code
                counts[code] += int(s.sum())
                ax.scatter(i1[s] + offsets[k], i2[s] + 0.12, marker=marker, color=face, edgecolor="k", s=36,
                           linewidths=0.8, zorder=3)
        for code, _, _, name in OUTCOMES:
            n_here.append(f"{int(np.sum(outcome == code))} {name.split(' ')[0]}")
        for i, j in zip(i1.ravel(), i2.ravel(), strict=True):
            dark = abs(float(norm(lin[i, j])) - 0.5) > 0.3
            ax.text(i, j - 0.3, f"{lin[i, j]:+.2f}", fontsize=7, ha="center", va="center", color="w" if dark else "0.1")
        ax.set_xticks(range(len(b1s)), [f"{v:g}" for v in b1s])
        ax.set_yticks(range(len(b2s)), [f"{v:g}" for v in b2s])
        if 0.0 in list(b1s):
            ax.axvline(int(np.flatnonzero(np.asarray(b1s) == 0.0)[0]), color="k", lw=0.8, ls=":")
        ax.set_title(f"{label}: {', '.join(n_here)} of {outcome.size} grid points", fontsize=9)
        ax.set_xlabel("b1 (categorical grid; dotted: b1 = 0)")
        ax.set_ylabel("b2 (categorical grid)")
        fig.colorbar(im, ax=ax, label="max Re λ of the linearised loop [1/s]")
    handles = [Line2D([], [], marker=marker, ls="", color=face, markeredgecolor="k", label=f"{name}: {counts[code]}")
               for code, marker, face, name in OUTCOMES]
    handles.append(Line2D([], [], color="k", lw=0.8, ls=":", label="b1 = 0"))
    fig.legend(handles=handles, loc="outside lower center", ncol=2, fontsize=8,
               title="simulated outcome (count over both panels); markers left to right per cell: b3 = "
               + ", ".join(f"{b:g}" for b in b3s) + "; number: max Re λ", title_fontsize=8)
    return fig
