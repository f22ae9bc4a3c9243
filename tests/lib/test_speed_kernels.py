"""Compiled kernels (ctrl_analysis.engine.codegen) against the blocks' numpy methods, and the compiled Loop engine."""

import numpy as np
import pytest

from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine import codegen as _kernels
from ctrl_analysis.engine.blocks import ContinuousBlock, DiscreteBlock
from ctrl_analysis.engine.codegen import kernel_of
from ctrl_analysis.engine.compiled import compiled_for
from ctrl_analysis.engine.kernels import Kernels, copy_output
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.differential import DifferentialEstimator, sigma_rhs
from ctrl_analysis.estimators.eso import ExtendedStateObserver, eso_rhs
from ctrl_analysis.noise import draw_noise, gaussian_noise, run_seeds


def osc_rhs(t, x, u, p, dx):
    """x'' + c x' + k x = w on one run or on batch columns; p = [k, c]."""
    dx[0] = x[1]
    dx[1] = -p[0] * x[0] - p[1] * x[1] + u[0]


def osc_output(t, x, u, p, y):
    y[0] = x[0] + u[1]


class KOsc(ContinuousBlock):
    """A noisy oscillator whose numpy methods are its kernel applied to the batch's columns."""

    inputs, outputs, states = ("w", "v"), ("y",), ("p", "q")
    feedthrough = True

    def __init__(self, k=4.0, c=0.4):
        self.p = np.array([k, c])

    def initial_state(self):
        return np.array([1.0, 0.0])

    def rhs(self, t, x, u, params=None):
        dx = np.empty_like(x)
        osc_rhs(t, x.T, u.T, self.p, dx.T)
        return dx

    def output(self, t, x, u, params=None):
        y = np.empty((x.shape[0], 1))
        osc_output(t, x.T, u.T, self.p, y.T)
        return y

    def kernel(self):
        return Kernels(output=osc_output, params=self.p, rhs=osc_rhs)


def acc_update(t, x, u, p, xn):
    xn[0] = x[0] + p[0] * u[0]


class KAcc(DiscreteBlock):
    """Discrete accumulator s(k+1) = s(k) + T y(k)."""

    inputs, outputs, states = ("y",), ("s",), ("s",)

    def __init__(self, T):
        self.p = np.array([T])

    def update(self, t, x, u, params=None):
        xn = np.empty_like(x)
        acc_update(t, x.T, u.T, self.p, xn.T)
        return xn

    def kernel(self):
        return Kernels(output=copy_output, params=self.p, update=acc_update)


def han_eso(h=1e-3):
    return ExtendedStateObserver((1 / h, 1 / (1.6 * h**1.5), 1 / (8.6 * h**2.2)), b0=0.5,
                                 alpha=[1.0, 0.5, 0.25], delta=h)


def per_run(fn, k, x, u):
    """Apply a kernel run by run (plain Python, or compiled) -> (B, n)."""
    out = np.empty_like(x)
    for b in range(x.shape[0]):
        fn(0.3, x[b], u[b], k.params, out[b])
    return out


