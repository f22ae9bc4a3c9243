"""Every kernel-first library block: its derived batched methods equal the compiled engine bit for bit.

A :class:`~ctrl_analysis.engine.kernels.KernelBlock` writes its equations once, as kernels; the
numpy methods are those kernels on the batch's columns (or run by run), the compiled engine the same
functions compiled. Held here for each block of the library: the methods against the compiled
kernel run by run, and the blocks side by side in a loop on both engines (with per-run parameters
where the block has a numeric one), both bit for bit. The Kalman filters are also held to their matrix form (the
docstrings' equations) to rounding.
"""

from __future__ import annotations

import control as ct
import numpy as np
import pytest

from analysis.pendulum.blocks import BackwardDifference, CartPendulum
from ctrl_analysis.arena.interface import _AlphaBetaGamma, _LowPass
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine import codegen as _kernels
from ctrl_analysis.engine.blocks import StaticGain
from ctrl_analysis.engine.kernels import KernelBlock
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.estimators.eso import ExtendedStateObserver
from ctrl_analysis.estimators.kalman import (
    AlphaBetaFilter,
    CharacteristicKalmanFilter,
    DiscreteKalmanFilter,
    ImprovedKalmanFilter,
    LinearKalmanFilter,
)
from ctrl_analysis.estimators.lowpass import LowPassFilter
from ctrl_analysis.estimators.tracking import TrackingDifferentiator
from ctrl_analysis.plants import DiscreteLTI

B = 4
F2 = np.array([[1.0, 0.1], [-0.2, 0.95]])
F3 = np.array([[0.9, 0.1, 0.0], [0.0, 0.8, 0.1], [0.05, 0.0, 0.7]])


def _blocks():
    """``(id, block, per-run parameters or None)`` of every kernel-first library block (and its variants)."""
    td = TrackingDifferentiator(r=20.0, h=0.01, substeps=2)
    return [
        ("kalman", DiscreteKalmanFilter(F2, [1.0, 0.0], np.diag([1e-3, 1e-2]), 0.1), {"R": [0.1, 0.2, 0.3, 0.1]}),
        ("kalman-b", DiscreteKalmanFilter(F3, [1.0, 0.0, 0.5], 1e-2 * np.eye(3), 0.2, b=[0.0, 0.1, 0.2]), None),
        ("ckf", CharacteristicKalmanFilter(Q=1e-3, R=0.5, P0=2.0), {"R": [0.5, 1.0, 2.0, 4.0]}),
        ("lkf", LinearKalmanFilter(F3, [0.1, 0.2, 0.3], [1.0, 0.0, 0.0], 1e-2, 0.3), {"R": [0.3, 0.6, 0.3, 0.9]}),
        ("ikf", ImprovedKalmanFilter(Q=0.1, R=1.0), {"Q": [0.1, 0.01, 0.3, 0.05]}),
        ("alpha-beta", AlphaBetaFilter(0.5, 0.2, 0.1), {"alpha": [0.5, 0.6, 0.4, 0.5]}),
        ("alpha-beta-b", AlphaBetaFilter(0.5, 0.2, 0.1, F=F2, b=[0.01, 0.3]), None),
        ("lowpass", LowPassFilter(5.0, order=3), {"omega": [5.0, 2.0, 8.0, 1.0]}),
        ("digital-lowpass", LowPassFilter(5.0, order=2).digital(0.01, channels=2, initial=[1.0, -1.0]),
         {"h": [0.01, 0.02, 0.05, 0.01]}),
        ("td", td, {"r": [20.0, 5.0, 50.0, 10.0]}),
        ("td-feedthrough", TrackingDifferentiator(r=20.0, h=0.01, substeps=3, feedthrough=True), None),
        ("td-step", td.step_block(), None),
        ("eso", ExtendedStateObserver.from_bandwidth(2, 10.0, b0=1.5),
         {"gains": [ExtendedStateObserver.from_bandwidth(2, w).L for w in (10.0, 5.0, 20.0, 10.0)]}),
        ("eso-fal", ExtendedStateObserver((100.0, 300.0, 1000.0), b0=0.5, alpha=[1.0, 0.5, 0.25], delta=0.01),
         {"delta": [0.01, 0.02, 0.05, 0.01]}),
        ("sigma", DifferentialEstimator(3, 2.0), {"a": [2.0, 1.0, 4.0, 2.0]}),
        ("sigma-corrected", DifferentialEstimator(4, 2.0, reading="corrected"), None),
        ("lti", DiscreteLTI(ct.tf([2.0, 4.0], [1.0, 3.0, 2.0, 0.5]), 0.05), None),
        ("lti-feedthrough", DiscreteLTI(ct.tf([1.0, 0.5], [1.0, 2.0]), 0.1), None),
        ("cart-pendulum", CartPendulum(14.7, 1.5), {"a21": [14.7, 10.0, 20.0, 14.7]}),
        ("cart-pendulum-nonlinear", CartPendulum(14.7, 1.5, nonlinear=True), {"b": [1.5, 1.0, 2.0, 1.5]}),
        ("backward-difference", BackwardDifference(0.01), {"T": [0.01, 0.02, 0.05, 0.01]}),
        ("arena-abg", _AlphaBetaGamma(0.5, 0.2, 0.02, 0.01), {"alpha": [0.5, 0.4, 0.6, 0.5]}),
        ("arena-lowpass", _LowPass(20.0, 0.002), {"omega": [20.0, 10.0, 40.0, 20.0]}),
        ("gain", StaticGain([[1.0, -2.0, 0.5], [0.0, 1.0, 3.0]], ("a", "b", "c"), ("p", "q")),
         {"D": np.random.default_rng(0).normal(size=(B, 2, 3))}),
    ]


