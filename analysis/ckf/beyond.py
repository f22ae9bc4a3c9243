"""The `ckf` study beyond Table 1: the frozen-Φ ablation, the identification, the options, the full-order KF,
the Q sweep and the second plant; every finding's text is generated from the computed numbers."""

from __future__ import annotations

import dataclasses

import numpy as np

from . import quantities as qty
from .loops import ID_OPTIONS, plant_tf
from .paper import CLAIMS, READINGS, frozen

__all__ = ["Q_SWEEP", "ablation", "beyond", "claims_table", "paper_number"]

Q_SWEEP = (1e-7, 1e-6, 1e-5, 1e-4, 1e-3)
FROZEN_TAG = "frozen-Φ ablation: "


def _plant2_tag(p):
    return f"second plant ({p.plant2}): "


def ablation(result, p, data, data_f):
    """The live identification against the frozen-Φ ablation: Table 1, filter errors, identification numbers."""
    qty.table1(result, data_f, p, prefix="frozen.", tag=FROZEN_TAG)
    qty.filter_errors(result, data_f, p, prefix="frozen.", tag=FROZEN_TAG)
    live = qty.identification(result, data["ckf"], p)
    fro = qty.identification(result, data_f["ckf"], p, prefix="frozen.", tag=FROZEN_TAG)
    fit, cond = qty.record_fit(result, data["ckf"], p)
    d = data["ckf"]
    ok = d["ok"]
    on_bound = float(np.mean(np.isclose(d["f2"][:, ok], p.upper[1], rtol=0, atol=1e-9)
                             | np.isclose(d["f1"][:, ok], p.lower[0], rtol=0, atol=1e-9)))
    s_live = live["f1_final"] + live["f2_final"]
    result.finding(
        "identification-live",
        f"With the reconstructed RLS settings (P0 = {p.P0_rls:g}, λ = {p.forgetting:g}, trace cap {p.max_trace:g}) the "
        f"characteristic model is identified online: f̂1 travels on average {live['f1_travel'][0]:.3g} (at most "
        f"{live['f1_travel'][1]:.3g}) from θ0 and f̂2 {live['f2_travel'][0]:.3g} (at most {live['f2_travel'][1]:.3g}), "
        f"against at most {fro['f1_travel'][1]:.3g} and {fro['f2_travel'][1]:.3g} in the frozen-Φ ablation "
        f"(P0, λ, cap = {p.frozen_rls}). At {p.t_end:g} s the live estimates are f̂1 = {live['f1_final']:.4f}, "
        f"f̂2 = {live['f2_final']:.4f}, ĝ0 = {live['g0_final']:.5f} (ablation: {fro['f1_final']:.4f}, "
        f"{fro['f2_final']:.4f}, {fro['g0_final']:.5f}); the noise-free LS fit of the true plant over the steady stage "
        f"is ({fit[:, 0].mean():.4f}, {fit[:, 1].mean():.4f}, {fit[:, 2].mean():.5f}), outside Wu's box, so the "
        f"estimates move towards it (f̂1 down, f̂2 up) while f̂1 + f̂2 stays near 1 ({s_live:.4f}): what is "
        f"identified is the model's dynamics, its static gain ĝ0 / (1 − f̂1 − f̂2) being held by ĝ0; "
        f"{on_bound:.1%} of the samples sit on a bound of the box. One-step prediction RMS error of the identified "
        f"model on the true output: transient {live['pred_transient']:.3g} (ablation {fro['pred_transient']:.3g}), "
        f"steady stage {live['pred_steady']:.3g} (ablation {fro['pred_steady']:.3g}; lower bound, the noise-free fit: "
        f"{result.get('fit.pred_rmse_steady').value:.3g}). Excitation: in the steady stage the regression is nearly "
        f"collinear (column-scaled condition number of the noise-free fit up to {cond:.3g}); the estimates keep "
        f"drifting slowly along f1 + f2 ≈ const (Fig. 10) at a rate the trace cap bounds.",
        evidence={"live": live, "frozen": fro, "fit": fit.mean(0).tolist(), "on_bound": on_bound})


