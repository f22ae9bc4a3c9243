"""Property tests (hypothesis) for the core invariants: Σ is stable, the Riccati residual vanishes,
a batch equals its stacked single runs, the scalar random-walk (IKF) steady gain lies in (0, 1)."""

import mpmath
import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from ctrl_analysis.engine.blocks import ContinuousBlock
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.estimators.kalman import (
    care_residual,
    continuous_steady_state,
    dare_residual,
    discrete_steady_state,
    random_walk_gain,
)
from ctrl_analysis.estimators.kalman._checks import check_detectable
from ctrl_analysis.noise import draw_noise, gaussian_noise, run_seeds, uniform_noise
from ctrl_analysis.symbolic.differential import MAX_ORDER

SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
finite = st.floats(-3.0, 3.0, allow_nan=False, allow_infinity=False)


@SETTINGS
@given(n0=st.integers(2, MAX_ORDER), a=st.floats(1e-3, 1e3))
def test_sigma_is_stable_for_every_order_and_zero(n0, a):
    est = DifferentialEstimator(n0, a)  # the breakaway design gain
    assert np.max(est.poles.real) < 0
    assert np.min(est.poles.real) == pytest.approx(-n0 * a, rel=1e-3)  # the double pole at -n0 a is the fastest
    if n0 <= 8 and 0.1 <= a <= 100:  # well-conditioned: python-control's eigenvalues of the model agree
        np.testing.assert_allclose(np.sort(np.real(est.ss.poles())), np.sort(est.poles.real),
                                   rtol=1e-4, atol=1e-6 * n0 * a)


def _system(draw, n, p, m):
    A = np.array(draw(st.lists(finite, min_size=n * n, max_size=n * n))).reshape(n, n)
    C = np.array(draw(st.lists(finite, min_size=p * n, max_size=p * n))).reshape(p, n)
    G = np.array(draw(st.lists(finite, min_size=n * m, max_size=n * m))).reshape(n, m)
    return A, C, G


@st.composite
def stabilisable_detectable(draw, discrete=False):
    n = draw(st.integers(1, 4))
    p = draw(st.integers(1, 2))
    A, C, G = _system(draw, n, p, n)
    G = G + 3.5 * np.eye(n)  # full-rank noise input (diagonally dominant): (A, G Q^½) stabilisable
    q = draw(st.floats(0.1, 10.0))
    r = draw(st.floats(0.1, 10.0))
    if discrete:
        A = A / max(1.0, np.max(np.abs(np.linalg.eigvals(A))))  # keep |λ| moderate
    # robustly detectable: every mode that is not clearly stable is clearly observable (PBH test with
    # a margin), so the generated pairs are detectable and not merely numerically so
    for lam in np.linalg.eigvals(A):
        clearly_stable = abs(lam) < 0.95 if discrete else lam.real < -0.05
        if not clearly_stable:
            pbh = np.vstack([A - lam * np.eye(n), C])
            assume(np.linalg.svd(pbh, compute_uv=False).min() > 0.1)
    check_detectable(A, C, discrete=discrete)
    return A, C, G, q * np.eye(n), r * np.eye(p)


@SETTINGS
@given(stabilisable_detectable())
def test_continuous_riccati_residual_vanishes(system):
    A, C, G, Q, R = system
    sol = continuous_steady_state(A, C, G, Q, R)
    residual = care_residual(A, C, G, Q, R, sol.P)
    scale = max(1.0, np.abs(sol.P).max() ** 2, np.abs(G @ Q @ G.T).max())
    assert np.abs(residual).max() <= 1e-7 * scale
    assert np.all(np.linalg.eigvalsh(sol.P) >= -1e-9 * np.abs(sol.P).max())
    assert np.max(sol.poles.real) < 0  # the stabilising solution


@SETTINGS
@given(stabilisable_detectable(discrete=True))
def test_discrete_riccati_residual_vanishes(system):
    F, H, G, Q, R = system
    sol = discrete_steady_state(F, H, G, Q, R)
    residual = dare_residual(F, H, G, Q, R, sol.P_prior)
    scale = max(1.0, np.abs(sol.P_prior).max(), np.abs(G @ Q @ G.T).max())
    assert np.abs(residual).max() <= 1e-7 * scale
    assert np.max(np.abs(sol.poles)) < 1


