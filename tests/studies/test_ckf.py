"""The ckf study: a short run's claims and files, the live identification against the frozen ablation, the loop,
the box's batched evaluation, the per-run claims, the no-filter loop's identification and the projection bounds."""

import dataclasses
import json

import numpy as np
import pytest

from analysis import ckf
from analysis.ckf import beyond, figures
from analysis.ckf import quantities as qty
from analysis.ckf.loops import (
    CASES,
    ID_OPTIONS,
    SIGNALS,
    simulate_cases,
    simulate_specs,
)
from analysis.ckf.paper import CLAIMS, PAPER, READINGS, frozen
from ctrl_analysis.reporting.box import Box
from ctrl_analysis.reporting.box_cells import cell_state
from ctrl_analysis.reporting.report import StudyContext, write_results_json
from ctrl_analysis.reporting.study import missing_plausible

SHORT = dataclasses.replace(PAPER, t_end=12.0, t_steady=8.0, option_t_end=12.0, option_runs=2, sweep_runs=8)


def _point(p=PAPER, r=READINGS, seed=1):
    return {"": p, "claims": r, "run": ckf.SweepRun(seed)}


def test_every_reconstruction_has_a_plausible_range_and_the_identification_settings_span_the_box():
    assert missing_plausible(PAPER) == [] and missing_plausible(READINGS) == []
    assert {c.id for c in CLAIMS} == set(qty.COMPARED) | {"smoother", "nofilter-accurate", "lpf-bandwidth", "cheaper"}
    box = Box(_point())
    names = {d.name for d in box.dims}
    # every RLS setting the paper does not print, and the identification signal, vary jointly
    assert {"P0_rls", "max_trace", "project", "forgetting", "theta0", "id_signal"} <= names
    # the no-filter loop's identification is the printed-vs-corrected axis, judged apart
    assert [d.name for d in box.algorithm_dims] == ["nofilter_id"] and box.algorithm == "corrected"


def test_short_run_writes_table1_claims_and_figures(tmp_path):
    result = ckf.run(StudyContext(out_dir=tmp_path, runs=8, seed=1, quick=True), params={"": SHORT})
    data = json.loads(write_results_json(result, tmp_path).read_text())
    q = {x["id"]: x for x in data["quantities"]}
    for case in CASES:
        for name in ("y_mean", "y_var", "u_mean", "u_var"):
            assert q[f"{case}.{name}"]["runs"] == 8
            # Table 1 was printed, its numbers lost in extraction: a cell without a paper value
            assert q[f"{case}.{name}"]["cell"].startswith("Table 1") and q[f"{case}.{name}"]["paper"] is None
            assert q[f"frozen.{case}.{name}"].get("cell") is None and "frozen" in q[f"frozen.{case}.{name}"]["label"]
            assert "second plant" in q[f"plant2.{case}.{name}"]["label"]
        assert abs(q[f"{case}.y_mean"]["value"] - 10.0) < 1.0  # every case tracks after the transient
    u = q["nofilter.u_rms"]
    assert u["paper"] == 1.27 and u["policy"] == "percentile"
    assert u["interval"][1] < 1.27  # the printed value lies above every run at the chosen μ = 1
    claims = {c["id"]: c for c in data["claims"]}
    assert set(claims) == {c.id for c in CLAIMS}
    # the transient claim is judged where both filters are fed back, per run
    assert claims["transient"]["evidence"][:2] == ["ckf.filter_rmse_transient_used", "lpf.filter_rmse_transient_used"]
    assert "cmp.transient.share" in claims["transient"]["evidence"]
    assert claims["cheaper"]["verdict"] == "holds" and claims["cheaper"]["evidence"] == [
        "cost.ckf_mults", "cost.fullorder_mults"]
    assert claims["lpf-bandwidth"]["base_verdict"] == "holds"  # the half-bandwidth LPF deviates more in every run
    # the quick box varies P0_rls, the LPF cut-off and the significance bar, under both algorithms
    assert set(data["sensitivity"]["ranges"]) == {"P0_rls", "lpf_omega", "claims.z_significant"}
    assert data["sensitivity"]["algorithm"]["fields"] == ["nofilter_id"]
    assert set(claims["cheaper"]["by_algorithm"]) == {"printed", "corrected"}
    findings = {f["id"] for f in data["findings"]}
    assert {"identification-live", "claims-live-vs-frozen", "plant2-offset", "full-order-kf", "u-rms-scale",
            "identification-signal", "nofilter-identification", "projection-box", "q-sweep"} <= findings
    assert {"plant2", "frozen_rls", "P0_rls", "max_trace", "nofilter_id", "claims.smoother_ratio", "claims.tracks"} <= {
        r["name"] for r in data["reconstructions"]}
    assert len(data["figures"]) == 12 and all((tmp_path / f).exists() for f in data["figures"])
    assert "still converging" not in data["captions"]["fig7_ckf_transient.png"]
    assert "lower bound" in data["captions"]["fig10_identified_parameters.png"]
    assert "identified online from the LPF output (an LPF run beside the loop" in data["captions"]["fig2_nofilter.png"]


