"""Tests of batch least squares with identifiability checks and recursive least squares."""

import warnings

import control as ct
import numpy as np
import pytest

from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.blocks import DiscreteBlock
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.identification import (
    ArxRegressor,
    IdentifiabilityWarning,
    RecursiveLeastSquares,
    RecursiveLeastSquaresBlock,
    batch_least_squares,
    identifiability,
)
from ctrl_analysis.plants import DiscreteLTI


def _data(N=400, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 6, N)
    H = np.column_stack([np.sin(t), np.cos(t), rng.normal(size=N), np.ones(N)])
    theta = np.array([1.3, -1.6, 0.95, 1.8])
    return H, H @ theta + noise * rng.normal(size=N), theta


def test_ls_recovers_parameters():
    H, z, theta = _data()
    res = batch_least_squares(H, z)
    np.testing.assert_allclose(res.theta, theta, rtol=1e-10)
    assert res.report.rank == 4 and res.report.full_rank and res.report.well_conditioned
    assert res.residual_rms < 1e-10
    H, z, theta = _data(N=4000, noise=0.01, seed=1)
    np.testing.assert_allclose(batch_least_squares(H, z).theta, theta, atol=5e-3)


def test_collinear_regressor_rejected_or_warned():
    H, z, _ = _data()
    Hc = H.copy()
    Hc[:, 2] = 2 * Hc[:, 0] - Hc[:, 3]  # exactly collinear
    rep = identifiability(Hc)
    assert rep.rank == 3 and not rep.full_rank
    with pytest.raises(ValueError, match="rank-deficient"):
        batch_least_squares(Hc, z, strict=True)
    with pytest.warns(IdentifiabilityWarning, match="rank-deficient"):
        batch_least_squares(Hc, z)
    # nearly collinear: full rank but ill-conditioned
    Hn = H.copy()
    Hn[:, 2] = Hn[:, 0] + 1e-9 * np.random.default_rng(3).normal(size=len(H))
    rep = identifiability(Hn)
    assert rep.full_rank and rep.cond_scaled > 1e6 and not rep.well_conditioned
    with pytest.warns(IdentifiabilityWarning, match="ill-conditioned"):
        batch_least_squares(Hn, z)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        batch_least_squares(Hn, z, warn=False)


def test_condition_number_is_scale_invariant():
    H, _, _ = _data()
    rep1 = identifiability(H)
    rep2 = identifiability(H * np.array([1e4, 1.0, 1e-3, 1.0]))
    assert rep2.cond > 100 * rep1.cond
    np.testing.assert_allclose(rep2.cond_scaled, rep1.cond_scaled, rtol=1e-8)


def test_rls_converges_to_ls():
    H, z, theta = _data(N=300, noise=0.01, seed=2)
    rls = RecursiveLeastSquares(4, forgetting=1.0, P0=1e8)
    hist = rls.run(H, z)
    np.testing.assert_allclose(rls.theta, batch_least_squares(H, z).theta, atol=1e-5)
    np.testing.assert_allclose(hist[-1], theta, atol=0.02)


