"""Tests of the PD law with feed-forward and model compensation (ctrl_analysis.controllers.pd)."""

import numpy as np
import pytest

from ctrl_analysis.controllers.pd import PDFeedforward, bandwidth_gains
from ctrl_analysis.engine import Execution


def test_bandwidth_gains():
    np.testing.assert_allclose(bandwidth_gains(2, 10.0), [100.0, 20.0, 1.0])
    np.testing.assert_allclose(bandwidth_gains(3, 2.0), [8.0, 12.0, 6.0, 1.0])
    pd = PDFeedforward(b0=3.0, omega_c=10.0)
    np.testing.assert_allclose(np.roots(pd.tracking_poly()), [-10.0, -10.0], atol=1e-6)
    np.testing.assert_allclose(pd.tracking_tf.dcgain(), 1.0)


def test_control_formula_batched():
    pd = PDFeedforward(b0=2.0, omega_c=10.0)
    rng = np.random.default_rng(0)
    ref = rng.normal(size=(6, 3))
    xh = rng.normal(size=(6, 3))
    f = rng.normal(size=6)
    u = pd.control(ref, xh, f)
    expected = (100 * (ref[:, 0] - xh[:, 0]) + 20 * (ref[:, 1] - xh[:, 1]) + (ref[:, 2] - xh[:, 2]) - f) / 2.0
    np.testing.assert_allclose(u, expected, rtol=1e-13)
    assert u.shape == (6,)


def test_perfect_estimates_give_tracking_dynamics():
    """Plant x'' = F + b0 u with exact estimates: tracking error obeys e'' + k2 e' + k1 e = 0."""
    from ctrl_analysis.engine.integrators import rk4_step

    b0, F = 2.0, 0.7
    pd = PDFeedforward(b0=b0, omega_c=5.0)

    def rhs(t, x, u, p):
        return np.stack([x[:, 1], F + b0 * u[:, 0]], axis=1)

    def ctrl(k, t, x, w):
        ref = np.array([np.sin(t), np.cos(t), -np.sin(t)])
        xh = np.concatenate([x, np.full((len(x), 1), F)], axis=1)
        return pd.control(ref, xh)[:, None]

    h, n = 1e-3, 3000
    t, x = h * np.arange(n + 1), [np.array([[0.3, 0.0]])]
    for k in range(n):  # the controller once per sample, its u held over the RK4 step
        x.append(rk4_step(rhs, t[k], x[-1], ctrl(k, t[k], x[-1], None), h))
    e = np.sin(t) - np.stack(x)[:, 0, 0]
    # critically damped at 5 rad/s: e = (e0 + (5 e0 + e0') t) exp(-5 t), e0 = -0.3, e0' = 1
    exact = (-0.3 + (5 * -0.3 + 1.0) * t) * np.exp(-5 * t)
    np.testing.assert_allclose(e, exact, atol=2e-3)  # ZOH of u over 1 ms


def test_block_output_is_the_control_law():
    pd = PDFeedforward(b0=2.0, omega_c=10.0)
    rng = np.random.default_rng(1)
    ref, xh = rng.normal(size=(2, 5, 3))
    u = pd.output(0.0, np.zeros((5, 0)), np.concatenate([ref, xh], axis=1))
    np.testing.assert_allclose(u[:, 0], pd.control(ref, xh), rtol=1e-14)
    assert pd.inputs == ("r[0]", "r[1]", "r[2]", "xhat[0]", "xhat[1]", "xhat[2]") and pd.states == ()


def test_model_term_uses_the_previous_sample_eq12():
    """u(k) = (Σ k_i (ξ^(i-1) − x̂_i)(k) − Θᵀ[x̂1(k-1), x̂2(k-1), u(k-1), 1]) / b0, zero before the first sample."""
    pd = PDFeedforward(b0=3.0, omega_c=10.0, model=True)
    rng = np.random.default_rng(2)
    ref, xh = rng.normal(size=(2, 4, 3))
    theta = np.array([1.3, -1.6, 0.95, 1.8])
    useq = np.concatenate([ref, xh, np.tile(theta, (4, 1))], axis=1)
    y, x = pd.run(useq)
    u = y[:, 0, 0]
    pdk = pd.control(ref, xh)
    assert u[0] == pytest.approx(pdk[0] - theta[3] / 3.0, rel=1e-14)
    for k in range(1, 4):
        f_prev = theta[0] * xh[k - 1, 0] + theta[1] * xh[k - 1, 1] + theta[2] * u[k - 1] + theta[3]
        assert u[k] == pytest.approx(pdk[k] - f_prev / 3.0, rel=1e-12)
    np.testing.assert_allclose(x[1:, 0, :], np.column_stack([xh[:, 0], xh[:, 1], u]))