def paper_number(result, p, data):
    """Where the printed 1.27 comes from."""
    m = qty.window(data["nofilter"]["t"], p.t_steady)
    f1, f2, g0 = (float(data["nofilter"][n][m].mean()) for n in qty.PARAMS)
    q = result.get("nofilter.u_rms")
    gain = float(np.hypot(p.l1 * f1, p.l2 * f2)) * p.noise_std / (g0 + p.mu)
    mu_eq = (g0 + p.mu) * q.value / p.u_rms_nofilter - g0
    result.finding("u-rms-scale", f"Without a filter the control's RMS ({q.value:.3g}) is set by the reconstructed "
                   f"regularisation μ = {p.mu:g}: it is close to the golden-section gain on the measurement noise, "
                   f"sqrt((l1 f̂1)² + (l2 f̂2)²) σ/(ĝ0 + μ) = {gain:.3g} with the steady-stage means f̂1 = {f1:.4g}, "
                   f"f̂2 = {f2:.4g}, ĝ0 = {g0:.4g} and σ = {p.noise_std:g}; μ ≈ {mu_eq:.3g} would give the printed "
                   f"{p.u_rms_nofilter:g}. The printed number therefore checks the reconstruction, not the method.")


def _options(ctx, result, p):
    """Identification signals and the projection switch, with the live RLS settings."""
    from . import simulate_study

    ctx.progress("ckf: identification options and projection")
    p_opt = dataclasses.replace(p, t_end=min(p.t_end, p.option_t_end))
    opts = simulate_study(p_opt, p.option_runs, ctx.seed + 10_000, options=tuple(ID_OPTIONS))
    bias = qty.identification_bias(result, opts, p_opt)
    best = max(ID_OPTIONS, key=lambda o: (bias[(o, "track")], -abs(bias[(o, "g0")])))
    result.finding("identification-signal", "Only the LPF output as identification signal lets every loop track "
                   f"({bias[('lpf', 'track')]:.0%} of runs within {READINGS.tracks:.0%} of the reference): raw measurement "
                   f"{bias[('raw', 'track')]:.0%}, fed-back signal {bias[('feedback', 'track')]:.0%} (live RLS "
                   f"settings, {p.option_runs} runs, {p_opt.t_end:g} s). Bias of ĝ0 against the noise-free fit (CKF "
                   "case): " + "; ".join(f"{o}: {bias[(o, 'g0')]:+.4f}" for o in ID_OPTIONS)
                   + f". Chosen: '{p.id_signal}'; best by tracking fraction, then |ĝ0 bias|: '{best}'. The raw "
                   "measurement (noise σ = 1 against a per-sample change of ~0.05) biases the regression towards "
                   "white noise, and the fed-back signal identifies the filter's own model (a feedback loop between "
                   "the CKF and its identification).")
    noproj = simulate_study(dataclasses.replace(p_opt, project=False), p.option_runs, ctx.seed + 10_000)[p.id_signal]
    qty.filter_errors(result, noproj, p_opt, prefix="noproj.", tag="no projection: ")
    d_proj, d_free = opts[p.id_signal]["ckf"], noproj["ckf"]
    m = qty.window(d_proj["t"], p.t_steady)
    rms = lambda d: float(np.mean(np.sqrt(np.mean((d["y_ckf"][m] - d["y"][m]) ** 2, axis=0))))
    shift = float(max(np.abs(d_free[n] - d_proj[n]).max() for n in qty.PARAMS))
    fin = [float(d_free[n][-1].mean()) for n in ("f1", "f2")]
    result.finding("projection-box", f"Switching Wu's projection off changes the CKF's steady RMS error from "
                   f"{rms(d_proj):.4g} to {rms(d_free):.4g} ({p.option_runs} runs, {p_opt.t_end:g} s): the estimates "
                   f"differ by at most {shift:.3g} between the two, and without the box f̂1, f̂2 end at "
                   f"({fin[0]:.4f}, {fin[1]:.4f}) (with it: ({float(d_proj['f1'][-1].mean()):.4f}, "
                   f"{float(d_proj['f2'][-1].mean()):.4f})).")