def test_rls_is_the_regularised_batch_least_squares_solution_at_every_sample():
    # with λ = 1, θ(k) minimises Σ_{i<=k} (z_i − h_iᵀθ)² + (θ − θ0)ᵀ P0⁻¹ (θ − θ0) and R(k) = (P0⁻¹ + H_kᵀH_k)⁻¹:
    # the batch problem with the prior as p extra rows P0^(-1/2) θ = P0^(-1/2) θ0, solved by numpy.linalg.lstsq
    rng = np.random.default_rng(11)
    N, p, P0 = 40, 3, 2.0
    H = rng.normal(size=(N, p))
    z = H @ np.array([1.5, -0.7, 0.5]) + 0.3 * rng.normal(size=N)
    theta0 = np.array([0.2, 0.1, -0.3])
    rls = RecursiveLeastSquares(p, forgetting=1.0, P0=P0, theta0=theta0)
    prior = np.eye(p) / np.sqrt(P0)
    for k in range(N):
        theta_k = rls.step(H[k], z[k])
        A = np.vstack([prior, H[:k + 1]])
        b = np.concatenate([prior @ theta0, z[:k + 1]])
        np.testing.assert_allclose(theta_k, np.linalg.lstsq(A, b, rcond=None)[0], rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(rls.P, np.linalg.inv(A.T @ A), rtol=1e-10, atol=1e-14)
    # a vague prior (P0 = 1e8): the plain batch solution of all N samples
    vague = RecursiveLeastSquares(p, forgetting=1.0, P0=1e8).run(H, z)[-1]
    np.testing.assert_allclose(vague, np.linalg.lstsq(H, z, rcond=None)[0], rtol=1e-6)
    # and the prior matters at P0 = 2: the two answers differ
    assert np.max(np.abs(rls.theta - vague)) > 1e-3


def test_rls_forgetting_tracks_jump_and_batch():
    rng = np.random.default_rng(4)
    N = 600
    H = np.column_stack([rng.normal(size=N), np.ones(N)])
    th = np.where(np.arange(N)[:, None] < 300, [2.0, 1.0], [2.0, -1.0])
    z = np.sum(H * th, axis=1)
    slow = RecursiveLeastSquares(2, forgetting=1.0).run(H, z)
    fast = RecursiveLeastSquares(2, forgetting=0.95).run(H, z)
    assert abs(fast[-1, 1] + 1.0) < 1e-6  # forgetting: follows the jump
    assert abs(slow[-1, 1] + 1.0) > 0.3  # no forgetting: averages both halves
    # batch of two independent runs equals the two single runs
    Hb = np.stack([H, H[::-1]], axis=1)
    zb = np.stack([z, z[::-1]], axis=1)
    rb = RecursiveLeastSquares(2, forgetting=0.95, batch=2).run(Hb, zb)
    np.testing.assert_allclose(rb[:, 0], fast, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"n_params": 0}, "n_params"),
        ({"n_params": 2, "forgetting": 0.0}, "forgetting"),
        ({"n_params": 2, "forgetting": 1.1}, "forgetting"),
        ({"n_params": 2, "P0": -1.0}, "P0"),
        ({"n_params": 2, "P0": np.eye(3)}, "P0"),
        ({"n_params": 2, "theta0": [1.0]}, "theta0"),
    ],
)
def test_rls_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        RecursiveLeastSquares(**kwargs)


def test_ls_bad_input():
    H, z, _ = _data()
    with pytest.raises(ValueError, match="z must have shape"):
        batch_least_squares(H, z[:-1])
    with pytest.raises(ValueError, match="H must be"):
        batch_least_squares(z, z)
    with pytest.raises(ValueError, match="finite"):
        batch_least_squares(H, np.full(len(z), np.nan))
    with pytest.raises(ValueError, match="h must have shape"):
        RecursiveLeastSquares(3).step(np.ones(2), 1.0)
    with pytest.raises(ValueError, match="batch"):
        RecursiveLeastSquares(3, batch=0)


# ----------------------------------------------------------------------------------------------
# RLS as a discrete block: ARX recovery, projection, anti-windup, python-control
# ----------------------------------------------------------------------------------------------


ARX = (1.5, -0.7, 0.5)  # y(k) = 1.5 y(k-1) - 0.7 y(k-2) + 0.5 u(k-1): poles 0.75 ± 0.37j


def arx_loop(rls, dt=0.1):
    plant = DiscreteLTI(ct.tf([ARX[2], 0.0], [1.0, -ARX[0], -ARX[1]], True), dt)
    return Loop([place(plant, "plant", inputs=["u"], outputs=["y"]),
                 place(ArxRegressor(2, 1), "reg", inputs=["y", "u"]),  # z, h[0..2] feed the RLS block's inputs
                 place(rls, "rls", outputs=["a1", "a2", "b1"])], dt)


