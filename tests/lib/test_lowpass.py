"""Tests of the low-pass filters (ctrl_analysis.estimators.lowpass)."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.estimators.lowpass import DiscreteLowPass, LowPassFilter
from ctrl_analysis.simulate import simulate_sampled


@pytest.mark.parametrize("order", [1, 2])
def test_tf_and_ss_agree(order):
    W = LowPassFilter(1.8, order=order)
    np.testing.assert_allclose(W.tf.dcgain(), 1.0)
    np.testing.assert_allclose(W.ss.dcgain(), 1.0)
    np.testing.assert_allclose(np.sort(W.ss.poles().real), -1.8, atol=1e-6)
    for w in (0.1, 1.8, 30.0):
        np.testing.assert_allclose(W.ss(1j * w), W.tf(1j * w), rtol=1e-12)
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
    res = simulate_sampled(W.rhs, np.zeros(2), h, 1000, noise=np.ones((1000, 1, 1)))
    ref = ct.step_response(W.tf, T=res.t).outputs
    np.testing.assert_allclose(res.x[:, 0, 0], ref, atol=1e-9)  # RK4 error at h*ω = 0.005


def test_vector_batch_filtering_and_initial():
    W = LowPassFilter(2.0)
    dig = DiscreteLowPass(W, 0.01, shape=(3, 4), initial=1.0)
    np.testing.assert_allclose(dig.output, np.ones((3, 4)))
    u = np.arange(12.0).reshape(3, 4)
    for _ in range(3000):
        y = dig.step(u)
    np.testing.assert_allclose(y, u, rtol=1e-8, atol=1e-12)
    dig.reset()
    np.testing.assert_allclose(dig.output, 1.0)


def test_bad_input():
    with pytest.raises(ValueError, match="omega_f"):
        LowPassFilter(0.0)
    with pytest.raises(ValueError, match="order"):
        LowPassFilter(1.0, order=3)
    with pytest.raises(ValueError, match="h must"):
        LowPassFilter(1.0).digital(-1.0)
    with pytest.raises(TypeError, match="lowpass"):
        DiscreteLowPass("x", 0.1)
