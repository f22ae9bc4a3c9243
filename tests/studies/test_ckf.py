"""The ckf study: a short run's claims and files, the live identification against the frozen ablation, the loop."""

import dataclasses
import json

import numpy as np

from analysis import ckf
from analysis.ckf import quantities as qty
from analysis.ckf.loops import CASES, ID_OPTIONS, SIGNALS, simulate_cases
from analysis.ckf.paper import CLAIMS, PAPER, READINGS, frozen
from ctrl_analysis.reporting.report import StudyContext, write_results_json
from ctrl_analysis.reporting.study import missing_plausible

SHORT = dataclasses.replace(PAPER, t_end=12.0, t_steady=8.0, option_t_end=12.0, option_runs=2, sweep_runs=2)


def test_every_reconstruction_has_a_plausible_range():
    assert missing_plausible(PAPER) == [] and missing_plausible(READINGS) == []
    assert {c.id for c in CLAIMS} == set(qty.judge_claims.__globals__["COMPARED"]) | {
        "smoother", "nofilter-accurate", "lpf-bandwidth", "cheaper"}


def test_short_run_writes_table1_claims_and_figures(tmp_path):
    result = ckf.run(StudyContext(out_dir=tmp_path, runs=3, seed=1, quick=True), params={"": SHORT})
    data = json.loads(write_results_json(result, tmp_path).read_text())
    q = {x["id"]: x for x in data["quantities"]}
    for case in CASES:
        for name in ("y_mean", "y_var", "u_mean", "u_var"):
            assert q[f"{case}.{name}"]["runs"] == 3
            # Table 1 was printed, its numbers lost in extraction: a cell without a paper value
            assert q[f"{case}.{name}"]["cell"].startswith("Table 1") and q[f"{case}.{name}"]["paper"] is None
            assert q[f"frozen.{case}.{name}"].get("cell") is None and "frozen" in q[f"frozen.{case}.{name}"]["label"]
            assert "second plant" in q[f"plant2.{case}.{name}"]["label"]
        assert abs(q[f"{case}.y_mean"]["value"] - 10.0) < 1.0  # every case tracks after the transient
    u = q["nofilter.u_rms"]
    assert u["paper"] == 1.27 and u["policy"] == "percentile" and u["verdict"] == "differs"
    assert u["interval"][1] < 1.27  # the printed value lies above every run: the reconstructed μ sets it
    claims = {c["id"]: c for c in data["claims"]}
    assert set(claims) == {c.id for c in CLAIMS}
    assert claims["transient"]["evidence"] == ["ckf.filter_rmse_transient", "lpf.filter_rmse_transient"]
    assert claims["cheaper"]["verdict"] == "holds" and claims["cheaper"]["evidence"] == [
        "cost.ckf_mults", "cost.fullorder_mults"]
    # the short run's judgements at the chosen reconstructions (seeded; 4 s of steady stage, 3 runs)
    held = {c: claims[c]["base_verdict"] for c in claims}
    assert held == {"transient": "holds", "steady": "fails", "steady-output": "fails", "steady-control": "fails",
                    "smoother": "holds", "nofilter-accurate": "fails", "lpf-bandwidth": "fails", "cheaper": "holds"}
    # the quick sweep varies P0_rls, the LPF cut-off and the significance bar; the steady-stage claims flip with the
    # cut-off
    assert set(data["sensitivity"]["ranges"]) == {"P0_rls", "lpf_omega", "claims.z_significant"}
    flips = {d["reconstruction"] for d in claims["steady"]["depends_on"]}
    assert claims["steady"]["verdict"] == ("depends" if flips else "holds")
    findings = {f["id"] for f in data["findings"]}
    assert {"identification-live", "claims-live-vs-frozen", "plant2-offset", "full-order-kf", "u-rms-scale",
            "identification-signal", "projection-box", "q-sweep"} <= findings
    assert {"plant2", "frozen_rls", "P0_rls", "max_trace", "claims.smoother_ratio", "claims.tracks"} <= {
        r["name"] for r in data["reconstructions"]}
    assert len(data["figures"]) == 12 and all((tmp_path / f).exists() for f in data["figures"])