def _full_order(result, p, data):
    """The full-order Kalman filter that knows the plant, on the CKF case's records, against the CKF."""
    ok = data["ckf"]["ok"]
    plant = plant_tf(p.plant)
    full, _ = qty.full_order_errors(data["ckf"], p, plant)
    for span in ("transient", "steady"):
        qty.record(result, f"fullkf.filter_rmse_{span}", f"full-order KF knowing the plant, on the CKF case's "
                   f"records: RMS error, {span}", full[span], ok)
    other = {q: qty.full_order_errors(data["ckf"], dataclasses.replace(p, kf_Q=q), plant)[0]["steady"][ok].mean()
             for q in (1e-4, 1.0)}
    c_t, c_s = (result.get(f"ckf.filter_rmse_{s}").value for s in ("transient", "steady"))
    f_t, f_s = (result.get(f"fullkf.filter_rmse_{s}").value for s in ("transient", "steady"))
    cost = result.get("cost.fullorder_known_mults").value / result.get("cost.ckf_mults").value
    result.finding("full-order-kf", f"A full-order Kalman filter that knows the plant is far more accurate than the "
                   f"CKF: steady RMS error {f_s:.3g} against {c_s:.3g} ({c_s / f_s:.0f}x), transient (0-10 s) "
                   f"{f_t:.3g} against {c_t:.3g} ({c_t / f_t:.0f}x), on the same records; it costs {cost:.3g}x the "
                   f"CKF's multiplications per step. Its steady error stays far below the CKF's across its process "
                   f"noise q = 1e-4 .. 1 ({other[1e-4]:.3g} .. {other[1.0]:.3g}; chosen {p.kf_Q:g}). The paper's case "
                   "for the CKF is therefore not accuracy but that it needs neither the plant's order nor its "
                   "parameters; its accuracy is limited by the 2nd-order model's one-step prediction error "
                   f"(steady {result.get('ident.pred_rmse_steady').value:.3g} per step, finding identification-live).")


def _q_sweep(result, p, data, errs):
    sweep = qty.q_sweep(data["lpf"], p, Q_SWEEP)
    lpf = {k: float(np.mean(errs[("lpf", f"filter_rmse_{k}")])) for k in ("transient", "steady")}
    both = [q for q, a, b in zip(Q_SWEEP, sweep["transient"], sweep["steady"])
            if a < lpf["transient"] and b < lpf["steady"]]
    result.finding("q-sweep", f"The CKF's process noise Q = q I trades the transient against the steady stage: run "
                   f"alone on the LPF case's records, its transient RMS error is "
                   f"{np.round(sweep['transient'], 3).tolist()} and its steady RMS error "
                   f"{np.round(sweep['steady'], 3).tolist()} for q = {list(Q_SWEEP)}; LPF: {lpf['transient']:.3f} / "
                   f"{lpf['steady']:.3f}. q beating the LPF in both: {both or 'none'}.")
    return sweep, lpf


