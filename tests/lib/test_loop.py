"""Tests of the block protocols (ctrl_analysis.engine.blocks) and the batched interconnect (engine.loop)."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.blocks import (
    ContinuousBlock,
    DiscreteBlock,
    SampledBlock,
    StaticGain,
)
from ctrl_analysis.engine.function_block import FunctionBlock
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.estimators.kalman import AlphaBetaFilter, kalata_gains
from ctrl_analysis.noise import draw_noise, gaussian_noise, run_seeds


class Oscillator(ContinuousBlock):
    """x1' = x2, x2' = -w^2 x1 + u; output y = x1 (a test plant)."""

    inputs, outputs, states = ("f",), ("y",), ("p", "v")

    def __init__(self, w):
        self.w = w

    def initial_state(self):
        return np.array([1.0, 0.0])

    def rhs(self, t, x, u, params=None):
        return np.stack([x[:, 1], -self.w**2 * x[:, 0] + u[:, 0]], axis=1)

    def output(self, t, x, u, params=None):
        return x[:, :1]


class DoubleIntegrator(DiscreteBlock):
    """Sampled double integrator driven by an acceleration input; output the position."""

    inputs, outputs, states = ("acc",), ("pos",), ("p", "v")

    def __init__(self, T):
        self.T = T

    def update(self, t, x, u, params=None):
        T = self.T
        return np.stack([x[:, 0] + T * x[:, 1] + 0.5 * T * T * u[:, 0], x[:, 1] + T * u[:, 0]], axis=1)

    def output(self, t, x, u, params=None):
        return x[:, :1]


def sigma_loop(dt=1e-3):
    sigma = DifferentialEstimator(3, 5.0)
    return Loop([place(Oscillator(2.0), "plant"), place(sigma, "sigma", inputs=["y"])], dt=dt,
                outputs=["y", "xhat[0]", "xhat[1]", "xhat[2]"])


def test_continuous_block_engine_equals_control_interconnect():
    loop = sigma_loop()
    res = loop.simulate(2000, inputs={"f": 0.0})
    sys = loop.interconnect()
    assert isinstance(sys, ct.InterconnectedSystem) and sys.isctime()
    resp = ct.input_output_response(sys, res.t, 0.0, X0=res.x[0, 0], solve_ivp_kwargs={"rtol": 1e-10, "atol": 1e-12})
    np.testing.assert_allclose(res.to_timeresponse(0).outputs, resp.outputs, atol=1e-8)
    # Σ tracks the oscillator: xhat[1] -> -2 sin(2t)
    np.testing.assert_allclose(res["xhat[1]"][-1, 0], -2 * np.sin(2 * res.t[-1]), atol=0.05)


def test_discrete_block_engine_equals_control_interconnect():
    T = 0.1
    alpha, beta = kalata_gains(0.3)
    noisy = FunctionBlock(lambda t, u: u[:, :1] + u[:, 1:], inputs=("pos", "v"), outputs=("y",))
    loop = Loop([place(DoubleIntegrator(T), "plant"), place(noisy, "sensor"),
                 place(AlphaBetaFilter(alpha, beta, T), "filter")], dt=T,
                outputs=["pos", "xhat[0]", "xhat[1]"])
    assert loop.external == ("acc", "v")
    seeds = run_seeds(3, 4)
    v = draw_noise(seeds, 300, gaussian_noise(0.5))[:, :, 0]
    acc = 0.2 * np.cos(0.05 * np.arange(300))
    res = loop.simulate(300, inputs={"acc": acc, "v": v}, seeds=seeds)
    sys = loop.interconnect()
    assert sys.isdtime() and sys.dt == T
    for b in (0, 3):
        resp = ct.input_output_response(sys, res.t[:300], np.stack([acc, v[:, b]]))
        np.testing.assert_allclose(res.to_timeresponse(b).outputs[:, :300], resp.outputs, rtol=1e-12, atol=1e-12)


class Motor(DiscreteBlock):
    """w(k+1) = 0.9 w(k) + 0.1 tau(k) - 0.5 TL(k): a sampled motor speed with a load torque TL."""

    inputs, outputs, states = ("tau", "TL"), ("w",), ("w",)

    def update(self, t, x, u, params=None):
        return 0.9 * x + 0.1 * u[:, :1] - 0.5 * u[:, 1:]


def test_interconnect_keeps_the_declared_input_order_and_the_engine_numbers():
    # r is read first (by the controller), TL second (by the motor): declared order r, TL, while
    # sorting by name would give ['TL', 'r'] ('T' < 'r')
    loop = Loop([place(StaticGain([[2.0, -2.0]], ("r", "w"), ("tau",)), "ctrl"), place(Motor(), "motor")], dt=0.1)
    assert loop.external == ("r", "TL")
    sys = loop.interconnect()
    assert sys.input_labels == ["r", "TL"]
    assert sys.output_labels == list(loop.outlist)
    n = 80
    r = np.where(np.arange(n + 1) < 10, 0.0, 1.0)
    TL = 0.3 * np.sin(0.2 * np.arange(n + 1))
    res = loop.simulate(n, inputs={"r": r, "TL": TL})
    stacked = np.stack([r, TL])  # [r, TL], the declared order
    resp = ct.input_output_response(sys, res.t, stacked)
    np.testing.assert_allclose(resp.outputs, res.to_timeresponse(0).outputs, rtol=1e-12, atol=1e-12)
    # the two inputs act differently, so the other order would have been caught
    swapped = ct.input_output_response(sys, res.t, stacked[::-1])
    assert np.max(np.abs(swapped.outputs - resp.outputs)) > 0.1


def test_a_block_with_state_that_declares_no_states_is_a_clear_error():
    class Forgot(DiscreteBlock):  # x(k+1) = x(k) + r(k), but no `states`: Block.states = () is inherited
        inputs, outputs = ("r",), ("s",)

        def update(self, t, x, u, params=None):
            return x + u

    class ForgotToo(ContinuousBlock):
        inputs, outputs = ("r",), ("s",)

        def rhs(self, t, x, u, params=None):
            return u

    rule = r"declares no states: a {} must name its states, e.g. states = \('x',\)"
    with pytest.raises(ValueError, match=r"block 'acc' \(Forgot\) " + rule.format("DiscreteBlock")):
        Loop([place(Forgot(), "acc")], dt=1.0)
    with pytest.raises(ValueError, match=r"block 'int' \(ForgotToo\) " + rule.format("ContinuousBlock")):
        Loop([place(ForgotToo(), "int")], dt=1.0)
    with pytest.raises(ValueError, match=r"block Forgot declares no states"):
        Forgot().run(np.ones(3))
    # a block whose state is really empty says so (states = ()), and runs
    res = Loop([place(Oscillator(2.0), "plant"), place(_Gain(), "k")], dt=0.01).simulate(3)
    np.testing.assert_array_equal(res["f"][:, 0], -3.0 * res["y"][:, 0])


def test_batch_equals_stacked_single_runs_bit_for_bit():
    T = 0.1
    alpha, beta = kalata_gains(0.3)
    noisy = FunctionBlock(lambda t, u: u[:, :1] + u[:, 1:], inputs=("pos", "v"), outputs=("y",))
    loop = Loop([place(DoubleIntegrator(T), "plant"), place(noisy, "sensor"),
                 place(AlphaBetaFilter(alpha, beta, T), "filter")], dt=T)
    seeds = run_seeds(0, 5)
    v = draw_noise(seeds, 100, gaussian_noise(0.5))[:, :, 0]
    batch = loop.simulate(100, inputs={"acc": 0.1, "v": v})
    for b in range(5):
        one = loop.simulate(100, inputs={"acc": 0.1, "v": v[:, b:b + 1]})
        np.testing.assert_array_equal(batch.x[:, b:b + 1], one.x)
    cont = sigma_loop()
    x0 = {"plant": np.array([[1.0, 0.0], [0.5, 1.0], [0.0, 2.0]])}
    batch = cont.simulate(200, inputs={"f": 0.0}, x0=x0)
    for b in range(3):
        one = cont.simulate(200, inputs={"f": 0.0}, x0={"plant": x0["plant"][b]})
        np.testing.assert_array_equal(batch.x[:, b:b + 1], one.x)


def test_sampled_block_runs_the_engine_integrator_in_python_control():
    osc = Oscillator(3.0)
    loop = Loop([place(osc, "plant")], dt=0.01, substeps=2)
    res = loop.simulate(100, inputs={"f": lambda t: np.sin(t)})
    # the same RK4 steps as a discrete-time nlsys (input held: use a held-input loop)
    held = Loop([place(osc, "plant")], dt=0.01, substeps=2).simulate(100, inputs={"f": np.sin(res.t[:100])})
    disc = SampledBlock(osc, 0.01, substeps=2).nlsys(0.01)
    resp = ct.input_output_response(disc, held.t[:100], np.sin(held.t[:100]), X0=osc.initial_state())
    np.testing.assert_allclose(held["y"][:100, 0], resp.outputs, rtol=1e-13, atol=1e-14)
    # a callable input is evaluated at the RK4 stages, an array is held: both close, not equal
    assert 0 < np.max(np.abs(res["y"] - held["y"])) < 1e-3
    # the exact solution of x'' = -9 x + sin t, x(0) = 1, x'(0) = 0
    t = res.t
    exact = np.cos(3 * t) + (np.sin(t) - np.sin(3 * t) / 3) / 8
    np.testing.assert_allclose(res["y"][:, 0], exact, atol=1e-8)


def test_divergence_is_flagged_per_run():
    class Growth(DiscreteBlock):
        inputs, outputs, states = ("g",), ("x",), ("x",)

        def initial_state(self):
            return np.ones(1)

        def update(self, t, x, u, params=None):
            return x * u

    res = Loop([place(Growth(), "g")], dt=1.0).simulate(30, inputs={"g": np.array([[0.5, 10.0]] * 30)},
                                                        execution=Execution(bound=1e6))
    assert res.diverged.tolist() == [False, True]
    assert res.diverged_step[1] == 7  # 10^7 > 1e6 first at step 7
    assert np.isnan(res["x"][-1, 1]) and res["x"][-1, 0] == pytest.approx(0.5**30)


def test_wiring_errors_are_clear():
    a = FunctionBlock(lambda t, u: u, inputs=("b",), outputs=("a",))
    b = FunctionBlock(lambda t, u: u, inputs=("a",), outputs=("b",))
    with pytest.raises(ValueError, match="algebraic loop"):
        Loop([place(a, "A"), place(b, "B")], dt=1.0)
    with pytest.raises(ValueError, match="produced by both"):
        Loop([place(a, "A"), place(a, "A2")], dt=1.0)
    with pytest.raises(ValueError, match="block names must be unique"):
        Loop([place(a, "A"), place(b, "A", outputs=["c"], inputs=["q"])], dt=1.0)
    loop = sigma_loop()
    with pytest.raises(ValueError, match="missing"):
        loop.simulate(10)
    with pytest.raises(ValueError, match="not external inputs"):
        loop.simulate(10, inputs={"f": 0.0, "zz": 1.0})
    with pytest.raises(ValueError, match=r"x0\['plant'\] must have shape"):
        loop.simulate(10, inputs={"f": 0.0}, x0={"plant": np.zeros(3)})
    with pytest.raises(ValueError, match="dt must be > 0"):
        Loop([place(a, "A")], dt=0.0)
    with pytest.raises(ValueError, match="inputs of 'A' must name 1 signals"):
        place(a, "A", inputs=["x", "y"])
    with pytest.raises(ValueError, match="all blocks continuous or all discrete"):
        Loop([place(Oscillator(1.0), "p"), place(AlphaBetaFilter(0.5, 0.2, 0.1), "f")], dt=0.1).interconnect()


def test_feedback_loop_plant_before_its_controller():
    """A non-feedthrough plant placed before the controller that drives it (a real feedback loop)."""

    class Integrator(ContinuousBlock):
        inputs, outputs, states = ("u",), ("y",), ("x",)

        def initial_state(self):
            return np.ones(1)

        def rhs(self, t, x, u, params=None):
            return u.copy()

    gain = FunctionBlock(lambda t, u: -3.0 * u, inputs=("y",), outputs=("u",))
    loop = Loop([place(Integrator(), "plant"), place(gain, "ctrl")], dt=0.01)
    res = loop.simulate(100)
    # x' = -3 x, x(0) = 1: one RK4 step multiplies by the degree-4 Taylor polynomial of exp(-3h)
    z = -3.0 * 0.01
    np.testing.assert_allclose(res["y"][:, 0], (1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24) ** np.arange(101), rtol=1e-13)
    np.testing.assert_allclose(res["u"][:, 0], -3.0 * res["y"][:, 0], rtol=1e-12)
    # and the same in python-control
    resp = ct.input_output_response(loop.interconnect(), res.t, 0.0, X0=[1.0],
                                    solve_ivp_kwargs={"rtol": 1e-10, "atol": 1e-12})
    np.testing.assert_allclose(resp.outputs[0], res["y"][:, 0], rtol=1e-7)


class _Gain(DiscreteBlock):
    """u = -k y, held over the sample (no state; direct feedthrough)."""

    inputs, outputs, states, feedthrough = ("y",), ("f",), (), True

    def update(self, t, x, u, params=None):
        return x

    def output(self, t, x, u, params=None):
        return -3.0 * u[:, :1]


def test_block_without_feedthrough_may_come_before_the_producer_of_its_input():
    """The plant (no feedthrough) is placed first; its input f is produced later in the list."""
    loop = Loop([place(Oscillator(2.0), "plant"), place(_Gain(), "k")], dt=0.01)
    res = loop.simulate(200)
    # closed loop x'' = -(4 + 3) x with the input held: close to cos(sqrt(7) t)
    np.testing.assert_allclose(res["y"][:, 0], np.cos(np.sqrt(7.0) * res.t), atol=0.05)


def test_continuation_from_final_states_equals_one_run():
    loop = Loop([place(Oscillator(2.0), "plant"), place(_Gain(), "k")], dt=0.01)
    whole = loop.simulate(100, runs=2)
    first = loop.simulate(50, runs=2, save=Save(states=False))
    assert first.x is None
    second = loop.simulate(50, runs=2, x0=first.final_states, t0=first.t[-1])
    np.testing.assert_array_equal(second["y"], whole["y"][50:])


# ---------------------------------------------------------------------------------------------- signal names
#: scalars the papers name with a digit (the characteristic model's coefficients): not vector indices
_PAPER_SCALARS = {"f1", "f2", "g0"}


def _library_blocks():
    """One instance of every library block (and the signals of the composed MFAC controllers)."""
    from ctrl_analysis.controllers.differential_feedback import (
        HighOrderDifferentialFeedback,
    )
    from ctrl_analysis.controllers.golden_section import GoldenSectionController
    from ctrl_analysis.controllers.mfac import (
        CFDLLaw,
        CFDLPredictor,
        DecreasingGainLaw,
        PPDEstimator,
        UnitDelay,
        mfac_controller,
    )
    from ctrl_analysis.controllers.pd import PDFeedforward
    from ctrl_analysis.estimators.eso import ExtendedStateObserver
    from ctrl_analysis.estimators.kalman import (
        CharacteristicKalmanFilter,
        ImprovedKalmanFilter,
    )
    from ctrl_analysis.estimators.kalman.filter import DiscreteKalmanFilter
    from ctrl_analysis.estimators.lowpass import LowPassFilter
    from ctrl_analysis.estimators.tracking import TrackingDifferentiator
    from ctrl_analysis.identification import ArxRegressor, RecursiveLeastSquaresBlock
    from ctrl_analysis.plants import DiscreteLTI

    td = TrackingDifferentiator(10.0, 0.01, substeps=2, feedthrough=True)
    ppd = PPDEstimator(0.5, 1.0, 1e-5, 2.0)
    blocks = [DifferentialEstimator(3, 5.0), ExtendedStateObserver.from_bandwidth(2, 10.0),
              PDFeedforward(b0=2.0, omega_c=10.0, model=True), td, td.step_block(), AlphaBetaFilter(0.5, 0.2, 0.1),
              DiscreteKalmanFilter(np.array([[1.0, 0.1], [0.0, 1.0]]), [1.0, 0.0], 0.01 * np.eye(2), 1.0),
              CharacteristicKalmanFilter(), ImprovedKalmanFilter(0.05, 0.1), LowPassFilter(10.0, 2),
              LowPassFilter(10.0, 2).digital(0.01, channels=2), RecursiveLeastSquaresBlock(3),
              ArxRegressor(2, 1, lag=1), UnitDelay(), ppd, CFDLLaw(1.0, 2.0), DecreasingGainLaw(1.0, 2.0, 0.3),
              CFDLPredictor(), GoldenSectionController(0.01, 0.95), HighOrderDifferentialFeedback([6.0, 11.0, 6.0]),
              DiscreteLTI(ct.tf([1.0], [1.0, -0.5, 0.1], 0.1), 0.1)]
    placed = mfac_controller(ppd, CFDLLaw(1.0, 2.0), td) + mfac_controller(ppd, CFDLLaw(1.0, 2.0),
                                                                           ImprovedKalmanFilter(0.05, 0.1))
    return blocks, placed


def test_every_library_signal_follows_the_naming_rule():
    """CONTRIBUTING's rule: a vector's components are base[i] (0-based), a matrix's base[i][j]; no index in a name."""
    import re

    pattern = re.compile(r"^(?P<base>[A-Za-z_][A-Za-z0-9_]*)(\[(0|[1-9][0-9]*)\])*$")
    blocks, placed = _library_blocks()
    names = {(type(b).__name__, kind, s) for b in blocks for kind in ("inputs", "outputs", "states")
             for s in getattr(b, kind)}
    names |= {(p.name, kind, s) for p in placed for kind in ("inputs", "outputs") for s in getattr(p, kind)}
    bad = sorted(f"{who}.{kind}: {s!r}" for who, kind, s in names
                 if not (m := pattern.match(s)) or (m["base"][-1].isdigit() and m["base"] not in _PAPER_SCALARS))
    assert not bad, "signal names outside the rule:\n" + "\n".join(bad)
    # and the rule's own examples, so the check is not vacuous
    for wrong in ("xhat1", "td_x2", "h0", "P[0,1]"):
        m = pattern.match(wrong)
        assert not m or m["base"][-1].isdigit()
    assert {"xhat[0]", "x[1]", "td_x[0]", "P[0][1]", "h[0]"} <= {s for *_, s in names}



