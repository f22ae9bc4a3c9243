"""Run-time block parameters (``Loop.simulate(params=...)``) and kernel-first blocks (Layout, Kernels, KernelBlock)."""

from __future__ import annotations

import numpy as np
import pytest

from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.blocks import DiscreteBlock
from ctrl_analysis.engine.kernels import KernelBlock, Kernels, Layout
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.differential import DifferentialEstimator

N = 150
A = np.array([1.0, 2.0, 3.0, 2.0])  # per-run Σ bandwidths (two runs share one)


def _y(B):
    return np.sin(5e-3 * np.arange(N + 1))[:, None] * np.linspace(1.0, 2.0, B)[None, :]


def _sigma_loop(a=2.0):
    return Loop([place(DifferentialEstimator(3, a), "sigma")], dt=1e-3)


@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_per_run_parameters_equal_single_runs_through_chunks(engine):
    y = _y(A.size)
    res = _sigma_loop().simulate(N, inputs={"y": y}, params={"sigma": {"a": A}}, execution=Execution(engine=engine))
    for b, a in enumerate(A):
        alone = _sigma_loop(a).simulate(N, inputs={"y": y[:, b]}, execution=Execution(engine=engine))
        assert np.array_equal(res.x[:, b], alone.x[:, 0]), f"run {b} (a = {a}) differs from the block built with a"
    chunked = _sigma_loop().simulate(N, inputs={"y": y}, params={"sigma": {"a": A}},
                                     execution=Execution(engine=engine, chunk_runs=3))
    assert np.array_equal(chunked.x, res.x)


def test_per_run_parameters_through_processes():
    y = _y(A.size)
    one = _sigma_loop().simulate(N, inputs={"y": y}, params={"sigma": {"a": A}})
    two = _sigma_loop().simulate(N, inputs={"y": y}, params={"sigma": {"a": A}}, execution=Execution(jobs=2))
    assert np.array_equal(one.x, two.x)


def test_shared_parameter_changes_every_run():
    y = _y(2)
    res = _sigma_loop(2.0).simulate(N, inputs={"y": y}, params={"sigma": {"a": 3.0}})
    ref = _sigma_loop(3.0).simulate(N, inputs={"y": y})
    assert np.array_equal(res.x, ref.x)


@pytest.mark.parametrize(("params", "match"), [
    ({"nope": {}}, "not in the loop"),
    ({"sigma": {"b": 1.0}}, "not parameters of DifferentialEstimator"),
    ({"sigma": {"a": [1.0, 2.0]}}, r"params\['sigma'\]\['a'\].*4 runs"),
    ({"sigma": {"a": -1.0}}, r"params\['sigma'\]: a must be > 0"),
    ({"sigma": {"n0": [3, 3, 4, 4]}}, "change the size"),
])
def test_bad_parameters_are_named(params, match):
    with pytest.raises(ValueError, match=match):
        _sigma_loop().simulate(N, inputs={"y": _y(4)}, params=params)


LAG = Layout("a", ("w", 2))
AT = LAG.at  # the offsets, a compile-time constant in numba (a Layout object is not)


def lag_update(t, x, u, p, x_next):
    x_next[0] = x[0] + p[AT.a] * (p[AT.w] * u[0] + p[AT.w + 1] - x[0])


def lag_branchy_update(t, x, u, p, x_next):
    e = u[0] - x[0]
    x_next[0] = x[0] + (p[AT.a] * e if e > 0 else 0.5 * p[AT.a] * e)  # a branch on a value


class Lag(KernelBlock, DiscreteBlock):
    inputs, outputs, states = ("u",), ("y",), ("y",)
    kernels = Kernels(update=lag_update)

    def __init__(self, a=0.5, w=(1.0, 0.0)):
        if not 0 < a < 2:
            raise ValueError(f"a must be in (0, 2) for a stable lag, got {a}")
        self.kernel_params = LAG.pack(a=a, w=w)


class BranchyLag(Lag):
    kernels = Kernels(update=lag_branchy_update, columns=False)


