"""Quantities and findings of the `ckf` study, computed from the simulated runs (finding texts from numbers)."""

from __future__ import annotations

import numpy as np

from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.kalman import (
    CharacteristicKalmanFilter,
    LinearKalmanFilter,
)
from ctrl_analysis.identification import batch_least_squares
from ctrl_analysis.metrics import mean_std
from ctrl_analysis.plants import DiscreteLTI

from .paper import READINGS

__all__ = [
    "COMPARED",
    "cost",
    "filter_errors",
    "full_order_errors",
    "identification",
    "identification_bias",
    "judge_claims",
    "kf_mults",
    "missing",
    "noise_free_fit",
    "offset_terms",
    "open_loop",
    "prediction_error",
    "q_sweep",
    "record",
    "record_claims",
    "record_fit",
    "rls_mults",
    "table1",
    "window",
]

#: Table 1's rows and columns as the paper names them (its numbers were lost in the extracted text).
TABLE1_ROWS = {"nofilter": "no filter", "lpf": "LPF", "ckf": "CKF"}
TABLE1_COLUMNS = {"y_mean": "output mean", "y_var": "output variance", "u_mean": "control mean",
                  "u_var": "control variance"}
PARAMS = ("f1", "f2", "g0")
HAT = {"f1": "f̂1", "f2": "f̂2", "g0": "ĝ0"}


def window(t, t0, t1=np.inf):
    """Boolean mask of the samples with ``t0 <= t < t1`` (``t1`` inclusive when infinite)."""
    return (t >= t0 - 1e-9) & ((t < t1 - 1e-9) if np.isfinite(t1) else True)


def record(result, id, label, per_run, ok, unit="", paper=None, tolerance=None, note="", **cell):
    """Add a quantity as mean ± std over the runs in ``ok`` (diverged runs excluded and counted).

    ``runs`` is every run, ``runs_diverged`` the excluded ones; ``cell`` / ``primary`` pass through.
    """
    per_run = np.asarray(per_run, dtype=float)
    mean, std, n = mean_std(per_run, ok)
    lost = int(np.size(ok) - np.count_nonzero(ok))
    if lost:
        note = (note + " " if note else "") + f"{lost} diverged run(s) excluded"
    if n == 0:
        note = (note + " " if note else "") + "all runs diverged"
        return result.quantity(id, label, None, paper=paper, runs=int(np.size(ok)), runs_diverged=int(np.size(ok)),
                               diverged=True, unit=unit, tolerance=tolerance, note=note, **cell)
    return result.quantity(id, label, float(mean), paper=paper, std=float(std), runs=int(np.size(ok)),
                           runs_diverged=lost, unit=unit, tolerance=tolerance, note=note, **cell)


def table1(result, data, p, prefix="", tag=""):
    """Table 1: mean and variance of the true output and of the control over the steady stage, per case.

    Also the steady RMS error of the output about the reference (``<case>.y_rmse``, for the claims) and,
    on the main run, the control's RMS without a filter beside the printed 1.27 (percentile policy).
    """
    stats = {}
    for case in ("nofilter", "lpf", "ckf"):
        d = data[case]
        m = window(d["t"], p.t_steady)
        y, u = d["y"][m], d["u"][m]
        per = {"y_mean": y.mean(0), "y_var": y.var(0), "u_mean": u.mean(0), "u_var": u.var(0)}
        for q, v in per.items():
            what = {"y": "true output", "u": "control"}[q[0]] + (" mean" if "mean" in q else " variance")
            # the paper's Table 1 cell: printed, but its number was lost in extraction (paper None)
            cell = {} if prefix else {"cell": f"Table 1 / {TABLE1_ROWS[case]} / {TABLE1_COLUMNS[q]}", "primary": True}
            record(result, f"{prefix}{case}.{q}", f"{tag}{TABLE1_ROWS[case]}: {what} over {p.t_steady:g}-{p.t_end:g} s",
                   v, d["ok"], **cell)
        per["y_rmse"] = np.sqrt(np.mean((y - p.reference) ** 2, axis=0))
        record(result, f"{prefix}{case}.y_rmse", f"{tag}{TABLE1_ROWS[case]}: RMS output error about the reference, "
               f"{p.t_steady:g}-{p.t_end:g} s", per["y_rmse"], d["ok"])
        stats[case] = per
    if not prefix:
        ok = data["nofilter"]["ok"]
        rms = np.sqrt(stats["nofilter"]["u_var"])
        record(result, "nofilter.u_rms", "no filter: RMS of the control about its mean (steady stage)", rms, ok,
               paper=p.u_rms_nofilter, samples=rms[ok],
               note=f"the paper's number comes from one noisy run: percentile policy over the runs; read as the RMS "
                    f"about the mean ('the signal stays within the mean ± 3 RMS'); it scales as 1/(ĝ0 + μ) with the "
                    f"reconstructed μ = {p.mu:g}",
               cell="§3 text / control RMS without filter", primary=True)
    return stats


