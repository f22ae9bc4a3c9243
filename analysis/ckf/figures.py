"""Figures of the `ckf` study: functions taking data and returning a matplotlib Figure (saving is the caller's)."""

from __future__ import annotations

import numpy as np

from ctrl_analysis.reporting.report import new_figure

__all__ = [
    "plot_case",
    "plot_filter_error",
    "plot_parameters",
    "plot_q_sweep",
    "plot_second_plant",
    "plot_steady_compare",
    "plot_steady_outputs",
    "plot_transient",
    "save_all",
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
                                   title=f"Fig. 8: steady stage ({t0:g} s on), LPF vs CKF: output and control (run "
                                   f"{run})")
    for case, ax_u in zip(("lpf", "ckf"), ax_us, strict=True):
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


def plot_filter_error(data, run=0, title="Fig. 9: filter error (filtered − true output)", t_filter=None,
                      t_zoom=10.0):
    """Fig. 9: filtered minus true output, LPF (in the LPF case) and CKF (in the CKF case).

    Left: the decisive transient ``0 .. t_zoom`` on a linear axis; right: the whole run on a symmetric-log axis.
    """
    fig, (ax_z, ax) = new_figure(1, 2, size=(12.0, 4.2), gridspec_kw={"width_ratios": [1.0, 1.3]},
                                 title=f"{title} (run {run})")
    for case, sig in (("lpf", "y_lpf"), ("ckf", "y_ckf")):
        d = data[case]
        m = d["t"] <= t_zoom
        ax_z.plot(d["t"][m], d[sig][m, run] - d["y"][m, run], color=COLORS[case], lw=0.8, label=NAMES[case])
    if t_filter is not None:
        ax_z.axvline(t_filter, color="k", ls=":", lw=0.8)
    ax_z.axhline(0.0, color="k", lw=0.5)
    ax_z.set_title(f"transient 0-{t_zoom:g} s (linear)", fontsize=10)
    ax_z.set_xlabel("time t [s]")
    ax_z.set_ylabel("filter error")
    _plot_errors(ax, data, run, t_filter)
    ax.set_title("whole run (symlog, linear within ±1)", fontsize=10)
    ax.set_xlabel("time t [s]")
    return fig


def plot_parameters(d, windows, fits, whole_fit, theta0=None, ablation=None, box=None):
    """Fig. 10: identified f̂1, f̂2, ĝ0 (mean and 10-90 % band over runs) against the noise-free LS fit.

    ``theta0`` (optional): the RLS's initial estimate (dotted); ``ablation``: the frozen-Φ ablation's CKF case,
    its mean drawn dashed; ``box``: ``(lower, upper)`` of the projection, every finite bound drawn as a grey line
    (ĝ0 on a log axis, so its lower bound and the plant's fit a decade above both show).
    """
    fig, axes = new_figure(3, 1, size=(10.0, 7.5), sharex=True,
                           title="Fig. 10 (beyond the paper): identified characteristic-model parameters (CKF case), "
                                 "live vs frozen-Φ ablation")
    t = d["t"]
    for i, (ax, name) in enumerate(zip(axes, ("f1", "f2", "g0"), strict=True)):
        v = d[name]
        ax.fill_between(t, np.percentile(v, 10, axis=1), np.percentile(v, 90, axis=1), color="tab:blue", alpha=0.2,
                        label="live RLS, 10-90 % of runs")
        ax.plot(t, v.mean(axis=1), color="tab:blue", lw=1.0, label="live RLS, mean over runs")
        if ablation is not None:
            ax.plot(t, ablation[name].mean(axis=1), color="tab:orange", ls="--", lw=1.0,
                    label="frozen-Φ ablation, mean")
        centres = [0.5 * (a + b) for a, b in windows]
        ax.plot(centres, fits[:, i], "ks", ms=4, label="noise-free LS fit per 10 s window")
        ax.axhline(whole_fit[i], color="k", ls="--", lw=0.8, label="noise-free LS fit, steady stage")
        if theta0 is not None:
            ax.axhline(theta0[i], color="tab:red", ls=":", lw=1.0, label="initial estimate θ0")
        if box is not None:
            for k, (side, bound) in enumerate((("lower", box[0][i]), ("upper", box[1][i]))):
                if np.isfinite(bound):
                    ax.axhline(bound, color="0.45", lw=1.5, alpha=0.7, ls="-" if k == 0 else "-.",
                               label=f"projection box, {side} bound {bound:g}")
        if name == "g0":
            ax.set_yscale("log")
        ax.set_ylabel({"f1": "f̂1", "f2": "f̂2", "g0": "ĝ0 (log)"}[name])
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