def test_claims_of_a_small_evaluation_and_a_known_flip():
    """40 s, 20 runs (seeded): the steady claims hold at the chosen values; a low LPF cut-off flips the steady claim."""
    p = dataclasses.replace(PAPER, t_end=40.0, t_steady=20.0, sweep_runs=20)
    res = ckf.evaluate(_point(p))
    held = {c.claim.id: c.holds for c in res.claims}
    assert held["steady"] is held["steady-output"] is held["cheaper"] is True
    assert res.get_claim("steady").evidence[:2] == ("ckf.filter_rmse_steady", "lpf.filter_rmse_steady")
    assert res.get_claim("smoother").evidence[:3] == ("ckf.u_var", "nofilter.u_var", "ckf.y_rmse")
    low = ckf.evaluate(_point(dataclasses.replace(p, lpf_omega=1.0)))
    assert low.get_claim("steady").holds is False  # a slower LPF smooths the steady stage better than the CKF


def test_transient_is_judged_where_both_filters_are_fed_back():
    """Over 0-10 s the CKF wins on the first 2 s, when neither filter is fed back; from 2 s on it does not."""
    p = dataclasses.replace(PAPER, t_end=12.0, t_steady=8.0)
    data = ckf.simulate_study(p, 20, 0)[p.id_signal]
    m = qty.metrics(data, p)
    whole = np.mean(m["ckf"]["filter_rmse_transient"] < m["lpf"]["filter_rmse_transient"])
    used = np.mean(m["ckf"]["filter_rmse_transient_used"] < m["lpf"]["filter_rmse_transient_used"])
    assert whole >= 0.9 and used <= 0.5
    assert qty.comparisons(m, p)["transient"]["share"] == pytest.approx(used)
    res = ckf.evaluate(_point(dataclasses.replace(p, sweep_runs=20), seed=0))
    assert res.get_claim("transient").evidence[0] == "ckf.filter_rmse_transient_used"
    assert res.get_claim("transient").holds is not True


