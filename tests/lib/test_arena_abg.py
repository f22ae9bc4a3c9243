"""The α-β-γ family: steady-state gains of the constant-acceleration model, and the arena's runner of them."""

import numpy as np
import pytest

from ctrl_analysis.arena.interface import estimate
from ctrl_analysis.estimators.kalman.alpha_beta import alpha_beta_gamma_gains
from ctrl_analysis.estimators.kalman.discrete import discrete_steady_state

LAMBDAS = np.array([1e-4, 0.03, 1.0, 30.0])


def test_gains_are_the_dare_solution_of_the_constant_acceleration_model():
    # an independent solver (control.dlqe inside discrete_steady_state) on the model written out at T = 0.1
    T = 0.1
    F = np.array([[1, T, T * T / 2], [0, 1, T], [0, 0, 1]])
    G = np.array([[T * T / 2], [T], [1.0]])
    a, b, g = alpha_beta_gamma_gains(LAMBDAS)
    for lam, ai, bi, gi in zip(LAMBDAS, a, b, g, strict=True):
        sigma_w = lam / T**2  # Λ = σ_w T² / σ_v with σ_v = 1
        K = discrete_steady_state(F, [[1, 0, 0]], G, sigma_w**2, 1.0).K_filter.ravel()
        assert np.allclose(K, [ai, bi / T, gi / (2 * T * T)], rtol=1e-8)


def test_gains_satisfy_kalatas_relations():
    # Kalata (1984): β = 2(2 - α) - 4√(1 - α), γ = β²/α, Λ² = γ²/(4(1 - α)); and 0 < α < 1
    a, b, g = alpha_beta_gamma_gains(LAMBDAS)
    assert np.all((a > 0) & (a < 1))
    assert np.allclose(b, 2 * (2 - a) - 4 * np.sqrt(1 - a), rtol=1e-9, atol=1e-15)
    assert np.allclose(g, b**2 / a, rtol=1e-9)
    assert np.allclose(LAMBDAS**2, g**2 / (4 * (1 - a)), rtol=1e-7)
    assert alpha_beta_gamma_gains(1.0)[0] == pytest.approx(a[2], rel=1e-12)  # scalar in, scalar out


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, [1.0, -2.0]])
def test_gains_reject_a_non_positive_index(bad):
    with pytest.raises(ValueError, match="Lambda"):
        alpha_beta_gamma_gains(bad)


@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_runner_is_the_steady_state_kalman_filter(engine):
    # the arena's estimate against the filter written with matrices: x̂(k|k) = x̂⁻ + K (y - x̂⁻[0]), x̂⁻ = F x̂(k-1|k-1)
    dt, lam = 0.01, 0.05
    rng = np.random.default_rng(3)
    y = np.sin(0.01 * np.arange(300))[:, None] + 0.01 * rng.uniform(-1, 1, (300, 1))
    a, b, g = alpha_beta_gamma_gains(lam)
    K = np.array([a, b / dt, g / (2 * dt * dt)])
    F = np.array([[1, dt, dt * dt / 2], [0, 1, dt], [0, 0, 1]])
    xp, ref = np.array([y[0, 0], 0.0, 0.0]), []  # at rest on the first sample (the arena's start)
    for v in y[:, 0]:
        xf = xp + K * (v - xp[0])
        ref.append(xf)
        xp = F @ xf
    est = estimate("abg", [[lam]], y, dt, engine=engine)
    assert est.shape == (300, 1, 3)
    assert np.allclose(est[:, 0], np.array(ref), rtol=1e-10, atol=1e-10)


def test_runner_is_exact_on_a_parabola_in_steady_state():
    # a constant-acceleration model tracks f = 1 + 2t + 1.5t² without bias: f' and f'' exact once the transient dies
    dt = 0.01
    t = dt * np.arange(800)
    y = (1 + 2 * t + 1.5 * t**2)[:, None]
    est = estimate("abg", [[0.3]], y, dt)
    assert np.allclose(est[-100:, 0, 1], 2 + 3 * t[-100:], atol=1e-9)
    assert np.allclose(est[-100:, 0, 2], 3.0, atol=1e-9)