BLOCKS = _blocks()
IDS = [b[0] for b in BLOCKS]


def _state_and_inputs(block, rng, runs=B):
    x0 = np.asarray(block.initial_state(), dtype=float)
    x = x0 + 0.5 * rng.standard_normal((runs, x0.size))
    if any(s.startswith("P") for s in block.states):  # covariance entries stay positive
        x = np.abs(x) + x0
    return x, rng.standard_normal((runs, len(block.inputs)))


def test_every_library_kernel_block_is_listed():
    from ctrl_analysis.estimators import tracking

    listed = {type(b) for _, b, _ in BLOCKS}
    library = {tracking.TDStep, StaticGain}
    for cls in (DiscreteKalmanFilter, CharacteristicKalmanFilter, LinearKalmanFilter, ImprovedKalmanFilter,
                AlphaBetaFilter, LowPassFilter, TrackingDifferentiator, ExtendedStateObserver,
                DifferentialEstimator, DiscreteLTI):
        library.add(cls)
    assert all(issubclass(cls, KernelBlock) for cls in library)
    assert library <= listed


@pytest.mark.parametrize(("name", "block", "per_run"), BLOCKS, ids=IDS)
def test_derived_methods_equal_the_compiled_kernels_run_by_run(name, block, per_run):
    rng = np.random.default_rng(7)
    x, u = _state_and_inputs(block, rng)
    k = block.kernel()
    P = np.asarray(k.params)
    rows = P if P.ndim == 2 else np.broadcast_to(P, (B, P.size))
    step = "update" if k.update is not None else "rhs"
    for kind, width in (("output", len(block.outputs)), (step, x.shape[1])):
        fn = getattr(k, kind)
        if fn is None:
            continue
        derived = getattr(block, kind)(0.3, x, u)
        compiled = np.empty((B, width))
        jit = _kernels._jit(fn)
        for b in range(B):
            jit(0.3, np.ascontiguousarray(x[b]), np.ascontiguousarray(u[b]), np.ascontiguousarray(rows[b]), compiled[b])
        assert np.array_equal(derived, compiled, equal_nan=True), f"{name}: {kind}"
        one = getattr(block, kind)(0.3, x[1], u[1]) if P.ndim == 1 else None  # one run, 1-D
        assert one is None or np.array_equal(one, derived[1], equal_nan=True)