def test_per_run_claims_use_a_sign_test_and_say_untestable_within_its_noise_floor():
    from ctrl_analysis.reporting.report import StudyInfo, StudyResult

    runs = 16
    ok = np.ones(runs, bool)
    base = {"ok": ok, "y_mean": np.full(runs, 10.0), "y_var": np.full(runs, 1e-3), "u_mean": np.full(runs, 10.0),
            "u_var": np.full(runs, 1e-3), "y_rmse": np.full(runs, 0.03)}
    filt = {q: np.full(runs, 0.1) for q in ("filter_rmse", "filter_rmse_transient", "filter_rmse_transient_used",
                                             "filter_rmse_steady")}
    m = {"nofilter": {**base, "u_var": np.full(runs, 1.0)}, "lpf": {**base, **filt},
         "ckf": {**base, **{q: v.copy() for q, v in filt.items()}}}
    m["lpf"]["half.filter_rmse_transient"] = np.full(runs, 0.2)
    m["ckf"]["filter_rmse_steady"][:15] = 0.05  # ahead in 15 of 16 runs: holds
    m["ckf"]["filter_rmse_transient_used"][:9] = 0.05  # ahead in 9 of 16: the runs cannot tell
    m["ckf"]["filter_rmse_transient_used"][9:] = 0.2
    m["ckf"]["y_var"][:] = 2e-3  # behind in every run: fails
    res = StudyResult(StudyInfo("t", "", "", ""))
    qty.cost(res, PAPER, 5)
    judged, comps = qty.judge_claims(res, PAPER, m=m)
    floor = 2 * 0.5 / np.sqrt(runs)
    assert comps["steady"]["floor"] == pytest.approx(floor)
    holds, _, _, measure, fl = judged["steady"]
    assert holds is True and measure == pytest.approx(15 / 16 - 0.5) and abs(measure) > fl
    holds, _, _, measure, fl = judged["transient"]
    assert abs(measure) < fl  # recorded as untestable, never fails
    holds, _, _, measure, fl = judged["steady-output"]
    assert holds is False and measure == pytest.approx(-0.5) and abs(measure) > fl
    assert judged["smoother"][0] is True and judged["lpf-bandwidth"][0] is True and judged["cheaper"][0] is True
    # a loop that loses the reference makes its comparisons untestable, not failed
    lost = {**m, "nofilter": {**m["nofilter"], "y_rmse": np.full(runs, 5.0)}}
    judged, _ = qty.judge_claims(res, PAPER, m=lost)
    assert judged["smoother"][0] is None and "does not track" in judged["smoother"][2]
    assert judged["nofilter-accurate"][0] is False  # the no-filter loop's accuracy is the claim itself
    # the bars are the readings' (varied by the box), not constants of the judge
    loose = dataclasses.replace(READINGS, smoother_ratio=1e-4, cheaper_ratio=1e3)
    judged, _ = qty.judge_claims(res, PAPER, loose, m=m)
    assert judged["smoother"][0] is False and judged["cheaper"][0] is False


def test_the_box_evaluates_many_points_on_one_batch_exactly_as_one_by_one():
    p = dataclasses.replace(PAPER, t_end=6.0, t_steady=3.0, sweep_runs=3)
    q = dataclasses.replace(p, Q=1e-4, P0_ckf=3.0, lpf_omega=3.3, P0_rls=0.1, forgetting=0.997, max_trace=0.2,
                            theta0=(1.8, -0.8, 0.02), project=False, k_I=0.01, c2=0.99, mu=0.7, id_signal="raw",
                            nofilter_id="raw")
    o2 = dataclasses.replace(p, lpf_order=2, mu=0.8)  # another structure: its own simulation
    points = [_point(x, seed=4) for x in (p, q, o2)] + [_point(p, dataclasses.replace(READINGS, z_significant=1.0), 4)]
    ckf._CACHE.clear()
    many = ckf.evaluate_many(points)
    for pt, r in zip(points, many, strict=True):
        ckf._CACHE.clear()
        one = ckf.evaluate(pt)
        assert [(c.claim.id, c.holds) for c in r.claims] == [(c.claim.id, c.holds) for c in one.claims]
        assert [(x.id, x.value) for x in r.quantities] == [(x.id, x.value) for x in one.quantities]
    # and a spec run among others equals the loop built for that point alone (no per-run parameters)
    specs = [(p, "ckf", "lpf"), (q, "ckf", "raw"), (q, "nofilter", "raw"), (p, "lpf", "lpf")]
    both = simulate_specs(specs, 2, 7)
    for spec, d in zip(specs, both, strict=True):
        alone = simulate_cases(spec[0], 2, 7, options=(spec[2],))[(spec[2], spec[1])]
        for s in SIGNALS:
            np.testing.assert_array_equal(alone[s], d[s], err_msg=f"{spec[1]} {s}")
        np.testing.assert_array_equal(alone["stats"], d["stats"])


