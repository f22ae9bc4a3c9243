"""The improved Kalman filter (IKF) block: textbook scalar Kalman filter, K∞(Q/R), data-model prediction."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.engine import Execution
from ctrl_analysis.estimators.kalman import ImprovedKalmanFilter, random_walk_gain
from ctrl_analysis.symbolic.riccati import derive_random_walk_gain


def textbook_kf(y, Q, R, x0, P0):
    """Scalar Kalman filter of x(k) = x(k−1) + w, y = x + v, written with Python floats."""
    x, P, out, gains = x0, P0, [], []
    for yk in y:
        x_prior, P_prior = x, P + Q
        K = P_prior / (P_prior + R)
        x = x_prior + K * (yk - x_prior)
        P = (1.0 - K) * P_prior
        out.append(x)
        gains.append(K)
    return np.array(out), np.array(gains)


def test_ikf_is_the_textbook_scalar_kf_on_a_random_walk_and_converges_to_k_inf():
    rng = np.random.default_rng(7)
    Q, R, n = 0.04, 0.5, 400
    x = np.cumsum(np.sqrt(Q) * rng.standard_normal(n))
    y = x + np.sqrt(R) * rng.standard_normal(n)
    f = ImprovedKalmanFilter(Q, R, y0=0.3, P0=2.0)
    out, _ = f.run(np.column_stack([y, np.zeros(n)]))
    ref, gains = textbook_kf(y, Q, R, 0.3, 2.0)
    np.testing.assert_allclose(out[:, 0, 0], ref, rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(out[:, 0, 1], gains, rtol=1e-13)
    # K(k) -> K∞(Q/R), the sympy fixed point of the scalar Riccati recursion
    k_sym = derive_random_walk_gain().numeric(Q / R)
    np.testing.assert_allclose(out[-1, 0, 1], k_sym, rtol=1e-12)
    assert f.steady_gain == pytest.approx(k_sym, rel=1e-12)
    # the filter error is smaller than the raw measurement error
    assert np.std(out[100:, 0, 0] - x[100:]) < 0.6 * np.std(y[100:] - x[100:])


def test_gain_depends_on_q_over_r_only():
    a = ImprovedKalmanFilter(0.1, 1.0, P0=0.0).run(np.zeros((50, 2)))[0][:, 0, 1]
    b = ImprovedKalmanFilter(10.0, 100.0, P0=0.0).run(np.zeros((50, 2)))[0][:, 0, 1]
    np.testing.assert_allclose(a, b, rtol=1e-13)
    assert random_walk_gain(10.0, 100.0) == pytest.approx(a[-1], rel=1e-12)


def test_prediction_adds_the_data_model_increment():
    # Q = 0, P0 = 0: K = 0, so ŷ(k|k) = ŷ(k−1|k−1) + δ(k) whatever y_m (eq. (11), (14))
    d = np.linspace(-1.0, 1.0, 20)
    out, _ = ImprovedKalmanFilter(0.0, 1.0, y0=2.0, P0=0.0).run(np.column_stack([np.full(20, 99.0), d]))
    np.testing.assert_allclose(out[:, 0, 0], 2.0 + np.cumsum(d), rtol=1e-13)
    # R -> 0 relative to Q: the estimate follows the measurement
    out, _ = ImprovedKalmanFilter(1e6, 1e-6).run(np.column_stack([np.arange(5.0), np.ones(5)]))
    np.testing.assert_allclose(out[:, 0, 0], np.arange(5.0), atol=1e-9)


def test_per_run_q_on_the_batch_axis_equals_single_runs():
    """Q per run is a run-time value (Loop.simulate(params=...)); each run equals the filter built with its Q."""
    from ctrl_analysis.engine.loop import Loop, place

    rng = np.random.default_rng(2)
    N, u = 60, rng.standard_normal((61, 3, 2))
    Qs = np.array([0.01, 0.1, 1.0])
    loop = Loop([place(ImprovedKalmanFilter(Qs[0], 0.5), "f", outputs=["yh", "K", "P"])], dt=1.0)
    grid = loop.simulate(N, inputs={"y_m": u[:, :, 0], "dy_model": u[:, :, 1]}, params={"f": {"Q": Qs}},
                         execution=Execution(bound=np.inf))
    for b, q in enumerate(Qs):
        one, _ = ImprovedKalmanFilter(q, 0.5).run(u[:N, b:b + 1])
        np.testing.assert_array_equal(grid["yh"][:N, b], one[:, 0, 0])
    with pytest.raises(TypeError, match="Q must be a real number"):
        ImprovedKalmanFilter(Qs, 0.5)


def test_nlsys_equals_the_block():
    f = ImprovedKalmanFilter(0.2, 0.7, y0=1.0, P0=0.5)
    U = np.random.default_rng(3).standard_normal((2, 80))
    out, _ = f.run(U.T)
    resp = ct.input_output_response(f.nlsys(dt=1), np.arange(80), U, X0=f.initial_state())
    np.testing.assert_allclose(resp.outputs.T, out[:, 0], rtol=1e-13, atol=1e-14)


@pytest.mark.parametrize("kw, msg", [({"Q": -1.0, "R": 1.0}, "Q must be >= 0"), ({"Q": 1.0, "R": 0.0}, "R must be > 0"),
                                     ({"Q": 1.0, "R": 1.0, "P0": -1.0}, "P0 must be >= 0"),
                                     ({"Q": 1.0, "R": np.nan}, "R must be")])
def test_errors(kw, msg):
    with pytest.raises(ValueError, match=msg):
        ImprovedKalmanFilter(**kw)


@pytest.mark.parametrize("compiled", [False, True])
def test_kernel_is_the_numpy_method_with_per_run_q_and_r(compiled):
    from ctrl_analysis.engine import codegen as _kernels
    from ctrl_analysis.estimators.kalman.ikf import ikf_output, ikf_update

    jit = _kernels._jit if compiled else (lambda f: f)
    rng = np.random.default_rng(2)
    x, u = np.abs(rng.standard_normal((8, 2))), rng.standard_normal((8, 2))
    Qs = rng.uniform(0.0, 1.0, 8)
    f = ImprovedKalmanFilter(Qs[0], 0.3, y0=1.0, P0=0.5)
    P = np.stack([f.with_params(Q=q).kernel_params for q in Qs])  # the rows Loop.simulate(params=...) gives
    assert P.shape == (8, 2)
    for fn, ref, width in ((jit(ikf_output), f.batched("output", 0.0, x, u, P), 3),
                           (jit(ikf_update), f.batched("update", 0.0, x, u, P), 2)):
        out = np.empty((8, width))
        for b in range(8):
            fn(0.0, x[b], u[b], P[b], out[b])
        assert np.array_equal(out, ref)
