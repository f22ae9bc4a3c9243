"""Han's fhan, the tracking differentiator and the setpoint prefilter."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.estimators.lowpass import LowPassFilter
from ctrl_analysis.estimators.tracking import (
    TrackingDifferentiator,
    fhan,
    softened_setpoint,
)


@pytest.mark.parametrize(
    "x1, x2, r, h0, expected",
    [
        # origin
        (0.0, 0.0, 1.0, 0.1, 0.0),
        # far from the origin: full braking, -r sign(a)
        (1.0, 0.0, 1.0, 0.1, -1.0),
        (-0.3, 0.05, 5.0, 0.02, 5.0),
        # linear layer |y| <= d: fhan = -(x1 + 2 h0 x2) / h0^2 = -(0.002 + 0.002) / 0.01
        (0.002, 0.01, 1.0, 0.1, -0.4),
        (0.001, 0.0, 1.0, 0.1, -0.1),
        # parabolic zone with |a| < d, worked by hand: d = 0.005, a0 = -0.021, y = 0.079,
        # a1 = sqrt(0.005 * 0.637) = 0.0564358, a2 = -0.021 + (a1 - d)/2 = 0.00471790,
        # sy = 0, a = a2, sa = 1, fhan = -2 (a/d - 1) - 2 = -1.8871608
        (0.1, -0.42, 2.0, 0.05, -1.8871608476179700),
    ],
)
def test_fhan_hand_values(x1, x2, r, h0, expected):
    np.testing.assert_allclose(fhan(x1, x2, r, h0), expected, rtol=1e-12, atol=1e-12)


def test_fhan_odd_bounded_and_vectorised():
    rng = np.random.default_rng(3)
    x1 = rng.normal(scale=0.5, size=500)
    x2 = rng.normal(scale=2.0, size=500)
    f = fhan(x1, x2, 3.0, 0.05)
    assert f.shape == (500,)
    np.testing.assert_allclose(fhan(-x1, -x2, 3.0, 0.05), -f, rtol=0, atol=1e-12)
    assert np.all(np.abs(f) <= 3.0 + 1e-12)
    # element-wise equals the scalar calls
    np.testing.assert_allclose(f[:5], [fhan(a, b, 3.0, 0.05) for a, b in zip(x1[:5], x2[:5], strict=True)], rtol=1e-14)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan])
def test_fhan_rejects_bad_r(bad):
    with pytest.raises(ValueError, match="r must be"):
        fhan(0.1, 0.0, bad, 0.1)


def test_td_tracks_a_constant_single_and_batched():
    td = TrackingDifferentiator(r=50.0, h=0.01)
    _, x = td.run(np.ones(300))
    assert abs(x[-1, 0, 0] - 1.0) < 1e-9 and abs(x[-1, 0, 1]) < 1e-9
    v = np.array([1.0, -2.0, 0.5])
    _, xb = td.run(np.broadcast_to(v[None, :, None], (400, 3, 1)))
    np.testing.assert_allclose(xb[-1, :, 0], v, atol=1e-9)
    np.testing.assert_allclose(xb[-1, :, 1], 0.0, atol=1e-9)
    # a batch equals its runs alone, bit for bit
    for b in range(3):
        _, x1 = td.run(np.full(400, v[b]))
        np.testing.assert_array_equal(x1[:, 0], xb[:, b])


def test_td_tracks_a_slow_sine_and_its_derivative():
    h = 1e-3
    td = TrackingDifferentiator(r=100.0, h=h)
    t = h * np.arange(4000)
    _, x = td.run(np.sin(t))
    out = x[1:, 0]
    late = t > 2.0
    # after the step driven by v(t_k) the state belongs to t_(k+1); the TD's tracking error is
    # below 1 % of the amplitude for r = 100 (measured: 6.5e-3 and 5.8e-3)
    np.testing.assert_allclose(out[late, 0], np.sin(t[late] + h), atol=1e-2)
    np.testing.assert_allclose(out[late, 1], np.cos(t[late] + h), atol=1e-2)


def test_fhan_reaches_a_step_in_minimum_time():
    """Bang-bang with |fhan| <= r: the double integrator needs 2 sqrt(L/r) to move L from rest to rest.

    The continuous minimum time is 2 sqrt(L/r) = 0.2 for L = 1, r = 100; the discrete TD with
    h = 1e-4 (h0 = h) must arrive within a few steps of it, and never before it (no admissible
    control is faster), without overshoot.
    """
    r, h, L = 100.0, 1e-4, 1.0
    t_min = 2.0 * np.sqrt(L / r)
    td = TrackingDifferentiator(r=r, h=h)
    _, x = td.run(np.full(4000, L))
    x1 = x[:, 0, 0]
    arrived = np.flatnonzero(np.abs(x1 - L) < 1e-6)[0] * h
    # (the explicit-Euler double integrator may land one step early; measured 0.1999 s)
    assert t_min - 2 * h <= arrived <= t_min + 10 * h
    assert x1.max() <= L + 1e-9
    # the acceleration is ±r away from the switching curve (full effort: time-optimal)
    fh = td.acceleration(x[:-1, 0, :], np.full((4000, 1), L))
    np.testing.assert_allclose(fh[: int(0.09 / h)], r, rtol=1e-12)
    np.testing.assert_allclose(fh[int(0.11 / h): int(0.19 / h)], -r, rtol=1e-12)


def test_td_substeps_and_errors():
    # 4 sub-steps of h per sample = the same TD with one step per sample, sampled every 4th step
    td4 = TrackingDifferentiator(r=20.0, h=0.01, substeps=4)
    td1 = TrackingDifferentiator(r=20.0, h=0.01)
    _, x4 = td4.run(np.ones(50))
    _, x1 = td1.run(np.ones(200))
    np.testing.assert_allclose(x4[:, 0], x1[::4, 0], rtol=0, atol=1e-14)
    assert td4.dt == pytest.approx(0.04)
    with pytest.raises(ValueError, match="h must be > 0"):
        TrackingDifferentiator(r=1.0, h=0.0)
    with pytest.raises(ValueError, match="substeps must be >= 1"):
        TrackingDifferentiator(r=1.0, h=0.1, substeps=0)


def test_td_block_in_control_interconnect_equals_engine():
    td = TrackingDifferentiator(r=30.0, h=0.01, h0=0.02, substeps=3, x0=[0.2, 0.0])
    v = np.sign(np.sin(0.05 * np.arange(200)))
    y, _ = td.run(v)
    resp = ct.input_output_response(td.nlsys(dt=1), np.arange(200), v, X0=td.initial_state())
    np.testing.assert_allclose(resp.outputs.T, y[:, 0], rtol=0, atol=1e-13)


def test_softened_setpoint_with_the_td_and_errors():
    h = 1e-3
    r = np.ones(3000)
    theta = softened_setpoint(TrackingDifferentiator(10.0, h), r, h)
    assert theta.shape == (3000, 3)
    # θ3 is the acceleration applied over each step: x2(k+1) = x2(k) + h θ3(k)
    np.testing.assert_allclose(np.diff(theta[:, 1]), h * theta[:-1, 2], atol=1e-12)
    assert abs(theta[-1, 0] - 1.0) < 1e-6
    with pytest.raises(ValueError, match="softener.dt"):
        softened_setpoint(TrackingDifferentiator(10.0, 2 * h), r, h)
    with pytest.raises(TypeError, match="softener must be"):
        softened_setpoint(object(), r, h)
    with pytest.raises(ValueError, match="r must be"):
        softened_setpoint(LowPassFilter(1.0, 2), np.ones((3, 2)), h)


@pytest.mark.parametrize("compiled", [False, True])
def test_td_kernel_is_the_numpy_method_and_fhan_compiles_to_the_same_bits(compiled):
    from ctrl_analysis.engine import codegen as _kernels
    from ctrl_analysis.estimators.tracking import _fhan, td_output, td_update

    jit = _kernels._jit if compiled else (lambda f: f)
    rng = np.random.default_rng(11)
    x, u = rng.standard_normal((40, 2)) * [1.0, 30.0], rng.standard_normal((40, 1))
    x[:4, 0] = u[:4, 0]      # on the target: fhan's linear layer and a = 0
    for ft in (False, True):
        td = TrackingDifferentiator(300.0, 0.01, 0.02, substeps=4, feedthrough=ft)
        k = td.kernel()
        for fn, ref in ((jit(td_update), td.update(0.0, x, u)), (jit(td_output), td.output(0.0, x, u))):
            out = np.empty_like(x)
            for b in range(x.shape[0]):
                fn(0.0, x[b], u[b], k.params, out[b])
            assert np.array_equal(out, ref)
    # fhan on floats (compiled: numba's sqrt/sign) = fhan on arrays (numpy), NaN and zeros included
    x1 = np.concatenate([rng.standard_normal(50), [0.0, -0.0, np.nan, 1e-6]])
    x2 = np.concatenate([rng.standard_normal(50) * 10, [0.0, 0.0, 1.0, 0.0]])
    if compiled:
        import numba

        scalar = numba.njit(lambda a, b: _fhan(a, b, 300.0, 0.02))
    else:
        scalar = lambda a, b: _fhan(a, b, 300.0, 0.02)  # noqa: E731
    assert np.array_equal([scalar(a, b) for a, b in zip(x1, x2, strict=True)], _fhan(x1, x2, 300.0, 0.02),
                          equal_nan=True)


@pytest.mark.parametrize("compiled", [False, True])
def test_step_block_is_the_feedthrough_output_run_once(compiled):
    from ctrl_analysis.engine import codegen as _kernels
    from ctrl_analysis.estimators.tracking import td_step_output

    fn = _kernels._jit(td_step_output) if compiled else td_step_output
    rng = np.random.default_rng(12)
    x, v = rng.standard_normal((30, 2)) * [1.0, 20.0], rng.standard_normal((30, 1))
    td = TrackingDifferentiator(500.0, 0.005, 0.01, substeps=5, feedthrough=True)
    step = td.step_block()
    u = np.column_stack([v, x])
    assert np.array_equal(step.output(0.0, x[:, :0], u), td.output(0.0, x, v))
    out = np.empty_like(x)
    for b in range(30):
        fn(0.0, x[b, :0], u[b], step.kernel().params, out[b])
    assert np.array_equal(out, td.update(0.0, x, v))
