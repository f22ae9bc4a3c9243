"""CFDL-MFAC blocks: PPD estimator and reset, control laws, predictor, compositions, batch and python-control."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.controllers.mfac import (
    CFDLLaw,
    CFDLPredictor,
    DecreasingGainLaw,
    PPDEstimator,
    UnitDelay,
    ikf_mfac,
    mfac_controller,
)
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.blocks import DiscreteBlock
from ctrl_analysis.engine.function_block import FunctionBlock
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.kalman import ImprovedKalmanFilter
from ctrl_analysis.estimators.tracking import TrackingDifferentiator
from ctrl_analysis.noise import draw_noise, gaussian_noise, run_seeds


class StaticGainPlant(DiscreteBlock):
    """y(k+1) = b u(k): its pseudo partial derivative is the constant b."""

    inputs, outputs, states = ("u",), ("y",), ("y",)

    def __init__(self, b):
        self.b = b

    def update(self, t, x, u, params=None):
        return self.b * u


class CubicPlant(DiscreteBlock):
    """y(k+1) = y(k)/(1 + y(k)^2) + u(k)^3 (a nonlinear test plant)."""

    inputs, outputs, states = ("u",), ("y",), ("y",)

    def initial_state(self):
        return np.array([1.0])

    def update(self, t, x, u, params=None):
        return x / (1.0 + x * x) + u * u * u


def ppd():
    return PPDEstimator(eta=0.5, mu=1.0, epsilon=1e-5, phi0=2.0, phi_reset=0.5)


def ppd_out(phi_prev, dy, du):
    # state (φ̂(k−1), y(k−1), u(k−2)) = (phi_prev, 0, 0); inputs (y(k), u(k−1)) = (dy, du)
    return ppd().output(0.0, np.array([[phi_prev, 0.0, 0.0]]), np.array([[dy, du]]))[0, 0]


def test_ppd_update_without_reset_is_equation_6():
    # φ̂ = 1 + 0.5 * 1 * (2 − 1 * 1) / (1 + 1) = 1.25
    assert ppd_out(1.0, 2.0, 1.0) == pytest.approx(1.25, rel=1e-15)


@pytest.mark.parametrize("phi_prev, dy, du, why", [
    (1.0, -3.0 + 2e-5, 1.0, "|phi| <= eps"),     # φ̂ = 5e-6 > 0: only the magnitude rule fires
    (1.0, 0.3, 1e-6, "|du| <= eps"),               # φ̂ ≈ 1: only the Δu rule fires
    (1.0, -10.0, 1.0, "sign change"),              # φ̂ = 1 + 0.25 (−11) = −1.75: only the sign rule fires
])
def test_ppd_reset_fires_on_each_condition(phi_prev, dy, du, why):
    est = ppd()
    du_ = du
    raw = phi_prev + est.eta * du_ * (dy - phi_prev * du_) / (est.mu + du_ * du_)
    rules = [abs(raw) <= est.epsilon, abs(du_) <= est.epsilon, np.sign(raw) != np.sign(est.phi0)]
    assert sum(rules) == 1, why  # each case isolates one rule
    assert ppd_out(phi_prev, dy, du) == 0.5


def test_ppd_first_sample_from_rest_is_the_reset_value_by_hand():
    # Lu & Hou's start: φ̂(1) = 2, reset value 0.5, u(k0−1) = u(k0−2) = 0, y_f(k0−1) = 1
    est = PPDEstimator(eta=0.5, mu=1.0, epsilon=1e-5, phi0=2.0, phi_reset=0.5, y0=1.0, u0=0.0)
    np.testing.assert_array_equal(est.initial_state(), [2.0, 1.0, 0.0])  # φ̂(k0−1) = phi0 in the state
    # k0: Δu(k0−1) = 0 − 0 = 0, so (6) gives φ̂ = 2 + 0 = 2 and (7) fires (|Δu| <= ε): φ̂(k0) = 0.5
    # k0+1: Δu = 0.4, Δy_f = 1.7 − 1.3 = 0.4: φ̂ = 0.5 + 0.5·0.4·(0.4 − 0.5·0.4)/(1 + 0.16) (no reset)
    y, x = est.run(np.array([[1.3, 0.0], [1.7, 0.4]]))
    assert y[0, 0, 0] == 0.5
    np.testing.assert_allclose(y[1, 0, 0], 0.5 + 0.5 * 0.4 * (0.4 - 0.2) / 1.16, rtol=1e-15)
    np.testing.assert_array_equal(x[1, 0], [0.5, 1.3, 0.0])  # stored (φ̂(k0), y_f(k0), u(k0−1))
    # had phi0 been used as the first estimate, the second one would be 2 + 0.5·0.4·(0.4 − 0.8)/1.16
    assert abs(y[1, 0, 0] - (2.0 - 0.08 / 1.16)) > 1.0
    # phi_reset defaults to phi0 (eq. (7) as printed resets to φ̂(1)): the first estimate is then 2
    y, _ = PPDEstimator(eta=0.5, mu=1.0, epsilon=1e-5, phi0=2.0, y0=1.0).run(np.array([[1.3, 0.0]]))
    assert y[0, 0, 0] == 2.0


def test_ppd_first_sample_with_an_input_step_starts_from_phi0_by_hand():
    # u(k0−2) = −1, u(k0−1) = 0: Δu = 1, Δy_f = 4 − 1 = 3: φ̂ = 2 + 0.5·1·(3 − 2·1)/(1 + 1) = 2.25, no reset
    est = PPDEstimator(eta=0.5, mu=1.0, epsilon=1e-5, phi0=2.0, phi_reset=0.5, y0=1.0, u0=-1.0)
    y, _ = est.run(np.array([[4.0, 0.0]]))
    assert y[0, 0, 0] == 2.25
    # Δy_f = −3: 2 + 0.25·(−5) = 0.75; Δy_f = −8 flips the sign of (6), 2 + 0.25·(−10) = −0.5, so (7) resets
    y, _ = est.run(np.array([[[-2.0, 0.0], [-7.0, 0.0]]]))
    np.testing.assert_array_equal(y[0, :, 0], [0.75, 0.5])


def test_ppd_first_sample_in_a_closed_loop_and_in_the_kernel_is_the_reset_value():
    from ctrl_analysis.controllers.mfac import ppd_output

    loop = Loop([place(StaticGainPlant(0.8), "plant")]
                + mfac_controller(ppd(), CFDLLaw(rho=1.0, lam=2.0), measured="y"), dt=1.0)
    res = loop.simulate(3, inputs={"y_ref_next": 1.0})
    assert res["phi_hat"][0, 0] == 0.5  # u(−1) = u(−2) = 0: the reset fires at the first sample
    # so the first control is (8) with φ̂ = 0.5: u = 0 + 1·0.5·(1 − 0)/(2 + 0.25)
    np.testing.assert_allclose(res["u"][0, 0], 0.5 / 2.25, rtol=1e-15)
    # the compiled engine's kernel does the same at the first sample
    est, y = ppd(), np.zeros(1)
    ppd_output(0.0, est.initial_state(), np.array([1.3, 0.0]), est.kernel().params, y)
    assert y[0] == 0.5


def test_mfac_converges_on_a_constant_ppd_plant():
    b = 0.8
    loop = Loop([place(StaticGainPlant(b), "plant")]
                        + mfac_controller(ppd(), CFDLLaw(rho=1.0, lam=2.0), measured="y"), dt=1.0)
    res = loop.simulate(300, inputs={"y_ref_next": 1.0})
    y = res["y"][:, 0]
    assert abs(y[-1] - 1.0) < 1e-9
    np.testing.assert_allclose(res["u"][-1, 0], 1.0 / b, rtol=1e-9)
    # the error decreases monotonically once the estimator has settled (no overshoot on this plant)
    assert np.max(np.abs(1.0 - y[50:])) < np.max(np.abs(1.0 - y[:50]))


@pytest.mark.parametrize("rearm, divisors", [(True, [1, 1, 2, 1, 1, 2]), (False, [1, 1, 2, 1, 4, 5])])
def test_decreasing_gain_divisors_and_rearming(rearm, divisors):
    e = np.array([1.0, 0.1, 0.1, 1.0, 0.1, 0.1])
    law = DecreasingGainLaw(rho=1.0, lam=1.0, e_m=0.5, rearm=rearm)
    # inputs (phi_hat, y, y_ref_next, u_prev) = (1, 0, e, 0): Δu0 = e / 2
    y, _ = law.run(np.column_stack([np.ones(6), np.zeros(6), e, np.zeros(6)]))
    np.testing.assert_allclose(y[:, 0, 0], e / 2 / np.array(divisors), rtol=1e-15)


def test_cfdl_law_and_predictor_values():
    law = CFDLLaw(rho=0.5, lam=2.0)
    # u = 0.3 + 0.5 * 1.5 * (2 − 1) / (2 + 2.25)
    u = law.output(0.0, np.zeros((1, 0)), np.array([[1.5, 1.0, 2.0, 0.3]]))
    np.testing.assert_allclose(u, [[0.3 + 0.75 / 4.25]], rtol=1e-15)
    pred = CFDLPredictor(phi0=2.0, u0=1.0, u00=0.25)
    assert pred.output(0.0, pred.initial_state()[None], np.zeros((1, 2)))[0, 0] == pytest.approx(1.5)
    x1 = pred.update(0.0, pred.initial_state()[None], np.array([[3.0, 2.0]]))
    np.testing.assert_array_equal(x1, [[3.0, 2.0, 1.0]])


def test_unit_delay_lives_in_engine_blocks_and_keeps_its_old_imports():
    import ctrl_analysis
    from ctrl_analysis.controllers import UnitDelay as from_controllers
    from ctrl_analysis.engine import blocks

    assert UnitDelay is blocks.UnitDelay is from_controllers is ctrl_analysis.UnitDelay
    y, _ = blocks.UnitDelay(u0=0.5).run(np.array([1.0, 2.0]))
    np.testing.assert_array_equal(y[:, 0, 0], [0.5, 1.0])


def closed_loop(scheme):
    est = ppd()
    law = DecreasingGainLaw(1.0, 2.0, 0.3) if scheme == "d" else CFDLLaw(1.0, 2.0)
    filt = {"td": TrackingDifferentiator(300.0, 0.01, 0.02, substeps=3, x0=(1.0, 0.0), feedthrough=True),
            "td_lag": TrackingDifferentiator(300.0, 0.01, 0.02, substeps=3, x0=(1.0, 0.0)),
            "ikf": ImprovedKalmanFilter(0.05, 0.1, y0=1.0, P0=0.0)}.get(scheme)
    meas = FunctionBlock(lambda t, u: u[:, :1] + u[:, 1:2], inputs=("y", "v"), outputs=("y_m",))
    blocks = [place(CubicPlant(), "plant"), place(meas, "meas")]
    blocks += ikf_mfac(est, law, filt) if scheme == "ikf" else mfac_controller(est, law, filt)
    return Loop(blocks, dt=1.0)


@pytest.mark.parametrize("scheme", ["plain", "d", "td", "td_lag", "ikf"])
def test_blocks_in_control_interconnect_equal_the_engine(scheme):
    loop = closed_loop(scheme)
    n = 120
    v = 0.05 * np.random.default_rng(1).standard_normal(n + 1)
    ref = np.sign(np.sin(0.05 * np.arange(n + 1)))
    res = loop.simulate(n, inputs={"v": v, "y_ref_next": ref})
    assert not res.diverged.any()
    sys = loop.interconnect()
    assert sys.isdtime() and sys.dt == 1.0
    U = np.stack([{"v": v, "y_ref_next": ref}[s][:n] for s in loop.external])
    resp = ct.input_output_response(sys, res.t[:n], U, X0=res.x[0, 0])
    np.testing.assert_allclose(res.to_timeresponse(0).outputs[:, :n], resp.outputs, rtol=1e-12, atol=1e-12)


def test_batch_equals_single_runs_and_parameter_grid_on_the_batch():
    seeds = run_seeds(5, 3)
    v = draw_noise(seeds, 200, gaussian_noise(0.1))[:, :, 0]
    loop = closed_loop("ikf")
    batch = loop.simulate(199, inputs={"v": v, "y_ref_next": 1.0})
    for b in range(3):
        one = loop.simulate(199, inputs={"v": v[:, b:b + 1], "y_ref_next": 1.0})
        np.testing.assert_array_equal(batch.x[:, b:b + 1], one.x)
    # a grid of rho on the batch axis (run-time parameters) equals the runs with scalar rho
    rhos = np.array([0.3, 0.6, 1.0])
    grid = Loop([place(CubicPlant(), "plant")] + mfac_controller(ppd(), CFDLLaw(1.0, 2.0), measured="y"),
                dt=1.0).simulate(100, inputs={"y_ref_next": 0.5}, params={"law": {"rho": rhos}})
    for b, r in enumerate(rhos):
        one = Loop([place(CubicPlant(), "plant")] + mfac_controller(ppd(), CFDLLaw(r, 2.0), measured="y"),
                           dt=1.0).simulate(100, inputs={"y_ref_next": 0.5})
        np.testing.assert_array_equal(grid.x[:, b:b + 1], one.x)


def test_errors_name_the_argument():
    with pytest.raises(ValueError, match=r"rho must be in \(0, 1\], got 1.5"):
        CFDLLaw(1.5, 1.0)
    with pytest.raises(ValueError, match="lam must be > 0"):
        CFDLLaw(1.0, -1.0)
    with pytest.raises(TypeError, match="rho must be a real number"):
        CFDLLaw(np.array([0.5, 0.6]), 1.0)  # per-run values go to simulate(params=...)
    with pytest.raises(ValueError, match=r"eta must be in \(0, 1\]"):
        PPDEstimator(0.0, 1.0, 1e-5, 2.0)
    with pytest.raises(ValueError, match="phi0 must be non-zero"):
        PPDEstimator(0.5, 1.0, 1e-5, 0.0)
    with pytest.raises(ValueError, match="phi_reset must have the sign of phi0"):
        PPDEstimator(0.5, 1.0, 1e-5, 2.0, phi_reset=-0.5)
    with pytest.raises(ValueError, match="e_m must be > 0"):
        DecreasingGainLaw(1.0, 1.0, 0.0)
    with pytest.raises(TypeError, match="rearm must be a bool"):
        DecreasingGainLaw(1.0, 1.0, 0.1, rearm="yes")
    with pytest.raises(TypeError, match="law must be"):
        mfac_controller(ppd(), UnitDelay())
    with pytest.raises(TypeError, match="output_filter must be"):
        mfac_controller(ppd(), CFDLLaw(1.0, 1.0), UnitDelay())
    with pytest.raises(TypeError, match="ikf must be"):
        ikf_mfac(ppd(), CFDLLaw(1.0, 1.0), None)


# ------------------------------------------------------------------ kernels
# (the derived batched methods equal the compiled kernels bit for bit: tests/lib/test_kernel_blocks.py)
def test_ppd_reset_rule_fires_and_keeps_on_edge_inputs():
    """Both branches of (7): tiny Δu, sign flips, a zero and a NaN; per-run η rows equal single blocks."""
    rng = np.random.default_rng(3)
    B = 64
    x = rng.standard_normal((B, 3))
    u = rng.standard_normal((B, 2))
    u[::7, 1] = x[::7, 2] + 1e-7         # |Δu| <= ε
    x[::5, 0] = -x[::5, 0]               # φ̂(k−1) of the other sign
    x[3, 0], u[3, 1], x[3, 2] = 0.0, 1.0, 0.0
    u[4, 0] = np.nan
    est = PPDEstimator(eta=0.7, mu=1.0, epsilon=1e-5, phi0=2.0, phi_reset=0.5)
    fired = est.output(0.0, x, u)[:, 0] == 0.5
    assert 5 < fired.sum() < B - 5
    etas = rng.uniform(0.2, 1.0, B)
    rows = np.stack([est.with_params(eta=e).kernel_params for e in etas])
    one = np.concatenate([est.with_params(eta=e).update(0.0, x[b:b + 1], u[b:b + 1]) for b, e in enumerate(etas)])
    assert np.array_equal(est.batched("update", 0.0, x, u, rows), one, equal_nan=True)


def cubic_update(t, x, u, p, x_next):
    """y(k+1) = y(k)/(1 + y(k)^2) + u(k)^3, one run or the batch's columns."""
    x_next[0] = x[0] / (1.0 + x[0] * x[0]) + u[0] * u[0] * u[0]