def _side_by_side(continuous: bool):
    """Every block of :data:`BLOCKS` with (without) a ``rhs`` in one loop, unconnected, each on inputs of its own.

    One loop of ``k`` blocks is one compiled structure instead of ``k`` (numba spends about half a
    second on the runner around the blocks, whatever they are): the suite compiles two here, not 25.
    Block ``i`` is named ``b{i}``; its inputs are ``in{i}_{j}``, its outputs ``out{i}_{j}``.
    """
    placed, per_run = [], {}
    for i, (_name, block, pr) in enumerate(BLOCKS):
        if (block.kernel().rhs is not None) != continuous:
            continue
        placed.append(place(block, f"b{i}", inputs=[f"in{i}_{j}" for j in range(len(block.inputs))],
                            outputs=[f"out{i}_{j}" for j in range(len(block.outputs))]))
        if pr is not None:
            per_run[f"b{i}"] = {k: np.asarray(v) for k, v in pr.items()}
    return Loop(placed, dt=0.01 if continuous else 1.0), per_run


@pytest.mark.parametrize("continuous", [False, True], ids=["discrete-and-static", "continuous"])
def test_every_block_in_a_loop_numpy_engine_equals_compiled_bit_for_bit(continuous):
    """Each block's states and outputs on both engines, with per-run parameters where it has them; and run
    ``b`` of a per-run block equals the block built with run ``b``'s values, alone in a loop."""
    rng = np.random.default_rng(3)
    loop, per_run = _side_by_side(continuous)
    N = 25
    inputs = {s: rng.standard_normal((N + 1, B)) for s in loop.external}
    res = {e: loop.simulate(N, inputs=inputs, runs=B, params=per_run, execution=Execution(engine=e, bound=np.inf))
           for e in ("numpy", "compiled")}
    differ = []
    for p in loop.placed:
        i = int(p.name[1:])
        sl = loop.slices.get(p.name, slice(0, 0))
        same = np.array_equal(res["numpy"].x[:, :, sl], res["compiled"].x[:, :, sl], equal_nan=True) and all(
            np.array_equal(res["numpy"][s], res["compiled"][s], equal_nan=True) for s in p.outputs)
        if not same:
            differ.append(BLOCKS[i][0])
        if p.name in per_run:  # on the numpy engine: numpy = compiled is what this test holds
            for b in (0, 2):
                one_block = p.block.with_params(**{k: v[b] for k, v in per_run[p.name].items()})
                alone = loop_with(one_block, loop.dt)
                one = alone.simulate(N, inputs={f"in{j}": inputs[s][:, b:b + 1] for j, s in enumerate(p.inputs)},
                                     runs=1, execution=Execution(bound=np.inf, engine="numpy"))
                if not np.array_equal(one.x[:, 0], res["compiled"].x[:, b, sl], equal_nan=True):
                    differ.append(f"{BLOCKS[i][0]} run {b} alone")
    assert differ == []


def loop_with(block, dt):
    """``block`` alone in a loop, its inputs named ``in{j}`` and its outputs ``out{j}`` (a TD step's outputs are
    named as its inputs)."""
    return Loop([place(block, "b", inputs=[f"in{j}" for j in range(len(block.inputs))],
                       outputs=[f"out{j}" for j in range(len(block.outputs))])], dt=dt)