def filter_errors(result, data, p, prefix="", tag=""):
    """RMS of (filtered − true output) per run: whole run, transient 0-10 s (and 2-10 s) and steady stage.

    Also the LPF at half its cut-off re-run on the LPF case's measurements (``lpf_half.filter_rmse_transient``):
    the paper's remark that a lower bandwidth deviates more in the transient.
    """
    from ctrl_analysis.estimators.lowpass import LowPassFilter

    t = data["lpf"]["t"]
    spans = {"filter_rmse": (0.0, np.inf), "filter_rmse_transient": (0.0, 10.0),
             "filter_rmse_transient_used": (p.t_filter, 10.0), "filter_rmse_steady": (p.t_steady, np.inf)}
    half = open_loop(LowPassFilter(p.lpf_omega / 2, p.lpf_order).digital(p.Ts), {"y_m": data["lpf"]["y_m"]}, "y_lpf")
    sigs = (("lpf", "lpf", data["lpf"]["y_lpf"]), ("ckf", "ckf", data["ckf"]["y_ckf"]), ("lpf_half", "lpf", half))
    out = {}
    for name, case, sig in sigs:
        d = data[case]
        for q, (a, b) in spans.items():
            if name == "lpf_half" and q != "filter_rmse_transient":
                continue
            m = window(t, a, b)
            v = np.sqrt(np.mean((sig[m] - d["y"][m]) ** 2, axis=0))
            who = (f"LPF at half the cut-off ({p.lpf_omega / 2:g} rad/s, re-run on the LPF case's measurements)"
                   if name == "lpf_half" else TABLE1_ROWS[name])
            record(result, f"{prefix}{name}.{q}", f"{tag}{who}: RMS filter error, {a:g}-{min(b, p.t_end):g} s", v,
                   d["ok"])
            out[(name, q)] = v
    return out


def kf_mults(n: int) -> int:
    """Multiplications per step of an ``n``-state Kalman filter with a scalar measurement, Joseph form."""
    return n * n + 2 * n ** 3 + 2 * n + n + 2 * n ** 3 + n * n + n


def rls_mults(n_params: int) -> int:
    """Multiplications per step of an RLS with ``n_params`` parameters (gain, estimate, covariance)."""
    return 2 * n_params * n_params + 3 * n_params + n_params * n_params


def cost(result, p, plant_order: int):
    """Operation counts per step: the CKF (2 states + RLS of 3) against a full-order KF (+ an ARX RLS of 2n)."""
    ckf = kf_mults(2) + rls_mults(3)
    full = kf_mults(plant_order) + rls_mults(2 * plant_order)
    result.quantity("cost.ckf_mults", "CKF: multiplications per step (2-state KF + RLS of f1, f2, g0)", float(ckf),
                    unit="")
    result.quantity("cost.fullorder_mults", f"full-order KF: multiplications per step ({plant_order}-state KF + RLS "
                    f"of the {2 * plant_order} ARX parameters it would need)", float(full), unit="")
    result.quantity("cost.fullorder_known_mults", f"full-order KF knowing the plant: multiplications per step "
                    f"({plant_order}-state KF only)", float(kf_mults(plant_order)), unit="")
    return ckf, full