def test_window_sums_equal_the_stored_signals():
    p = dataclasses.replace(PAPER, t_end=30.0, t_steady=10.0)
    data = simulate_cases(p, 3, 2, keep=SIGNALS + ("y_lpf_half",))
    t = data[("lpf", "lpf")]["t"][:-1]  # the sums hold every sample but the last
    st = qty.window(t, p.t_steady)
    for case in CASES:
        d = data[("lpf", case)]
        m = qty.case_metrics(d, p, case)
        y, u = d["y"][:-1], d["u"][:-1]
        np.testing.assert_allclose(m["y_var"], y[st].var(0), rtol=1e-8)
        np.testing.assert_allclose(m["u_mean"], u[st].mean(0), rtol=1e-12)
        np.testing.assert_allclose(m["y_rmse"], np.sqrt(np.mean((y[st] - 10.0) ** 2, axis=0)), rtol=1e-12)
        if case != "nofilter":
            sig = d["y_lpf" if case == "lpf" else "y_ckf"][:-1]
            for name, (a, b) in qty.spans(p).items():
                w = qty.window(t, a, b)
                np.testing.assert_allclose(m[name], np.sqrt(np.mean((sig[w] - y[w]) ** 2, axis=0)), rtol=1e-10)
    w = qty.window(t, 0.0, 10.0)
    d = data[("lpf", "lpf")]
    ref = np.sqrt(np.mean((d["y_lpf_half"][:-1][w] - d["y"][:-1][w]) ** 2, axis=0))
    np.testing.assert_allclose(qty.case_metrics(d, p, "lpf")["half.filter_rmse_transient"], ref, rtol=1e-10)


def test_the_no_filter_loop_identified_from_its_own_measurement():
    """The printed algorithm: the no-filter loop reads only its measurement; under Wu's box it loses the reference,
    so its claims fail or are untestable, and the printed cell is not measured; the filtered loops are unchanged."""
    p = dataclasses.replace(PAPER, t_end=40.0, t_steady=20.0, sweep_runs=10)
    own = dataclasses.replace(p, nofilter_id="raw")
    res_c, res_p = ckf.evaluate_many([_point(p), _point(own)])
    assert res_c.get("nofilter.y_rmse").value < 0.1 and res_p.get("nofilter.y_rmse").value > 1.0
    assert res_p.get_claim("nofilter-accurate").holds is False and res_p.get_claim("smoother").holds is None
    assert res_p.get("nofilter.u_rms").value is None and cell_state(res_p.get("nofilter.u_rms")) is None
    for case in ("lpf", "ckf"):
        assert res_c.get(f"{case}.y_var").value == res_p.get(f"{case}.y_var").value
    a = simulate_cases(own, 2, 3)
    b = simulate_cases(own, 2, 3, options=("raw",))
    np.testing.assert_array_equal(a[("lpf", "nofilter")]["f1"], b[("raw", "nofilter")]["f1"])


def test_the_printed_control_rms_is_reached_at_mu_068():
    """μ ≈ 0.68 (inside its plausible 0.5-2) puts the printed 1.27 inside the runs' band; μ = 1 does not."""
    at = {mu: ckf.evaluate(_point(dataclasses.replace(PAPER, mu=mu), seed=0)).get("nofilter.u_rms")
          for mu in (0.678, 1.0)}
    assert cell_state(at[0.678])["in_band"] and not cell_state(at[1.0])["in_band"]


def test_identification_is_live_and_predicts_better_than_the_frozen_ablation():
    p = dataclasses.replace(PAPER, t_end=40.0, t_steady=20.0)
    out = {}
    for name, variant in (("live", p), ("frozen", frozen(p))):
        data = ckf.simulate_study(variant, 4, seed=3)[p.id_signal]["ckf"]
        travel = max(np.abs(data[n] - p.theta0[i]).max() for i, n in enumerate(("f1", "f2")))
        out[name] = (travel, qty.prediction_error(data, p.t_steady).mean(), data)
    assert out["live"][0] > 0.05 and out["frozen"][0] < 0.01  # f̂1, f̂2 leave θ0 only with the live settings
    assert out["live"][1] < 0.8 * out["frozen"][1]  # and the identified model predicts the true output better
    d = out["live"][2]
    # ĝ0 falls onto the box's lower bound in every run; the on-bound share counts it
    bounds = beyond.on_bounds(d, p)
    assert bounds["g0"]["runs_hit"] == 1.0 and bounds["g0"]["which"] == "lower" and bounds["g0"]["first"] < 2.0
    assert bounds["any"] >= bounds["g0"]["share"] > 0.0
    # f̂1 still drifts at the end: its last 10 s move it as much as any earlier 10 s after the first
    prog = beyond.drift(d, p)
    assert prog["late_vs_peak"]["f1"] > 0.5 and prog["moves"]["f1"][-1] < 0


