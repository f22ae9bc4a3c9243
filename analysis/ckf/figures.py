"""Figures of the `ckf` study: functions taking data and returning a matplotlib Figure (saving is the caller's)."""

from __future__ import annotations

import numpy as np

from ctrl_analysis.report import new_figure

__all__ = [
    "plot_case",
    "plot_filter_error",
    "plot_parameters",
    "plot_q_sweep",
    "plot_second_plant",
    "plot_steady_compare",
    "plot_steady_outputs",
    "plot_transient",
]

NAMES = {"nofilter": "no filter", "lpf": "LPF", "ckf": "CKF"}
COLORS = {"nofilter": "tab:gray", "lpf": "tab:orange", "ckf": "tab:blue"}


def _legend(ax):
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)


def _plot_errors(ax, data, run, t_filter=None):
    """Filtered minus true output: the LPF in the LPF case, the CKF in the CKF case.

    Symmetric-log scale, linear within ±1: the transient errors (tens) and the steady ones (~0.1)
    stay on one axis, nothing clipped.
    """
    for case, sig in (("lpf", "y_lpf"), ("ckf", "y_ckf")):
        d = data[case]
        ax.plot(d["t"], d[sig][:, run] - d["y"][:, run], color=COLORS[case], lw=0.6, alpha=0.85,
                label=NAMES[case])
    if t_filter is not None:
        ax.axvline(t_filter, color="k", ls=":", lw=0.8, label=f"filter fed back from {t_filter:g} s")
    from matplotlib.ticker import FuncFormatter

    ax.set_yscale("symlog", linthresh=1.0)
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.set_ylabel("filter error (symlog, linear within ±1)")
    _legend(ax)


def plot_case(d, case, fig_no, run=0):
    """Fig. 2-4: true output, measurement and control of one run."""
    t = d["t"]
    fig, (ax, ax_u) = new_figure(2, 1, size=(9.0, 5.5), sharex=True,
                                 title=f"Fig. {fig_no}: {NAMES[case]} — output, measurement and control (run {run})")
    ax.plot(t, d["y_m"][:, run], color="0.75", lw=0.4, label="measurement y")
    ax.plot(t, d["y"][:, run], color="k", lw=1.0, label="true output x", zorder=3)
    if case != "nofilter":
        ax.plot(t, d["y_fb"][:, run], color=COLORS[case], lw=0.8, label=f"fed back ({NAMES[case]} after 2 s)")
    ax.set_ylabel("output")
    _legend(ax)
    ax_u.plot(t, d["u"][:, run], color=COLORS[case], lw=0.5, label="control u")
    ax_u.set_ylabel("control u")
    ax_u.set_xlabel("time t [s]")
    _legend(ax_u)
    return fig


def plot_steady_outputs(data, t0, run=0):
    """Fig. 5: steady-state detail of the true output in the three cases."""
    fig, ax = new_figure(size=(9.0, 4.0), title=f"Fig. 5: true output in the steady stage ({t0:g} s on, run {run})")
    for case, d in data.items():
        m = d["t"] >= t0
        ax.plot(d["t"][m], d["y"][m, run], color=COLORS[case], lw=0.7, label=NAMES[case])
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("true output x")
    _legend(ax)
    return fig


def plot_transient(d, case, fig_no, t1=10.0, run=0, t_filter=None):
    """Fig. 6-7: the filter in the transient: measurement, filtered signal and true output."""
    sig = {"lpf": "y_lpf", "ckf": "y_ckf"}[case]
    m = d["t"] <= t1
    t = d["t"][m]
    fig, ax = new_figure(size=(9.0, 4.0), title=f"Fig. {fig_no}: {NAMES[case]} in the transient 0-{t1:g} s (run {run})")
    ax.plot(t, d["y_m"][m, run], color="0.75", lw=0.4, label="measurement y")
    ax.plot(t, d["y"][m, run], color="k", lw=1.0, label="true output x")
    ax.plot(t, d[sig][m, run], color=COLORS[case], lw=1.0, label=f"{NAMES[case]} output")
    if t_filter is not None:
        ax.axvline(t_filter, color="k", ls=":", lw=0.8, label=f"fed back from {t_filter:g} s")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("output")
    _legend(ax)
    return fig


