"""Smoke test of the ckf study (short horizon, 2 runs) and checks of its loop."""

import dataclasses
import json

import numpy as np

from analysis import ckf
from analysis.ckf.loops import CASES, ID_OPTIONS, SIGNALS, simulate_cases
from analysis.ckf.paper import PAPER
from ctrl_analysis.report import StudyContext, write_results_json

SHORT = dataclasses.replace(PAPER, t_end=10.0, t_steady=6.0, option_t_end=10.0, option_runs=2)


def test_short_run_writes_table1_claims_and_figures(tmp_path):
    result = ckf.run(StudyContext(out_dir=tmp_path, runs=2, seed=1), p=SHORT)
    data = json.loads(write_results_json(result, tmp_path).read_text())
    q = {x["id"]: x for x in data["quantities"]}
    for case in CASES:
        for name in ("y_mean", "y_var", "u_mean", "u_var"):
            assert q[f"{case}.{name}"]["runs"] == 2
        # every case is near the reference 10 after the transient (6-10 s)
        assert abs(q[f"{case}.y_mean"]["value"] - 10.0) < 1.0
    assert q["nofilter.u_rms"]["paper"] == 1.27 and q["nofilter.u_rms"]["tolerance"] == 0.25
    assert {"lpf.filter_rmse", "ckf.filter_rmse", "fullkf.filter_rmse_steady", "plant2.ckf.u_var"} <= set(q)
    # filtering smooths the control by orders of magnitude (the paper's least controversial claim)
    assert q["ckf.u_var"]["value"] < 0.1 * q["nofilter.u_var"]["value"]
    names = {r["name"] for r in data["reconstructions"]}
    assert {"plant", "Q", "k_I", "c2", "mu", "lpf_omega", "forgetting", "P0_rls", "theta0", "id_signal"} <= names
    assert {f["id"] for f in data["findings"]} >= {"claim-transient", "claim-steady", "identification-signal",
                                                   "projection-box", "q-sweep", "claim-plant2.steady"}
    assert len(data["figures"]) == 11 and all((tmp_path / f).exists() for f in data["figures"])


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
