"""Tests for ctrl_analysis.estimators.differential (Σ)."""

from __future__ import annotations

import dataclasses

import control as ct
import numpy as np
import pytest

from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.symbolic.differential import breakaway_gain, breakaway_point

CASES = [(n0, a) for n0 in (2, 3, 5, 8) for a in (2.0, 5.0, 7.0)]


@pytest.mark.parametrize("n0, a", CASES)
def test_defaults_and_coefficients(n0, a):
    est = DifferentialEstimator(n0, a)
    assert est.K == breakaway_gain(n0, a)
    assert est.breakaway_point == breakaway_point(n0, a)
    np.testing.assert_allclose(est.a_coeffs, est.K * np.poly(-a * np.ones(n0 - 1)), rtol=1e-13)
    with pytest.raises(ValueError):
        est.a_coeffs[0] = 1.0  # read-only
    with pytest.raises(dataclasses.FrozenInstanceError):
        est.K = 1.0


@pytest.mark.parametrize("n0, a", CASES)
def test_tf_ss_open_loop_agree(n0, a):
    est = DifferentialEstimator(n0, a)
    tol = 1e-5 * n0 * a  # the double pole splits by ~sqrt(eps) relative
    p_tf = np.sort_complex(est.tf.poles())
    p_ss = np.sort_complex(est.ss.poles())
    p_fb = np.sort_complex(ct.feedback(est.open_loop_tf, 1).poles())
    np.testing.assert_allclose(p_ss, p_tf, atol=tol)
    np.testing.assert_allclose(p_fb, p_tf, atol=tol)
    np.testing.assert_allclose(np.sort_complex(est.poles), p_tf, atol=tol)
    assert np.sum(np.abs(est.poles - est.breakaway_point) < tol) == 2  # double pole at -n0 a
    assert np.all(est.poles.real < 0)
    # DC: z_1 follows y, the derivative states z_2.. go to 0
    assert float(ct.dcgain(est.tf)) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(np.ravel(ct.dcgain(est.ss)), np.eye(n0)[0], atol=1e-9)
    # same frequency response y -> z_1
    w = np.array([0.1, 1.0, 10.0, 100.0]) * a
    np.testing.assert_allclose(est.ss[0, 0](1j * w), est.tf(1j * w), rtol=1e-9)


def test_custom_gain_changes_poles():
    est = DifferentialEstimator(5, 2.0, K=50.0)
    assert est.K == 50.0
    np.testing.assert_allclose(est.a_coeffs, 50.0 * np.poly(-2.0 * np.ones(4)), rtol=1e-13)
    assert np.sum(np.abs(est.poles - est.breakaway_point) < 1e-3) == 0


@pytest.mark.parametrize("n0", [2, 3, 5])
def test_rhs_equals_linear_state_space(n0):
    est = DifferentialEstimator(n0, 5.0)
    rng = np.random.default_rng(1)
    A, B = est.A, est.B
    np.testing.assert_allclose(A, est.ss.A)
    np.testing.assert_allclose(B, est.ss.B)
    # block protocol: x of shape (B, n0), u of shape (B, 1)
    zb = rng.normal(size=(6, n0))
    yb = rng.normal(size=(6, 1))
    np.testing.assert_allclose(est.rhs(0.0, zb, yb), zb @ A.T + yb @ B.T, rtol=1e-12)
    # extra leading batch axes
    zbb = rng.normal(size=(2, 3, n0))
    ybb = rng.normal(size=(2, 3, 1))
    np.testing.assert_allclose(est.rhs(0.0, zbb, ybb), zbb @ A.T + ybb @ B.T, rtol=1e-12)
    # the output of the "corrected" reading has direct feedthrough from y
    corr = DifferentialEstimator(n0, 5.0, reading="corrected")
    C, D = corr.estimate_matrices("corrected")
    assert corr.feedthrough and not est.feedthrough
    np.testing.assert_allclose(corr.output(0.0, zb, yb), zb @ C.T + yb @ D.T, rtol=1e-12)