def test_rls_block_recovers_second_order_arx():
    u = np.random.default_rng(5).standard_normal((400, 3))
    res = arx_loop(RecursiveLeastSquaresBlock(3, forgetting=1.0, P0=1e4)).simulate(399, inputs={"u": u},
                                                                                   execution=Execution(engine="numpy"))
    theta = np.stack([res["a1"][-1], res["a2"][-1], res["b1"][-1]], axis=1)
    # exact data: only the prior P0 = 1e4 I biases the estimate, by ~ 1 / (P0 Σ h²) ≪ 1e-4
    np.testing.assert_allclose(theta, np.tile(ARX, (3, 1)), atol=1e-4)


def test_rls_block_equals_step_interface_and_batch():
    rng = np.random.default_rng(6)
    H, z = rng.normal(size=(50, 2, 3)), rng.normal(size=(50, 2))
    rls = RecursiveLeastSquares(3, forgetting=0.98, P0=10.0, batch=2)
    hist = rls.run(H, z)
    block = RecursiveLeastSquaresBlock(3, forgetting=0.98, P0=10.0)
    y, x = block.run(np.concatenate([z[:, :, None], H], axis=2))  # the block protocol's open-loop runner
    np.testing.assert_array_equal(y, hist)  # block output theta(k) == step()'s theta after sample k
    np.testing.assert_array_equal(x[-1, :, 3:].reshape(2, 3, 3), rls.P)  # the same covariance, bit for bit
    single, _ = block.run(np.concatenate([z[:, :1, None], H[:, :1]], 2))
    np.testing.assert_array_equal(single[:, 0], y[:, 0])  # a run does not depend on the batch size
    # the estimator object is not a block (its run(H, z) is not the protocol's run(u, x0, params, t))
    assert not isinstance(rls, DiscreteBlock) and isinstance(rls.block, RecursiveLeastSquaresBlock)


def test_projection_keeps_parameters_in_bounds():
    rng = np.random.default_rng(7)
    H = rng.normal(size=(300, 4, 3))
    z = H @ np.array([3.0, -2.0, 0.5]) + rng.normal(size=(300, 4))
    lo, hi = np.array([-1.0, -1.0, 0.0]), np.array([1.0, 1.0, 0.2])
    hist = RecursiveLeastSquares(3, 0.99, 100.0, batch=4, lower=lo, upper=hi).run(H, z)
    assert np.all(hist >= lo) and np.all(hist <= hi)
    assert np.any(hist[-1] == hi) and np.any(hist[-1] == lo)  # the box is active, not vacuous
    free = RecursiveLeastSquares(3, 0.99, 100.0, batch=4).run(H, z)
    assert np.any(free > hi) and np.any(free < lo)


def test_max_trace_bounds_covariance_windup():
    H = np.tile([1.0, 1.0], (2000, 1))  # no excitation: P grows like λ^-k without a bound
    z = np.ones(2000)
    free = RecursiveLeastSquares(2, 0.99, 1.0)
    free.run(H, z)
    bounded = RecursiveLeastSquares(2, 0.99, 1.0, max_trace=2.0)
    bounded.run(H, z)
    assert np.trace(free.P) > 1e3 and np.trace(bounded.P) <= 2.0 + 1e-12


@pytest.mark.parametrize("kwargs,match", [
    ({"n_params": 2, "forgetting": -0.5}, "forgetting must be in"),
    ({"n_params": 2, "P0": np.array([[1.0, 1.0], [1.0, 1.0]])}, "singular or negative"),
    ({"n_params": 2, "P0": np.array([[1.0, 0.0], [0.0, -1.0]])}, "singular or negative"),
    ({"n_params": 2, "lower": [1.0, 0.0], "upper": [0.0, 1.0]}, "lower must be <= upper"),
    ({"n_params": 2, "lower": [1.0, 1.0], "theta0": [0.0, 0.0]}, "theta0 must lie within"),
    ({"n_params": 2, "max_trace": 0.0}, "max_trace"),
])
def test_rls_block_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        RecursiveLeastSquaresBlock(**kwargs)
    with pytest.raises(ValueError, match=match):  # the estimator object validates through its block
        RecursiveLeastSquares(**kwargs)