@pytest.mark.parametrize("compiled", [False, True])
def test_sigma_kernel_equals_the_block_rhs_bit_for_bit(compiled):
    est = DifferentialEstimator(5, 7.0)
    k = kernel_of(est)
    rng = np.random.default_rng(0)
    z, u = rng.standard_normal((6, 5)), rng.standard_normal((6, 1))
    fn = _kernels._jit(sigma_rhs) if compiled else sigma_rhs
    assert np.array_equal(per_run(fn, k, z, u), est.rhs(0.3, z, u))
    corr = DifferentialEstimator(5, 7.0, reading="corrected")  # eq. (11) as a kernel: equal to the matrix form
    np.testing.assert_allclose(corr.output(0.3, z, u), corr.estimates(z, u, "corrected"), rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("compiled", [False, True])
def test_eso_kernel_equals_the_block_rhs(compiled):
    rng = np.random.default_rng(1)
    fn = _kernels._jit(eso_rhs) if compiled else eso_rhs
    for eso in (han_eso(), ExtendedStateObserver.from_bandwidth(2, 20.0, b0=2.0)):
        k = kernel_of(eso)
        x = rng.standard_normal((40, 3)) * 1e-3  # both sides of fal's linear zone |e| <= δ = 1e-3
        u = rng.standard_normal((40, 2)) * 1e-3
        got, want = per_run(fn, k, x, u), eso.rhs(0.3, x, u)
        if eso.alpha is None:
            assert np.array_equal(got, want)
        else:  # |e|^α: libm's pow and numpy's vectorised power may differ in the last bit
            np.testing.assert_allclose(got, want, rtol=4e-16, atol=0)
    assert kernel_of(ExtendedStateObserver([3.0, 2.0], known=lambda t, x, u, p: 0.0)) is None


def sigma_loop(plant=None):
    """Plant, Σ and an accumulator: one loop structure (one compile) shared by several tests."""
    return Loop([place(KOsc() if plant is None else plant, "plant"), place(DifferentialEstimator(3, 4.0), "sigma"),
                 place(KAcc(0.01), "acc", inputs=["xhat[0]"])], dt=0.01)


def test_compiled_loop_equals_numpy_loop_bit_for_bit_without_pow():
    seeds = run_seeds(4, 5)
    noise = draw_noise(seeds, 300, gaussian_noise([0.3, 0.01]))
    inputs = {"w": noise[:, :, 0], "v": noise[:, :, 1]}
    loop = sigma_loop()
    a = loop.simulate(300, inputs=inputs, execution=Execution(engine="numpy"))
    b = loop.simulate(300, inputs=inputs, execution=Execution(engine="compiled"))
    assert np.array_equal(a.x, b.x)
    for s in a.signals:
        assert np.array_equal(a[s], b[s]), s
    one = loop.simulate(300, inputs={"w": noise[:, 3:4, 0], "v": noise[:, 3:4, 1]},
                        execution=Execution(engine="compiled"))
    assert np.array_equal(one.x[:, 0], b.x[:, 3])
    assert _kernels.compile_seconds() >= 0.0
    # without stored states the final state still comes back (chunk carry-over), on both paths
    fa = loop.simulate(300, inputs=inputs, save=Save(states=False), execution=Execution(engine="numpy")).final_states
    fb = loop.simulate(300, inputs=inputs, save=Save(states=False), execution=Execution(engine="compiled")).final_states
    for name, sl in loop.slices.items():
        assert np.array_equal(fa[name], a.x[-1][:, sl]) and np.array_equal(fb[name], a.x[-1][:, sl]), name


def test_compiled_loop_with_han_eso_agrees_and_is_batch_independent():
    seeds = run_seeds(0, 6)
    noise = draw_noise(seeds, 400, gaussian_noise([0.3, 0.001]))
    loop = Loop([place(KOsc(), "plant"), place(han_eso(), "eso", inputs=["y", "uc"])], dt=1e-3)
    inputs = {"w": noise[:, :, 0], "v": noise[:, :, 1], "uc": 0.2}
    a = loop.simulate(400, inputs=inputs, execution=Execution(engine="numpy"))
    b = loop.simulate(400, inputs=inputs)  # auto: every block has a kernel
    np.testing.assert_allclose(b.x, a.x, rtol=0, atol=1e-9)
    c = loop.simulate(400, inputs=inputs, execution=Execution(chunk_runs=4))
    assert np.array_equal(b.x, c.x) and np.array_equal(b["y"], c["y"])
    one = loop.simulate(400, inputs={"w": noise[:, 5:, 0], "v": noise[:, 5:, 1], "uc": 0.2})
    assert np.array_equal(one.x[:, 0], b.x[:, 5])


def test_compiled_loop_flags_divergence_like_the_numpy_loop():
    loop = sigma_loop(KOsc(k=-400.0, c=0.0))  # unstable plant; Σ follows it
    w = np.zeros((200, 2))
    w[:, 1] = 1e-300  # run 1 starts the same; the bound decides
    x0 = {"plant": np.array([[1e-6, 0.0], [1.0, 0.0]])}
    a = loop.simulate(200, inputs={"w": 0.0, "v": w}, x0=x0, execution=Execution(bound=1e3, engine="numpy"))
    b = loop.simulate(200, inputs={"w": 0.0, "v": w}, x0=x0, execution=Execution(bound=1e3, engine="compiled"))
    assert a.diverged.all() and np.array_equal(a.diverged_step, b.diverged_step)
    assert a.diverged_step[1] < a.diverged_step[0]
    assert np.array_equal(np.isnan(a.x), np.isnan(b.x))


def test_compiled_engine_says_why_it_cannot_run():
    loop = Loop([place(DifferentialEstimator(3, 4.0), "sigma")], dt=0.01)
    with pytest.raises(ValueError, match="callable inputs"):
        loop.simulate(5, inputs={"y": lambda t: 1.0}, execution=Execution(engine="compiled"))
    meso = ExtendedStateObserver([3.0, 2.0], known=_no_model)  # a Python model term: no kernel
    osc = Loop([place(KOsc(), "plant"), place(meso, "s")], dt=0.1)
    with pytest.raises(ValueError, match="block 's' .* has no kernel"):
        osc.simulate(5, inputs={"w": 0.0, "v": 0.0, "u": 0.0}, execution=Execution(engine="compiled"))
    with pytest.raises(ValueError, match="engine"):
        osc.simulate(5, inputs={"w": 0.0, "v": 0.0, "u": 0.0}, execution=Execution(engine="fast"))


def _no_model(t, x, u, params=None):
    return 0.0 * x[..., 0]


def _plain_python(v):
    return v


def bad_rhs(t, x, u, p, dx):
    dx[0] = _plain_python(-x[0]) + u[0]  # calls a plain Python function: numba cannot type this kernel


class BadKernel(ContinuousBlock):
    inputs, outputs, states = ("f",), ("y",), ("y",)

    def rhs(self, t, x, u, params=None):
        return -x + u

    def kernel(self):
        return Kernels(output=copy_output, params=np.zeros(1), rhs=bad_rhs)


def test_auto_engine_falls_back_to_numpy_with_a_warning_when_a_kernel_does_not_compile():
    loop = Loop([place(BadKernel(), "b")], dt=0.1)
    with pytest.warns(RuntimeWarning, match="compiled engine unavailable"):
        res = loop.simulate(10, inputs={"f": 1.0})
    np.testing.assert_allclose(res["y"][-1, 0], 1 - np.exp(-1.0), rtol=1e-6)
    with pytest.raises(Exception, match="(?i)typing|type"):
        loop.simulate(10, inputs={"f": 1.0}, execution=Execution(engine="compiled"))


def test_environment_can_make_auto_mean_numpy(monkeypatch):
    loop = sigma_loop()
    monkeypatch.setenv("CTRL_ANALYSIS_ENGINE", "numpy")
    assert compiled_for(loop.plan, "auto", {}, None) is None
    assert compiled_for(loop.plan, "compiled", {}, None) is not None  # an explicit request still compiles


def test_study_kernels_are_the_numpy_methods():
    """Kernels of study blocks (differential-estimator's plant (19), its sensor, a StaticGain), run in plain Python."""
    from analysis.differential_estimator.loops import Plant19, sensor
    from analysis.differential_estimator.paper import EX1

    rng = np.random.default_rng(3)
    plant, sens = Plant19(EX1), sensor()
    x, u = rng.normal(size=(7, 2)), rng.normal(size=(7, 1))
    for t in (0.0, 2.0, 7.0):
        k = plant.kernel()
        out = np.empty_like(x)
        for b in range(7):
            k.rhs(t, x[b], u[b], k.params, out[b])
        assert np.array_equal(out, plant.rhs(t, x, u))
    u2 = rng.normal(size=(7, 2))
    k = sens.kernel()
    y = np.empty((7, 1))
    for b in range(7):
        k.output(0.0, None, u2[b], k.params, y[b])
    assert np.array_equal(y, sens.output(0.0, np.zeros((7, 0)), u2))
    assert np.array_equal(y[:, 0], u2[:, 0] + u2[:, 1])


def test_per_run_params_follow_their_runs_through_chunks_and_processes():
    """Per-run values given to simulate(params=...): a kernel block (rows) and a static gain (a gain per
    run) equal their runs alone on both engines, through chunks and processes."""
    from ctrl_analysis.engine.blocks import StaticGain

    k = np.array([1.0, 4.0, 9.0, 16.0, 25.0])
    D = np.zeros((5, 1, 2))
    D[:, 0, 0] = 1.0
    D[::2, 0, 1] = 1.0  # runs 0, 2, 4 see the noise, runs 1, 3 do not: a per-run switch
    loop = Loop([place(KOsc(), "plant"), place(StaticGain([[1.0, 0.0]], ("y", "v"), ("ym",)), "sw"),
                 place(KAcc(0.01), "acc", inputs=["ym"])], dt=0.01)
    params = {"plant": {"k": k}, "sw": {"D": D}}
    noise = draw_noise(run_seeds(1, 5), 300, gaussian_noise([0.0, 0.1]))
    inputs = {"w": 0.0, "v": noise[:, :, 1]}
    a = loop.simulate(300, inputs=inputs, params=params, execution=Execution(engine="numpy"))
    b = loop.simulate(300, inputs=inputs, params=params, execution=Execution(engine="compiled"))
    c = loop.simulate(300, inputs=inputs, params=params, execution=Execution(engine="compiled", chunk_runs=2))
    d = loop.simulate(300, inputs=inputs, params=params, execution=Execution(engine="compiled", jobs=2))
    e = loop.simulate(300, inputs=inputs, params=params, execution=Execution(engine="numpy", chunk_runs=2))
    for r in (b, c, d, e):
        assert np.array_equal(a.x, r.x) and np.array_equal(a["ym"], r["ym"])
    for i in range(5):  # run i = the loop with run i's values, alone
        alone = loop.simulate(300, inputs={"w": 0.0, "v": noise[:, i, 1]}, execution=Execution(engine="compiled"),
                              params={"plant": {"k": k[i]}, "sw": {"D": D[i]}})
        assert np.array_equal(alone.x[:, 0], a.x[:, i])
    # each run oscillates at its own frequency sqrt(k) (damped, c = 0.4): zero crossings of x ~ 2 f T
    crossings = (np.diff(np.sign(a.x[:, :, 0]), axis=0) != 0).sum(axis=0)
    assert np.all(np.diff(crossings) > 0)
    assert np.array_equal(a["ym"][:, 1], a["y"][:, 1]) and not np.array_equal(a["ym"][:, 0], a["y"][:, 0])
    for runs in (4, 6):  # values for 5 runs: a batch of another size is refused, not silently cut
        with pytest.raises(ValueError, match=f"the batch's {runs} runs"):
            loop.simulate(300, inputs={"w": 0.0, "v": 0.0}, runs=runs, params=params,
                          execution=Execution(engine="compiled"))


def test_static_gain_kernel_equals_its_numpy_output():
    from ctrl_analysis.engine.blocks import StaticGain, gain_output

    rng = np.random.default_rng(3)
    u = rng.normal(size=(7, 3))
    D = rng.normal(size=(2, 3))
    g = StaticGain(D, ("a", "b", "c"), ("p", "q"))
    y = g.output(0.0, np.zeros((7, 0)), u)
    np.testing.assert_allclose(y, (D @ u.T).T, rtol=1e-14)
    k = g.kernel()
    for fn in (gain_output, _kernels._jit(gain_output)):
        out = np.empty((7, 2))
        for b in range(7):
            fn(0.0, np.zeros(0), u[b], k.params, out[b])
        assert np.array_equal(out, y)
    with pytest.raises(ValueError, match=r"D must have shape \(p, m\) = \(1, 2\)"):
        StaticGain(np.ones((2, 2)), ("a", "b"), ("y",))
    with pytest.raises(ValueError, match=r"a gain per run is given to Loop.simulate"):
        StaticGain(np.ones((3, 1, 2)), ("a", "b"), ("y",))
    with pytest.raises(ValueError, match="D must .*finite"):
        StaticGain([[np.nan, 1.0]], ("a", "b"), ("y",))


def test_discrete_lowpass_kernel_runs_the_compiled_engine_like_numpy():
    from ctrl_analysis.estimators.lowpass import LowPassFilter

    f = LowPassFilter(5.0, order=2).digital(0.01, channels=3, initial=[0.5, -1.0, 2.0])
    loop = Loop([place(f, "W")], dt=0.01)
    noise = draw_noise(run_seeds(2, 4), 200, gaussian_noise([1.0, 1.0, 1.0]))
    inputs = {f"u[{c}]": noise[:, :, c] for c in range(3)}
    a = loop.simulate(200, inputs=inputs, execution=Execution(engine="numpy"))
    b = loop.simulate(200, inputs=inputs, execution=Execution(engine="compiled"))
    assert np.array_equal(a.x, b.x) and np.array_equal(a["w[2]"], b["w[2]"])
    # unit DC gain: a constant input is reached (ZOH of W(s) is exact for a held input)
    c = loop.simulate(400, inputs={f"u[{i}]": 1.0 for i in range(3)}, runs=1, execution=Execution(engine="compiled"))
    np.testing.assert_allclose(c["w[1]"][-1], 1.0, atol=1e-6)


def sloppy_rhs(t, x, u, p, dx):
    dx[0] = -x[0] + u[0]
    u[0] = 0.0  # writes into its inputs: in the compiled runner they are a view of the loop's signals


def overreaching_rhs(t, x, u, p, dx):
    dx[0] = -x[0] + u[0] + p[3]  # its parameter vector has one entry


class CheckedKernel(ContinuousBlock):
    inputs, outputs, states = ("f",), ("y",), ("y",)

    def __init__(self, rhs):
        self._rhs = rhs

    def rhs(self, t, x, u, params=None):
        return -x + u

    def kernel(self):
        return Kernels(output=copy_output, params=np.zeros(1), rhs=self._rhs)


@pytest.mark.parametrize("rhs,message", [(sloppy_rhs, "writes into its inputs u"),
                                         (overreaching_rhs, "reads or writes outside its vectors")])
def test_kernels_are_checked_in_python_before_they_run_compiled(rhs, message):
    loop = Loop([place(CheckedKernel(rhs), "b")], dt=0.1)
    with pytest.raises(ValueError, match=message):
        loop.simulate(5, inputs={"f": 1.0}, execution=Execution(engine="compiled"))


@pytest.mark.parametrize("method", ["rk4", "euler"])
def test_heap_scratch_and_euler_give_the_numpy_numbers(monkeypatch, method):
    # a loop too large for stack scratch gets heap vectors: the same code, the same numbers
    seeds = run_seeds(7, 3)
    noise = draw_noise(seeds, 120, gaussian_noise([0.3, 0.01]))
    inputs = {"w": noise[:, :, 0], "v": noise[:, :, 1]}

    def mk():
        return Loop([place(KOsc(), "plant"), place(DifferentialEstimator(3, 4.0), "sigma"),
                     place(KAcc(0.01), "acc", inputs=["xhat[0]"])], dt=0.01, method=method, substeps=2)

    a = mk().simulate(120, inputs=inputs, execution=Execution(engine="numpy"))
    b = mk().simulate(120, inputs=inputs, execution=Execution(engine="compiled"))
    monkeypatch.setattr(_kernels, "STACK_VALUES", 0)
    monkeypatch.setattr(_kernels, "_RUNNERS", {})
    c = mk().simulate(120, inputs=inputs, execution=Execution(engine="compiled"))
    for r in (b, c):
        assert np.array_equal(a.x, r.x)
        for s in a.signals:
            assert np.array_equal(a[s], r[s]), s