def test_layout_offsets_pack_and_unpack():
    assert LAG.at == (0, 1) and LAG.size == 3
    p = LAG.pack(a=0.25, w=[2.0, -1.0])
    assert p.tolist() == [0.25, 2.0, -1.0]
    back = LAG.unpack(p)
    assert back["a"] == 0.25 and back["w"].tolist() == [2.0, -1.0]
    with pytest.raises(ValueError, match="'w' must have shape"):
        LAG.pack(a=1.0, w=[1.0])


@pytest.mark.parametrize("cls", [Lag, BranchyLag])
def test_kernel_block_derived_methods_equal_the_compiled_engine_and_a_hand_computation(cls):
    u = np.cos(0.1 * np.arange(N + 1))[:, None] * np.array([[1.0, -2.0, 0.5]])
    a = np.array([0.2, 0.7, 1.3])
    loop = Loop([place(cls(), "lag")], dt=1.0)
    res = {e: loop.simulate(N, inputs={"u": u}, params={"lag": {"a": a}},
                            execution=Execution(engine=e)) for e in ("numpy", "compiled")}
    assert np.array_equal(res["numpy"].x, res["compiled"].x)
    x = np.zeros(3)  # the recursion by hand, run by run
    for k in range(N):
        e = u[k] - x
        x = x + (a * e if cls is Lag else np.where(e > 0, a * e, 0.5 * a * e))
    assert np.allclose(res["numpy"].x[-1, :, 0], x, rtol=1e-14, atol=0)


def test_kernel_block_validates_run_time_values_with_its_constructor_and_serves_python_control():
    with pytest.raises(ValueError, match=r"params\['lag'\]: a must be in \(0, 2\)"):
        Loop([place(Lag(), "lag")], dt=1.0).simulate(3, inputs={"u": np.ones((4, 2))},
                                                    params={"lag": {"a": [0.5, 2.5]}})
    import control as ct

    sys = Lag(0.5).nlsys(1.0)
    t = np.arange(6.0)
    r = ct.input_output_response(sys, t, np.ones(6), params={"a": 0.25})
    assert np.allclose(r.outputs, 1.0 - 0.75 ** t)  # python-control's params change a by name


@pytest.mark.parametrize("engine", ["numpy", "compiled"])
@pytest.mark.parametrize("every", [1, 7])
def test_keep_and_every_store_the_decimated_signals_of_the_full_run(engine, every):
    y = _y(3)
    full = _sigma_loop().simulate(N, inputs={"y": y}, execution=Execution(engine=engine))
    some = _sigma_loop().simulate(N, inputs={"y": y},
                                  save=Save(keep=["xhat[1]"], every=every, states=False),
                                  execution=Execution(engine=engine))
    assert list(some.signals) == ["xhat[1]"] and some.x is None
    assert np.array_equal(some.t, full.t[::every]) and some.t.size == N // every + 1
    assert np.array_equal(some["xhat[1]"], full["xhat[1]"][::every])
    assert np.array_equal(some.x_final, full.x[-1])  # the final state whatever is stored
    with pytest.raises(ValueError, match="every must be"):
        _sigma_loop().simulate(N, inputs={"y": y}, save=Save(every=0))


@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_per_run_initial_states_and_substeps_equal_single_runs(engine):
    """Issue 29: a per-run x0 given through params was accepted and ignored (x0's default is None, so it could not
    vary per run), and per-run substeps ran compiled but raised on the numpy engine."""
    from ctrl_analysis.estimators.tracking import TrackingDifferentiator

    u = np.linspace(0.0, 1.0, 31)
    x0s = np.array([[1.0, 0.0], [2.0, -1.0], [0.5, 3.0]])
    subs = np.array([1, 2, 3])
    loop = Loop([place(TrackingDifferentiator(r=50.0, h=0.01), "td")], dt=0.01)
    (name,) = loop.external
    both = loop.simulate(30, inputs={name: u}, params={"td": {"x0": x0s, "substeps": subs}},
                         execution=Execution(engine=engine))
    assert both.runs == 3  # the batch size comes from the per-run values
    for b in range(3):
        one = Loop([place(TrackingDifferentiator(r=50.0, h=0.01, x0=x0s[b], substeps=int(subs[b])), "td")],
                   dt=0.01).simulate(30, inputs={name: u}, execution=Execution(engine=engine))
        np.testing.assert_array_equal(both.states["td"][:, b], one.states["td"][:, 0])
    # a value for a None-default argument that the constructor takes whole is shared, not per run
    shared = loop.simulate(30, inputs={name: u}, params={"td": {"x0": [1.0, 0.0]}}, runs=3,
                           execution=Execution(engine=engine))
    assert np.all(shared.states["td"][0] == [1.0, 0.0])


