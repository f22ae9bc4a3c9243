"""The arena on a user's record (``ctrl-analysis arena --signal F.csv``): the ranking, written where it can be kept.

:func:`run_record` tunes every causal estimator family and every offline smoother on the record
(:func:`.recommend.recommend_for_record`), and writes into its output folder ``results.json`` (both rankings as
quantities, the price of causality, the untuned difference-quotient reference, the settings, the recommendation),
``estimate.csv`` (at every sample the recommended causal estimator's f̂' and the best smoother's f̂', then each
one's f̂'' where it estimates one; the header names every column), figures (the record with the estimate and its
error over time, the ranking, and without a derivative column the Pareto fronts) and a short ``REPORT.md``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..reporting.report import StudyContext, StudyInfo, StudyResult
from .bound import lower_bound

__all__ = ["INFO", "SURROGATE_RATIO", "report_lines", "run_record"]

#: The printed worst-case error over the real one where the arena scores on its surrogate (no derivative column),
#: measured on 20 records with their truth that it was not tuned on (``benchmarks/arena_truth_free.py``: five signal
#: classes, uniform and Gaussian noise, two levels, bounds estimated from the record; 2026-11-28): lowest, median,
#: highest.
SURROGATE_RATIO = (0.541, 0.975, 1.249)

INFO = StudyInfo(name="arena", seed_file="", paper="",
                 reproduces="the estimator families tuned fairly on a user's record, ranked against the bound 2√(εL)")


def run_record(ctx: StudyContext, t, y, d1, eps: float, L: float, source: str = "",
               check: dict | None = None, bounds_source: dict | None = None) -> tuple:
    """Rank every family on one record and save the outputs into ``ctx.out_dir``.

    Parameters
    ----------
    ctx : StudyContext
        Output folder, jobs, progress.
    t, y : numpy.ndarray, shape (N,)
        Time (uniform steps) and measurement.
    d1 : numpy.ndarray or None
        The true derivative, when the record has it (its errors are then exact).
    eps, L : float
        Noise bound and bound on |f''|.
    source : str
        Where the record came from (the CSV's path), recorded in results.json.
    check : dict, optional
        :func:`~ctrl_analysis.arena.recordcheck.check_record`'s result (made here when not given): the record's
        own noise and curvature estimates beside the stated bounds, and the warnings, go into results.json and
        REPORT.md.
    bounds_source : dict, optional
        Where ``eps`` and ``L`` came from, ``{"noise_bound": "stated" | "estimated from the record", "accel_bound":
        ...}`` (default both stated), recorded in results.json and said in the recommendation.

    Returns
    -------
    (StudyResult, list)
        The record for results.json and the causal ranking (best first; the offline smoothers' is in the record).
    """
    from .interface import estimate, family
    from .recommend import recommend_for_record, record_case
    from .recordcheck import check_record

    if not isinstance(ctx, StudyContext):
        raise TypeError(f"ctx must be a StudyContext, got {ctx!r:.80}")
    if check is None:
        check = check_record(t, y, d1, eps, L)
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    d1 = None if d1 is None else np.asarray(d1, dtype=float)
    eps, L = float(eps), float(L)
    ctx.progress("tuning every family on the record, causal filters and offline smoothers")
    everything = recommend_for_record(t, y, d1, eps, L, jobs=ctx.jobs, offline=True)
    ranking = [r for r in everything if r["causal"]]
    smooth = [r for r in everything if not r["causal"]]
    setup, (ref, _, fit) = record_case(t, y, d1, eps, L)
    bound = lower_bound(eps, L)
    win = ranking[0]
    fam = family(win["family"])
    causal = estimate(fam, [[win["params"][p.name] for p in fam.params]], y[:, None], setup.dt, init=setup.init)[:, 0]
    est = causal[:, 1]
    best_off = family(smooth[0]["family"])
    off = estimate(best_off, [[smooth[0]["params"][p.name] for p in best_off.params]], y[:, None], setup.dt)[:, 0]
    result = StudyResult(INFO)
    lo, mid, hi = SURROGATE_RATIO
    scored = ("the record's own derivative column" if d1 is not None else
              "a surrogate: a zero-phase Savitzky-Golay fit of the record plus uniform noise of bound ε "
              f"(no derivative given; the errors are estimates: on benchmark records with their truth the printed "
              f"error was {lo:.2f}-{hi:.2f}x the real one, median {mid:.2f})")
    bounds_source = dict(bounds_source or {"noise_bound": "stated", "accel_bound": "stated"})
    result.settings.update({"mode": "record", "signal": source, "noise_bound": float(eps), "accel_bound": float(L),
                            "bounds_source": bounds_source, "offline_families": [r["family"] for r in smooth],
                            "dt": setup.dt, "samples": int(y.size), "startup_window_s": setup.transient,
                            "scored_on": scored, "record_check": _check_settings(check, float(t[0]))})
    result.quantity("bound", "lower bound 2√(εL) on the worst-case error of any causal estimator", bound,
                    unit="signal unit/s")
    e = check["estimates"]
    result.quantity("record.noise_estimate", "the record's own noise bound ε̂ (uniform noise of the spread that the "
                    "median absolute deviation of its third differences shows)", e["noise_bound"], unit="signal unit",
                    note=f"stated ε = {eps:.4g}" + (f"; quantised, step {e['quantum']:.4g}" if e["quantum"] else ""))
    result.quantity("record.accel_estimate", "the record's own |f''| beyond its noise (smoothed second differences; "
                    "0 = none resolved)", e["accel"], unit="signal unit/s²", note=f"stated L = {L:.4g}")
    for i, w in enumerate(check["warnings"]):
        result.finding(f"bound-warning-{i + 1}", f"Warning: {w}.")
    for r in ranking + smooth:
        kind = "" if r["causal"] else " (offline)"
        result.quantity(f"{r['family']}.worst", f"{r['label']}{kind}: tuned worst-case |f̂' - f'| after the start-up "
                        "window", r["worst"], unit="signal unit/s",
                        note=", ".join(f"{k} = {v:.4g}" for k, v in r["params"].items()))
        result.quantity(f"{r['family']}.ratio", f"{r['label']}{kind}: worst-case error / 2√(εL)", r["ratio"], unit="")
        result.quantity(f"{r['family']}.rms", f"{r['label']}{kind}: tuned RMS |f̂' - f'| after the start-up window",
                        r["rms"], unit="signal unit/s",
                        note=", ".join(f"{k} = {v:.4g}" for k, v in r["rms_params"].items()))
        result.quantity(f"{r['family']}.startup", f"{r['label']}{kind}: worst |f̂' - f'| in the start-up window "
                        "(scored apart) / max |f'|, at its worst-case tuning", r["startup"], unit="")
    _price_of_causality(result, ranking, smooth, d1 is not None)
    _reference(result, y, ref[:, 0], setup, eps, L)
    result.finding("recommendation",
                   f"Recommended: {win['label']} ({', '.join(f'{k} = {v:.4g}' for k, v in win['params'].items())}), "
                   f"the smallest worst-case derivative error on this record: {win['worst']:.4g} signal unit/s, "
                   f"{win['ratio']:.2f}× the bound 2√(εL) = {bound:.4g}. Errors are scored on {scored}, after a "
                   f"start-up window of {setup.transient:.4g} s (the first {int(round(setup.transient / setup.dt))} "
                   "samples, left out of every family's error)."
                   + ("" if set(bounds_source.values()) == {"stated"} else
                      f" The bounds were estimated from the record (ε {bounds_source['noise_bound']}, L "
                      f"{bounds_source['accel_bound']}): the bound and the ratios to it are estimates too."))
    # time, measurement, the causal winner's f̂', the best smoother's f̂', then each one's f̂'' where it estimates one
    cols = [t, y, est, off[:, 1]] + ([off[:, 2]] if off.shape[1] > 2 else []) + ([causal[:, 2]]
                                                                                if causal.shape[1] > 2 else [])
    names = ["time", "measurement", f"derivative estimate (causal: {win['family']})",
             f"derivative estimate (offline: {best_off.name})"]
    names += [f"second derivative estimate (offline: {best_off.name})"] if off.shape[1] > 2 else []
    names += [f"second derivative estimate (causal: {win['family']})"] if causal.shape[1] > 2 else []
    np.savetxt(ctx.out_dir / "estimate.csv", np.column_stack(cols), delimiter=",", fmt="%.10g", header=",".join(names),
               comments="")
    _figures(ctx, result, t, y, (est, off[:, 1], best_off.name), ref[:, 0], fit[:, 0], setup, ranking + smooth, bound,
             d1 is not None)
    if d1 is None:  # the surrogate's noise-free signal separates lag from noise; a record with d1 has none
        _pareto(ctx, result, ranking + smooth)
    return result, ranking


def _reference(result, y, ref, setup, eps, L) -> None:
    """The bound-attaining difference quotient (:func:`~.bound.difference_quotient`): no tuning, a guarantee."""
    from .bound import difference_quotient

    try:
        d, m, guarantee = difference_quotient(y, setup.dt, eps, L)
    except ValueError:  # a window longer than the record: no reference
        return
    k = max(m, int(round(setup.transient / setup.dt)))
    worst = float(np.max(np.abs(d[k:] - ref[k:]))) if k < y.size else float("nan")
    result.quantity("reference.difference_quotient.worst", f"reference, not tuned: the difference quotient over "
                    f"{m} samples (2√(ε/L) rounded up): worst-case |f̂' - f'| after the start-up window", worst,
                    unit="signal unit/s",
                    note=f"guaranteed at most {guarantee:.4g} = 2ε/(m dt) + L m dt/2 on every record within ε and L")
    result.quantity("reference.difference_quotient.guarantee", "the difference quotient's worst-case error on any "
                    "record with noise <= ε and |f''| <= L: the lower bound 2√(εL) attained (plus at most L dt/2)",
                    guarantee, unit="signal unit/s")


def _price_of_causality(result, ranking, smooth, exact) -> None:
    """The best causal filter against the best offline smoother on this record: the two questions and the ratio."""
    c, o = ranking[0], smooth[0]
    c_rms, o_rms = min(ranking, key=lambda r: r["rms"]), min(smooth, key=lambda r: r["rms"])
    worst, rms = c["worst"] / o["worst"], c_rms["rms"] / o_rms["rms"]
    result.quantity("price_of_causality.worst", "best causal worst-case error / best offline worst-case error", worst,
                    unit="")
    result.quantity("price_of_causality.rms", "best causal RMS error / best offline RMS error", rms, unit="")
    result.finding(
        "price-of-causality",
        f"Two questions, two rankings. Online (a filter that at t knows the samples up to t): {c['label']}, worst-case "
        f"error {c['worst']:.4g}; RMS-tuned best {c_rms['family']}, {c_rms['rms']:.4g}. After the fact (the derivative "
        f"of this record, every sample used): {o['label']}, worst-case error {o['worst']:.4g}; RMS-tuned best "
        f"{o_rms['family']}, {o_rms['rms']:.4g}. The price of causality on this record: {worst:.3g}× in worst-case "
        f"error, {rms:.3g}× in RMS (the worst-case theory's price is √2 over all signals with these bounds)."
        + ("" if exact else " Without the true derivative both are scored on the surrogate, whose signal is a "
           "zero-phase Savitzky-Golay fit of the record: the offline ranking then favours smoothers like that fit."),
        {"worst": worst, "rms": rms, "causal": c["family"], "offline": o["family"]})


def _check_settings(check: dict, t0: float) -> dict:
    """The record check for results.json: stated bounds, the record's estimates, the factor, warnings, cost."""
    e = check["estimates"]
    return {"stated": dict(check["stated"]), "factor": check["factor"], "warnings": list(check["warnings"]),
            "estimates": {"noise_bound": float(e["noise_bound"]), "noise_sigma": float(e["noise_sigma"]),
                          "quantum": float(e["quantum"]), "accel": float(e["accel"]),
                          "accel_time_s": None if e["accel_time"] is None else t0 + float(e["accel_time"]),
                          "accel_scale_s": None if e["accel_scale_s"] is None else float(e["accel_scale_s"])},
            "cost": {k: float(v) for k, v in (check.get("cost") or {}).items()}}


def _figures(ctx, result, t, y, ests, ref, fit, setup, ranking, bound, exact) -> None:
    from ..reporting.report import new_figure

    est, off, off_name = ests
    fig, (ax, bx, cx) = new_figure(3, 1, size=(9.0, 8.5), sharex=True,
                                   title=f"Record and the recommended estimator ({ranking[0]['label']})")
    ax.plot(t, y, lw=0.8, color="0.5", label="measurement")
    if not exact:
        ax.plot(t, fit, lw=1.2, color="tab:blue", label="zero-phase fit (the surrogate's signal)")
    ax.set_ylabel("signal (signal unit)")
    ax.legend(fontsize=8)
    what = "true derivative (from the record)" if exact else "surrogate derivative (zero-phase fit)"
    bx.plot(t, ref, lw=1.2, color="k", label=what)
    bx.plot(t, est, lw=0.9, color="tab:orange", label=f"f̂' of {ranking[0]['family']} (causal)")
    bx.axvspan(t[0], t[0] + setup.transient, color="0.85", label="start-up window (scored apart)")
    span = np.ptp(ref) if np.ptp(ref) > 0 else 1.0
    bx.set_ylim(ref.min() - 0.5 * span, ref.max() + 0.5 * span)
    bx.set_ylabel("derivative (signal unit/s)")
    bx.legend(fontsize=8)
    cx.plot(t, est - ref, lw=0.8, color="tab:orange", label=f"{ranking[0]['family']} (causal)")
    cx.plot(t, off - ref, lw=0.8, color="tab:green", label=f"{off_name} (offline)")
    cx.axvspan(t[0], t[0] + setup.transient, color="0.85")
    for sign in (-1, 1):
        cx.axhline(sign * bound, color="k", ls="--", lw=0.8, label="±2√(εL)" if sign > 0 else None)
    k = int(round(setup.transient / setup.dt))
    scored = np.abs(np.concatenate([est[k:] - ref[k:], off[k:] - ref[k:]]))
    top = max(float(np.max(scored)) if scored.size else 0.0, bound)
    cx.set_ylim(-1.5 * top, 1.5 * top)
    cx.set_xlabel("time (s)")
    cx.set_ylabel("f̂' - f' (signal unit/s)")
    cx.legend(fontsize=8, ncol=3)
    ctx.save_figure(result, fig, "record_estimate.png",
                    caption=f"Top: the record. Middle: the recommended estimator's causal derivative estimate against "
                            f"the {what}. Bottom: the error over time of the recommended causal estimator and of the "
                            f"best offline smoother, against the lower bound ±2√(εL) of any causal estimator's "
                            f"worst case. The grey start-up window ({setup.transient:.3g} s) is left out of every "
                            "family's ranking error and scored apart (the estimator starts at rest on the first "
                            "sample: f̂ = y0, f̂' = 0); the error axis is scaled to the scored window.")
    fams = [r["family"] for r in ranking][::-1]
    ratios = [r["ratio"] for r in ranking][::-1]
    offline = {r["family"] for r in ranking if not r.get("causal", True)}
    fig, ax = new_figure(size=(8.0, 0.45 * len(fams) + 2.0),
                         title="Every family tuned on the record: worst-case derivative error")
    ax.barh(range(len(fams)), ratios, color=["tab:orange" if f == ranking[0]["family"] else
                                             "tab:green" if f in offline else "tab:blue" for f in fams])

    ax.axvline(1.0, color="k", ls="--", lw=1,
               label="2√(εL): no causal estimator stays below it on every signal with |f''| ≤ L and noise ≤ ε\n"
                     "(one record is one such signal: an error below it proves nothing by itself)")
    ax.set_xlim(0.7 * min(ratios), 1.5 * max(1.0, max(ratios)))
    ax.set_yticks(range(len(fams)), fams)
    ax.set_xscale("log")
    ax.set_xlabel(f"worst-case |f̂' - f'| / 2√(εL)   (2√(εL) = {bound:.3g} signal unit/s)")
    handles, _ = ax.get_legend_handles_labels()
    if offline:
        from matplotlib.patches import Patch

        handles.append(Patch(color="tab:green", label="offline smoother (uses the whole record: not bound by 2√(εL))"))
    ax.legend(handles=handles, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.1))
    ctx.save_figure(result, fig, "ranking.png",
                    caption="Each family at its best tuning on this record: worst-case derivative error after the "
                            "start-up window, relative to the lower bound (dashed); the recommended causal one in "
                            "orange, the offline smoothers in green.")


def _pareto(ctx, result, rows) -> None:
    """Each family's Pareto front on the record: lag (noise-free worst error) against noise-induced RMS error."""
    import matplotlib

    from ..reporting.report import new_figure

    colours = matplotlib.colormaps["tab20"]
    fig, ax = new_figure(size=(8.5, 6.0), title="Every family on the record: lag against noise-induced error of f̂'")
    for i, r in enumerate(rows):
        pts = np.array(r.get("pareto") or [])
        if pts.size:
            ax.loglog(pts[:, 0], pts[:, 1], ".-" if r["causal"] else "s--", ms=4, color=colours(i % 20),
                      label=r["family"] + ("" if r["causal"] else " (offline)"))
    ax.set_xlabel("lag: worst |f̂' - f'| without noise (signal unit/s)")
    ax.set_ylabel("noise-induced RMS error of f̂' (signal unit/s)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)
    ctx.save_figure(result, fig, "record_pareto.png",
                    caption="Per family, the Pareto front of every configuration evaluated while tuning on the "
                            "record's surrogate: its lag (the worst derivative error on the surrogate's noise-free "
                            "signal, the zero-phase fit) against the RMS of what the noise adds. Lower left is "
                            "better; a front's corner is the family's best trade-off.")


def report_lines(results: dict, out_dir: Path | str = ".") -> list[str]:
    """A short REPORT.md for a record run, from its results.json dict.

    Parameters
    ----------
    results : dict
        The results.json of :func:`run_record`.
    out_dir : str or Path
        Where the figures are, relative to the report (default: beside it).

    Returns
    -------
    list of str
    """
    if not isinstance(results, dict) or (results.get("settings") or {}).get("mode") != "record":
        raise ValueError("results must be the results.json of an arena run on a record (settings.mode 'record')")
    s = results["settings"]
    q = {x["id"]: x for x in results["quantities"]}
    # a family has its worst-case error and its ratio to the bound (the references and the price have no ratio)
    fams = [x["id"][:-len(".worst")] for x in results["quantities"]
            if x["id"].endswith(".worst") and x["id"][:-len(".worst")] + ".ratio" in q]
    lines = ["# Estimator arena on a record", "",
             f"Record `{s['signal']}`: {s['samples']} samples at dt = {s['dt']:.4g} s; noise bound ε = "
             f"{s['noise_bound']:.4g}, bound L = {s['accel_bound']:.4g} on |f''|; lower bound 2√(εL) = "
             f"{q['bound']['value']:.4g}. Errors are scored on {s['scored_on']}, after a start-up window of "
             f"{s['startup_window_s']:.4g} s.", ""]
    rc = s.get("record_check")
    if rc:
        e = rc["estimates"]
        said = ("Stated bounds" if set((s.get("bounds_source") or {"": "stated"}).values()) == {"stated"} else
                "Bounds (stated, or estimated from the record: settings.bounds_source)")
        lines += [f"{said} against the record's own estimates: noise ε = {rc['stated']['noise_bound']:.4g} "
                  f"(record: ε̂ ≈ {e['noise_bound']:.4g}, from the robust spread of its third differences"
                  + (f"; quantised, step {e['quantum']:.4g}" if e["quantum"] else "") + f"), |f''| ≤ L = "
                  f"{rc['stated']['accel_bound']:.4g} (record: "
                  + (f"≈ {e['accel']:.4g} beyond its noise, from its smoothed second differences" if e["accel"] > 0
                     else "no curvature resolved beyond its noise")
                  + f"). A bound tighter than the record by more than {rc['factor']:g}× is refused; a looser one is "
                  "a warning.", ""]
        lines += [f"**Warning:** {w}." for w in rc["warnings"]] + ([""] if rc["warnings"] else [])
    off = set(s.get("offline_families") or [])
    for title, group in (("Causal filters (online: the samples up to t)", [f for f in fams if f not in off]),
                         ("Offline smoothers (the whole record)", [f for f in fams if f in off])):
        if not group:
            continue
        lines += [f"**{title}**", "", "| rank | family | worst-case error | × bound | tuning | RMS error (RMS-tuned) "
                  "| start-up error / max abs f' |", "|---|---|---|---|---|---|---|"]
        for i, f in enumerate(group, 1):
            rms, start = q.get(f + ".rms"), q.get(f + ".startup")
            lines.append(f"| {i} | {q[f + '.worst']['label'].split(':')[0]} | {q[f + '.worst']['value']:.4g} "
                         f"| {q[f + '.ratio']['value']:.3g} | {q[f + '.worst']['note']} | "
                         + (f"{rms['value']:.4g} ({rms['note']})" if rms else "") + " | "
                         + (f"{start['value']:.3g}" if start else "") + " |")
        lines.append("")
    dq = q.get("reference.difference_quotient.worst")
    if dq:
        lines += [f"Reference, not tuned: {dq['label'].split(': ', 1)[1]}: {dq['value']:.4g} ({dq['note']}).", ""]
    findings = [f for f in results.get("findings") or [] if not str(f.get("id", "")).startswith("bound-warning")]
    lines += ["", *[f"- {f['text']}" for f in findings], "",
              "The estimates at every sample: `estimate.csv` (time, measurement, the recommended causal estimator's "
              "f̂', the best offline smoother's f̂', then each one's f̂'' where it estimates one; the header names "
              "every column).", ""]
    for fig in results.get("figures") or []:
        lines += [f"![{fig}]({Path(out_dir) / fig})", "", (results.get("captions") or {}).get(fig, ""), ""]
    return lines
