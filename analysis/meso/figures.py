"""Figures of the study: functions taking data and returning a :class:`matplotlib.figure.Figure`.

Titles say what is plotted (with the paper's figure number); captions and conclusions are in the
report. Saving is the caller's business (``ctx.save_figure``).
"""

from __future__ import annotations

import control as ct
import numpy as np

from ctrl_analysis.reporting.report import new_figure

from .chunk_errors import x3_true
from .identification import equivalent_theta
from .loops import SituationRun
from .paper import PAPER

__all__ = ["plot_eps_scaling", "plot_error_bode", "plot_identifiability", "plot_situation", "plot_theta"]

COLORS = {"eso": "tab:red", "meso": "tab:blue", "literal": "tab:orange", "direct": "tab:purple",
          "noW": "tab:brown", "no_const": "tab:gray"}


def plot_error_bode(lin):
    """Bode plot of the disturbance-to-estimation-error transfer functions E_i(s)/H(s) of the linear ESO.

    Parameters
    ----------
    lin : LinearAnalysis

    Returns
    -------
    matplotlib.figure.Figure
    """
    w = np.logspace(-2, 3.5, 600)
    fig, (ax_m, ax_p) = new_figure(2, 1, size=(8.5, 6.5), sharex=True,
                                   title=f"Linear ESO (6) / MESO (29) error dynamics, ε = {PAPER.epsilon:g}, β = (3, "
                                   f"3, 1): "
                                         "Bode plots of disturbance → estimation error (no paper figure)")
    for i, g in enumerate(lin.observer.disturbance_error_tf(), start=1):
        c = np.squeeze(ct.frequency_response(g, w).complex)
        ax_m.semilogx(w, 20 * np.log10(np.abs(c)), label=f"$E_{i}(s)/H(s)$, $e_{i} = x_{i} - \\hat x_{i}$")
        ax_p.semilogx(w, np.degrees(np.unwrap(np.angle(c))))
    ax_m.axvline(lin.omega_o, color="k", ls=":", lw=1, label=f"$\\omega_o$ = {lin.omega_o:g} rad/s")
    ax_m.set_ylabel("magnitude (dB; $E_1/H$ in s³, $E_2/H$ in s², $E_3/H$ in s)", fontsize=9)
    ax_m.set_title("input h = dx₃/dt (derivative of the total disturbance)", fontsize=9)
    ax_p.set_ylabel("phase (deg)")
    ax_p.set_xlabel("frequency ω (rad/s)")
    ax_m.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return fig


