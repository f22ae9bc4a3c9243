"""Tests of the characteristic-model Kalman filter, the full-order reference filter and the DiscreteLTI plant block."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.engine import Execution
from ctrl_analysis.estimators.kalman import (
    CharacteristicKalmanFilter,
    LinearKalmanFilter,
    discrete_steady_state,
)
from ctrl_analysis.plants import DiscreteLTI

F1, F2, G0 = 1.9, -0.95, 0.05  # a stable 2nd-order characteristic model (poles 0.95 ± 0.22j)
Q = np.array([[1e-3, 2e-4], [2e-4, 5e-4]])
R = 0.5


def textbook_kf(y, u_prev, P0):
    """The standard equations with numpy matrices (P = (I − K C) P⁻, not the Joseph form)."""
    Phi, Gam, C = np.array([[F1, F2], [1.0, 0.0]]), np.array([G0, 0.0]), np.array([[1.0, 0.0]])
    x, P, out, Ps = np.zeros(2), P0.copy(), [], []
    for yk, uk in zip(y, u_prev, strict=True):
        xp = Phi @ x + Gam * uk
        Pp = Phi @ P @ Phi.T + Q
        K = Pp @ C.T / (C @ Pp @ C.T + R)
        x = xp + (K * (yk - xp[0])).ravel()
        P = (np.eye(2) - K @ C) @ Pp
        out.append(x.copy())
        Ps.append(P.copy())
    return np.array(out), np.array(Ps)


def records(N=300, B=1, seed=0):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(N, B))
    return rng.normal(size=(N, B)) + np.cumsum(u, axis=0) * 0.05, u


def ckf_inputs(y, u):
    N, B = y.shape
    return np.stack([y, u, np.full((N, B), F1), np.full((N, B), F2), np.full((N, B), G0)], axis=2)


def test_ckf_with_exact_parameters_equals_textbook_kalman_filter():
    y, u = records()
    P0 = np.array([[2.0, 0.5], [0.5, 1.0]])
    out, xs = CharacteristicKalmanFilter(Q=Q, R=R, P0=P0).run(ckf_inputs(y, u))
    ref, Ps = textbook_kf(y[:, 0], u[:, 0], P0)
    np.testing.assert_allclose(out[:, 0, :], ref, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(xs[1:, 0, 2], Ps[:, 0, 0], rtol=1e-10)
    np.testing.assert_allclose(xs[1:, 0, 3], Ps[:, 0, 1], rtol=1e-10)
    np.testing.assert_allclose(xs[1:, 0, 4], Ps[:, 1, 1], rtol=1e-10)


def test_ckf_covariance_converges_to_dare_steady_state():
    y, u = records(N=2000)
    _, xs = CharacteristicKalmanFilter(Q=Q, R=R, P0=10.0).run(ckf_inputs(y, u))
    ss = discrete_steady_state([[F1, F2], [1.0, 0.0]], [[1.0, 0.0]], np.eye(2), Q, R)
    P = xs[-1, 0]
    np.testing.assert_allclose([P[2], P[3], P[4]], [ss.P_post[0, 0], ss.P_post[0, 1], ss.P_post[1, 1]], rtol=1e-8)


def test_ckf_batch_is_stacked_single_runs_and_full_order_filter_agrees():
    y, u = records(B=3, seed=1)
    out, _ = CharacteristicKalmanFilter(Q=Q, R=R).run(ckf_inputs(y, u))
    one, _ = CharacteristicKalmanFilter(Q=Q, R=R).run(ckf_inputs(y[:, 1:2], u[:, 1:2]))
    np.testing.assert_array_equal(out[:, 1], one[:, 0])
    full = LinearKalmanFilter([[F1, F2], [1.0, 0.0]], [G0, 0.0], [1.0, 0.0], Q, R, P0=1.0)
    yh, _ = full.run(np.stack([y, u], axis=2))
    np.testing.assert_allclose(yh[:, :, 0], out[:, :, 0], rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("kwargs,match", [
    ({"R": 0.0}, "R must be > 0"),
    ({"Q": -1e-3}, "Q must be positive semidefinite"),
    ({"Q": [[1.0, 0.0], [1.0, 1.0]]}, "Q must be symmetric"),
    ({"P0": [[1.0, 1.0], [1.0, 1.0]]}, "singular or negative"),
    ({"P0": -1.0}, "singular or negative"),
])
def test_ckf_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        CharacteristicKalmanFilter(**kwargs)


def test_discrete_lti_matches_control_c2d_and_checks_siso():
    G = ct.tf([2.0, 4.0], [1.0, 3.0, 2.0, 0.5])
    plant = DiscreteLTI(G, 0.05)
    u = np.sin(0.3 * np.arange(200))
    y, _ = plant.run(u)
    ref = ct.forced_response(ct.c2d(G, 0.05, method="zoh"), T=0.05 * np.arange(200), U=u)
    np.testing.assert_allclose(y[:, 0, 0], ref.outputs, rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="must be SISO"):
        DiscreteLTI(ct.rss(3, 2, 1), 0.1)
    with pytest.raises(ValueError, match="must equal dt"):
        DiscreteLTI(ct.tf([1.0], [1.0, -0.5], 0.2), 0.1)
    with pytest.raises(TypeError, match="TransferFunction or control.StateSpace"):
        DiscreteLTI([1.0, 2.0], 0.1)


def ckf_loop():
    """Plant, delay, a static sensor (0 states) and the CKF: every block has a kernel."""
    from ctrl_analysis.engine.loop import Loop, place

    plant = DiscreteLTI(ct.tf([G0, 0.0], [1.0, -F1, -F2], True), 0.1)
    delay = DiscreteLTI(ct.tf([1.0], [1.0, 0.0], True), 0.1)
    meas = DiscreteLTI(ct.tf([1.0], [1.0], True), 0.1)  # a static pass-through (0 states, feedthrough)
    return Loop([place(plant, "plant", inputs=["u"], outputs=["y"]),
                 place(delay, "delay", inputs=["u"], outputs=["u_prev"]),
                 place(meas, "sensor", inputs=["y_v"], outputs=["y_m"]),
                 place(CharacteristicKalmanFilter(Q=Q, R=R), "ckf", inputs=["y_m", "u_prev", "f1", "f2", "g0"])],
                0.1, outputs=["y", "xhat[0]", "xhat[1]"])


def test_ckf_and_plant_run_in_control_interconnect():
    loop = ckf_loop()
    rng = np.random.default_rng(3)
    ext = {"u": rng.normal(size=120), "y_v": rng.normal(size=120), "f1": np.full(120, F1),
           "f2": np.full(120, F2), "g0": np.full(120, G0)}
    res = loop.simulate(119, inputs=ext,
                        execution=Execution(engine="numpy"))  # compiled = numpy: test_golden_section's adaptive loop
    resp = ct.input_output_response(loop.interconnect(), res.t, np.stack([ext[s] for s in loop.external]),
                                    X0=res.x[0, 0])
    np.testing.assert_allclose(res.to_timeresponse(0).outputs, resp.outputs, rtol=1e-10, atol=1e-12)


# ------------------------------------------------------------------ compiled kernels
def kernel_runs(fn, p, x, u, width):
    """Apply a block kernel ``fn(t, x, u, p, out)`` run by run (plain Python or jitted) -> ``(B, width)``."""
    out = np.empty((x.shape[0], width))
    for b in range(x.shape[0]):
        fn(0.3, x[b], u[b], p, out[b])
    return out


def random_ckf_inputs(rng, B=40):
    """CKF states (a random SPD covariance) and inputs [y, u(k−1), f1, f2, g0]."""
    x = rng.normal(size=(B, 5))
    x[:, 2], x[:, 4] = 1.0 + x[:, 2] ** 2, 1.0 + x[:, 4] ** 2
    x[:, 3] = 0.3 * x[:, 3]
    u = rng.normal(size=(B, 5))
    u[:, 2:] = [F1, F2, G0] + 0.1 * u[:, 2:]
    return x, u


@pytest.mark.parametrize("compiled", [False, True])
def test_ckf_lti_and_full_kf_kernels_equal_the_numpy_methods(compiled):
    from ctrl_analysis.engine import codegen as _kernels

    jit = _kernels._jit if compiled else (lambda f: f)
    rng = np.random.default_rng(11)
    ckf = CharacteristicKalmanFilter(Q=Q, R=R)
    x, u = random_ckf_inputs(rng)
    k = ckf.kernel()
    assert np.array_equal(kernel_runs(jit(k.update), k.params, x, u, 5), ckf.update(0.3, x, u))
    assert np.array_equal(kernel_runs(jit(k.output), k.params, x, u, 2), ckf.output(0.3, x, u))
    for plant in (DiscreteLTI(ct.tf([2.0, 4.0], [1.0, 3.0, 2.0, 0.5]), 0.05),
                  DiscreteLTI(ct.tf([1.0, 0.5], [1.0, 2.0]), 0.1)):
        xp, up = rng.normal(size=(30, plant.n_states)), rng.normal(size=(30, 1))
        k = plant.kernel()
        assert np.array_equal(kernel_runs(jit(k.update), k.params, xp, up, plant.n_states), plant.update(0.3, xp, up))
        assert np.array_equal(kernel_runs(jit(k.output), k.params, xp, up, 1), plant.output(0.3, xp, up))
    assert DiscreteLTI(ct.tf([1.0, 0.5], [1.0, 2.0]), 0.1).feedthrough  # the D u branch was exercised
    # the full-order KF's kernel sums in another order than einsum: equal to rounding
    sysd = DiscreteLTI(ct.zpk([], [-1.0, -2.0, -3.0], 6.0), 0.05)
    kf = LinearKalmanFilter(sysd.A, sysd.B, sysd.C, 0.01 * np.outer(sysd.B, sysd.B) + 1e-4 * np.eye(3), R, 1.0)
    M = rng.normal(size=(25, 3, 3))
    xk = np.concatenate([rng.normal(size=(25, 3)), (M @ M.transpose(0, 2, 1) + np.eye(3)).reshape(25, 9)], axis=1)
    uk = rng.normal(size=(25, 2))
    k = kf.kernel()
    np.testing.assert_allclose(kernel_runs(jit(k.update), k.params, xk, uk, 12), kf.update(0.3, xk, uk),
                               rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(kernel_runs(jit(k.output), k.params, xk, uk, 1), kf.output(0.3, xk, uk),
                               rtol=1e-13, atol=1e-14)

