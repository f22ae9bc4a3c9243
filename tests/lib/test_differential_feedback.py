"""High-order differential feedback: Hurwitz check, gain order, closed-loop poles, the block protocol."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.controllers.differential_feedback import (
    HighOrderDifferentialFeedback,
    gains_from_poles,
    hurwitz_roots,
)
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.blocks import ContinuousBlock, StaticBlock
from ctrl_analysis.engine.loop import Loop, place


class Chain(ContinuousBlock):
    """x''' = u, all states as outputs (a test plant)."""

    inputs, outputs, states = ("u",), ("x[0]", "x[1]", "x[2]"), ("x[0]", "x[1]", "x[2]")

    def rhs(self, t, x, u, params=None):
        return np.stack([x[:, 1], x[:, 2], u[:, 0]], axis=1)


def test_places_the_poles():
    ctrl = HighOrderDifferentialFeedback([2184.0, 506.0, 39.0])
    np.testing.assert_allclose(ctrl.poles, [-12.0, -13.0, -14.0], atol=1e-9)
    np.testing.assert_allclose(ctrl.characteristic_polynomial, [1, 39, 506, 2184])
    np.testing.assert_allclose(gains_from_poles([-12, -13, -14]), [2184, 506, 39])


@pytest.mark.parametrize("K", [[1.0, -1.0, 3.0], [6.0, 0.0, 1.0], [-1.0, 2.0],
                               [2184.0, 506.0, 39.0, 1.0]])  # a trailing 1 is a 4th gain: not Hurwitz
def test_rejects_non_hurwitz_gains(K):
    with pytest.raises(ValueError, match=r"K must make .* Hurwitz"):
        HighOrderDifferentialFeedback(K)


def test_rejects_bad_shapes():
    with pytest.raises(ValueError, match="K must be finite"):
        HighOrderDifferentialFeedback([1.0, np.nan])
    with pytest.raises(ValueError, match="K must be a 1-D gain vector"):
        HighOrderDifferentialFeedback(np.ones((2, 2)))


def test_closed_loop_chain_poles_against_python_control():
    ctrl = HighOrderDifferentialFeedback([2184.0, 506.0, 39.0])
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


def test_is_a_static_feedthrough_block():
    ctrl = HighOrderDifferentialFeedback([6.0, 11.0, 6.0])
    assert isinstance(ctrl, StaticBlock) and ctrl.feedthrough and ctrl.n_states == 0
    assert ctrl.outputs == ("u",) and len(ctrl.inputs) == 6
    rng = np.random.default_rng(1)
    u = rng.normal(size=(7, 6))
    expected = (u[:, :3] - u[:, 3:]) @ ctrl.K
    np.testing.assert_allclose(ctrl.output(0.0, np.zeros((7, 0)), u)[:, 0], expected, rtol=1e-13, atol=1e-12)
    # a row does not depend on the batch it is in
    np.testing.assert_array_equal(ctrl.output(0.0, np.zeros((1, 0)), u[3:4]), ctrl.output(0.0, None, u)[3:4])
    np.testing.assert_allclose(ctrl.u(u[:, :3], np.c_[u[:, 3:], np.ones(7)]), expected, rtol=1e-13, atol=1e-12)
    with pytest.raises(ValueError, match="theta must have n = 3"):
        ctrl.u(np.zeros((2, 2)), np.zeros((2, 5)))


def test_loop_step_response_equals_the_designed_closed_loop_and_interconnect():
    ctrl = HighOrderDifferentialFeedback([6.0, 11.0, 6.0])  # poles -1, -2, -3
    loop = Loop([place(Chain(), "plant"),
                 place(ctrl, "ctrl", inputs=["v", "dv", "ddv", "x[0]", "x[1]", "x[2]"])],
                dt=1e-3, outputs=["x[0]", "u"])
    res = loop.simulate(6000, inputs={"v": 1.0, "dv": 0.0, "ddv": 0.0}, runs=2)
    ref = ct.step_response(ctrl.closed_loop_chain(), res.t).outputs
    np.testing.assert_allclose(res["x[0]"][:, 1], ref, atol=1e-8)
    sys = loop.interconnect()
    resp = ct.input_output_response(sys, res.t, np.stack([np.ones_like(res.t), 0 * res.t, 0 * res.t]),
                                    solve_ivp_kwargs={"rtol": 1e-10, "atol": 1e-12})
    np.testing.assert_allclose(resp.outputs[0], ref, atol=1e-7)
    np.testing.assert_allclose(resp.outputs[1, 0], 6.0, rtol=1e-12)  # u(0) = k_3 (v - 0)


def test_hurwitz_roots_order():
    np.testing.assert_allclose(hurwitz_roots([2.0, 3.0]), [-1.0, -2.0])


@pytest.mark.parametrize("compiled", [False, True])
def test_kernel_is_the_numpy_method_run_by_run(compiled):
    from ctrl_analysis.controllers.differential_feedback import feedback_output
    from ctrl_analysis.engine.codegen import _jit

    ctrl = HighOrderDifferentialFeedback([2184.0, 506.0, 39.0])
    k = ctrl.kernel()
    assert k.output is feedback_output and k.rhs is None and k.update is None
    fn = _jit(k.output) if compiled else k.output
    u = np.random.default_rng(4).normal(scale=3.0, size=(9, 6))
    y = np.empty((9, 1))
    for b in range(9):
        fn(0.0, np.empty(0), u[b], k.params, y[b])
    assert np.array_equal(y, ctrl.output(0.0, np.zeros((9, 0)), u))  # bit for bit
    np.testing.assert_allclose(y[:, 0], (u[:, :3] - u[:, 3:]) @ ctrl.K, rtol=1e-12)


def test_per_run_gains_equal_single_blocks():
    """Gains per run (``Loop.simulate(params={"ctrl": {"K": ...}})``) give each run the loop of its own block."""
    Ks = np.array([[6.0, 11.0, 6.0], [24.0, 26.0, 9.0], [6.0, 11.0, 6.0]])  # poles -1,-2,-3 and -2,-3,-4
    loop = Loop([place(Chain(), "plant"),
                 place(HighOrderDifferentialFeedback(Ks[0]), "ctrl",
                       inputs=["v", "dv", "ddv", "x[0]", "x[1]", "x[2]"])],
                dt=1e-2, outputs=["x[0]", "u"])
    ins = {"v": 1.0, "dv": 0.0, "ddv": 0.0}
    runs = loop.simulate(300, inputs=ins, runs=3, params={"ctrl": {"K": Ks}}, execution=Execution(engine="numpy"))
    for b, K in enumerate(Ks):
        alone = Loop([place(Chain(), "plant"), place(HighOrderDifferentialFeedback(K), "ctrl",
                                                     inputs=["v", "dv", "ddv", "x[0]", "x[1]", "x[2]"])],
                     dt=1e-2, outputs=["x[0]", "u"]).simulate(300, inputs=ins, runs=1,
                                                              execution=Execution(engine="numpy"))
        assert np.array_equal(runs["u"][:, b], alone["u"][:, 0])
    assert not np.array_equal(runs["u"][:, 0], runs["u"][:, 1])
