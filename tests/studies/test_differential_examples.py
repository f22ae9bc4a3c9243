"""Examples 1-2 of the differential-estimator study: Σ through the engine, the Example 2 linearisation, a smoke run."""

import json

import control as ct
import numpy as np
import pytest

from analysis.differential_estimator import INFO
from analysis.differential_estimator.examples import (
    EX2,
    example2_linear_matrix,
    example2_rhs,
    linearise,
    run_examples,
    sigma_linear_rhs,
    stable_estimator_a,
)
from ctrl_analysis.controllers.differential_feedback import HighOrderDifferentialFeedback
from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.report import StudyContext, StudyResult, compute_verdict, write_results_json
from ctrl_analysis.simulate import run_seeds, simulate_sampled


@pytest.mark.parametrize("n0, a", [(5, 7.0), (3, 2.0)])
def test_sigma_step_through_the_engine_matches_its_transfer_function(n0, a):
    est = DifferentialEstimator(n0, a)
    sigma = sigma_linear_rhs(est)
    h, n = 1e-3, 3000
    # unit step in y, held per sample (the engine's input)
    res = simulate_sampled(lambda t, z, u, p: sigma(t, z, u[:, 0]), np.zeros(n0), h, n,
                           noise=np.ones((n, 1, 1)))
    ref = ct.step_response(est.tf, res.t).outputs
    np.testing.assert_allclose(res.x[:, 0, 0], ref, atol=1e-9)
    ref_all = np.squeeze(ct.step_response(est.ss, res.t).outputs)  # (n0 outputs, time)
    np.testing.assert_allclose(res.x[:, 0, :].T, ref_all, atol=1e-7 * np.abs(ref_all).max())


def test_sigma_linear_form_equals_the_block_rhs():
    est = DifferentialEstimator(5, 7.0)
    rng = np.random.default_rng(0)
    z, y = rng.normal(size=(4, 5)), rng.normal(size=4)
    np.testing.assert_allclose(sigma_linear_rhs(est)(0.0, z, y), est.rhs(0.0, z, y[:, None]), rtol=1e-12)
    rows = [DifferentialEstimator(5, a) for a in (5.0, 5.0, 34.0, 7.0)]
    per_row = sigma_linear_rhs(rows)(0.0, z, y)
    for b, e in enumerate(rows):
        np.testing.assert_allclose(per_row[b], e.rhs(0.0, z[b:b + 1], y[b:b + 1, None])[0], rtol=1e-12)


def test_example2_linearisation_and_stable_preset():
    ctrl = HighOrderDifferentialFeedback(EX2.K, n=EX2.n)
    est = DifferentialEstimator(EX2.n0, EX2.a)
    J = linearise(example2_rhs(EX2, est, ctrl, w_amp=0.0), 3 + EX2.n0, EX2.n + 2)
    M = example2_linear_matrix(EX2, est, ctrl.K, EX2.b1, EX2.b2)
    np.testing.assert_allclose(J, M, atol=1e-6 * np.abs(M).max())
    assert np.linalg.eigvals(M).real.max() > 0  # the printed loop is unstable
    a_new, a_star = stable_estimator_a(EX2)
    assert a_star < a_new
    M_new = example2_linear_matrix(EX2, DifferentialEstimator(EX2.n0, a_new), ctrl.K, EX2.b1, EX2.b2)
    assert np.linalg.eigvals(M_new).real.max() <= -1.0
    M_prev = example2_linear_matrix(EX2, DifferentialEstimator(EX2.n0, a_new - 1), ctrl.K, EX2.b1, EX2.b2)
    assert np.linalg.eigvals(M_prev).real.max() > -1.0  # a_new is the smallest integer with the margin


EXPECTED_IDS = {
    "ex1.sigma.mean_abs_err_x1", "ex1.sigma.mean_abs_err_x2",
    "ex1.eso.mean_abs_err_x1", "ex1.eso.mean_abs_err_x2",
    "ex1.sigma.corrected.mean_abs_err_x2",
    "ex1.euler.sigma.mean_abs_err_x1", "ex1.euler.eso.mean_abs_err_x2",
    "ex1.h0.5ms_same_noise.sigma.err_ratio_x1", "ex1.h0.5ms_noise_0.5ms.sigma.err_ratio_x2",
    "ex2.literal.max_real_eig", "ex2.fast_estimator.max_real_eig",
    "ex2.fast_estimator.mean_abs_tracking_error", "ex2.literal.mean_abs_tracking_error",
    "ex2.sweep.fraction_stable", "ex2.sweep.literal.fraction_stable",
}
FIGURES = {"fig3_sigma_x2.png", "fig4_eso_x2.png", "fig5_tracking.png", "fig_ex2_literal.png",
           "fig_ex2_stability_map.png"}


def test_run_examples_quick_smoke(tmp_path):
    result = StudyResult(INFO)
    ctx = StudyContext(out_dir=tmp_path, quick=True, runs=2, seed=5)
    run_examples(ctx, result)
    ids = {q.id for q in result.quantities}
    assert EXPECTED_IDS <= ids
    assert "ex2.controller_poles" not in ids  # recorded by the linear part of the study
    for q in result.quantities:
        assert q.verdict == compute_verdict(q.value, q.paper, q.tolerance)
        if q.paper is not None:
            assert q.verdict in ("agrees", "differs") and q.runs == 2
    assert result.seeds["ex1"] == run_seeds(5, 2)
    assert result.get("ex2.literal.max_real_eig").value > 0
    assert result.get("ex2.fast_estimator.max_real_eig").value < 0
    assert FIGURES <= set(result.figures)
    for name in FIGURES:
        assert (tmp_path / name).stat().st_size > 10_000
    assert {r["name"] for r in result.reconstructions} >= {"ex1.h", "ex1.eso_gains", "ex2.K", "ex2.setpoint"}
    path = write_results_json(result, tmp_path)
    data = json.loads(path.read_text())
    assert data["settings"]["ex2"]["stable_preset"]["name"] == "fast_estimator"
