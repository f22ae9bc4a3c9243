"""Tests of the PD law with feed-forward and model compensation (ctrl_analysis.controllers.pd)."""

import numpy as np
import pytest

from ctrl_analysis.controllers.pd import PDFeedforward, bandwidth_gains


def test_bandwidth_gains():
    np.testing.assert_allclose(bandwidth_gains(2, 10.0), [100.0, 20.0, 1.0])
    np.testing.assert_allclose(bandwidth_gains(3, 2.0), [8.0, 12.0, 6.0, 1.0])
    pd = PDFeedforward(b0=3.0, omega_c=10.0)
    np.testing.assert_allclose(np.roots(pd.tracking_poly()), [-10.0, -10.0], atol=1e-6)
    np.testing.assert_allclose(pd.tracking_tf.dcgain(), 1.0)


def test_control_formula_batched():
    pd = PDFeedforward(b0=2.0, omega_c=10.0)
    rng = np.random.default_rng(0)
    ref = rng.normal(size=(6, 3))
    xh = rng.normal(size=(6, 3))
    f = rng.normal(size=6)
    u = pd.control(ref, xh, f)
    expected = (100 * (ref[:, 0] - xh[:, 0]) + 20 * (ref[:, 1] - xh[:, 1]) + (ref[:, 2] - xh[:, 2]) - f) / 2.0
    np.testing.assert_allclose(u, expected, rtol=1e-13)
    assert u.shape == (6,)


def test_perfect_estimates_give_tracking_dynamics():
    """Plant x'' = F + b0 u with exact estimates: tracking error obeys e'' + k2 e' + k1 e = 0."""
    from ctrl_analysis.simulate import simulate_sampled

    b0, F = 2.0, 0.7
    pd = PDFeedforward(b0=b0, omega_c=5.0)

    def rhs(t, x, u, p):
        return np.stack([x[:, 1], F + b0 * u[:, 0]], axis=1)

    def ctrl(k, t, x, w):
        ref = np.array([np.sin(t), np.cos(t), -np.sin(t)])
        xh = np.concatenate([x, np.full((len(x), 1), F)], axis=1)
        return pd.control(ref, xh)[:, None]

    res = simulate_sampled(rhs, [0.3, 0.0], 1e-3, 3000, controller=ctrl)
    e = np.sin(res.t) - res.x[:, 0, 0]
    # critically damped at 5 rad/s: e = (e0 + (5 e0 + e0') t) exp(-5 t), e0 = -0.3, e0' = 1
    t = res.t
    exact = (-0.3 + (5 * -0.3 + 1.0) * t) * np.exp(-5 * t)
    np.testing.assert_allclose(e, exact, atol=2e-3)  # ZOH of u over 1 ms


@pytest.mark.parametrize(
    "kwargs,exc,match",
    [
        (dict(b0=0.0, omega_c=1.0), ValueError, "b0"),
        (dict(b0=1.0), ValueError, "exactly one"),
        (dict(b0=1.0, omega_c=1.0, gains=[1, 2]), ValueError, "exactly one"),
        (dict(b0=1.0, omega_c=-1.0), ValueError, "omega_c"),
        (dict(b0=1.0, gains=[1.0, -2.0]), ValueError, "Hurwitz"),
        (dict(b0=1.0, gains=[1.0]), ValueError, "gains"),
    ],
)
def test_bad_input(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        PDFeedforward(**kwargs)
