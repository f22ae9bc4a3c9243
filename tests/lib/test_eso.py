"""Tests of the extended state observers (linear, nonlinear fal, modified) in ctrl_analysis.estimators.eso."""

from math import comb

import numpy as np
import pytest

from ctrl_analysis.engine.integrators import rk4_step
from ctrl_analysis.estimators.eso import ExtendedStateObserver, fal

# ---------------------------------------------------------------------------------------------
# fal
# ---------------------------------------------------------------------------------------------

def _rk4(rhs, x0, h, n, u=None):
    """``(t, x)``: one run of ``x' = rhs(t, x, u, None)`` over ``n`` steps of the engine's RK4, ``u`` held."""
    xs = [np.atleast_2d(np.asarray(x0, dtype=float))]
    for k in range(n):
        xs.append(rk4_step(rhs, k * h, xs[-1], u, h))
    return h * np.arange(n + 1), np.stack(xs)


def test_fal_hand_values():
    assert fal(0.5, 0.5, 0.1) == pytest.approx(np.sqrt(0.5), rel=1e-14)
    assert fal(0.05, 0.5, 0.1) == pytest.approx(0.05 / 0.1**0.5, rel=1e-14)
    assert fal(0.0, 0.5, 0.1) == 0.0
    assert fal(2.0, 1.0, 0.3) == pytest.approx(2.0)  # alpha = 1 is linear


def test_fal_odd_and_continuous_and_vectorised():
    e = np.linspace(-2, 2, 401)
    for alpha in (0.25, 0.5, 0.75, 1.5):
        np.testing.assert_allclose(fal(-e, alpha, 0.1), -fal(e, alpha, 0.1), rtol=0, atol=1e-15)
    delta = 0.2
    for alpha in (0.25, 0.5, 0.75):
        inside = fal(delta, alpha, delta)
        outside = fal(delta * (1 + 1e-12), alpha, delta)
        assert inside == pytest.approx(delta**alpha, rel=1e-12)
        assert outside == pytest.approx(inside, rel=1e-10)
    out = fal(np.ones((3, 1)), np.array([0.5, 0.25]), 0.1)
    assert out.shape == (3, 2)


@pytest.mark.parametrize("delta", [0.0, -1.0, np.nan])
def test_fal_bad_delta(delta):
    with pytest.raises(ValueError, match="delta"):
        fal(0.1, 0.5, delta)


# ---------------------------------------------------------------------------------------------
# Linear analysis
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_from_bandwidth_poles_clustered(n):
    w = 7.0
    obs = ExtendedStateObserver.from_bandwidth(n, w)
    assert obs.n == n and obs.nstates == n + 1
    np.testing.assert_allclose(obs.L, [comb(n + 1, i) * w**i for i in range(1, n + 2)])
    # a root of multiplicity m is computed to ~ eps^(1/m) relative accuracy
    tol = 10 * w * np.finfo(float).eps ** (1.0 / (n + 1))
    np.testing.assert_allclose(obs.poles, -w, atol=tol)
    np.testing.assert_allclose(np.mean(obs.poles).real, -w, rtol=1e-9)
    # python-control agrees with the polynomial roots
    np.testing.assert_allclose(np.sort_complex(obs.ss.poles()), np.sort_complex(obs.poles), atol=tol)


@pytest.mark.parametrize("n,beta", [(1, (2.0, 1.0)), (2, (3.0, 3.0, 1.0)), (3, (1.0, 2.0, 3.0, 4.0))])
def test_from_epsilon_characteristic_polynomial(n, beta):
    eps = 0.05
    obs = ExtendedStateObserver.from_epsilon(n, eps, beta, allow_unstable=True)  # (1, 2, 3, 4) is not Hurwitz
    expected = [1.0] + [b / eps**i for i, b in enumerate(beta, start=1)]
    np.testing.assert_allclose(obs.characteristic_polynomial(), expected, rtol=1e-14)
    # the state-space matrix has the same characteristic polynomial
    np.testing.assert_allclose(np.poly(obs.ss.A), expected, rtol=1e-9)