def plot_eps_scaling(sc: dict, lin):
    """Left: closed-loop mean |e_i| vs ε with the ε^(n+2−i) law; right: noise std of e_i vs ε.

    Parameters
    ----------
    sc : dict
        From :func:`.quantities.eps_scaling`.
    lin : LinearAnalysis

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, (ax, ax2) = new_figure(1, 2, size=(13, 5.2),
                                title="ESO estimation errors vs ε (situation 1): noise-free loop (left), "
                                      "measurement-noise part (right) (no paper figure)")
    eps = sc["eps"]
    i0 = list(eps).index(PAPER.epsilon)
    for i in range(3):
        line, = ax.loglog(eps, sc["err"][:, i], "o-", label=f"mean $|e_{i + 1}|$, fitted slope {sc['slope'][i]:.2f}")
        law = lin.law[i]
        ref = 2.0 * sc["err"][i0, i] * (eps / eps[i0]) ** law
        ax.loglog(eps, ref, "--", color=line.get_color(), lw=1.5, alpha=0.7,
                  label=f"law ε^{law} (×2 through ε = {PAPER.epsilon:g}, offset to stay visible)")
        ax2.loglog(lin.eps, lin.noise_std[:, i], "s-", color=line.get_color(), label=f"std of $e_{i + 1}$ from noise")
    for a in (ax, ax2):
        a.set_xticks(eps, [f"{e:g}" for e in eps])
        a.minorticks_off()
        a.set_xlabel("ε (observer high-gain parameter)")
    ax.set_ylabel(f"mean |estimation error| over [{sc['window'][0]:g}, {sc['window'][1]:g}) s "
                  "(x1: –, x2: 1/s, x3: 1/s²)")
    ax2.set_ylabel("steady std (x1: –, x2: 1/s, x3: 1/s²)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.15), ncol=2)
    ax2.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.15))
    return fig


#: the transient column: the start-up and the θ4 step, each this long (s), drawn side by side
_TRANSIENT = 2.0


def _transient_x(t):
    """x-coordinates of the transient column: [0, 2) s as is, [t_step − 0.2, t_step + 1.8) s shifted next to it."""
    first = t < _TRANSIENT
    second = (t >= PAPER.t_step - 0.2) & (t < PAPER.t_step - 0.2 + _TRANSIENT)
    x = np.full(t.shape, np.nan)
    x[first] = t[first]
    x[second] = t[second] - (PAPER.t_step - 0.2) + _TRANSIENT + 0.3
    return x


def _steady(t):
    """Samples that set the steady y-range: after the start-up (first tenth, at least 5 s) and not within 4 s
    after the θ4 step."""
    return (t >= max(5.0, 0.1 * t[-1])) & ~((t >= PAPER.t_step) & (t < PAPER.t_step + 4.0))


def plot_situation(sim: SituationRun, series: dict, title: str, max_points: int = 4000, smooth: dict | None = None):
    """Fig. 3 / Fig. 5: control input, tracking and estimation errors; noise off, noise on, and the transients.

    Columns: noise off and noise on over the whole run, their y-ranges set by the steady behaviour (the
    start-up and θ4-step peaks are off scale, their size written in the panel); the third column shows
    those two transients at full scale (noise off).

    Parameters
    ----------
    sim : SituationRun
    series : dict
        Column title -> ``[(run, label, color), ...]`` (runs kept in ``sim.keep``); the first column's runs
        are also drawn in the transient column.
    title : str
    max_points : int
        Decimation of the full-horizon panels.
    smooth : dict, optional
        Column title -> window (s). In those columns the estimation errors are drawn faint and
        overlaid with their centred moving average over the window, so that the noise band of one
        observer does not hide the other's error.

    Returns
    -------
    matplotlib.figure.Figure
    """
    t = sim.t
    dec = max(1, len(t) // max_points)
    fig, ax = new_figure(5, 3, size=(16, 13), title=title, gridspec_kw={"width_ratios": [1.0, 1.0, 0.55]})
    steady = _steady(t)
    xt = _transient_x(t)
    windows = [(t < _TRANSIENT), np.isfinite(xt) & (t >= _TRANSIENT)]   # drawn apart: the axis is broken between
    cols = list(series.items())
    for c, (col, runs) in enumerate(cols):
        peaks = {r: 0.0 for r in range(5)}
        lims = {r: 0.0 for r in range(5)}
        urange = [np.inf, -np.inf]
        for b, name, color in runs:
            k = sim.keep[b]
            x3 = _x3(sim, b)
            for r, y in enumerate((k["u"], np.sin(t) - k["x[0]"], k["x[0]"] - k["xhat[0]"], k["x[1]"] - k["xhat[1]"],
                                   x3 - k["xhat[2]"])):
                a = ax[r, c]
                if r >= 2 and col in (smooth or {}):
                    a.plot(t[::dec], y[::dec], color=color, lw=0.4, alpha=0.3)
                    a.plot(t[::dec], _moving_average(y, max(1, int(round(smooth[col] / (t[1] - t[0])))))[::dec],
                           color=color, lw=1.2, label=name)
                else:  # the first run (ESO) wide and faint beneath: the control inputs nearly coincide
                    first = b == runs[0][0]
                    a.plot(t[::dec], y[::dec], color=color, lw=2.0 if first else 0.6, alpha=0.5 if first else 1.0,
                           label=name)
                fin = np.isfinite(y)
                if r == 0 and np.any(steady & fin):
                    lo, hi = np.min(y[steady & fin]), np.max(y[steady & fin])
                    urange = [min(urange[0], lo), max(urange[1], hi)]
                lims[r] = max(lims[r],
                              float(np.percentile(np.abs(y[steady & fin]), 99.9)) if np.any(steady & fin) else 0)
                peaks[r] = max(peaks[r], float(np.max(np.abs(y[~steady & fin]), initial=0.0)))
                if c == 0:
                    for w in windows:
                        ax[r, 2].plot(xt[w], y[w], color=color, lw=0.8)
        _steady_limits(ax[:, c], lims, peaks, urange)
        ax[0, c].set_title(col, fontsize=10.5)
        ax[4, c].set_xlabel("time t (s)")
    ax[0, 2].set_title("noise off: the start-up and the θ4 step\nat full scale", fontsize=10.5)
    shift = _TRANSIENT + 0.3 + 0.2   # x of t = t_step
    for r in range(5):
        a = ax[r, 2]
        a.axvline(_TRANSIENT + 0.15, color="k", lw=0.8, ls=":")
        a.set_xticks([0, 1, shift, shift + 1], ["0", "1", f"{PAPER.t_step:g}", f"{PAPER.t_step + 1:g}"])
    ax[4, 2].set_xlabel("time t (s); axis broken at the dotted line")
    labels = ["control input u", "tracking error ξ − $x_1$ (ξ = sin t)", "estimation error $x_1 − \\hat x_1$",
              "estimation error $x_2 − \\hat x_2$ (1/s)", "estimation error $x_3 − \\hat x_3$ (1/s²)"]
    for r, lab in enumerate(labels):
        ax[r, 0].set_ylabel(lab, fontsize=9)
    handles, labs = ax[0, 0].get_legend_handles_labels()
    fig.legend(handles, labs, loc="outside lower center", ncol=3, fontsize=9)
    return fig


def _steady_limits(axes, lims, peaks, urange) -> None:
    """y-ranges of one column from the steady behaviour; the clipped transient peak written in each panel."""
    for r, a in enumerate(axes):
        lim = 1.2 * lims[r]
        if lim <= 0:
            continue
        if r == 0:  # u is not centred on zero: its steady range
            pad = 0.1 * (urange[1] - urange[0])
            a.set_ylim(urange[0] - pad, urange[1] + pad)
        else:
            a.set_ylim(-lim, lim)
        if peaks[r] > lim:
            a.text(0.99, 0.03, f"off scale: start-up / θ4-step peak |·| = {peaks[r]:.3g}", transform=a.transAxes,
                   ha="right", va="bottom", fontsize=7.5, bbox={"facecolor": "white", "alpha": 0.8, "lw": 0})


def _moving_average(y, n):
    """Centred moving average of ``y`` over ``n`` samples (shorter at the ends)."""
    c = np.concatenate([[0.0], np.cumsum(np.nan_to_num(y))])
    i = np.arange(len(y))
    lo, hi = np.clip(i - n // 2, 0, len(y)), np.clip(i + n - n // 2, 0, len(y))
    return (c[hi] - c[lo]) / (hi - lo)


def _x3(sim, b):
    """True x3 at the samples for kept run ``b`` (x2' − b0 u − XᵀΘ_used)."""
    k = sim.keep[b]
    sig = {"x[0]": k["x[0]"][:, None], "x[1]": k["x[1]"][:, None], "u": k["u"][:, None],
           "level": np.where(sim.t >= PAPER.t_step - 0.5 * PAPER.h, PAPER.step, 0.0)[:, None],
           "xhat[0]": k["xhat[0]"][:, None], "xhat[1]": k["xhat[1]"][:, None]}
    sig.update({f"theta[{i}]": k[f"theta[{i}]"][:, None] for i in range(4)})
    return x3_true(sig, [sim.rows[b]], PAPER, sim.b0)[:, 0]


def plot_theta(sim: SituationRun, key: str, runs: list, title: str, max_points: int = 3000):
    """Fig. 4 / Fig. 6: identified Θ per batch (markers), the Θ in use (lines, after W(s) unless bypassed), the truth.

    A diverged run's lines stop at its divergence (marked ×).

    Parameters
    ----------
    sim : SituationRun
    key : {"s1", "s2"}
    runs : list of (int, str, str)
        ``(run, label, color)`` of runs kept in ``sim.keep``.
    title : str
    max_points : int

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .quantities import theta_truth

    t = sim.t
    dec = max(1, len(t) // max_points)
    fig, axes = new_figure(2, 2, size=(13, 9), sharex=True, title=title)
    names = ["θ₁ (x₁ coefficient, 1/s²)", "θ₂ (x₂ coefficient, 1/s)", "θ₃ (u coefficient)",
             "θ₄ (non-model-class term, 1/s²)"]
    truth = theta_truth(key, t)
    eq = np.array([equivalent_theta(row, PAPER.b) for row in truth[::dec]]) if key == "s2" else None
    for j, ax in enumerate(axes.ravel()):
        ax.plot(t, truth[:, j], "k--", lw=1.5, label="true Θ")
        if eq is not None:
            ax.plot(t[::dec], eq[:, j], color="tab:green", ls=":", lw=1.8, label="trajectory-equivalent Θ")
        for b, label, color in runs:
            y = sim.keep[b][f"theta[{j}]"]
            ax.plot(t[::dec], y[::dec], color=color, lw=1.0, label=f"{label}: Θ used by observer and controller")
            ax.plot(sim.t_batch, sim.theta_batch[:, b, j], "o", ms=3.5, color=color, label=f"{label}: LSM per batch")
            if sim.diverged[b]:
                k = max(sim.diverged_step[b] - 2, 0)
                ax.plot(t[k], np.nan_to_num(y[k]), "x", ms=10, mew=2, color=color, label=f"{label}: diverged")
        lo = np.nanmin(truth[:, j]) if eq is None else min(np.nanmin(truth[:, j]), np.nanmin(eq[:, j]))
        hi = np.nanmax(truth[:, j]) if eq is None else max(np.nanmax(truth[:, j]), np.nanmax(eq[:, j]))
        span = max(hi - lo, 1.0)
        ax.set_ylim(lo - 0.8 * span, hi + 0.8 * span)
        ax.set_title(names[j], fontsize=10)
        ax.set_ylabel("parameter value")
    for ax in axes[1]:
        ax.set_xlabel("time t (s)")
    handles, labels = [], []
    for ax in axes.ravel():
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=8)
    return fig


def plot_identifiability(per_sit: dict, threshold: float):
    """Column-scaled condition number of each LSM batch's regression, per situation and series.

    Parameters
    ----------
    per_sit : dict
        Panel title -> ``(t_batch, [(cond (nb,) or (lo, med, hi), label, style), ...], gated)``; the
        threshold line is drawn only in panels with ``gated`` true (where the gate decides anything).
    threshold : float
        The identifiability gate, drawn as a line.

    Returns
    -------
    matplotlib.figure.Figure
    """
    title = ("Identifiability of each LSM batch (Theorem 1): condition number of the column-scaled regression "
             "matrix (no paper figure)")
    fig, axes = new_figure(1, 2, size=(13, 5.5), title=title)
    for ax, (name, (tb, series, gated)) in zip(np.atleast_1d(axes), per_sit.items(), strict=True):
        for values, label, style in series:
            if isinstance(values, tuple):
                lo, med, hi = values
                ax.fill_between(tb, lo, hi, color=style["color"], alpha=0.2, label=f"{label}: min–max over runs")
                ax.semilogy(tb, med, label=f"{label}: median", **style)
            else:
                ax.semilogy(tb, values, label=label, **style)
        if gated:
            ax.axhline(threshold, color="k", ls=":", lw=1.2,
                       label=f"gate threshold {threshold:g} (well-posed full regression only)")
        ax.set_yscale("log")
        # cond >= 1; at least up to 10× the threshold, so that a flat series is not blown up to fill the panel
        ax.set_ylim(1.0, max(ax.get_ylim()[1], 10.0 * threshold))
        ax.set_title(name, fontsize=10)
        ax.set_xlabel("end of batch t (s)")
        ax.set_ylabel("cond (column-scaled)")
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.14), ncol=2)
    return fig