def noise_free_fit(d, p, t0=None, t1=np.inf):
    """Noise-free least-squares fit of the characteristic model to the true plant, per run.

    ``x(k) = f1 x(k−1) + f2 x(k−2) + g0 u(k−1)`` fitted on the true output ``x`` and the applied
    control over ``[t0, t1)`` (the regression the RLS sees, without the measurement noise).

    Returns
    -------
    theta : ndarray, shape (runs, 3)
    cond : float
        Largest column-scaled condition number of the batches.
    """
    t = d["t"]
    k = np.nonzero(window(t, p.t_steady if t0 is None else t0, t1))[0]
    k = k[k >= 2]
    theta, cond = [], 0.0
    for b in range(d["y"].shape[1]):
        x, u = d["y"][:, b], d["u"][:, b]
        fit = batch_least_squares(np.column_stack([x[k - 1], x[k - 2], u[k - 1]]), x[k], warn=False)
        theta.append(fit.theta)
        cond = max(cond, fit.report.cond_scaled)
    return np.array(theta), cond


def prediction_error(d, t0, t1=np.inf, theta=None):
    """RMS one-step prediction error of a characteristic model on the true output, per run.

    ``x(k) − [f1 x(k−1) + f2 x(k−2) + g0 u(k−1)]`` over ``[t0, t1)``, with the estimates the loop used at
    step ``k−1`` (``theta=None``) or a fixed ``theta`` per run, shape ``(runs, 3)``.
    """
    x, u, t = d["y"], d["u"], d["t"]
    k = np.nonzero(window(t, t0, t1))[0]
    k = k[k >= 2]
    if theta is None:
        f1, f2, g0 = d["f1"][k - 1], d["f2"][k - 1], d["g0"][k - 1]
    else:
        f1, f2, g0 = (theta[:, i][None, :] for i in range(3))
    e = x[k] - (f1 * x[k - 1] + f2 * x[k - 2] + g0 * u[k - 1])
    return np.sqrt(np.mean(e ** 2, axis=0))


def identification(result, d, p, prefix="", tag=""):
    """How far the identification travels and how well its model predicts (CKF case ``d``); returns the numbers.

    Records ``{prefix}ident.f1_travel`` / ``f2_travel`` (largest |f̂ − θ0| over the run, per run), the final
    estimates ``{prefix}ident.f1_final`` ... and the one-step prediction errors of the identified model on the
    true output, transient (2-10 s) and steady stage.
    """
    ok = d["ok"]
    out = {}
    for i, n in enumerate(("f1", "f2")):
        travel = np.abs(d[n] - p.theta0[i]).max(axis=0)
        record(result, f"{prefix}ident.{n}_travel", f"{tag}largest |{HAT[n]} − θ0| over the run (CKF case)", travel, ok,
               note=f"θ0 = {p.theta0}")
        out[f"{n}_travel"] = (float(np.mean(travel[ok])), float(np.max(travel[ok])))
    for n in PARAMS:
        record(result, f"{prefix}ident.{n}_final", f"{tag}identified {HAT[n]} at {p.t_end:g} s (CKF case)", d[n][-1], ok)
        out[f"{n}_final"] = float(np.mean(d[n][-1][ok]))
    for span, (a, b) in {"transient": (p.t_filter, 10.0), "steady": (p.t_steady, np.inf)}.items():
        v = prediction_error(d, a, b)
        record(result, f"{prefix}ident.pred_rmse_{span}", f"{tag}one-step prediction RMS error of the identified "
               f"model on the true output, {a:g}-{min(b, p.t_end):g} s (CKF case)", v, ok)
        out[f"pred_{span}"] = float(np.mean(v[ok]))
    return out


def record_fit(result, d, p):
    """The noise-free LS fit of the characteristic model to the true plant (steady stage, CKF case) and its error."""
    fit, cond = noise_free_fit(d, p)
    for i, n in enumerate(PARAMS):
        record(result, f"fit.{n}", f"noise-free LS fit of the true plant: {n} ({p.t_steady:g}-{p.t_end:g} s, CKF case)",
               fit[:, i], d["ok"], note=f"column-scaled condition number <= {cond:.3g}")
    v = prediction_error(d, p.t_steady, theta=fit)
    record(result, "fit.pred_rmse_steady", "one-step prediction RMS error of the noise-free LS fit on the true output "
           f"(its own data, {p.t_steady:g}-{p.t_end:g} s): the lower bound", v, d["ok"])
    return fit, cond