def _second_plant(ctx, result, p):
    """The three loops on the second plant, its claims and why its output settles below the reference."""
    from . import simulate_study

    ctx.progress("ckf: second plant")
    p2 = dataclasses.replace(p, plant=p.plant2)
    tag = _plant2_tag(p)
    data2 = simulate_study(p2, ctx.runs_or(p.runs, 4), ctx.seed + 20_000)[p.id_signal]
    qty.table1(result, data2, p2, prefix="plant2.", tag=tag)
    qty.filter_errors(result, data2, p2, prefix="plant2.", tag=tag)
    terms = {c: qty.offset_terms(data2[c], p2) for c in data2}
    home = qty.offset_terms(simulate_study(p, ctx.runs_or(20, 3), ctx.seed + 20_000)[p.id_signal]["ckf"], p)
    leak = dataclasses.replace(p2, c2=1.0)
    no_leak = qty.offset_terms(simulate_study(leak, ctx.runs_or(20, 3), ctx.seed + 20_000)[p.id_signal]["ckf"], leak)
    fro = qty.offset_terms(simulate_study(frozen(p2), ctx.runs_or(20, 3), ctx.seed + 20_000)[p.id_signal]["ckf"], p2)
    t = terms["ckf"]
    eff = p.k_I / (t["c2_share"] * (1 - p.c2))
    result.finding(
        "plant2-offset", f"On the second plant the CKF loop's output averages {t['y']:.3g} over the steady stage instead "
        f"of {p.reference:g}, still rising at the end ({t['y_end']:.3g} over the last tenth of the run; frozen-Φ "
        f"ablation: {fro['y']:.3g}, identified gain {fro['gain']:.3g}), because the identified static gain ĝ0 / (1 − f̂1 − f̂2) = {t['gain']:.3g} overestimates the plant's 1, and "
        f"the leaky logic integral cannot make up the difference: in the steady stage the maintaining-tracking term "
        f"gives u0 = {t['u0']:.3g} (≈ {p.reference:g} / {t['gain']:.3g}), the golden-section term {t['ul']:.3g} and the "
        f"integral {t['ui']:.3g} (u = {t['u']:.3g}). The integral leaks (c = c2 = {p.c2:g}) in {t['c2_share']:.0%} of "
        f"the steps, so it settles at about −k_I e / ({t['c2_share']:.2f} (1 − c2)) = {eff:.3g} · (−e): a finite gain "
        f"on the offset of the fed-back signal e = {t['e']:.3g}. The fed-back CKF output itself sits {t['bias']:+.3g} "
        f"above the true output (its model has the wrong static gain), so even without the leak (c2 = 1) the loop "
        f"settles at {no_leak['y']:.4g}, its fed-back signal at {no_leak['y'] + no_leak['bias']:.4g} (bias "
        f"{no_leak['bias']:+.3g}): most of the remaining offset is the CKF's bias. No filter "
        f"and LPF settle at {terms['nofilter']['y']:.3g} and {terms['lpf']['y']:.3g} (identified gains "
        f"{terms['nofilter']['gain']:.3g}, {terms['lpf']['gain']:.3g}); on the paper plant the CKF loop's identified "
        f"gain is {home['gain']:.3g} and it settles at {home['y']:.4g}.",
        evidence={"terms": terms, "paper_plant": home, "no_leak": no_leak, "frozen": fro})
    return data2


def beyond(ctx, result, p, data, errs):
    """Identification options, projection, full-order KF, Q sweep and the second plant; returns figure data."""
    _options(ctx, result, p)
    ctx.progress("ckf: full-order Kalman filter and Q sweep")
    _full_order(result, p, data)
    sweep, lpf = _q_sweep(result, p, data, errs)
    data2 = _second_plant(ctx, result, p)
    return {"sweep": sweep, "lpf": lpf, "data2": data2}


def claims_table(result, p, r=READINGS):
    """Every claim judged three ways (live identification, frozen-Φ ablation, second plant), as one finding."""
    word = {True: "holds", False: "fails", None: "untestable"}
    cols = {"live": "", "frozen": "frozen.", "plant2": "plant2."}
    judged = {k: qty.judge_claims(result, p, r, prefix=v) for k, v in cols.items()}
    rows = [f"{c.id}: live {word[judged['live'][c.id][0]]}, frozen-Φ {word[judged['frozen'][c.id][0]]}, second "
            f"plant {word[judged['plant2'][c.id][0]]}" for c in CLAIMS]
    changed = [c.id for c in CLAIMS if judged["live"][c.id][0] != judged["frozen"][c.id][0]]
    result.finding("claims-live-vs-frozen", f"Claims whose verdict the live identification changes against the "
                   f"frozen-Φ ablation: {', '.join(changed) or 'none'}. Per claim (before the sensitivity sweep): "
                   + "; ".join(rows) + ".",
                   evidence={k: {c: {"holds": v[0], "evidence": v[1], "note": v[2]} for c, v in j.items()}
                             for k, j in judged.items()})