def test_arx_regressor_lags_and_bad_input():
    y, _ = ArxRegressor(1, 2, lag=1).run(np.column_stack([np.arange(5.0), 10 + np.arange(5.0)]))
    np.testing.assert_array_equal(y[-1, 0], [3.0, 2.0, 12.0, 11.0])  # z = s(3), h = [s(2), u(2), u(1)]
    with pytest.raises(ValueError, match="na \\+ nb"):
        ArxRegressor(0, 0)


def test_rls_loop_runs_in_control_interconnect():
    loop = arx_loop(RecursiveLeastSquaresBlock(3, forgetting=0.99, P0=100.0, lower=[-2, -2, 0], upper=[2, 2, 1]))
    u = np.random.default_rng(8).standard_normal(60)
    res = loop.simulate(59, inputs={"u": u},
                        execution=Execution(engine="numpy"))  # compiled = numpy: test_golden_section's adaptive loop
    sys = loop.interconnect()
    assert sys.isdtime()
    resp = ct.input_output_response(sys, res.t, u[None, :], X0=res.x[0, 0])
    np.testing.assert_allclose(res.to_timeresponse(0).outputs, resp.outputs, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("compiled", [True])  # numba against the batched methods (which run the Python kernel)
def test_rls_and_arx_kernels_equal_the_numpy_methods_bit_for_bit(compiled):
    from test_kalman_ckf import kernel_runs

    from ctrl_analysis.engine import codegen as _kernels

    jit = _kernels._jit if compiled else (lambda f: f)
    rng = np.random.default_rng(9)
    B = 50
    theta = rng.uniform(-1.0, 1.0, (B, 3))
    M = rng.normal(size=(B, 3, 3))
    P = M @ M.transpose(0, 2, 1) + 0.1 * np.eye(3)
    x = np.concatenate([theta, P.reshape(B, 9)], axis=1)
    u = rng.normal(size=(B, 4)) * [3.0, 1.0, 1.0, 1.0]
    for rls in (RecursiveLeastSquaresBlock(3, 0.98, lower=[-1, -1, -1], upper=[1, 1, 1], max_trace=4.0),
                RecursiveLeastSquaresBlock(3, 1.0, feedthrough=False)):
        k = rls.kernel()
        nxt = kernel_runs(jit(k.update), k.params, x, u, 12)
        assert np.array_equal(nxt, rls.update(0.0, x, u))
        assert np.array_equal(kernel_runs(jit(k.output), k.params, x, u, 3), rls.output(0.0, x, u))
    tr = nxt[:, [3, 7, 11]].sum(axis=1)
    first = RecursiveLeastSquaresBlock(3, 0.98, lower=[-1, -1, -1], upper=[1, 1, 1], max_trace=4.0).update(0.0, x, u)
    assert np.any(np.abs(first[:, :3]) == 1.0) and np.isclose(first[:, [3, 7, 11]].sum(axis=1), 4.0).any()
    assert np.any(tr > 4.0)  # without the cap the trace exceeds it: the cap branch was exercised above
    for reg in (ArxRegressor(2, 1), ArxRegressor(1, 2, lag=2)):
        xs, us = rng.normal(size=(20, reg.n_states)), rng.normal(size=(20, 2))
        k = reg.kernel()
        assert np.array_equal(kernel_runs(jit(k.update), k.params, xs, us, reg.n_states), reg.update(0.0, xs, us))
        assert np.array_equal(kernel_runs(jit(k.output), k.params, xs, us, 4), reg.output(0.0, xs, us))