def plot_second_plant(data, name, reference, t_steady, run=0, t_filter=None, of=None):
    """Fig. 12: the second plant ``name`` (a formula): true output (whole run; steady stage zoomed with the steady
    means over all runs) and the filter errors. ``of``: the run count when ``data`` holds the first runs only
    (:func:`analysis.ckf.simulate_main`), said in the means' labels."""
    fig, (ax, ax_s, ax_e) = new_figure(3, 1, size=(10.0, 8.0), sharex=True,
                                       title=f"Fig. 12 (beyond the paper): second plant {name} (run {run})")
    for case, d in data.items():
        ax.plot(d["t"], d["y"][:, run], color=COLORS[case], lw=0.7, label=NAMES[case])
        m = d["t"] >= t_steady
        mean = float(d["y"][m][:, d["ok"]].mean())
        n = d["y"].shape[1]
        over = "all runs" if of is None or of <= n else f"first {n} of {of} runs"
        ax_s.plot(d["t"][m], d["y"][m, run], color=COLORS[case], lw=0.6, alpha=0.8, label=f"{NAMES[case]} (run {run})")
        ax_s.hlines(mean, t_steady, d["t"][-1], color=COLORS[case], ls="--", lw=1.5,
                    label=f"{NAMES[case]}: steady mean {mean:.2f} ({over})")
    for a in (ax, ax_s):
        a.axhline(reference, color="k", ls=":", lw=1.0, label=f"reference {reference:g}")
    _plot_errors(ax_e, data, run, t_filter)
    ax.set_ylabel("true output x")
    ax_s.set_ylabel(f"true output x, {t_steady:g} s on")
    ax_e.set_xlabel("time t [s]")
    _legend(ax)
    _legend(ax_s)
    return fig

PLANT2_FORMULA = {"resonant-delay": "9 / ((s² + 0.9 s + 9)(s + 1)) · e^(−0.1 s)"}


def _traced_note(runs, traced) -> str:
    """A caption's note when the figures draw the first ``traced`` of ``runs`` runs: above
    :data:`analysis.ckf.RUNS_PER_PART` runs only the first part's traces are kept
    (:func:`analysis.ckf.simulate_main`)."""
    return (f" Bands, means and shares over the first {traced} of the {runs} runs, whose traces are kept (finding "
            "traced-runs)." if runs > traced else "")