class _Leak(DiscreteBlock):
    """A plain Python block (no kernel): x(k+1) = a x(k) + u(k), y = x, starting from x0."""

    inputs, outputs, states = ("u",), ("y",), ("x",)

    def __init__(self, a=0.5, x0=0.0):
        self.a, self.x0 = float(a), float(x0)

    def initial_state(self):
        return np.array([self.x0])

    def update(self, t, x, u, params=None):
        return self.a * x + u


def _acc_update(t, x, u, p, xn):
    xn[0] = x[0] + p[0] * u[0]


class _OwnKernel(DiscreteBlock):
    """A block with its own kernel() and no batched methods (the kernel is run row by row on numpy)."""

    inputs, outputs, states = ("u",), ("y",), ("s",)

    def __init__(self, T=1.0, s0=0.0):
        self.p, self.s0 = np.array([float(T)]), float(s0)

    def initial_state(self):
        return np.array([self.s0])

    def update(self, t, x, u, params=None):
        return x + self.p[0] * u

    def kernel(self):
        return Kernels(params=self.p, update=_acc_update)


def _alone(cls, u, engine, **kw):
    return Loop([place(cls(**kw), "b")], dt=1.0).simulate(u.size - 1, inputs={"u": u},
                                                          execution=Execution(engine=engine))


def test_per_run_values_of_a_block_without_kernel_equal_single_runs_on_numpy_and_are_refused_compiled():
    """Issue 29: a block without kernel takes per-run values as a Python row kernel (its rows select the run's
    rebuilt block; ``Variant.groups`` is gone); only the numpy engine runs it, and engine='compiled' says why."""
    u = np.cos(0.3 * np.arange(21))
    a, x0 = np.array([0.5, 0.9, 0.5, -0.2]), np.array([0.0, 1.0, 2.0, 1.0])
    loop = Loop([place(_Leak(), "b")], dt=1.0)
    res = loop.simulate(20, inputs={"u": u}, params={"b": {"a": a, "x0": x0}}, execution=Execution(engine="numpy"),
                        save=Save(states=True))
    for r in range(a.size):
        one = _alone(_Leak, u, "numpy", a=a[r], x0=x0[r])
        np.testing.assert_array_equal(res.signals["y"][:, r], one.signals["y"][:, 0])
    with pytest.raises(ValueError, match="'b' .*per-run parameters but no kernel"):
        loop.simulate(20, inputs={"u": u}, params={"b": {"a": a}}, execution=Execution(engine="compiled"))


@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_per_run_initial_state_alone_is_kept_where_the_kernel_rows_are_equal(engine):
    """Runs that differ only by their initial state have equal kernel rows: each still starts from its own."""
    u = np.sin(0.2 * np.arange(16))
    s0 = np.array([0.0, 5.0, -1.0])
    res = Loop([place(_OwnKernel(T=0.5), "b")], dt=1.0).simulate(15, inputs={"u": u}, params={"b": {"s0": s0}},
                                                                 execution=Execution(engine=engine))
    for r in range(s0.size):
        one = _alone(_OwnKernel, u, engine, T=0.5, s0=s0[r])
        np.testing.assert_array_equal(res.signals["y"][:, r], one.signals["y"][:, 0])


@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_per_run_values_of_a_block_with_its_own_kernel_and_no_batched_methods_equal_single_runs(engine):
    u = np.sin(0.2 * np.arange(16))
    T = np.array([0.5, 2.0, 0.5])
    res = Loop([place(_OwnKernel(), "b")], dt=1.0).simulate(15, inputs={"u": u}, params={"b": {"T": T}},
                                                            execution=Execution(engine=engine))
    for r in range(T.size):
        one = _alone(_OwnKernel, u, engine, T=T[r])
        np.testing.assert_array_equal(res.signals["y"][:, r], one.signals["y"][:, 0])