def offset_terms(d, p):
    """Steady-stage means of the control law's terms in one case: why the output settles where it does.

    Returns ``{"y_end", "y", "u", "bias", "u0", "ul", "ui", "gain", "c2_share", "e"}``: output and control means, the
    steady bias of the fed-back signal (``y_end``: the output mean over the last tenth of the run) (fed back minus true output), the maintaining-
    tracking, golden-section and logic-integral terms (eq. 17-19, recomputed from the records), the identified
    static gain ĝ0 / (1 − f̂1 − f̂2) and the share of steps in which the integral leaks (c = c2).
    """
    m = window(d["t"], p.t_steady)
    ok = d["ok"]
    r = p.reference
    f1, f2, g0 = (d[n][:, ok] for n in PARAMS)
    e = d["y_fb"][:, ok] - r
    e_prev = np.vstack([e[:1], e[:-1]])
    u0 = (r - f1 * r - f2 * r) / g0
    ul = -(p.l1 * f1 * e + p.l2 * f2 * e_prev) / (g0 + p.mu)
    ui = d["u"][:, ok] - u0 - ul
    leak = e * (e - e_prev) <= 0.0
    mean = lambda v: float(np.mean(v[m]))
    end = window(d["t"], 0.9 * d["t"][-1])
    return {"y_end": float(np.mean(d["y"][end][:, ok])), "y": mean(d["y"][:, ok]), "u": mean(d["u"][:, ok]), "bias": mean(d["y_fb"][:, ok] - d["y"][:, ok]), "u0": mean(u0), "ul": mean(ul), "ui": mean(ui),
            "gain": float(np.mean(g0[m]) / (1.0 - np.mean(f1[m]) - np.mean(f2[m]))), "c2_share": mean(leak),
            "e": mean(e)}


def identification_bias(result, data_opts, p, r=READINGS):
    """Bias of f̂1, f̂2, ĝ0 (steady-stage mean minus the noise-free fit) per identification option, CKF case."""
    out = {}
    for opt, data in data_opts.items():
        d = data["ckf"]
        ref, _ = noise_free_fit(d, p)
        m = window(d["t"], p.t_steady)
        for i, name in enumerate(PARAMS):
            bias = d[name][m].mean(0) - ref[:, i]
            record(result, f"ident.{opt}.{name}_bias", f"identification from '{opt}': bias of {name} (CKF case)",
                   bias, d["ok"], note="steady-stage mean of the estimate minus the noise-free LS fit of the same run")
            out[(opt, name)] = float(np.mean(bias))
        track = np.mean([np.mean(np.abs(data[c]["y"][m].mean(0) - p.reference) < r.tracks * p.reference)
                         for c in data])
        result.quantity(f"ident.{opt}.tracking_fraction", f"identification from '{opt}': fraction of runs (all "
                        f"cases) whose steady output mean is within {r.tracks:.0%} of the reference", float(track),
                        runs=int(sum(data[c]["y"].shape[1] for c in data)), unit="")
        out[(opt, "track")] = float(track)
    return out


def open_loop(block, signals, output):
    """Drive a discrete ``block`` with recorded inputs through a one-block :class:`Loop` (compiled engine).

    Parameters
    ----------
    block : DiscreteBlock
    signals : dict of str -> numpy.ndarray, shape (N, B)
        The block's inputs in order, one record per input.
    output : str
        The output kept (the block's first output).

    Returns
    -------
    numpy.ndarray, shape (N, B)
        ``output(k)`` for ``k = 0 .. N-1``, as ``block.run`` gives it.
    """
    outs = (output,) + tuple(f"_{o}" for o in block.outputs[1:])
    loop = Loop([place(block, "b", inputs=list(signals), outputs=list(outs))], dt=1.0)
    N, B = next(iter(signals.values())).shape
    res = loop.simulate(N - 1, inputs=signals, runs=B, store_states=False, keep=[output], bound=np.inf)
    return res[output]