def test_kalman_kernels_follow_the_matrix_form():
    """The docstrings' matrix equations, run with numpy matrices, against the kernels (to rounding)."""
    rng = np.random.default_rng(5)
    F, h, Qd, R, b = F3, np.array([1.0, 0.0, 0.5]), 1e-2 * np.eye(3), 0.2, np.array([0.0, 0.1, 0.2])
    kf = DiscreteKalmanFilter(F, h, Qd, R, b=b)
    x, u = _state_and_inputs(kf, rng, runs=1)
    xp, P = x[0, :3], x[0, 3:].reshape(3, 3)
    S = h @ P @ h + R
    K = P @ h / S
    xf = xp + K * (u[0, 0] - h @ xp)
    Pf = P - np.outer(K, K) * S
    np.testing.assert_allclose(kf.output(0.0, x, u)[0], xf, rtol=1e-12)
    nxt = kf.update(0.0, x, u)[0]
    np.testing.assert_allclose(nxt[:3], F @ xf + b * u[0, 1], rtol=1e-12)
    np.testing.assert_allclose(nxt[3:].reshape(3, 3), F @ Pf @ F.T + Qd, rtol=1e-12)

    G, H = np.array([0.1, 0.2, 0.3]), np.array([1.0, 0.0, 0.0])
    lkf = LinearKalmanFilter(F, G, H, Qd, R)
    x, u = _state_and_inputs(lkf, rng, runs=1)
    xh, P = x[0, :3], x[0, 3:].reshape(3, 3)
    xp = F @ xh + G * u[0, 1]
    Pp = F @ P @ F.T + Qd
    K = Pp @ H / (H @ Pp @ H + R)
    xf = xp + K * (u[0, 0] - H @ xp)
    A = np.eye(3) - np.outer(K, H)
    nxt = lkf.update(0.0, x, u)[0]
    np.testing.assert_allclose(nxt[:3], xf, rtol=1e-12)
    np.testing.assert_allclose(nxt[3:].reshape(3, 3), A @ Pp @ A.T + R * np.outer(K, K), rtol=1e-12)
    np.testing.assert_allclose(lkf.output(0.0, x, u)[0, 0], H @ xf, rtol=1e-12)


def test_a_size_that_differs_between_runs_runs_run_by_run():
    # a size cannot serve every column of one call: the batched methods then go run by run (issue 29: per-run
    # substeps raised on the numpy engine), equal to each run alone
    from ctrl_analysis.engine.kernels import RowsNeeded, as_int

    td = TrackingDifferentiator(r=20.0, h=0.01)
    P = np.stack([td.kernel_params, td.with_params(substeps=2).kernel_params])
    x, u = np.array([[0.1, 0.0], [0.2, 0.5]]), np.ones((2, 1))
    both = td.batched("update", 0.0, x, u, P)
    for b in range(2):
        np.testing.assert_array_equal(both[b], td.batched("update", 0.0, x[b:b + 1], u[b:b + 1], P[b])[0])
    with pytest.raises(RowsNeeded, match="differs between runs"):
        as_int(np.array([1.0, 2.0]))


def _outside_block(read: bool):
    """A branching row kernel (columns=False) that reads, or writes, one slot past its vectors when u > 0."""
    from ctrl_analysis.engine.blocks import DiscreteBlock
    from ctrl_analysis.engine.kernels import Kernels, Layout

    layout = Layout("k")

    def out(t, x, u, p, y):
        y[0] = x[0]

    def upd(t, x, u, p, xn):
        if u[0] > 0:
            if read:
                xn[0] = x[0] + p[3]  # the layout has one slot
            else:
                xn[2] = 1.0  # the state has one entry
        else:
            xn[0] = x[0]

    class Outside(KernelBlock, DiscreteBlock):
        inputs, outputs, states = ("u",), ("y",), ("x",)
        kernels = Kernels(output=out, update=upd, columns=False)

        def __init__(self):
            self.kernel_params = layout.pack(k=1.0)

    return Outside()


@pytest.mark.parametrize("runs", [10, 100], ids=["python-rows", "compiled-rows"])
@pytest.mark.parametrize("read", [True, False], ids=["reads-outside", "writes-outside"])
def test_a_row_kernel_outside_its_vectors_is_a_clear_error_on_every_path(runs, read):
    # issue 28: from 64 runs on the numpy engine runs such a kernel compiled over the rows, where an index
    # outside the vectors used to corrupt memory ("double free or corruption") or return garbage (5e-321)
    loop = Loop([place(_outside_block(read), "blk")], dt=1.0)
    for engine in ("numpy", "auto"):
        with pytest.raises(ValueError,
                           match=r"\(Outside\): its kernel update 'upd' reads or writes outside its vectors"):
            loop.simulate(5, inputs={"u": np.ones((6, runs))}, execution=Execution(engine=engine))