def _oscillator(t, x, u, params):
    # x1' = x2, x2' = -x1 - 0.4 x2 + tanh(u1) + u2 (nonlinear in the held noise)
    return np.stack([x[:, 1], -x[:, 0] - 0.4 * x[:, 1] + np.tanh(u[:, 0]) + u[:, 1]], axis=1)


class _Oscillator(ContinuousBlock):
    """:func:`_oscillator` as a block driven by the held noise ``w[0]``, ``w[1]``."""

    inputs, outputs, states = ("w[0]", "w[1]"), ("x[0]", "x[1]"), ("x[0]", "x[1]")

    def rhs(self, t, x, u, params=None):
        return _oscillator(t, x, u, params)


def _run(x0, noise, method):
    loop = Loop([place(_Oscillator(), "osc")], 0.05, method=method)
    return loop.simulate(50, inputs={"w[0]": noise[:, :, 0], "w[1]": noise[:, :, 1]}, x0={"osc": x0}).x


@SETTINGS
@given(base=st.integers(0, 2**32 - 1), runs=st.integers(1, 5), method=st.sampled_from(["rk4", "euler"]),
       x0=st.tuples(finite, finite))
def test_a_batch_equals_its_stacked_single_runs(base, runs, method, x0):
    seeds = run_seeds(base, runs)
    noise = draw_noise(seeds, 50, uniform_noise(-1.0, 1.0), gaussian_noise(0.3))
    batch = _run(np.broadcast_to(np.asarray(x0, dtype=float), (runs, 2)), noise, method)
    for b, seed in enumerate(seeds):
        single_noise = draw_noise([seed], 50, uniform_noise(-1.0, 1.0), gaussian_noise(0.3))
        np.testing.assert_array_equal(single_noise[:, 0], noise[:, b])
        single = _run(x0, single_noise, method)
        np.testing.assert_array_equal(single[:, 0], batch[:, b])


@SETTINGS
@given(Q=st.floats(1e-6, 1e6), R=st.floats(1e-6, 1e6))
def test_random_walk_gain_stays_in_open_unit_interval(Q, R):
    K = random_walk_gain(Q, R)
    assert 0.0 < K < 1.0
    # the fixed point of P⁻ = P + Q, K = P⁻/(P⁻ + R), P = (1 − K) P⁻ is the root in (0, 1) of
    # K² + qK − q = 0 (q = Q/R); compared with that root in 50-digit arithmetic
    with mpmath.workdps(50):
        q = mpmath.mpf(Q) / mpmath.mpf(R)
        exact = (-q + mpmath.sqrt(q * q + 4 * q)) / 2
    assert K == pytest.approx(float(exact), rel=1e-12)


def test_random_walk_gain_extremes_do_not_overflow():
    assert random_walk_gain(1e200, 1.0) == 1.0  # 1 − K ≈ R/Q rounds away, never 0 from an overflow
    assert random_walk_gain(0.0, 1.0) == 0.0
    assert 0.0 < random_walk_gain(1e-200, 1.0) < 1e-99


def test_badly_scaled_riccati_is_solved_not_silently_wrong():
    # found by the property test: scipy's balancing returned P11 = 0 (residual 12.25) for this pair
    A = np.array([[-1.0, 0.0, 0.0], [2.44e-200, 0.0, 1.0], [0.0, 0.0, 0.0]])
    C = np.array([[0.0, 1.0, 0.0]])
    sol = continuous_steady_state(A, C, 3.5 * np.eye(3), np.eye(3), 1.0)
    assert sol.P[0, 0] == pytest.approx(3.5**2 / 2, rel=1e-9)  # the unobservable stable mode: 2 p11 = 12.25
    assert np.abs(care_residual(A, C, 3.5 * np.eye(3), np.eye(3), 1.0, sol.P)).max() < 1e-8