def test_beta_331_is_bandwidth_form():
    a = ExtendedStateObserver.from_epsilon(2, 0.05, (3, 3, 1))
    b = ExtendedStateObserver.from_bandwidth(2, 20.0)
    np.testing.assert_allclose(a.L, b.L, rtol=1e-12)


@pytest.mark.parametrize("B", [None, 5])
def test_rhs_linear_part_equals_ss(B):
    rng = np.random.default_rng(1)
    obs = ExtendedStateObserver.from_epsilon(3, 0.1, (4, 6, 4, 1), b0=2.5)
    sys = obs.ss
    shape = (obs.nstates,) if B is None else (B, obs.nstates)
    x = rng.normal(size=shape)
    u = rng.normal(size=shape[:-1] + (2,))
    expected = x @ sys.A.T + u @ sys.B.T
    np.testing.assert_allclose(obs.rhs(0.0, x, u), expected, rtol=1e-12, atol=1e-12)
    assert sys.ninputs == 2 and sys.noutputs == 4
    np.testing.assert_allclose(sys.C, np.eye(4))


def test_nlsys_matches_rhs():
    obs = ExtendedStateObserver.from_bandwidth(2, 5.0, b0=1.5)
    sys = obs.nlsys(name="eso")
    x = np.array([0.1, -0.2, 0.3])
    u = np.array([0.5, 2.0])
    np.testing.assert_allclose(sys._rhs(0.0, x, u), obs.rhs(0.0, x, u), rtol=1e-14)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_disturbance_error_tf_dc_gain_and_scaling(n):
    beta = [comb(n + 1, i) for i in range(1, n + 2)]
    for eps in (0.1, 0.05):
        obs = ExtendedStateObserver.from_epsilon(n, eps, beta)
        tfs = obs.disturbance_error_tf()
        assert len(tfs) == n + 1
        for i, g in enumerate(tfs, start=1):
            # steady error for a constant h: L_{i-1}/L_{n+1} (L_0 = 1) = (beta_{i-1}/beta_{n+1}) eps^(n+2-i)
            b_prev = 1.0 if i == 1 else beta[i - 2]
            np.testing.assert_allclose(g.dcgain(), b_prev / beta[-1] * eps ** (n + 2 - i), rtol=1e-9)
    # wrt="state" is s times wrt="derivative"
    gs = obs.disturbance_error_tf("state")
    np.testing.assert_allclose(gs[-1](1j * 3.0), 3j * tfs[-1](1j * 3.0), rtol=1e-12)


def test_error_tf_matches_simulation_of_ramp_disturbance():
    """x'' = c t (no known part): ESO errors settle at c * dcgain of disturbance_error_tf."""
    c, b0 = 2.0, 1.0
    obs = ExtendedStateObserver.from_bandwidth(2, 10.0, b0=b0)

    def rhs(t, z, u, p):
        x, xh = z[:, :2], z[:, 2:]
        dx = np.stack([x[:, 1], c * t * np.ones(len(z))], axis=1)
        return np.concatenate([dx, obs.rhs(t, xh, np.stack([x[:, 0], np.zeros(len(z))], axis=1))], axis=1)

    t, x = _rk4(rhs, np.zeros(5), 1e-3, 3000)
    xf = x[-1, 0]
    t_end = t[-1]
    err = np.array([xf[0] - xf[2], xf[1] - xf[3], c * t_end - xf[4]])
    expected = c * np.array([g.dcgain() for g in obs.disturbance_error_tf()])
    np.testing.assert_allclose(err, expected, rtol=1e-4)


# ---------------------------------------------------------------------------------------------
# MESO vs ESO
# ---------------------------------------------------------------------------------------------