class KCubicPlant(CubicPlant):
    """CubicPlant with a compiled kernel (its numpy update is the kernel on columns)."""

    def update(self, t, x, u, params=None):
        x_next = np.empty_like(x)
        cubic_update(t, x.T, u.T, None, x_next.T)
        return x_next

    def kernel(self):
        from ctrl_analysis.engine.kernels import Kernels, copy_output

        return Kernels(output=copy_output, params=np.zeros(0), update=cubic_update)


def test_every_mfac_block_in_one_loop_compiled_equals_numpy_engine_bit_for_bit():
    """One loop structure (one compile) holds every kernel: IKF-D-MFAC, a TD and a CFDL law beside it."""
    from ctrl_analysis.engine.blocks import StaticGain

    B, n = 6, 300
    rng = np.random.default_rng(5)
    est = PPDEstimator(eta=0.5, mu=1.0, epsilon=1e-5, phi0=2.0, phi_reset=0.5, y0=1.0)
    law = DecreasingGainLaw(0.5, 2.0, e_m=0.2, rearm=False)
    Qs = rng.uniform(0.01, 0.1, B)
    ikf = ImprovedKalmanFilter(Qs[0], 0.05, y0=1.0, P0=0.0)
    blocks = [place(KCubicPlant(), "plant"),
              place(StaticGain([[1.0, 1.0]], inputs=("y", "v"), outputs=("y_m",)), "meas")]
    blocks += ikf_mfac(est, law, ikf)
    blocks += [place(TrackingDifferentiator(300.0, 0.01, 0.02, substeps=3, x0=(1.0, 0.0), feedthrough=True), "td",
                     inputs=["y_m"], outputs=["td_x[0]", "td_x[1]"]),
               place(CFDLLaw(0.6, 2.0), "law2", inputs=["phi_hat", "td_x[0]", "y_ref_next", "u_prev"],
                     outputs=["u_td"])]
    loop = Loop(blocks, dt=1.0)
    v = 0.1 * rng.standard_normal((n, B))
    ref = np.where(np.arange(n + 1) < n // 2, 1.0, -1.0)
    params = {"law": {"rho": rng.uniform(0.3, 1.0, B)}, "law2": {"lam": rng.uniform(1.0, 3.0, B)},
              "filter": {"Q": Qs}}
    runs = {e: loop.simulate(n, inputs={"v": v, "y_ref_next": ref}, params=params,
                             execution=Execution(engine=e, bound=1e4))
            for e in ("numpy", "compiled")}
    a, c = runs["numpy"], runs["compiled"]
    assert not a.diverged.any() and np.array_equal(a.diverged, c.diverged)
    assert np.array_equal(a.x, c.x)
    for s in ("y", "u", "phi_hat", "y_f", "K", "P", "td_x[0]", "td_x[1]", "u_td", "dy_model"):
        assert np.array_equal(a[s], c[s]), s
    assert np.std(a["u"][-1]) > 0  # the per-run parameters act
