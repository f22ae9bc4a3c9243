"""Tests of plain right-hand sides (ctrl_analysis.engine.ivp: the adaptive path, python-control wrapping) and of the
fixed-step integrators' order (ctrl_analysis.engine.integrators)."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.engine.blocks import ContinuousBlock
from ctrl_analysis.engine.integrators import STEPPERS, rk4_step
from ctrl_analysis.engine.ivp import continuous_nlsys, simulate_ivp
from ctrl_analysis.engine.loop import Loop, place

# A damped oscillator x'' + 2 ζ ω x' + ω² x = u with known solution.
OMEGA, ZETA = 2.0, 0.1
A = np.array([[0.0, 1.0], [-OMEGA**2, -2 * ZETA * OMEGA]])
Bm = np.array([0.0, 1.0])


def linear_rhs(t, x, u, params=None):
    dx = x @ A.T
    if u is not None:
        dx = dx + np.asarray(u)[:, :1] * Bm
    return dx


def exact_free(t, x0):
    from scipy.linalg import expm

    return np.array([expm(A * tk) @ x0 for tk in t])


@pytest.mark.parametrize("method,order", [("euler", 1), ("rk4", 4)])
def test_order_of_convergence(method, order):
    x0 = np.array([1.0, 0.0])
    T = 2.0
    errs = []
    hs = [0.02, 0.01, 0.005]
    for h in hs:
        n = round(T / h)
        x = x0[None, :]
        for k in range(n):
            x = STEPPERS[method](linear_rhs, k * h, x, None, h)
        errs.append(np.max(np.abs(x[0] - exact_free([T], x0)[0])))
    slopes = np.diff(np.log(errs)) / np.diff(np.log(hs))
    np.testing.assert_allclose(slopes, order, atol=0.15)


class _Oscillator(ContinuousBlock):
    """The damped oscillator as a block with no input (its state is its output)."""

    inputs, outputs, states = (), ("x[0]", "x[1]"), ("x[0]", "x[1]")

    def rhs(self, t, x, u, params=None):
        return linear_rhs(t, x, None)


def test_substeps_refine_inside_a_held_sample():
    x0 = np.array([1.0, 0.0])

    def run(substeps):
        loop = Loop([place(_Oscillator(), "osc")], 0.1, method="euler", substeps=substeps)
        return loop.simulate(20, x0={"osc": x0}, runs=1)

    coarse, fine = run(1), run(50)
    exact = exact_free(coarse.t, x0)
    assert np.max(np.abs(fine.x[:, 0] - exact)) < 0.1 * np.max(np.abs(coarse.x[:, 0] - exact))


def test_ivp_path_matches_closed_form_for_a_batch():
    x0 = np.array([[1.0, 0.0], [0.0, 1.0]])
    t = np.linspace(0, 3, 31)
    res = simulate_ivp(linear_rhs, x0, t)
    for b in range(2):
        np.testing.assert_allclose(res.x[:, b], exact_free(t, x0[b]), atol=1e-7)
    assert not res.diverged.any()


def test_continuous_block_as_nlsys_in_an_interconnection():
    """The engine's rhs wrapped as control.nlsys, closed with a static gain via ct.feedback,
    matches the same loop simulated by the engine."""
    plant = continuous_nlsys(linear_rhs, states=2, inputs=1, outputs=1,
                             output=lambda t, x, u, p: x[:, :1], name="osc")
    assert isinstance(plant, ct.NonlinearIOSystem)
    closed = ct.feedback(plant, 3.0)  # u = r - 3 x1
    t = np.linspace(0, 5, 501)
    resp = ct.input_output_response(closed, t, U=np.ones_like(t), X0=[0, 0],
                                    solve_ivp_kwargs={"rtol": 1e-10, "atol": 1e-12})

    def rhs_cl(tt, x, u, p):
        return linear_rhs(tt, x, 1.0 - 3.0 * x[:, :1])

    x = [np.zeros((1, 2))]
    for k in range(500):
        x.append(rk4_step(rhs_cl, t[k], x[-1], None, 0.01))
    x1 = np.stack(x)[:, 0, 0]
    np.testing.assert_allclose(resp.outputs, x1, atol=1e-5)
    # and against the linear closed loop as a python-control StateSpace
    lin = ct.ss(A - np.outer(Bm, [3.0, 0.0]), Bm.reshape(2, 1), [[1.0, 0.0]], 0)
    np.testing.assert_allclose(ct.step_response(lin, t).outputs, x1, atol=1e-8)


def test_ivp_one_diverging_run_does_not_poison_the_batch():
    rate = np.array([[-1.0], [3.0], [-2.0]])
    t = np.linspace(0.0, 10.0, 101)
    # run 1 grows past the bound: it is frozen and flagged, the others finish unflagged
    res = simulate_ivp(lambda t, x, u, p: rate * x, np.ones((3, 1)), t, bound=1e3)
    assert res.diverged.tolist() == [False, True, False]
    assert res.diverged_step[1] in (23, 24)  # e^(3t) passes 1e3 at t = 2.30 s
    np.testing.assert_allclose(res.x[-1, [0, 2], 0], np.exp([-10.0, -20.0]), rtol=1e-5, atol=1e-9)

    # run 1 blows up in finite time (x' = x^2 from 1 at t = 1) with no bound: the batch solve fails,
    # each run is then solved on its own and only run 1 is flagged
    def blowup(t, x, u, p):
        out = rate * x
        out[1] = x[1] ** 2
        return out

    res = simulate_ivp(blowup, np.ones((3, 1)), t, bound=np.inf)
    assert res.info["per_run"] and res.diverged.tolist() == [False, True, False]
    np.testing.assert_allclose(res.x[-1, [0, 2], 0], np.exp([-10.0, -20.0]), rtol=1e-5, atol=1e-9)
    healthy = simulate_ivp(lambda t, x, u, p: -x, np.ones((2, 1)), t)
    assert not healthy.info["per_run"] and not healthy.diverged.any()


@pytest.mark.parametrize("kw,fragment", [
    ({"rtol": float("nan")}, "rtol must be finite"),
    ({"atol": -1.0}, "atol must be > 0"),
    ({"rtol": [1e-6]}, "rtol must be a real number"),
    ({"bound": float("nan")}, "bound must be > 0"),
    ({"bound": -np.inf}, "bound must be > 0"),
    ({"method": "Euler"}, "method must be one of"),
])
def test_ivp_rejects_bad_tolerances_and_bounds(kw, fragment):
    with pytest.raises((ValueError, TypeError), match=fragment):
        simulate_ivp(lambda t, x, u, p: -x, [1.0], [0.0, 1.0], **kw)