def full_order_errors(d, p, plant):
    """A full-order Kalman filter that knows the plant, run on the CKF case's records: RMS errors per run."""
    sys = DiscreteLTI(plant, p.Ts)
    kf = LinearKalmanFilter(sys.A, sys.B, sys.C, p.kf_Q * np.outer(sys.B, sys.B), p.R, p.kf_P0)
    yhat = open_loop(kf, {"y_m": d["y_m"], "u_prev": d["u_prev"]}, "yhat")
    err = yhat - d["y"]
    t = d["t"]
    return {q: np.sqrt(np.mean(err[window(t, a, b)] ** 2, axis=0))
            for q, (a, b) in {"transient": (0.0, 10.0), "steady": (p.t_steady, np.inf)}.items()}, yhat[:, 0]


def q_sweep(d, p, qs, runs=10):
    """The CKF alone (open loop) on the LPF case's records for each ``Q = q I``: RMS errors, transient and steady."""
    t = d["t"][:-1]
    inp = {s: d[s][:-1, :runs] for s in ("y_m", "u_prev", "f1", "f2", "g0")}
    out = {"transient": [], "steady": []}
    for q in qs:
        y = open_loop(CharacteristicKalmanFilter(Q=q, R=p.R, P0=p.P0_ckf), inp, "y_ckf")
        err = y - d["y"][:-1, :runs]
        out["transient"].append(float(np.sqrt(np.mean(err[window(t, 0.0, 10.0)] ** 2))))
        out["steady"].append(float(np.sqrt(np.mean(err[window(t, p.t_steady)] ** 2))))
    return {k: np.array(v) for k, v in out.items()}


#: Comparisons behind the claims: claim id -> (quantity, case the CKF is compared with).
COMPARED = {"transient": ("filter_rmse_transient", "lpf"), "steady": ("filter_rmse_steady", "lpf"),
            "steady-output": ("y_var", "lpf"), "steady-control": ("u_var", "lpf")}
def _not_tracking(result, p, r, prefix, cases) -> str | None:
    """A note naming the cases whose loop does not track the reference (None when all track)."""
    bad = []
    for case in cases:
        q = result.get(f"{prefix}{case}.y_rmse")
        if q.value is None or q.value >= r.tracks * p.reference:
            bad.append(f"{q.label} = {'—' if q.value is None else f'{q.value:.3g}'}")
    if not bad:
        return None
    return (f"untestable: the loop does not track the reference ({'; '.join(bad)}, against {r.tracks:.0%} of the "
            "reference), so the filters are not compared in the working closed loop the paper describes")