def _sqrt_block():
    """A static block whose output is NaN for a negative input (y = sqrt(u)): its states stay finite."""
    from ctrl_analysis.engine.blocks import StaticBlock as _Static
    from ctrl_analysis.engine.kernels import KernelBlock, Kernels, Layout

    def out(t, x, u, p, y):
        y[0] = np.sqrt(u[0])

    class Sqrt(KernelBlock, _Static):
        inputs, outputs, states = ("u",), ("y",), ()
        kernels = Kernels(output=out)

        def __init__(self):
            self.kernel_params = Layout().pack()

    return Sqrt()


@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_a_signal_that_is_not_finite_is_a_diverged_run_named_by_its_block(engine):
    # issue 28: a block whose output is NaN while its states stay finite, or a stateless loop producing NaN,
    # was not reported as diverged
    u = np.where(np.arange(11)[:, None] >= np.array([3, 99, 7])[None, :], -1.0, 1.0)  # run 1 never goes negative
    stateless = Loop([place(_sqrt_block(), "root")], dt=0.1)
    res = stateless.simulate(10, inputs={"u": u}, execution=Execution(engine=engine))
    assert res.diverged.tolist() == [True, False, True] and res.diverged_step.tolist() == [3, -1, 7]
    recs = res.divergences()
    assert [r["where"] for r in recs] == ["root.y (output of block 'root')"] * 2 and recs[0]["t"] == pytest.approx(0.3)
    # with a stateful block downstream: the state stays finite until it reads the NaN, the run ends at the output
    from ctrl_analysis.engine.blocks import UnitDelay

    loop = Loop([place(_sqrt_block(), "root"), place(UnitDelay(), "delay", inputs=["y"], outputs=["y_prev"])],
                dt=0.1)
    res = loop.simulate(10, inputs={"u": u}, execution=Execution(engine=engine))
    assert res.diverged.tolist() == [True, False, True] and res.diverged_step.tolist() == [3, -1, 7]
    assert res.divergences()[0]["where"] == "root.y (output of block 'root')"
    assert np.all(np.isnan(res.final_states["delay"][[0, 2]])) and np.isfinite(res.final_states["delay"][1]).all()


def test_the_engines_agree_on_where_and_when_a_run_diverged():
    from ctrl_analysis.engine.blocks import UnitDelay

    u = np.where(np.arange(21)[:, None] >= np.array([4, 50, 13, 2])[None, :], -1.0, 1.0)
    loop = Loop([place(_sqrt_block(), "root"), place(UnitDelay(), "delay", inputs=["y"], outputs=["y_prev"])],
                dt=0.1)
    a, b = (loop.simulate(20, inputs={"u": u}, execution=Execution(engine=e)) for e in ("numpy", "compiled"))
    assert a.divergences() == b.divergences()
    np.testing.assert_array_equal(a["y_prev"], b["y_prev"])
    # a state that leaves the bound names the state
    grow = Loop([place(UnitDelay(), "delay", inputs=["g"], outputs=["d"]),
                 place(StaticGain([[10.0]], inputs=("d",), outputs=("g",)), "gain")], dt=1.0)
    for engine in ("numpy", "compiled"):
        res = grow.simulate(30, x0={"delay": np.ones((2, 1))}, runs=2, execution=Execution(bound=1e6, engine=engine))
        assert res.diverged.all() and res.divergences()[0]["where"] == "delay.u_prev"