def plot_steady_compare(data, t0, run=0):
    """Fig. 8: steady-stage true output (one panel) and control (one panel per filter, same scale), LPF vs CKF."""
    fig, (ax, *ax_us) = new_figure(3, 1, size=(9.0, 7.0), sharex=True,
                                   title=f"Fig. 8: steady stage ({t0:g} s on), LPF vs CKF: output and control (run {run})")
    for case, ax_u in zip(("lpf", "ckf"), ax_us):
        d = data[case]
        m = d["t"] >= t0
        ax.plot(d["t"][m], d["y"][m, run], color=COLORS[case], lw=0.7, label=NAMES[case])
        ax_u.plot(d["t"][m], d["u"][m, run], color=COLORS[case], lw=0.5, label=f"{NAMES[case]}")
        ax_u.set_ylabel(f"control u, {NAMES[case]}")
        _legend(ax_u)
    lo = min(a.get_ylim()[0] for a in ax_us)
    hi = max(a.get_ylim()[1] for a in ax_us)
    for a in ax_us:
        a.set_ylim(lo, hi)
    ax.set_ylabel("true output x")
    ax_us[-1].set_xlabel("time t [s]")
    _legend(ax)
    return fig


def plot_filter_error(data, run=0, title="Fig. 9: filter error (filtered − true output) over the whole run",
                      t_filter=None):
    """Fig. 9: filtered minus true output, LPF (in the LPF case) and CKF (in the CKF case)."""
    fig, ax = new_figure(size=(9.0, 4.0), title=f"{title} (run {run})")
    _plot_errors(ax, data, run, t_filter)
    ax.set_xlabel("time t [s]")
    return fig


def plot_parameters(d, windows, fits, whole_fit, theta0=None):
    """Fig. 10: identified f̂1, f̂2, ĝ0 (mean and 10-90 % band over runs) against the noise-free LS fit.

    ``theta0`` (optional): the RLS's initial estimate, drawn as a dotted line.
    """
    fig, axes = new_figure(3, 1, size=(9.0, 7.0), sharex=True,
                           title="Fig. 10 (beyond the paper): identified parameters vs noise-free LS fit of the true plant")
    t = d["t"]
    for i, (ax, name) in enumerate(zip(axes, ("f1", "f2", "g0"))):
        v = d[name]
        ax.fill_between(t, np.percentile(v, 10, axis=1), np.percentile(v, 90, axis=1), color="tab:blue", alpha=0.2,
                        label="RLS, 10-90 % of runs")
        ax.plot(t, v.mean(axis=1), color="tab:blue", lw=1.0, label="RLS, mean over runs")
        centres = [0.5 * (a + b) for a, b in windows]
        ax.plot(centres, fits[:, i], "ks", ms=4, label="noise-free LS fit per 10 s window")
        ax.axhline(whole_fit[i], color="k", ls="--", lw=0.8, label="noise-free LS fit, steady stage")
        if theta0 is not None:
            ax.axhline(theta0[i], color="tab:red", ls=":", lw=1.0, label="initial estimate θ0")
        ax.set_ylabel({"f1": "f̂1", "f2": "f̂2", "g0": "ĝ0"}[name])
        _legend(ax)
    axes[-1].set_xlabel("time t [s]")
    return fig


def plot_q_sweep(qs, sweep, lpf_rmse):
    """Fig. 11: RMS error of the CKF alone against Q = q I, transient and steady, with the LPF's."""
    fig, ax = new_figure(size=(8.0, 4.0), title="Fig. 11 (beyond the paper): CKF filter error vs process noise Q = q I")
    for key, style in (("transient", "-o"), ("steady", "-s")):
        ax.loglog(qs, sweep[key], style, color="tab:blue", label=f"CKF, {key}")
        ax.axhline(lpf_rmse[key], color="tab:orange", ls="--" if key == "transient" else ":",
                   label=f"LPF, {key}")
    ax.set_xlabel("q (process-noise variance per state)")
    ax.set_ylabel("RMS filter error")
    _legend(ax)
    return fig


def plot_second_plant(data, name, run=0, t_filter=None):
    """Fig. 12: the second plant: true output per case and the filter errors."""
    fig, (ax, ax_e) = new_figure(2, 1, size=(9.0, 5.5), sharex=True,
                                 title=f"Fig. 12 (beyond the paper): second plant, {name} (run {run})")
    for case, d in data.items():
        ax.plot(d["t"], d["y"][:, run], color=COLORS[case], lw=0.7, label=NAMES[case])
    _plot_errors(ax_e, data, run, t_filter)
    ax.set_ylabel("true output x")
    ax_e.set_xlabel("time t [s]")
    _legend(ax)
    return fig
