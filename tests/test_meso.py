"""Smoke test of the meso study (--quick, shortened horizons) and checks of its building pieces."""

import json

import numpy as np
import pytest

import analysis.meso as meso
from ctrl_analysis.report import StudyContext, write_results_json
from ctrl_analysis.simulate import run_seeds


def test_equivalent_theta_is_the_closed_loop_projection():
    eq = meso.equivalent_theta([1.3, -1.6, 0.95, 1.8], 3.95)
    np.testing.assert_allclose(eq, [0.74684, -1.21519, 0.0, 1.36709], atol=1e-5)
    # on x1 = sin t, x2 = cos t with u from x2' = -x1 both models give the same disturbance
    t = np.linspace(0, 6, 50)
    x1, x2 = np.sin(t), np.cos(t)
    u = -((1 + 1.3) * x1 - 1.6 * x2 + 1.8) / 3.95
    np.testing.assert_allclose(1.3 * x1 - 1.6 * x2 + 0.95 * u + 1.8, eq[0] * x1 + eq[1] * x2 + eq[3], atol=1e-12)


def test_quick_run_writes_every_quantity(tmp_path, monkeypatch):
    monkeypatch.setattr(meso, "QUICK", {"s1": 3.0, "s2": 6.0, "eps_T": 2.0, "eps_from": 1.0})
    ctx = StudyContext(out_dir=tmp_path, runs=1, seed=3, quick=True)
    result = meso.run(ctx)
    path = write_results_json(result, tmp_path)
    data = json.loads(path.read_text())
    ids = {q["id"] for q in data["quantities"]}
    required = {"leso.omega_o", "s1.theta_final", "s2.theta_final",
                "leso.eps_slope.x1", "leso.eps_slope.x2", "leso.eps_slope.x3"}
    for s in ("s1", "s2"):
        for o in ("meso", "eso"):
            required |= {f"{s}.{o}.{m}" for m in meso.METRICS}
    assert required <= ids
    for q in data["quantities"]:
        assert q["verdict"] in ("agrees", "differs", "new")
        if q["paper"] is None:
            assert q["verdict"] == "new"
        else:
            assert q["tolerance"] == meso.TOLERANCE
    assert result.get("leso.omega_o").value == pytest.approx(20.0)
    assert result.get("s1.eso.est_x1").paper == pytest.approx(1.7115e-4)
    assert data["seeds"]["noise"] == run_seeds(3, 1)
    for name in data["figures"]:
        assert (tmp_path / name).stat().st_size > 10_000
    assert {"leso_error_bode.png", "fig3_situation1.png", "fig4_theta_situation1.png",
            "fig5_situation2.png", "fig6_theta_situation2.png"} <= set(data["figures"])
    assert {f["id"] for f in data["findings"]} >= {"tables-are-noise-free", "situation2-not-identifiable"}
    assert len(data["reconstructions"]) >= 8