def test_claims_of_a_small_evaluation_and_a_known_flip():
    """40 s, 8 runs (seeded): every claim holds at the chosen values; a low LPF cut-off flips the steady claim."""
    p = dataclasses.replace(PAPER, t_end=40.0, t_steady=20.0, sweep_runs=8)
    res = ckf.evaluate({"": p, "claims": READINGS, "run": ckf.SweepRun(1)})
    assert {c.claim.id: c.holds for c in res.claims} == dict.fromkeys((c.id for c in CLAIMS), True)
    assert res.get_claim("steady").evidence == ("ckf.filter_rmse_steady", "lpf.filter_rmse_steady")
    assert res.get_claim("smoother").evidence == ("ckf.u_var", "nofilter.u_var", "ckf.y_rmse", "nofilter.y_rmse")
    low = ckf.evaluate({"": dataclasses.replace(p, lpf_omega=1.0), "claims": READINGS, "run": ckf.SweepRun(1)})
    assert low.get_claim("steady").holds is False  # a slower LPF smooths the steady stage better than the CKF


def test_identification_is_live_and_predicts_better_than_the_frozen_ablation():
    p = dataclasses.replace(PAPER, t_end=40.0, t_steady=20.0)
    out = {}
    for name, variant in (("live", p), ("frozen", frozen(p))):
        data = ckf.simulate_study(variant, 4, seed=3)[p.id_signal]["ckf"]
        travel = max(np.abs(data[n] - p.theta0[i]).max() for i, n in enumerate(("f1", "f2")))
        out[name] = (travel, qty.prediction_error(data, p.t_steady).mean())
    assert out["live"][0] > 0.05 and out["frozen"][0] < 0.01  # f̂1, f̂2 leave θ0 only with the live settings
    assert out["live"][1] < 0.8 * out["frozen"][1]  # and the identified model predicts the true output better


def test_judge_claims_fails_when_the_ckf_is_not_ahead():
    from ctrl_analysis.reporting.report import StudyInfo, StudyResult

    res = StudyResult(StudyInfo("t", "", "", ""))
    for case, v in (("ckf", 2.0), ("lpf", 1.0), ("lpf_half", 0.5)):
        res.quantity(f"{case}.filter_rmse_transient", case, v, std=0.1, runs=10, unit="")
    for case, v in (("ckf", 0.05), ("lpf", 0.1), ("nofilter", 0.1)):
        for q in ("filter_rmse_steady", "y_var", "u_var", "y_rmse"):
            res.quantity(f"{case}.{q}", case, v, std=0.001, runs=10, unit="")
    qty.cost(res, PAPER, 5)
    judged = qty.judge_claims(res, PAPER)
    assert judged["transient"][0] is False  # the CKF is behind
    assert judged["lpf-bandwidth"][0] is False  # the half-bandwidth LPF deviates *less* here
    assert judged["steady"][0] is True and judged["cheaper"][0] is True
    assert judged["smoother"][0] is False  # 0.05 / 0.1 is not "far smoother" (needs < 0.1)
    # the bars are the readings' (swept by the sensitivity analysis), not constants of the judge
    loose = dataclasses.replace(READINGS, smoother_ratio=0.6, accurate=0.1, cheaper_ratio=1e3, z_significant=200.0)
    judged = qty.judge_claims(res, PAPER, loose)
    assert judged["smoother"][0] is True and judged["cheaper"][0] is False
    assert judged["steady"][0] is False  # 0.05 vs 0.1 with std 0.001 (about 110 standard errors) is not 200 apart
    assert qty.judge_claims(res, PAPER, dataclasses.replace(READINGS, tracks=0.001))["steady"][0] is None


def test_batch_run_equals_single_run():
    p = dataclasses.replace(PAPER, t_end=3.0)
    res2, idx2 = simulate_cases(p, 2, seed=5)
    res1, idx1 = simulate_cases(p, 1, seed=5)
    for case in CASES:
        a = res2["y_fb"][:, idx2[(p.id_signal, case)]][:, 0]
        b = res1["y_fb"][:, idx1[(p.id_signal, case)]][:, 0]
        np.testing.assert_array_equal(a, b)


def test_compiled_engine_equals_numpy_engine_and_switches_at_t_filter():
    p = dataclasses.replace(PAPER, t_end=3.0)
    a, idx = simulate_cases(p, 2, seed=5, options=tuple(ID_OPTIONS), engine="numpy")
    b, _ = simulate_cases(p, 2, seed=5, options=tuple(ID_OPTIONS), engine="compiled")
    for s in SIGNALS:
        assert np.array_equal(a[s], b[s]), s
    before = a.t < p.t_filter - 1e-9
    for case, fed in (("nofilter", "y_m"), ("lpf", "y_lpf"), ("ckf", "y_ckf")):
        sl = idx[("feedback", case)]
        assert np.array_equal(a["y_fb"][before, sl], a["y_m"][before, sl])  # raw before t_filter
        assert np.array_equal(a["y_fb"][~before, sl], a[fed][~before, sl])  # then the case's signal
        assert not np.array_equal(a["y_fb"][:, sl], a[fed][:, sl]) or case == "nofilter"