def save_all(ctx, result, p, data, data_f, extra, ident):
    """Draw and save Fig. 2-12 with their captions (``ident``: :func:`.beyond.ablation`'s bounds and progress)."""
    from .beyond import Q_SWEEP
    from .loops import case_id
    from .quantities import TABLE1_ROWS, noise_free_fit

    bounds, _ = ident
    runs = result.seeds["runs"]
    subset = _traced_note(runs, data["ckf"]["y"].shape[1])
    id_note = {"lpf": "the characteristic model identified online from the LPF output",
               "raw": "the characteristic model identified online from the measurement"}
    for no, case in ((2, "nofilter"), (3, "lpf"), (4, "ckf")):
        own = case_id(p, case)
        extra_words = (" (an LPF run beside the loop, not fed back: the no-filter loop's feedback is unfiltered, its "
                       "identification is not; finding nofilter-identification)" if case == "nofilter" and own == "lpf"
                       else "")
        loop = "without a filter" if case == "nofilter" else "with the " + TABLE1_ROWS[case]
        ctx.save_figure(result, plot_case(data[case], case, no), f"fig{no}_{case}.png",
                        caption=f"Redraws the paper's Fig. {no}: true output, measurement and control of the "
                                f"golden-section loop {loop} over the whole run (one run, "
                                f"{id_note.get(own, own)}{extra_words}); the plant is the study's reconstruction.")
    ctx.save_figure(result, plot_steady_outputs(data, p.t_steady), "fig5_steady_outputs.png",
                    caption="Redraws the paper's Fig. 5: the three true outputs (no filter, LPF, CKF) in the steady "
                            "stage, zoomed in; Table 1's output mean and variance summarise them.")
    ctx.save_figure(result, plot_transient(data["lpf"], "lpf", 6, t_filter=p.t_filter), "fig6_lpf_transient.png",
                    caption="Redraws the paper's Fig. 6: the LPF's output against the true output and the measurement "
                            "in the transient (0-10 s); the LPF lags. Dotted line: 2 s, from when the filtered signal "
                            "is fed back.")
    d = data["ckf"]
    early = d["t"] < p.t_filter - 1e-9
    moved = max(float(np.abs(d[n][early] - p.theta0[i]).max()) for i, n in enumerate(("f1", "f2")))
    g0 = bounds["g0"]
    hit = float(np.mean([np.isclose(d["g0"][early, b], p.lower[2], rtol=1e-9).any() for b in range(d["g0"].shape[1])]))
    ctx.save_figure(result, plot_transient(data["ckf"], "ckf", 7, t_filter=p.t_filter), "fig7_ckf_transient.png",
                    caption="Redraws the paper's Fig. 7: the CKF's output against the true output and the measurement "
                            f"in the transient (0-10 s), to compare with Fig. 6. Before {p.t_filter:g} s (dotted line) "
                            f"the CKF is not fed back; its model then is θ0 with a falling ĝ0: f̂1 and f̂2 stay within "
                            f"{moved:.3g} of θ0, while ĝ0 drops from {p.theta0[2]:g} onto its lower bound "
                            f"{p.lower[2]:g} in {hit:.0%} of the runs (median first time "
                            f"{g0['first'] if g0['first'] is not None else float('nan'):.2f} s; Fig. 10)." + subset)
    ctx.save_figure(result, plot_steady_compare(data, p.t_steady), "fig8_steady_lpf_vs_ckf.png",
                    caption="Redraws the paper's Fig. 8: steady-stage true output (top, both filters) and control with "
                            "the LPF (middle) and with the CKF (bottom), the two control panels on one scale; the "
                            "paper claims both are steadier with the CKF (claims steady-output, steady-control).")
    ctx.save_figure(result, plot_filter_error(data, t_filter=p.t_filter), "fig9_filter_error.png",
                    caption="Redraws the paper's Fig. 9: filter error (filtered minus true output) of the LPF and the "
                            "CKF; left, the transient 0-10 s on a linear axis; right, the whole run on a "
                            "symmetric-log axis (linear within ±1). Dotted line: 2 s, from when the filters are fed "
                            "back. The paper claims the CKF's error is smaller in both stages (claims transient, "
                            "steady); the transient claim is judged from 2 s on, where the two filters compete in the "
                            "loop (before, both loops feed back the measurement).")
    wins = [(a, a + 10.0) for a in np.arange(0.0, p.t_end, 10.0)]
    fits = np.array([noise_free_fit(d, p, a, b)[0].mean(0) for a, b in wins])
    ctx.save_figure(result, plot_parameters(d, wins, fits, noise_free_fit(d, p)[0].mean(0), theta0=p.theta0,
                                            ablation=data_f["ckf"], box=(p.lower, p.upper) if p.project else None),
                    "fig10_identified_parameters.png",
                    caption="Beyond the paper: the identified f̂1, f̂2, ĝ0 of the characteristic model over time (CKF "
                            "case, live identification: band and mean; frozen-Φ ablation: dashed) against the "
                            "noise-free least-squares fit of the true plant on 10-s windows and on the whole steady "
                            "stage; dotted red: θ0; grey: the bounds of the projection box (ĝ0 on a log axis). f̂1 and "
                            f"f̂2 drift the whole run without settling; ĝ0 reaches its lower bound {p.lower[2]:g} "
                            f"(median first time {g0['first'] if g0['first'] is not None else float('nan'):.2f} s) and "
                            f"stays near it (steady-stage mean {bounds['g0_steady']:.2g}), "
                            f"{bounds['g0_fit'] / bounds['g0_steady']:.0f}x below the plant's fit (finding "
                            "identification-live)." + subset)
    ctx.save_figure(result, plot_q_sweep(Q_SWEEP, extra["sweep"], extra["lpf"]), "fig11_q_sweep.png",
                    caption="Beyond the paper: the CKF's transient and steady RMS error against its process-noise "
                            "level Q = q I (the CKF run alone on the LPF case's records), with the LPF's errors as "
                            "reference lines (finding q-sweep).")
    name = PLANT2_FORMULA.get(p.plant2, p.plant2)
    ctx.save_figure(result, plot_second_plant(extra["data2"], name, p.reference, p.t_steady, t_filter=p.t_filter,
                                                      of=runs),
                    "fig12_second_plant.png",
                    caption=f"Beyond the paper: the three loops on a second plant, {name} (lightly damped, ζ = 0.15, "
                            "with a 0.1 s delay as a 2nd-order Padé; unit DC gain): true outputs over the whole run "
                            "(top), the steady stage zoomed with the steady means over all runs (middle) and filter "
                            "errors on a symmetric-log axis (bottom). The outputs stay below the reference 10 over the "
                            "steady stage, the CKF loop lowest and still rising at 100 s: finding plant2-offset "
                            "computes why." + subset)

