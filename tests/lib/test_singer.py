"""Singer's manoeuvre model: the exact transition, its steady-state gains and the arena's family."""

import numpy as np
import pytest
import scipy.linalg

from ctrl_analysis.arena.interface import estimate
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.blocks import DiscreteBlock
from ctrl_analysis.engine.kernels import KernelBlock, Kernels
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.kalman.alpha_beta import (
    alpha_beta_gamma_gains,
    alpha_beta_gamma_output,
    alpha_beta_gamma_update,
    kalata_gains,
)
from ctrl_analysis.estimators.kalman.singer import singer_gains, singer_transition

DECAYS = [0.0, 1e-7, 1e-4, 0.05, 0.0999, 0.1, 0.7, 3.0, 40.0]


@pytest.mark.parametrize("s", DECAYS)
def test_the_transition_is_the_continuous_models_exponential(s):
    # ẍ = a, ȧ = -a/τ_m over T: expm(A T) in the states [x, T ẋ, T² ẍ] (T = 1, 1/τ_m = s)
    E = scipy.linalg.expm(np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -s]]))
    a, b, rho = singer_transition(s)
    np.testing.assert_allclose([a, b, rho], [E[0, 2], E[1, 2], E[2, 2]], rtol=1e-12, atol=1e-300)  # expm: ~1e-13


@pytest.mark.parametrize("lam", [1e-4, 0.05, 1.0, 30.0])
def test_gains_are_the_dare_solution_and_constant_acceleration_at_zero_decay(lam):
    np.testing.assert_allclose(singer_gains(lam, 0.0), alpha_beta_gamma_gains(lam), rtol=1e-12)
    for s in (0.05, 2.0):
        a, b, rho = singer_transition(s)
        F = np.array([[1.0, 1.0, a], [0.0, 1.0, b], [0.0, 0.0, rho]])
        G = np.array([[0.5], [1.0], [1.0]])
        H = np.array([[1.0, 0.0, 0.0]])
        P = scipy.linalg.solve_discrete_are(F.T, H.T, lam**2 * G @ G.T, np.eye(1))  # scipy's own solver
        K = (P @ H.T / (H @ P @ H.T + 1.0))[:, 0]
        np.testing.assert_allclose(singer_gains(lam, s), [K[0], K[1], 2.0 * K[2]], rtol=1e-7)


def test_a_fast_decay_tends_to_the_constant_velocity_alpha_beta_filter():
    # ρ -> 0 and a, b ~ 1/s: the acceleration decouples and the position and velocity follow Kalata's α-β model
    ka, kb = kalata_gains(0.3)
    for s, tol in ((100.0, 1e-2), (1e4, 1e-4)):
        a, b, _ = singer_gains(0.3, s)
        assert a == pytest.approx(ka, rel=tol) and b == pytest.approx(kb, rel=tol)


def test_bad_arguments_name_themselves():
    with pytest.raises(ValueError, match="decay"):
        singer_transition(-0.1)
    with pytest.raises(ValueError, match="Lambda"):
        singer_gains(0.0, 0.1)
    with pytest.raises(ValueError, match="Lambda and decay must broadcast"):
        singer_gains([0.1, 0.2], [0.1, 0.2, 0.3])
    assert [g.shape for g in singer_gains([0.1, 0.2], 0.5)] == [(2,), (2,), (2,)]


def test_the_arena_family_is_the_matrix_form_filter():
    dt, lam, tau = 0.01, 0.05, 0.2
    rng = np.random.default_rng(4)
    y = np.sin(0.02 * np.arange(300))[:, None] + 0.01 * rng.uniform(-1, 1, (300, 1))
    a, b, rho = singer_transition(dt / tau)
    F = np.array([[1, dt, a * dt * dt], [0, 1, b * dt], [0, 0, rho]])
    al, be, ga = singer_gains(lam, dt / tau)
    K = np.array([al, be / dt, ga / (2 * dt * dt)])
    xp, ref = np.array([y[0, 0], 0.0, 0.0]), []
    for v in y[:, 0]:
        xf = xp + K * (v - xp[0])
        ref.append(xf)
        xp = F @ xf
    for engine in ("numpy", "compiled"):
        est = estimate("singer", [[lam, tau]], y, dt, engine=engine)
        np.testing.assert_allclose(est[:, 0], np.array(ref), rtol=1e-10, atol=1e-10)


class _ConstantAcceleration(KernelBlock, DiscreteBlock):
    """The α-β-γ filter with the library's constant-acceleration kernels (the arena's block before Singer)."""

    inputs, states, outputs = ("y",), ("xpred[0]", "xpred[1]", "xpred[2]"), ("xhat[0]", "xhat[1]", "xhat[2]")
    feedthrough = True
    kernels = Kernels(output=alpha_beta_gamma_output, update=alpha_beta_gamma_update)

    def __init__(self, gains, T):
        self.kernel_params = np.array([gains[0], gains[1] / T, gains[2] / (2 * T * T), T])


def test_the_abg_family_runs_the_constant_acceleration_prediction_to_the_last_bit():
    dt, lam = 0.002, 0.001
    y = np.cos(dt * np.arange(500))[:, None] + 0.01 * np.random.default_rng(5).uniform(-1, 1, (500, 1))
    loop = Loop([place(_ConstantAcceleration(alpha_beta_gamma_gains(lam), dt), "x")], dt)
    res = loop.simulate(500, inputs={"y": y[:, 0]}, x0={"x": [y[0, 0], 0.0, 0.0]},
                        execution=Execution(engine="numpy", progress=False))
    est = estimate("abg", [[lam]], y, dt, engine="numpy")
    for j in range(3):
        assert np.array_equal(est[:, 0, j], res.signals[f"xhat[{j}]"][:-1, 0])