def _run_observer(obs, a=4.0, c=0.8, b0=2.0, T=4.0, h=2e-3):
    """Plant x'' = -a x - c x' + b0 sin(t), observed by ``obs``; returns the x1..x3 error histories."""

    def rhs(t, z, u, p):
        x, xh = z[:, :2], z[:, 2:]
        uc = np.sin(t) * np.ones(len(z))
        dx = np.stack([x[:, 1], -a * x[:, 0] - c * x[:, 1] + b0 * uc], axis=1)
        return np.concatenate([dx, obs.rhs(t, xh, np.stack([x[:, 0], uc], axis=1))], axis=1)

    x0 = np.array([1.0, 0.0, 0.0, 0.0, 0.0])
    _, x = _rk4(rhs, x0, h, int(T / h))
    z = x[:, 0]
    known = -a * z[:, 0] - c * z[:, 1]
    x3_true = known if obs.known is None else np.zeros_like(known)  # ESO: extended state holds f
    return np.abs(np.stack([z[:, 0] - z[:, 2], z[:, 1] - z[:, 3], x3_true - z[:, 4]], axis=1))


def test_meso_with_true_model_beats_eso():
    a, c, b0 = 4.0, 0.8, 2.0
    eso = ExtendedStateObserver.from_bandwidth(2, 15.0, b0=b0)
    meso = ExtendedStateObserver.from_bandwidth(
        2, 15.0, b0=b0, known=lambda t, xh, u, p: -a * u[..., 0] - c * xh[..., 1])
    e_eso = _run_observer(eso)
    e_meso = _run_observer(meso)
    late = slice(1500, None)  # after the transient (t > 3 s)
    # with the true model the MESO's extended state is exactly 0: its errors vanish
    assert np.max(e_meso[late]) < 1e-6
    # the ESO tracks f(t), a sinusoid, with an error of the size of |E_3(j1)| * |f'|
    assert np.mean(e_eso[late, 2]) > 1e-3
    assert np.all(np.mean(e_meso[late], axis=0) < 1e-3 * np.mean(e_eso[late], axis=0))


def test_nonlinear_eso_runs_and_converges():
    obs = ExtendedStateObserver.from_bandwidth(2, 15.0, b0=2.0, alpha=(1.0, 0.5, 0.25), delta=0.01)
    assert not obs.is_linear
    e = _run_observer(obs)
    assert np.all(np.isfinite(e))
    assert np.mean(e[1000:, 0]) < 1e-2
    with pytest.raises(ValueError, match="linear"):
        _ = obs.ss


# ---------------------------------------------------------------------------------------------
# Bad input
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(gains=[1.0]), "gains"),
        (dict(gains=[1.0, 0.0, 2.0]), "gains"),
        (dict(gains=[1.0, -2.0]), "gains"),
        (dict(gains=[1.0, np.nan]), "gains"),
        (dict(gains=[1.0, 2.0], alpha=[0.5]), "alpha"),
        (dict(gains=[1.0, 2.0], alpha=[0.5, 0.25]), "delta"),
        (dict(gains=[1.0, 2.0], alpha=[0.5, 0.25], delta=0.0), "delta"),
    ],
)
def test_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ExtendedStateObserver(**kwargs)


def test_bad_constructor_args():
    with pytest.raises(ValueError, match="epsilon"):
        ExtendedStateObserver.from_epsilon(2, 0.0, (3, 3, 1))
    with pytest.raises(ValueError, match="beta"):
        ExtendedStateObserver.from_epsilon(2, 0.05, (3, 3))
    with pytest.raises(ValueError, match="omega_o"):
        ExtendedStateObserver.from_bandwidth(2, -1.0)
    with pytest.raises(ValueError, match="n must be"):
        ExtendedStateObserver.from_bandwidth(0, 1.0)
    with pytest.raises(TypeError, match="known"):
        ExtendedStateObserver([1.0, 2.0], known=3.0)
    with pytest.raises(ValueError, match="wrt"):
        ExtendedStateObserver([1.0, 2.0]).disturbance_error_tf("bad")