def test_on_bounds_and_drift_on_known_records():
    p = dataclasses.replace(PAPER, t_end=40.0)
    t = np.arange(0, 40.01, 0.01)[:, None]
    d = {"t": t[:, 0], "ok": np.ones(2, bool),
         "f1": np.tile(1.9 - 0.001 * t, (1, 2)),  # a steady drift: never settles
         "f2": np.tile(-0.9 + 0.1 * np.exp(-t), (1, 2)),  # converges within the first seconds
         "g0": np.tile(np.where(t < 1.0, 0.02, p.lower[2]), (1, 2))}  # on its lower bound from 1 s on
    b = beyond.on_bounds(d, p)
    assert b["g0"]["share"] == pytest.approx(np.mean(t >= 1.0), abs=1e-3) and b["g0"]["first"] == pytest.approx(1.0)
    assert b["f1"]["share"] == 0.0 and b["any"] == pytest.approx(b["g0"]["share"])
    assert beyond.on_bounds(d, dataclasses.replace(p, project=False))["any"] == 0.0  # no box, no bound
    prog = beyond.drift(d, p)
    assert prog["late_vs_peak"]["f1"] == pytest.approx(1.0) and prog["late_vs_peak"]["f2"] < 0.01


def test_fig10_draws_every_bound_of_the_projection_box():
    p = dataclasses.replace(PAPER, t_end=6.0, t_steady=3.0)
    d = ckf.simulate_study(p, 2, 0)[p.id_signal]["ckf"]
    fig = figures.plot_parameters(d, [(0.0, 6.0)], np.zeros((1, 3)), np.zeros(3), theta0=p.theta0, ablation=d,
                                  box=(p.lower, p.upper))
    for ax, lo, hi in zip(fig.axes, p.lower, p.upper, strict=True):
        labels = [line.get_label() for line in ax.get_lines()]
        assert f"projection box, lower bound {lo:g}" in labels and f"projection box, upper bound {hi:g}" in labels
    assert fig.axes[2].get_yscale() == "log"  # ĝ0 and its lower bound a decade below the plant's fit both show


def test_compiled_engine_equals_numpy_engine_and_switches_at_t_filter():
    p = dataclasses.replace(PAPER, t_end=3.0)
    a = simulate_cases(p, 2, seed=5, options=tuple(ID_OPTIONS), engine="numpy")
    b = simulate_cases(p, 2, seed=5, options=tuple(ID_OPTIONS), engine="compiled")
    for key in a:
        for s in SIGNALS + ("stats",):
            assert np.array_equal(a[key][s], b[key][s]), (key, s)
    t = a[("feedback", "lpf")]["t"]
    before = t < p.t_filter - 1e-9
    for case, fed in (("nofilter", "y_m"), ("lpf", "y_lpf"), ("ckf", "y_ckf")):
        d = a[("feedback", case)]
        assert np.array_equal(d["y_fb"][before], d["y_m"][before])  # raw before t_filter
        assert np.array_equal(d["y_fb"][~before], d[fed][~before])  # then the case's signal
        assert not np.array_equal(d["y_fb"], d[fed]) or case == "nofilter"


def test_runs_in_parts_give_every_runs_numbers_and_the_first_parts_traces():
    """Above its part, simulate_main simulates the runs a part at a time (memory bounded by the part): every run's
    per-run numbers equal one simulation's bit for bit, the traces are those of the first part's runs."""
    p = dataclasses.replace(PAPER, t_end=6.0, t_steady=3.0)
    whole, m_whole = ckf.simulate_main(p, 5, 4)
    data, m = ckf.simulate_main(p, 5, 4, part=2)
    assert set(m) == set(m_whole) == set(CASES)
    for case in CASES:
        assert set(m[case]) == set(m_whole[case])
        for k, v in m_whole[case].items():
            assert v.shape == (5,)
            np.testing.assert_array_equal(m[case][k], v, err_msg=f"{case} {k}")
        for s in SIGNALS:
            assert data[case][s].shape[1] == 2
            np.testing.assert_array_equal(data[case][s], whole[case][s][:, :2], err_msg=f"{case} {s}")
    with pytest.raises(ValueError, match="part must be at least 1"):
        ckf.simulate_main(p, 5, 4, part=0)
    with pytest.raises(ValueError, match="seeds must hold one seed per run"):
        simulate_cases(p, 2, 4, seeds=[1])