def judge_claims(result, p, r=READINGS, prefix=""):
    """Judge the paper's claims on recorded quantities: ``{claim id: (holds, evidence ids, note)}``.

    The same function judges the main run, the frozen-Φ ablation, the second plant and every evaluation of the
    sensitivity sweep. Every bar is a reconstruction of ``r`` (:class:`.paper.Readings`): a comparison holds only
    when the CKF is on the claimed side by more than ``r.z_significant`` standard errors of the difference of the
    means.
    """
    out = {}
    for key, (q, other) in COMPARED.items():
        a, b = f"{prefix}ckf.{q}", f"{prefix}{other}.{q}"
        ok, significant, numbers = _compare(result, a, b, r.z_significant)
        broken = _not_tracking(result, p, r, prefix, ("ckf", other))
        out[key] = ((None, [a, b], broken) if broken else
                    (None if ok is None else bool(ok and significant), [a, b], numbers))
    g = lambda i: result.get(prefix + i)
    u_c, u_n, y_c, y_n = g("ckf.u_var"), g("nofilter.u_var"), g("ckf.y_rmse"), g("nofilter.y_rmse")
    vals = [x.value for x in (u_c, u_n, y_c, y_n)]
    if any(v is None for v in vals):
        out["smoother"] = (None, [u_c.id, u_n.id, y_c.id, y_n.id], "a case has no value (all runs diverged)")
    else:
        holds = vals[0] < r.smoother_ratio * vals[1] and vals[2] < r.accurate * p.reference
        note = (f"control variance CKF / no filter = {vals[0] / vals[1]:.3g} (needs < {r.smoother_ratio:g}); steady "
                f"output RMS error about the reference CKF {vals[2]:.3g}, no filter {vals[3]:.3g} (the CKF's needs < "
                f"{r.accurate:.1%} of the reference, {r.accurate * p.reference:g}, the bar of claim nofilter-accurate)")
        broken = _not_tracking(result, p, r, prefix, ("ckf",))
        out["smoother"] = (None if broken else holds, [u_c.id, u_n.id, y_c.id, y_n.id], broken or note)
    v = y_n.value
    out["nofilter-accurate"] = (None if v is None else v < r.accurate * p.reference, [y_n.id],
                                "no value" if v is None else f"no filter: steady output RMS error about the reference "
                                f"{v:.3g} against {r.accurate:.1%} of the reference, {r.accurate * p.reference:g}")
    ok, significant, numbers = _compare(result, f"{prefix}lpf.filter_rmse_transient",
                                        f"{prefix}lpf_half.filter_rmse_transient", r.z_significant)
    broken = _not_tracking(result, p, r, prefix, ("lpf",))
    out["lpf-bandwidth"] = (None if ok is None or broken else bool(ok and significant),
                            [f"{prefix}lpf_half.filter_rmse_transient", f"{prefix}lpf.filter_rmse_transient"],
                            broken or numbers)
    ckf, full = result.get("cost.ckf_mults").value, result.get("cost.fullorder_mults").value
    known = result.get("cost.fullorder_known_mults").value
    note = (f"multiplications per step: full-order KF with the identification it would need {full:g} (knowing the "
            f"plant, without identification, {known:g}) vs CKF with its identification {ckf:g}: {full / ckf:.3g}x "
            f"(needs >= {r.cheaper_ratio:g}x)")
    out["cheaper"] = (full / ckf >= r.cheaper_ratio, ["cost.ckf_mults", "cost.fullorder_mults"], note)
    return out


def record_claims(result, p, r=READINGS):
    """Judge the paper's claims on the main quantities and record them (``result.claim``)."""
    from .paper import CLAIMS

    judged = judge_claims(result, p, r)
    for c in CLAIMS:
        holds, evidence, note = judged[c.id]
        result.claim(c, holds, evidence=evidence, note=note)
    return judged


def _compare(result, a, b, z):
    """Whether ``a < b``, whether the difference exceeds ``z`` standard errors, and the numbers (with labels)."""
    qa, qb = result.get(a), result.get(b)
    if qa.value is None or qb.value is None:
        return None, None, f"{qa.label} or {qb.label} has no value (all runs diverged)"
    diff = qa.value - qb.value
    na, nb = (max(q.runs - (q.runs_diverged or 0), 1) for q in (qa, qb))  # the runs the means are over
    se = float(np.sqrt(qa.std**2 / na + qb.std**2 / nb))
    significant = bool(abs(diff) > z * se)
    sig = "significant" if significant else "NOT significant"
    return qa.value < qb.value, significant, (f"{qa.label} = {qa.value:.4g} ± {qa.std:.2g} vs {qb.label} = "
                                              f"{qb.value:.4g} ± {qb.std:.2g} (difference {diff:+.3g}, standard error "
                                              f"{se:.2g}: {sig} at {z:g} SE)")


def missing(result) -> list:
    """What the study does not reproduce beyond its differing cells (listed by the report) and its claims (scorecard).

    Parameters
    ----------
    result : StudyResult
        With its claims judged (and the sensitivity sweep applied).

    Returns
    -------
    list of str
    """
    lost = [q.id for q in result.quantities if q.cell and q.cell.startswith("Table 1") and q.paper is None]
    out = [(f"Table 1's printed numbers were lost in the extracted text: its {len(lost)} cells are reproduced "
            "without a verdict"),
           ("plant (12) was lost in the extracted text: every number comes from the reconstructed plant "
            "(reconstruction plant)")]
    return out