@pytest.mark.parametrize("n0", [2, 3, 5])
def test_estimate_readings(n0):
    est = DifferentialEstimator(n0, 5.0)
    rng = np.random.default_rng(2)
    z = rng.normal(size=(4, n0))
    y = rng.normal(size=4)
    np.testing.assert_array_equal(est.estimates(z, y, "state"), z)
    corrected = est.estimates(z, y, reading="corrected")
    # (11) x̂_i = z_i + a_(i-1)(y - z_1) = z_(i-1)'  (the derivative of the previous state)
    np.testing.assert_allclose(corrected[:, 0], z[:, 0])
    np.testing.assert_allclose(corrected[:, 1:], est.rhs(0.0, z, y[:, None])[:, :-1], rtol=1e-12)
    # y -> x̂_2 is s Φ(s) under the corrected reading
    C, D = est.estimate_matrices("corrected")
    sys = ct.ss(est.A, est.B, C, D)
    w = np.array([0.3, 3.0, 30.0])
    np.testing.assert_allclose(sys[1, 0](1j * w), 1j * w * est.tf(1j * w), rtol=1e-9)


def test_nlsys_step_matches_linear_step_response():
    est = DifferentialEstimator(5, 5.0)
    t = np.linspace(0.0, 2.0, 401)
    sys = est.nlsys(name="sigma")
    assert sys.name == "sigma"
    assert sys.ninputs == 1 and sys.nstates == 5 and sys.noutputs == 5
    resp = ct.input_output_response(sys, t, np.ones_like(t),
                                    solve_ivp_kwargs={"rtol": 1e-9, "atol": 1e-12})
    lin = ct.step_response(est.tf, t)
    np.testing.assert_allclose(resp.outputs[0], lin.outputs, atol=1e-6)
    lin_all = ct.step_response(est.ss, t)
    np.testing.assert_allclose(resp.outputs, np.squeeze(lin_all.outputs), atol=1e-5 * est.a_coeffs.max())


def test_nlsys_in_interconnect_with_corrected_reading():
    """Σ behind a plant P = 1/(s+1)^2 in ct.interconnect: x̂_1 = Φ P u and x̂_2 = s Φ P u."""
    est = DifferentialEstimator(3, 5.0)
    plant = ct.tf2ss([1.0], [1.0, 2.0, 1.0], inputs="u", outputs="y", name="plant")
    sigma = est.nlsys(name="sigma", reading="corrected")
    loop = ct.interconnect([plant, sigma], inputs="u", outputs=["xhat[0]", "xhat[1]", "xhat[2]"])
    t = np.linspace(0.0, 4.0, 401)
    resp = ct.input_output_response(loop, t, np.ones_like(t), solve_ivp_kwargs={"rtol": 1e-9, "atol": 1e-12})
    s = ct.tf("s")
    p = ct.tf([1.0], [1.0, 2.0, 1.0])
    np.testing.assert_allclose(resp.outputs[0], ct.step_response(est.tf * p, t).outputs, atol=1e-6)
    np.testing.assert_allclose(resp.outputs[1], ct.step_response(s * est.tf * p, t).outputs, atol=1e-5)


@pytest.mark.parametrize(
    "kwargs, exc, name",
    [
        (dict(n0=1, a=2.0), ValueError, "n0"),
        (dict(n0=0, a=2.0), ValueError, "n0"),
        (dict(n0=2.5, a=2.0), TypeError, "n0"),
        (dict(n0=True, a=2.0), TypeError, "n0"),
        (dict(n0=5, a=0.0), ValueError, "a"),
        (dict(n0=5, a=-2.0), ValueError, "a"),
        (dict(n0=5, a=float("nan")), ValueError, "a"),
        (dict(n0=5, a=float("inf")), ValueError, "a"),
        (dict(n0=5, a=2.0, K=0.0), ValueError, "K"),
        (dict(n0=5, a=2.0, K=-1.0), ValueError, "K"),
        (dict(n0=5, a=2.0, K=float("nan")), ValueError, "K"),
    ],
)
def test_bad_parameters_name_the_argument(kwargs, exc, name):
    with pytest.raises(exc, match=rf"^{name} "):
        DifferentialEstimator(**kwargs)


def test_bad_call_arguments():
    est = DifferentialEstimator(3, 2.0)
    with pytest.raises(ValueError, match=r"^reading "):
        est.estimates(np.zeros(3), 0.0, reading="hat")
    with pytest.raises(ValueError, match=r"^reading "):
        est.nlsys(reading="x")
    with pytest.raises(ValueError, match=r"^z "):
        est.estimates(np.zeros(4), 0.0)
    with pytest.raises(ValueError, match=r"^y "):
        est.estimates(np.zeros((5, 3)), np.zeros(4))
