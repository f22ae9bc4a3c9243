"""Closed-loop metrics of the `pendulum` study per case and regime, and the per-run comparisons.

:data:`METRICS` names every closed-loop metric; :func:`case_metrics` computes them for one case,
:func:`paired_changes` / :class:`Paired` compare the filter case with no filter on the same noise, and
:func:`record_regime` records one regime's cases (the main run and every box evaluation).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from ctrl_analysis import metrics
from ctrl_analysis.reporting.report import StudyResult

__all__ = ["METRICS", "PAIRED", "PAIRED_LITERAL", "PER_RUN", "SINGLE", "Paired", "case_label", "case_metrics",
           "case_stats", "cid", "paired_changes", "phi_band", "qid", "record_comparisons", "record_regime",
           "regime_label"]


#: quantity -> (label, unit); per-run metrics are mean ± std over the healthy runs, the others single values
METRICS = {
    "overshoot": (("step overshoot per run (peak of φ for t < t_tr over the run's own final value, the mean for "
                   "t ≥ t_ss; noise excursions included, as one run of Fig. 4 shows it)"), "%"),
    "overshoot_noise_only": (("the same per-run peak over an equally long window from t_ss, without a step (what the "
                              "noise alone makes of it)"), "%"),
    "overshoot_mean_response": (("step overshoot of the mean response over the runs (peak of the run-averaged φ "
                                 "for t < t_tr above its own final value)"), "%"),
    "overshoot_mean_response_floor": (("noise floor of the mean-response overshoot: the same peak statistic of the "
                                       "run-averaged φ over an equally long steady window from t_ss (no step "
                                       "there)"), "%"),
    "overshoot_noise_free": ("step overshoot of the noise-free response (peak for t < t_tr above its final value)",
                             "%"),
    "steady_offset": ("steady-state offset: mean of φ − r over the steady-state window", "rad"),
    "settling_time": ("settling time of φ into the band, per run (runs that settle and stay)", "s"),
    "settled_share": ("fraction of the runs that settle into the band and stay there", ""),
    "settling_time_mean": ("settling time of the mean response over the runs into the band", "s"),
    "settling_time_noise_free": ("settling time of the noise-free response into the band", "s"),
    "angle_rms": ("RMS of φ − r over the steady-state window", "rad"),
    "accel_rms": ("RMS of the cart acceleration u over the steady-state window (control effort)", "m/s²"),
    "chatter": (("RMS of the control increments Δu(k) = u(k) − u(k−1) over the steady-state window (control "
                 "chatter)"), "m/s²"),
    "sat_e": ("fraction of steady-state samples in which the angle-error input e is saturated (|Ke·e| ≥ 6)", ""),
    "sat_ec": ("fraction of steady-state samples in which the rate input ec is saturated (|Kec·ec| ≥ 6)", ""),
    "angle_input_error": (("RMS error of the angle the controller receives (y, or φ̂) against the true φ, "
                           "steady-state window"), "rad"),
    "rate_input_error": (("RMS error of the rate the controller receives (backward difference of y, or φ̂') "
                          "against the true φ', steady-state window"), "rad/s"),
}
#: metrics computed once from the mean response or the noise-free run (no spread over runs)
SINGLE = ("overshoot_mean_response", "overshoot_mean_response_floor", "overshoot_noise_free", "settled_share",
          "settling_time_mean", "settling_time_noise_free")

#: per-run comparisons of the filter case with no filter (same noise in both: common random numbers), what the
#: claims read: metric -> (what it is, what a lower value means)
PAIRED = {
    "overshoot": ("step overshoot", "a lower peak"),
    "angle_rms": ("oscillation (steady RMS of φ − r)", "less jitter of the pendulum"),
    "angle_input_error": ("error of the angle the controller receives", "closer to the true angle"),
    "rate_input_error": ("error of the rate the controller receives", "closer to the true rate"),
    "settling_time": ("settling time", "earlier; a run that does not settle counts at the end of the record"),
    "accel_rms": ("control effort (steady RMS of u)", "less effort"),
    "chatter": ("control chatter (steady RMS of Δu)", "less chatter"),
}
#: the comparisons of the literal regime (its claims: overshoot and oscillation)
PAIRED_LITERAL = ("overshoot", "angle_rms")

_FILTER_LABEL = {
    "paper": "paper's suboptimal filter, K = [0.950, 0.863] read as a discrete α-β filter (k2 = β/T)",
    "steady-state": ("the suboptimal filter with the corrected gain: the steady-state Kalman gain of the noise "
                     "simulated (algorithm axis, gain_reading = steady-state)"),
}
CASE_LABELS = {
    "nofilter": "no filter (e and its backward difference)",
    "filter": _FILTER_LABEL["paper"],
    "kf": "time-varying discrete Kalman filter (beyond the paper)",
    "kf_ss": "correct steady-state gain for the simulated noise (beyond the paper)",
    "kf_ss_qr": "steady-state gain of the paper's Q/R = 2, i.e. σ_w/σ_v = √2 (beyond the paper)",
    "paper_continuous": "paper's filter as printed (continuous, Euler-sampled) (beyond the paper)",
    "nonlinear.nofilter": "nonlinear sin φ pendulum, no filter (beyond the paper)",
    "nonlinear.filter": "nonlinear sin φ pendulum, paper's α-β filter (beyond the paper)",
}


def case_label(name: str, p) -> str:
    """The label of case ``name`` (the filter case says which gain reading it runs)."""
    return _FILTER_LABEL[p.gain_reading] if name == "filter" else CASE_LABELS[name]


def _gain_word(p) -> str:
    """How the claims' notes name the filter case: the paper's K or the corrected gain."""
    return "the paper's K" if p.gain_reading == "paper" else "the corrected (steady-state) gain"


def regime_label(p, literal: bool) -> str:
    """``main regime (T = 2 ms, σ_v = 0.5 mrad, σ_w = 0.5 rad/s²)`` or the literal one."""
    return (f"{'literal' if literal else 'main'} regime (T = {p.T * 1e3:g} ms, σ_v = {p.sigma_v * 1e3:g} mrad, "
            f"σ_w = {p.sigma_w:.3g} rad/s²)")


def qid(case: str, metric: str, literal: bool = False) -> str:
    """Quantity id of a closed-loop metric: ``cl.<case>`` (main, the paper's), ``beyond.<case>``, ``literal.<case>``."""
    prefix = "literal" if literal else ("cl" if case in ("nofilter", "filter") else "beyond")
    return f"{prefix}.{case}.{metric}"


def cid(metric: str, literal: bool = False) -> str:
    """Quantity id of a per-run comparison of the filter case with no filter: ``cl.filter_vs_nofilter.<metric>``."""
    return f"{'literal' if literal else 'cl'}.filter_vs_nofilter.{metric}"


def _settled_at(t, phi, p) -> np.ndarray:
    """Settling time into the band; NaN for a response that is not inside it for the last ``p.settle_hold`` s."""
    st = np.atleast_1d(metrics.settling_time(t, phi, p.step, band=p.settle_band))
    return np.where(st <= t[-1] - p.settle_hold, st, np.nan)


def _peak_over_final(phi, final) -> np.ndarray:
    """Per-run overshoot ``max(max φ / final − 1, 0) · 100`` (:func:`ctrl_analysis.metrics.overshoot` of a step
    from 0 to each run's own ``final``, vectorised over the runs; equal to it run by run, tested)."""
    with np.errstate(all="ignore"):
        return np.maximum(np.max(phi, axis=0) / final - 1.0, 0.0) * 100.0


def phi_band(run):
    """Mean and standard deviation of φ per sample over the runs that did not diverge, and their number.

    Parameters
    ----------
    run : loops.ClosedLoopRun or loops.StreamedRuns
        A case's runs; for runs reduced part by part, from their running moments.

    Returns
    -------
    mean, std : numpy.ndarray
    n : int
    """
    m = getattr(run, "phi_moments", None)
    if m is not None:
        return m.mean, m.std(), int(m.count)
    ok = ~run.diverged
    return np.mean(run.phi[:, ok], axis=1), np.std(run.phi[:, ok], axis=1), int(ok.sum())


#: The metrics of :func:`case_metrics` that are one value per run (the others are one value per case).
PER_RUN = ("overshoot", "overshoot_noise_only", "settling_time", "angle_rms", "accel_rms", "chatter", "sat_e", "sat_ec",
           "angle_input_error", "rate_input_error", "steady_offset")


def case_metrics(c, p, keys=None) -> dict:
    """Metrics of one case (:class:`~.loops.CaseRuns`): per-run arrays (NaN where a run diverged) and single values.

    ``keys``: only these metrics (the box exploration computes what its claims read); default all of
    :data:`METRICS`.
    """
    keys = set(METRICS) if keys is None else set(keys)
    run, quiet = c.noisy, c.quiet
    ss = run.t >= p.t_ss
    tr = run.t < p.t_tr  # the step transient
    floor = ss & (run.t < p.t_ss + p.t_tr)  # an equally long window without a step
    ok = ~run.diverged
    per_run = {
        "overshoot": lambda: _peak_over_final(run.phi[tr], final_run),
        "overshoot_noise_only": lambda: _peak_over_final(run.phi[floor], final_run),
        "settling_time": lambda: _settled_at(run.t, run.phi, p),
        "angle_rms": lambda: np.sqrt(np.mean((run.phi[ss] - p.step) ** 2, axis=0)),
        "accel_rms": lambda: np.sqrt(np.mean(run.u[ss] ** 2, axis=0)),
        "chatter": lambda: np.sqrt(np.mean(np.diff(run.u, axis=0)[ss[1:]] ** 2, axis=0)),
        "sat_e": lambda: np.mean(np.abs(p.Ke * run.e[ss]) >= p.input_range, axis=0),
        "sat_ec": lambda: np.mean(np.abs(p.Kec * run.ec[ss]) >= p.input_range, axis=0),
        # what the fuzzy controller receives: e = r − φ_in, ec = −φ_in'
        "angle_input_error": lambda: np.sqrt(np.mean((p.step - run.e[ss] - run.phi[ss]) ** 2, axis=0)),
        "rate_input_error": lambda: np.sqrt(np.mean((-run.ec[ss] - run.dphi[ss]) ** 2, axis=0)),
        "steady_offset": lambda: final_run - p.step,
    }
    m = {}
    streamed = getattr(run, "per_run", None)  # runs reduced part by part (loops.StreamedRuns): metrics kept
    with np.errstate(all="ignore"):
        final_run = None if streamed is not None else np.mean(run.phi[ss], axis=0)  # each run's own final value
        for k, f in per_run.items():
            if k in keys or (k == "settling_time" and "settled_share" in keys):
                m[k] = streamed[k] if streamed is not None else np.where(ok, f(), np.nan)
        quiet_ok = not quiet.diverged[0]
        if "settled_share" in keys:
            m["settled_share"] = float(np.mean(np.isfinite(m["settling_time"][ok]))) if ok.any() else None
        if keys & {"overshoot_mean_response", "overshoot_mean_response_floor", "settling_time_mean"}:
            if streamed is not None:
                mean_phi = run.phi_moments.mean if ok.any() else np.full(run.t.size, np.nan)
            else:
                mean_phi = np.mean(run.phi[:, ok], axis=1) if ok.any() else np.full(run.t.size, np.nan)
            final = float(np.mean(mean_phi[ss]))  # the mean response's own final value
            m["overshoot_mean_response"] = (float(metrics.overshoot(run.t[tr], mean_phi[tr], final))
                                            if ok.any() else None)
            m["overshoot_mean_response_floor"] = (float(metrics.overshoot(run.t[floor], mean_phi[floor], final))
                                                  if ok.any() else None)
            m["settling_time_mean"] = float(_settled_at(run.t, mean_phi, p)[0]) if ok.any() else None
        if "overshoot_noise_free" in keys:
            m["overshoot_noise_free"] = (float(metrics.overshoot(quiet.t[tr], quiet.phi[tr, 0],
                                                                 np.mean(quiet.phi[ss, 0]))) if quiet_ok else None)
        if "settling_time_noise_free" in keys:
            m["settling_time_noise_free"] = float(_settled_at(quiet.t, quiet.phi[:, 0], p)[0]) if quiet_ok else None
    return m


@functools.cache
def _median_ci_ranks(n: int) -> tuple:
    """0-based ranks of the order statistics that bound the 95 % interval of the median of ``n`` values.

    scipy's distribution-free interval (:func:`scipy.stats.quantile_test`) evaluated once per ``n`` on the
    ranks themselves; ``(None, None)`` where ``n`` is too small for a 95 % interval.
    """
    from scipy.stats import quantile_test

    ci = quantile_test(np.arange(n, dtype=float), q=0.0, p=0.5).confidence_interval(0.95)
    if not (np.isfinite(ci.low) and np.isfinite(ci.high)):
        return (None, None)
    return (int(ci.low), int(ci.high))


@dataclasses.dataclass(frozen=True)
class Paired:
    """Per-run changes of one metric, filter vs no filter, in units of the no-filter median.

    ``median`` is the claim's measure; ``lo``/``hi`` the 95 % interval of the median; ``floor`` the half-width of
    that interval on zero's side (the smallest median change the runs resolve: ``|median| < floor`` means the
    interval contains 0); ``share`` the fraction of runs in which the filter lowers the metric.
    """

    n: int
    median: float
    lo: float
    hi: float
    share: float

    @property
    def floor(self) -> float:
        if self.n == 0:
            return math.inf
        return (self.hi - self.median) if self.median < 0 else (self.median - self.lo)

    @property
    def resolved(self) -> bool:
        return bool(self.n and abs(self.median) >= self.floor)

    @classmethod
    def of(cls, changes) -> Paired:
        d = np.sort(np.asarray(changes, dtype=float))
        d = d[np.isfinite(d)]
        if not d.size:
            return cls(0, math.nan, -math.inf, math.inf, math.nan)
        i, j = _median_ci_ranks(d.size)
        return cls(int(d.size), float(np.median(d)), -math.inf if i is None else float(d[i]),
                   math.inf if j is None else float(d[j]), float(np.mean(d < 0)))


def paired_changes(a, b, horizon: float | None = None):
    """Per-run changes ``b − a`` over the median of ``a`` (runs healthy in both; NaN marks a diverged run).

    With ``horizon`` (settling times) a run that does not settle counts as settling at the end of the record.
    Returns ``(changes, median of a)``.
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if horizon is not None:
        a, b = np.where(np.isnan(a), horizon, a), np.where(np.isnan(b), horizon, b)
    both = np.isfinite(a) & np.isfinite(b)
    if not both.any():
        return np.array([]), math.nan
    base = float(np.median(a[both]))
    with np.errstate(all="ignore"):
        return (b[both] - a[both]) / base, base


def record_comparisons(result: StudyResult, ma: dict, mb: dict, p, literal: bool = False, metrics_=None) -> None:
    """Record the per-run comparisons (:data:`PAIRED`) of the filter case (``mb``) with no filter (``ma``).

    Each quantity's value is the median per-run change in units of the no-filter median, its samples the
    per-run changes (the claims read the interval of the median and the share of runs from them).
    """
    for key in metrics_ or (PAIRED_LITERAL if literal else PAIRED):
        horizon = p.t_end if key == "settling_time" else None
        ch, base = paired_changes(ma[key], mb[key], horizon)
        st = Paired.of(ch)
        unit = METRICS[key][1]
        step = "percentage points" if unit == "%" else unit
        note = (f"{'literal' if literal else 'main'} regime, {case_label('filter', p)} against no filter, same noise "
                f"in both: " + (f"lower in {round(st.share * st.n)} of {st.n} runs ({st.share:.0%}); median "
                                f"change {st.median * base:+.3g} {step} ({st.median:+.1%} of the no-filter median "
                                f"{base:.3g} {unit}); 95 % interval of the median {st.lo:+.1%} to {st.hi:+.1%} "
                                "(order statistics, scipy.stats.quantile_test)" if st.n else "no run healthy in both"))
        name, lower = PAIRED[key]
        result.quantity(cid(key, literal), f"{name}: per-run change with the filter against no filter, same noise "
                        f"(median, fraction of the no-filter median; below 0: {lower})",
                        None if not st.n else st.median,
                        runs=int(np.size(ma[key])), unit="", note=note, samples=ch if st.n else None)


def case_stats(result: StudyResult, case: str, literal: bool) -> dict:
    """``{metric: (value, std, runs)}`` of one recorded case (for the figures)."""
    out = {}
    for key in METRICS:
        q = result.get(qid(case, key, literal))
        out[key] = (None if q.is_diverged else q.value, q.std, q.runs)
    return out


def record_regime(result: StudyResult, cases: dict, p, literal: bool = False, keys=None, metrics_=None) -> dict:
    """Record every metric of every case of one regime, and the per-run comparisons of the filter case with no
    filter; returns ``{case: {metric: (value, std, n)}}``.

    ``keys``: ``{case: metrics}``, only these (the box exploration records what its claims read); ``metrics_``:
    ``{case: case_metrics(...)}`` computed already (then ``cases`` need only say which runs diverged,
    :meth:`~.loops.CaseRuns.light`).
    """
    ms = metrics_ or {name: case_metrics(c, p, None if keys is None else keys[name]) for name, c in cases.items()}
    out = {name: _record_case(result, name, c, p, literal, ms[name], None if keys is None else keys[name])
           for name, c in cases.items()}
    if "nofilter" in ms and "filter" in ms:
        record_comparisons(result, ms["nofilter"], ms["filter"], p, literal)
    return out


def _record_case(result: StudyResult, name: str, c, p, literal: bool, m: dict, keys=None) -> dict:
    run = c.noisy
    ok = ~run.diverged
    where = f"{case_label(name, p)}; {regime_label(p, literal)}"
    out = {}
    for key, (label, unit) in METRICS.items():
        if keys is not None and key not in keys:
            continue
        vals = m[key]
        if key in SINGLE:
            value, std, n = (None if vals is None or not np.isfinite(vals) else vals), None, int(ok.sum())
            quiet = key.endswith("noise_free")
            runs = 1 if quiet else int(ok.size)
            diverged = int(c.quiet.diverged[0]) if quiet else int((~ok).sum())
            note = where + ("; one noise-free run" if quiet else f"; mean response over {n} of {ok.size} runs")
            if vals is not None and not np.isfinite(vals):
                note += " (does not settle: not inside the band for the last "f"{p.settle_hold:g} s)"
        else:
            good = ok & np.isfinite(vals)
            value, std, n = metrics.mean_std(vals, good)
            value = None if n == 0 else float(value)
            std = None if n == 0 else float(std)
            runs, diverged = int(ok.size), int((~ok).sum())
            note = f"{where}; mean ± std over {n} of {ok.size} runs"
            if key == "settling_time" and n < ok.sum():
                note += (f" ({int(ok.sum() - n)} runs did not stay in the ±{p.settle_band:.0%} band for the last "
                         f"{p.settle_hold:g} s)")
        if diverged:
            steps = run.diverged_step[~ok] if not key.endswith("noise_free") else c.quiet.diverged_step[:1]
            note += f"; {diverged} diverged (first at t = {int(np.min(steps)) * p.T:.3g} s), excluded"
        all_div = runs > 0 and diverged == runs
        result.quantity(qid(name, key, literal), f"{label} — {case_label(name, p)}, "
                        f"{'literal' if literal else 'main'} regime", None if all_div else value,
                        std=None if all_div else std, runs=runs, runs_diverged=diverged, unit=unit, note=note)
        out[key] = (None if all_div else value, std, n)
    return out
