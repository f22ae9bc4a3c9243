"""Figures of the study: functions taking data and returning a :class:`matplotlib.figure.Figure`.

Titles say what is plotted (with the paper's figure number); captions and conclusions are in the
report. Saving is the caller's business (``ctx.save_figure``).
"""

from __future__ import annotations

import control as ct
import numpy as np

from ctrl_analysis.report import new_figure

from .identification import equivalent_theta
from .loops import SituationRun, x3_true
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
                                   title=f"Linear ESO (6) / MESO (29) error dynamics, ε = {PAPER.epsilon:g}, β = (3, 3, 1): "
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


def _window(t, T):
    """A 15-s window around the θ4 step (or the end of a short run) where sin t is readable."""
    lo = PAPER.t_step - 5.0 if T > PAPER.t_step + 10 else max(0.0, T - 15.0)
    return (t >= lo) & (t <= lo + 15.0)


def plot_situation(sim: SituationRun, series: dict, title: str, max_points: int = 4000, smooth: dict | None = None):
    """Fig. 3 / Fig. 5: x1 in a window, tracking and estimation errors; noise off (left) and on (right).

    Parameters
    ----------
    sim : SituationRun
    series : dict
        Column title -> ``[(run, label, color), ...]`` (runs kept in ``sim.keep``).
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
    x3_of = {}
    fig, ax = new_figure(5, 2, size=(13, 13), sharex="row", title=title)
    win = _window(t, t[-1])
    for c, (col, runs) in enumerate(series.items()):
        ax[0, c].plot(t[win], np.sin(t[win]), "k--", lw=1.2, label="reference ξ = sin t")
        for b, name, color in runs:
            k = sim.keep[b]
            ax[0, c].plot(t[win], k["x1"][win], color=color, lw=1.0, label=name)
            x3_of[b] = _x3(sim, b)
            for r, y in ((1, np.sin(t) - k["x1"]), (2, k["x1"] - k["xhat1"]), (3, k["x2"] - k["xhat2"]),
                         (4, x3_of[b] - k["xhat3"])):
                if r >= 2 and col in (smooth or {}):
                    ax[r, c].plot(t[::dec], y[::dec], color=color, lw=0.4, alpha=0.3)
                    ax[r, c].plot(t, _moving_average(y, max(1, int(round(smooth[col] / (t[1] - t[0]))))),
                                  color=color, lw=1.2, label=name)
                else:
                    ax[r, c].plot(t[::dec], y[::dec], color=color, lw=0.6, label=name)
        ax[0, c].set_title(col, fontsize=11)
    labels = ["$x_1$ (window around the θ4 step)", "tracking error ξ − $x_1$", "estimation error $x_1 − \\hat x_1$",
              "estimation error $x_2 − \\hat x_2$ (1/s)", "estimation error $x_3 − \\hat x_3$ (1/s²)"]
    for r, lab in enumerate(labels):
        ax[r, 0].set_ylabel(lab, fontsize=9)
        if r:
            for c in range(2):
                _robust_ylim(ax[r, c], len(t[::dec]))
    for c in range(2):
        ax[0, c].set_xlabel("time t (s)")
        ax[4, c].set_xlabel("time t (s)")
    handles, labs = ax[0, 0].get_legend_handles_labels()
    fig.legend(handles, labs, loc="outside lower center", ncol=3, fontsize=9)
    return fig


def _moving_average(y, n):
    """Centred moving average of ``y`` over ``n`` samples (shorter at the ends)."""
    c = np.concatenate([[0.0], np.cumsum(np.nan_to_num(y))])
    i = np.arange(len(y))
    lo, hi = np.clip(i - n // 2, 0, len(y)), np.clip(i + n - n // 2, 0, len(y))
    return (c[hi] - c[lo]) / (hi - lo)


def _x3(sim, b):
    """True x3 at the samples for kept run ``b`` (x2' − b0 u − XᵀΘ_used)."""
    k = sim.keep[b]
    sig = {"x1": k["x1"][:, None], "x2": k["x2"][:, None], "u": k["u"][:, None],
           "level": np.where(sim.t >= PAPER.t_step - 0.5 * PAPER.h, PAPER.step, 0.0)[:, None],
           "xhat1": k["xhat1"][:, None], "xhat2": k["xhat2"][:, None]}
    sig.update({f"theta[{i}]": k[f"theta[{i}]"][:, None] for i in range(4)})
    return x3_true(sig, [sim.rows[b]], PAPER, sim.b0)[:, 0]


def _robust_ylim(a0, n):
    """Limits that show the steady behaviour (99.9th percentile after the first tenth), not the start-up peak."""
    ys = [np.abs(line.get_ydata()[n // 10:]) for line in a0.get_lines()]
    y = np.concatenate(ys) if ys else np.zeros(1)
    y = y[np.isfinite(y)]
    lim = 1.2 * np.percentile(y, 99.9) if y.size else 1.0
    if lim > 0:
        a0.set_ylim(-lim, lim)


def plot_theta(sim: SituationRun, key: str, runs: list, title: str, max_points: int = 3000):
    """Fig. 4 / Fig. 6: identified Θ per batch (markers) and the Θ in use (lines, after W(s) unless bypassed) vs the truth.

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
        for h, lab in zip(*ax.get_legend_handles_labels()):
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
    fig, axes = new_figure(1, 2, size=(13, 5.5), title="Identifiability of each LSM batch (Theorem 1): condition "
                                                       "number of the column-scaled regression matrix (no paper figure)")
    for ax, (name, (tb, series, gated)) in zip(np.atleast_1d(axes), per_sit.items()):
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
