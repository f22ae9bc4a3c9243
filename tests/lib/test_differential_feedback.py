"""High-order differential feedback: Hurwitz check, gain order, closed-loop poles."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.controllers.differential_feedback import (
    HighOrderDifferentialFeedback,
    gains_from_poles,
    hurwitz_roots,
)
from ctrl_analysis.simulate import simulate_sampled


def test_accepts_the_papers_gains_and_places_the_poles():
    ctrl = HighOrderDifferentialFeedback([2184.0, 506.0, 39.0])
    np.testing.assert_allclose(ctrl.poles, [-12.0, -13.0, -14.0], atol=1e-9)
    np.testing.assert_allclose(ctrl.characteristic_polynomial, [1, 39, 506, 2184])
    # the printed vector with its trailing 1 (the coefficient of s^3)
    ctrl4 = HighOrderDifferentialFeedback([2184.0, 506.0, 39.0, 1.0], n=3)
    np.testing.assert_array_equal(ctrl4.K, ctrl.K)
    np.testing.assert_allclose(gains_from_poles([-12, -13, -14]), [2184, 506, 39])


@pytest.mark.parametrize("K", [[1.0, -1.0, 3.0], [6.0, 0.0, 1.0], [-1.0, 2.0]])
def test_rejects_non_hurwitz_gains(K):
    with pytest.raises(ValueError, match=r"K must make .* Hurwitz"):
        HighOrderDifferentialFeedback(K)


def test_rejects_bad_shapes():
    with pytest.raises(ValueError, match="must end with the leading coefficient 1"):
        HighOrderDifferentialFeedback([2184.0, 506.0, 39.0, 2.0], n=3)
    with pytest.raises(ValueError, match="K must have n = 3 gains"):
        HighOrderDifferentialFeedback([1.0, 2.0], n=3)
    with pytest.raises(ValueError, match="K must be finite"):
        HighOrderDifferentialFeedback([1.0, np.nan])


def test_closed_loop_chain_poles_against_python_control():
    ctrl = HighOrderDifferentialFeedback([2184.0, 506.0, 39.0])
    # independent construction: chain of integrators under static state feedback via ct.feedback
    n = 3
    A = np.diag(np.ones(n - 1), 1)
    B = np.zeros((n, 1))
    B[-1, 0] = 1.0
    chain = ct.ss(A, B, np.eye(n), np.zeros((n, 1)))
    loop = ct.feedback(chain, ctrl.gain_matrix)
    np.testing.assert_allclose(np.sort(loop.poles().real), [-14.0, -13.0, -12.0], atol=1e-8)
    cl = ctrl.closed_loop_chain()
    np.testing.assert_allclose(np.sort(cl.poles().real), [-14.0, -13.0, -12.0], atol=1e-8)
    np.testing.assert_allclose(ct.dcgain(cl), 1.0, rtol=1e-12)


def test_u_is_batched_and_simulates_the_designed_step_response():
    ctrl = HighOrderDifferentialFeedback([6.0, 11.0, 6.0])  # poles -1, -2, -3
    theta = np.array([[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    x_hat = np.zeros((2, 5))  # a higher-order estimate vector: the first n entries are used
    np.testing.assert_allclose(ctrl.u(theta, x_hat), [6.0, 12.0])
    with pytest.raises(ValueError, match="theta must have n = 3"):
        ctrl.u(np.zeros((2, 2)), x_hat)

    # chain of integrators x''' = u with exact states, setpoint v = 1 (θ = (1, 0, 0))
    def rhs(t, x, u, p):
        dx = np.empty_like(x)
        dx[:, :2] = x[:, 1:]
        dx[:, 2] = ctrl.u(np.array([1.0, 0.0, 0.0]), x)
        return dx

    h, n = 1e-3, 6000
    res = simulate_sampled(rhs, np.zeros(3), h, n)
    ref = ct.step_response(ctrl.closed_loop_chain(), res.t).outputs
    np.testing.assert_allclose(res.x[:, 0, 0], ref, atol=1e-8)


def test_hurwitz_roots_order():
    np.testing.assert_allclose(hurwitz_roots([2.0, 3.0]), [-1.0, -2.0])
