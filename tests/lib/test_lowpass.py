"""Tests of the low-pass filters (ctrl_analysis.estimators.lowpass)."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.engine.integrators import rk4_step
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.lowpass import DiscreteLowPass, LowPassFilter


@pytest.mark.parametrize("order", [1, 2, 3, 5])
def test_tf_and_ss_agree(order):
    W = LowPassFilter(1.8, order=order)
    np.testing.assert_allclose(W.tf.dcgain(), 1.0)
    S = W.ss[0, 0]
    np.testing.assert_allclose(S.dcgain(), 1.0)
    np.testing.assert_allclose(np.sort(S.poles().real), -1.8, atol=1e-2)
    for w in (0.1, 1.8, 30.0):
        np.testing.assert_allclose(S(1j * w), W.tf(1j * w), rtol=1e-10)
    # magnitude at the corner: (1/sqrt 2)^order
    np.testing.assert_allclose(abs(W.tf(1j * 1.8)), 2 ** (-order / 2), rtol=1e-12)


@pytest.mark.parametrize("order", [1, 2])
def test_digital_step_matches_control_step_response(order):
    """The exact ZOH digital filter reproduces control.step_response of W(s) at the samples (tol 1e-10)."""
    W = LowPassFilter(1.8, order=order)
    h = 0.003
    t = h * np.arange(2001)
    ref = ct.step_response(W.tf, T=t).outputs
    dig = W.digital(h)
    out = np.concatenate([[0.0], dig.filter(np.ones(2000))])
    np.testing.assert_allclose(out, ref, atol=1e-10)


def test_rhs_with_engine_matches_step_response():
    W = LowPassFilter(1.8)
    h = 0.003
    x = [np.zeros((1, 2))]
    for k in range(1000):
        x.append(rk4_step(W.rhs, k * h, x[-1], np.ones((1, 1)), h))
    ref = ct.step_response(W.tf, T=h * np.arange(1001)).outputs
    np.testing.assert_allclose(np.stack(x)[:, 0, 0], ref, atol=1e-9)  # RK4 error at h*ω = 0.005


def test_vector_batch_filtering_and_initial():
    W = LowPassFilter(2.0)
    dig = DiscreteLowPass(W, 0.01, channels=4, initial=1.0)
    u = np.broadcast_to(np.arange(12.0).reshape(3, 4), (3000, 3, 4))
    y, x = dig.run(u)
    np.testing.assert_allclose(x[0].reshape(3, 4, 2)[..., 0], 1.0)  # starts at rest at `initial`
    np.testing.assert_allclose(y[-1], u[-1], rtol=1e-8, atol=1e-12)
    # each run and channel of the batch equals its single-channel filter
    one = W.digital(0.01, initial=1.0).filter(u[:, 1, 2])
    np.testing.assert_array_equal(y[:, 1, 2], one)


def test_prefilter_poles_and_derivative_tfs():
    pf = LowPassFilter(2.0, 3)
    np.testing.assert_allclose(np.sort(pf.ss.poles().real), [-2.0, -2.0, -2.0], atol=1e-4)
    np.testing.assert_allclose(ct.ss2tf(pf.ss[0, 0]).num[0][0][-1], 8.0, rtol=1e-12)
    # the states are u -> s^k W(s)
    for k in range(3):
        for w in (0.5, 2.0, 9.0):
            np.testing.assert_allclose(pf.ss[k, 0](1j * w), pf.derivative_tf(k)(1j * w), rtol=1e-10)


@pytest.mark.parametrize("method", ["zoh", "rk4"])
def test_prefilter_states_are_the_derivatives_of_its_step_response(method):
    from ctrl_analysis.estimators.tracking import softened_setpoint

    h = 1e-3
    pf = LowPassFilter(2.0, 3)
    n = 4000
    theta = softened_setpoint(pf, np.ones(n), h, method=method)
    t = h * np.arange(n)
    for k in range(3):
        ref = ct.step_response(pf.derivative_tf(k), t).outputs
        np.testing.assert_allclose(theta[:, k], ref, atol=1e-8, err_msg=f"v^({k})")


@pytest.mark.parametrize("method", ["rk4", "euler"])
def test_prefilter_fixed_step_states_equal_a_loop_of_the_block_bit_for_bit(method):
    """softened_setpoint's fixed-step recursion (before: the removed runner simulate_sampled, a Loop of
    pf.rhs on the numpy engine) gives the numbers of a Loop of the block itself, to the last bit."""
    from ctrl_analysis.estimators.tracking import softened_setpoint

    pf, h = LowPassFilter(4.0, 3), 0.01
    r = np.random.default_rng(3).normal(size=300)
    theta = softened_setpoint(pf, r, h, method=method)
    res = Loop([place(pf, "pf")], h, method=method).simulate(r.size, inputs={"u": r})
    loop = np.stack([res[f"w[{k}]"][:-1, 0] for k in range(3)], axis=-1)
    np.testing.assert_array_equal(theta, loop)
    assert not np.allclose(theta[:, 2], 0.0)  # the input moved every state


def test_bad_input():
    with pytest.raises(ValueError, match="omega must be > 0"):
        LowPassFilter(0.0)
    with pytest.raises(ValueError, match="order must be >= 1"):
        LowPassFilter(1.0, order=0)
    with pytest.raises(ValueError, match="h must"):
        LowPassFilter(1.0).digital(-1.0)
    with pytest.raises(TypeError, match="lowpass"):
        DiscreteLowPass("x", 0.1)