def test_block_runs_in_control_interconnect():
    import control as ct

    pd = PDFeedforward(b0=3.0, omega_c=10.0, model=True)
    rng = np.random.default_rng(3)
    useq = rng.normal(size=(6, 10))
    y, _ = pd.run(useq)
    resp = ct.input_output_response(pd.nlsys(0.1), 0.1 * np.arange(6), useq.T, X0=np.zeros(3))
    np.testing.assert_allclose(np.ravel(resp.outputs), y[:, 0, 0], rtol=1e-13)


@pytest.mark.parametrize(
    "kwargs,exc,match",
    [
        (dict(b0=0.0, omega_c=1.0), ValueError, "b0"),
        (dict(b0=1.0), ValueError, "exactly one"),
        (dict(b0=1.0, omega_c=1.0, gains=[1, 2]), ValueError, "exactly one"),
        (dict(b0=1.0, omega_c=-1.0), ValueError, "omega_c"),
        (dict(b0=1.0, gains=[1.0, -2.0]), ValueError, "Hurwitz"),
        (dict(b0=1.0, gains=[1.0]), ValueError, "gains"),
        (dict(b0=1.0, omega_c=1.0, model=1), TypeError, "model"),
    ],
)
def test_bad_input(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        PDFeedforward(**kwargs)


@pytest.mark.parametrize("compiled", [False, True])
@pytest.mark.parametrize("model", [False, True])
def test_kernel_is_the_numpy_method_run_by_run(model, compiled):
    """pd_step on one run (plain Python or jitted) equals the block's batched output and update bit for bit."""
    from ctrl_analysis.engine.codegen import _jit

    pd = PDFeedforward(b0=3.0, omega_c=10.0, model=model)
    k = pd.kernel()
    fn = _jit(k.output) if compiled else k.output
    rng = np.random.default_rng(4)
    B = 5
    x = rng.normal(size=(B, len(pd.states)))
    u = rng.normal(size=(B, len(pd.inputs)))
    y, xn = np.empty((B, 1)), np.empty((B, len(pd.states)))
    for b in range(B):
        fn(0.0, x[b], u[b], k.params, y[b])
        fn(0.0, x[b], u[b], k.params, xn[b])
    assert np.array_equal(y, pd.output(0.0, x, u))
    assert np.array_equal(xn, pd.update(0.0, x, u))
    # the law itself: (30) with (12)'s previous-sample model term
    f = (u[:, 6] * x[:, 0] + u[:, 7] * x[:, 1] + u[:, 8] * x[:, 2] + u[:, 9]) if model else 0.0
    np.testing.assert_allclose(y[:, 0], pd.control(u[:, :3], u[:, 3:6], f), rtol=1e-13)
    if model:
        np.testing.assert_array_equal(xn[:, :2], u[:, 3:5])
        np.testing.assert_array_equal(xn[:, 2], y[:, 0])


def test_compiled_loop_with_the_law_equals_the_numpy_loop():
    """A double integrator under the model-compensated law: compiled engine = numpy engine bit for bit."""
    from ctrl_analysis.engine.blocks import StaticGain
    from ctrl_analysis.engine.loop import Loop, place
    from ctrl_analysis.estimators.lowpass import LowPassFilter

    pd = PDFeedforward(b0=2.0, omega_c=5.0, model=True)
    # x̂ = the filtered reference, Θ ∝ ξ: a kernel-only loop that exercises every input of the law
    lpf = LowPassFilter(3.0, order=2).digital(0.01, channels=3)
    theta = StaticGain(np.array([[0.1], [-0.2], [0.05], [0.3]]), inputs=("r[0]",),
                       outputs=("theta[0]", "theta[1]", "theta[2]", "theta[3]"))
    loop = Loop([place(lpf, "obs", inputs=("r[0]", "r[1]", "r[2]"), outputs=("xhat[0]", "xhat[1]", "xhat[2]")),
                 place(theta, "model"), place(pd, "pd")], 0.01)
    t = 0.01 * np.arange(201)
    ins = {"r[0]": np.sin(t), "r[1]": np.cos(t), "r[2]": -np.sin(t)}
    a = loop.simulate(200, inputs=ins, runs=3, execution=Execution(engine="numpy"))
    b = loop.simulate(200, inputs=ins, runs=3, execution=Execution(engine="compiled"))
    assert np.array_equal(a["u"], b["u"]) and np.abs(a["u"]).max() > 0.1
    assert np.array_equal(a.final_states["pd"], b.final_states["pd"])
