"""Tests of the `pendulum` study (verify part): physics of a21, printed P and K checks, smoke run."""

import json

import numpy as np
import pytest

from analysis import pendulum as pm
from ctrl_analysis.report import StudyContext, write_results_json
from ctrl_analysis.symbolic.riccati import second_order_gain


def test_a21_from_physics_matches_printed_digits():
    length, a21 = pm.physical_a21()
    np.testing.assert_allclose(a21, pm.G_ACCEL * pm.B2, rtol=1e-15)
    np.testing.assert_allclose(length, 3 / (4 * pm.B2), rtol=1e-15)
    # g·B = 26.149 reproduces the printed digits 2.6149 up to the decimal point
    np.testing.assert_allclose(a21 / 10, pm.A21_PRINTED, rtol=2e-5)
    with pytest.raises(ValueError, match="b2 and g must be > 0"):
        pm.physical_a21(b2=-1.0)


def test_printed_P_is_not_a_covariance_of_the_model():
    check = pm.verify_printed_P(pm.P_PRINTED, {"P_bar": np.eye(2)})
    assert check["shape"] == [6, 6]
    assert not check["symmetric"]
    assert check["asymmetric_entry"] == [2, 6]
    assert check["min_eig_symmetric_part"] < 0
    assert check["min_eig_if_symmetrised_with_larger_entry"] > 0
    assert not check["is_covariance_of_2_state_system"]
    # a genuine 2×2 covariance passes
    good = pm.verify_printed_P(np.array([[2.0, 0.5], [0.5, 1.0]]), {"P_bar": np.eye(2)})
    assert good["is_covariance_of_2_state_system"]


def test_interpretations_contain_the_continuous_gain_and_miss_the_paper():
    rows = pm.gain_interpretations((pm.A21_PHYSICAL,), T_grid=(0.01, 0.1))
    cont = [g for g in rows if g.kind == "continuous" and not g.swapped][0]
    np.testing.assert_allclose([cont.alpha, cont.beta], second_order_gain(pm.A21_PHYSICAL, pm.Q_W / pm.R_V),
                               rtol=1e-9)
    assert rows == sorted(rows, key=lambda g: g.error)
    assert rows[0].error > pm.GAIN_TOL  # the printed K is not reproduced
    # the discrete filter/predictor rows obey L = F K (α of the predictor differs from the filter's)
    f = [g for g in rows if g.kind == "discrete" and g.T == 0.01 and g.noise == "sampled" and not g.swapped
         and g.form == "filter" and g.beta_rule == "beta = T k2"][0]
    F, ss = pm._discrete(pm.A21_PHYSICAL, pm.Q_W, pm.R_V, 0.01, "sampled")
    np.testing.assert_allclose([f.alpha, f.beta / 0.01], ss.K_filter.ravel(), rtol=1e-8)


def test_run_smoke(tmp_path):
    result = pm.run(StudyContext(out_dir=tmp_path, quick=True))
    ids = {q.id for q in result.quantities}
    for qid in ("ss.gain_alpha", "ss.gain_beta", "ss.gain_continuous", "ss.printed_filter_stable",
                "ss.printed_P_is_covariance"):
        assert qid in ids
    verdicts = {q.id: q.verdict for q in result.quantities}
    # verdicts are computed from value, paper and tolerance
    for qid in ("ss.gain_alpha", "ss.gain_beta"):
        q = result.get(qid)
        expected = "agrees" if abs(q.value - q.paper) <= q.tolerance * abs(q.paper) else "differs"
        assert verdicts[qid] == expected
    assert verdicts["ss.gain_continuous"] == "new"
    assert result.get("ss.printed_filter_stable").value == 0
    assert result.get("ss.printed_P_is_covariance").value == 0
    np.testing.assert_allclose(result.get("ss.gain_continuous").value,
                               second_order_gain(pm.A21_PHYSICAL, 2.0), rtol=1e-9)
    finding_ids = {f["id"] for f in result.findings}
    assert {"are-sign-flipped", "riccati-limit", "observability-rank", "printed-P-6x6",
            "gain-not-reproducible", "printed-filter-unstable"} <= finding_ids
    assert result.missing == ["fuzzy controller and closed-loop simulation (Fig. 3-4)"]
    for name in result.figures:
        assert (tmp_path / name).stat().st_size > 10_000
    data = json.loads(write_results_json(result, tmp_path).read_text(encoding="utf-8"))
    assert data["settings"]["a21"] == pytest.approx(pm.A21_PHYSICAL)
    assert all(q["verdict"] in ("agrees", "differs", "new") for q in data["quantities"])
