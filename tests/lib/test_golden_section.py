"""Tests of the golden-section + maintaining-tracking + logic-integral controller."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.controllers.golden_section import GoldenSectionController
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.function_block import FunctionBlock
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.plants import DiscreteLTI

F1, F2, G0 = 1.8, -0.85, 0.1  # x(k+1) = f1 x(k) + f2 x(k-1) + g0 u(k): DC gain g0 / (1 - f1 - f2) = 2


def golden_loop(ctrl, dt=0.01):
    plant = DiscreteLTI(ct.tf([G0, 0.0], [1.0, -F1, -F2], True), dt)  # x(k+1) = f1 x + f2 x(k-1) + g0 u(k)
    params = FunctionBlock(lambda t, u: np.tile([F1, F2, G0], (u.shape[0], 1)), (), ("f1", "f2", "g0"))
    return Loop([place(plant, "plant", inputs=["u"], outputs=["y"]), place(params, "theta"),
                 place(ctrl, "ctrl", inputs=["y", "r", "f1", "f2", "g0"], outputs=["u"])], dt)


@pytest.mark.parametrize("k_I,mu", [(0.0, 0.0), (0.02, 0.0), (0.02, 0.5)])
def test_golden_section_tracks_constant_reference(k_I, mu):
    res = golden_loop(GoldenSectionController(k_I=k_I, c2=0.9, mu=mu)).simulate(1500, inputs={"r": 3.0})
    assert not res.diverged.any()
    np.testing.assert_allclose(res["y"][-50:, 0], 3.0, atol=1e-6)
    # in steady state the control is the model's DC input, r (1 - f1 - f2) / g0
    np.testing.assert_allclose(res["u"][-1, 0], 3.0 * (1 - F1 - F2) / G0, atol=1e-5)


def test_golden_section_error_dynamics_are_the_golden_polynomial():
    # exact model, μ = 0, no integral: e(k+1) = (1 − l1) f1 e(k) + (1 − l2) f2 e(k−1)
    res = golden_loop(GoldenSectionController(k_I=0.0, c2=0.9)).simulate(40, inputs={"r": 1.0})
    e = res["y"][:, 0] - 1.0
    np.testing.assert_allclose(e[3:], (1 - 0.382) * F1 * e[2:-1] + (1 - 0.618) * F2 * e[1:-2], atol=1e-12)


def test_logic_integral_switches_factor():
    c = GoldenSectionController(k_I=1.0, c2=0.5)
    x = np.array([[1.0, 0.0, 4.0, 1.0], [3.0, 0.0, 4.0, 1.0]])  # e(k-1) = 1 (error grows) / 3 (shrinks)
    u = np.array([[2.0, 0.0, 1.0, -0.5, 1.0]] * 2)  # e(k) = 2
    np.testing.assert_allclose(c.update(0.0, x, u)[:, 2], [1.0 * 4.0 - 2.0, 0.5 * 4.0 - 2.0])


@pytest.mark.parametrize("kwargs,match", [
    ({"k_I": -1.0}, "k_I must be >= 0"),
    ({"c2": 0.0}, "0 < c2 <= c1 <= 1"),
    ({"c2": 0.9, "c1": 0.8}, "0 < c2 <= c1 <= 1"),
    ({"c1": 1.5}, "0 < c2 <= c1 <= 1"),
    ({"mu": -0.1}, "mu must be >= 0"),
])
def test_golden_section_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        GoldenSectionController(**kwargs)


def test_golden_section_loop_runs_in_control_interconnect():
    # the parameters are external inputs here: python-control solves the loop by fixed-point
    # iteration from u = 0, and a static ĝ0 block would divide by 0 on the first pass
    plant = DiscreteLTI(ct.tf([G0, 0.0], [1.0, -F1, -F2], True), 0.01)
    loop = Loop([place(plant, "plant", inputs=["u"], outputs=["y"]),
                 place(GoldenSectionController(k_I=0.02, c2=0.9, mu=0.1), "ctrl")], 0.01)
    r = 2.0 + np.sign(np.sin(0.05 * np.arange(200)))
    ext = {"r": r, "f1": np.full(200, F1), "f2": np.full(200, F2), "g0": np.full(200, G0)}
    res = loop.simulate(199, inputs=ext, execution=Execution(engine="numpy"))
    sys = loop.interconnect()
    assert sys.isdtime()
    resp = ct.input_output_response(sys, res.t, np.stack([ext[s] for s in loop.external]), X0=res.x[0, 0])
    np.testing.assert_allclose(res.to_timeresponse(0).outputs, resp.outputs, rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("compiled", [True])  # numba against the batched methods (which run the Python kernel)
def test_golden_kernel_equals_the_numpy_methods_bit_for_bit(compiled):
    from test_kalman_ckf import kernel_runs

    from ctrl_analysis.engine import codegen as _kernels

    ctrl = GoldenSectionController(k_I=0.02, c2=0.9, mu=0.5)
    k = ctrl.kernel()
    rng = np.random.default_rng(5)
    x = rng.normal(size=(60, 4))
    x[:, 3] = rng.integers(0, 2, 60)  # started or not: both branches of e(k−1), r(k−1)
    u = rng.normal(size=(60, 5))
    u[:, 4] = 0.05 + np.abs(u[:, 4])
    out = _kernels._jit(k.output) if compiled else k.output
    upd = _kernels._jit(k.update) if compiled else k.update
    assert np.array_equal(kernel_runs(out, k.params, x, u, 1), ctrl.output(0.0, x, u))
    nxt = kernel_runs(upd, k.params, x, u, 4)
    assert np.array_equal(nxt, ctrl.update(0.0, x, u))
    grow = (u[:, 0] - u[:, 1]) * ((u[:, 0] - u[:, 1]) - np.where(x[:, 3] > 0, x[:, 0], u[:, 0] - u[:, 1])) > 0
    assert grow.any() and (~grow).any()  # both factors c1 and c2 of the logic integral were used


def test_adaptive_loop_compiled_equals_numpy_engine_bit_for_bit():
    """Plant, delay, measurement, CKF, ARX regressor, RLS (projection, trace cap) and golden-section control.

    One loop structure holds every kernel of these library blocks against its numpy method inside the
    engine (one compile on a cold cache, not one per block).
    """
    from ctrl_analysis.engine.blocks import StaticGain
    from ctrl_analysis.estimators.kalman import CharacteristicKalmanFilter
    from ctrl_analysis.identification import ArxRegressor, RecursiveLeastSquaresBlock

    dt = 0.01
    loop = Loop([
        place(DiscreteLTI(ct.tf([G0, 0.0], [1.0, -F1, -F2], True), dt), "plant", inputs=["u"], outputs=["y"]),
        place(DiscreteLTI(ct.tf([1.0], [1.0, 0.0], True), dt), "delay", inputs=["u"], outputs=["u_prev"]),
        place(StaticGain([[1.0, 1.0]], ("y", "v"), ("y_m",)), "meas"),
        place(CharacteristicKalmanFilter(Q=1e-4, R=0.01), "ckf", inputs=["y_m", "u_prev", "f1", "f2", "g0"],
              outputs=["y_f", "y_f1"]),
        place(ArxRegressor(2, 1), "reg", inputs=["y_f", "u"]),
        place(RecursiveLeastSquaresBlock(3, 0.995, 1e-3, (1.7, -0.75, 0.05), lower=(1.0, -1.0, 0.01),
                                         upper=(2.0, -0.5, 1.0), max_trace=3e-3, feedthrough=False), "rls",
              outputs=["f1", "f2", "g0"]),
        place(GoldenSectionController(k_I=0.01, c2=0.95, mu=0.5), "ctrl", inputs=["y_f", "r", "f1", "f2", "g0"],
              outputs=["u"])], dt)
    v = 0.1 * np.random.default_rng(12).normal(size=(1001, 3))
    ext = {"v": v, "r": np.where(np.arange(1001) < 500, 3.0, 1.0)}
    a, b = loop.simulate(1000, inputs=ext,
                         execution=Execution(engine="numpy")), loop.simulate(1000, inputs=ext,
                                                                             execution=Execution(engine="compiled"))
    assert np.array_equal(a.x, b.x)
    for s in a.signals:
        assert np.array_equal(a[s], b[s]), s
    assert np.all(np.abs(a["y"][-100:] - 1.0) < 0.3)  # the adaptive loop tracks the second reference
    assert np.ptp(a["f1"]) > 0 and np.ptp(a["g0"]) > 0  # the identification is active
