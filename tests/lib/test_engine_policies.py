"""Loop.simulate's typed policies (Save, Execution), the resolved Batch and the Engine protocol (issue 29)."""

from __future__ import annotations

import inspect
from pathlib import Path

import numpy as np
import pytest

import ctrl_analysis
from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.batch import resolve_batch
from ctrl_analysis.engine.blocks import DiscreteBlock
from ctrl_analysis.engine.engines import CompiledEngine, NumpyEngine, select_engine
from ctrl_analysis.engine.kernels import KernelBlock, Kernels, Layout
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.engine.policies import MOVED
from ctrl_analysis.engine.processes import ProcessEngine

LEAK = Layout("a")


def leak_update(t, x, u, p, x_next):
    x_next[0] = p[0] * x[0] + u[0]  # p[0]: a


def leak_output(t, x, u, p, y):
    y[0] = x[0]


class Leak(KernelBlock, DiscreteBlock):
    """x(k+1) = a x(k) + u(k); y = x: a kernel block, compiled."""

    inputs, outputs, states = ("u",), ("y",), ("y",)
    kernels = Kernels(output=leak_output, update=leak_update)

    def __init__(self, a=0.5, x0=0.0):
        self.a, self.x0 = float(a), float(x0)
        self.kernel_params = LEAK.pack(a=a)

    def initial_state(self):
        return np.array([self.x0])


def _loop():
    return Loop([place(Leak(), "leak")], dt=1.0)


def test_simulate_has_eight_typed_parameters_and_no_hidden_ones():
    sig = inspect.signature(Loop.simulate)
    assert list(sig.parameters) == ["self", "n_steps", "inputs", "x0", "params", "runs", "seeds", "t0", "save",
                                    "execution"]
    assert not any(p.kind is inspect.Parameter.VAR_KEYWORD for p in sig.parameters.values())
    assert not hasattr(Loop, "OPTIONS")


@pytest.mark.parametrize("old", sorted(MOVED))
def test_an_old_keyword_says_in_one_line_where_it_moved(old):
    with pytest.raises(TypeError) as err:
        _loop().simulate(3, inputs={"u": 1.0}, **{old: None})
    msg = str(err.value)
    assert "\n" not in msg and f"{old}= moved to {MOVED[old]}" in msg


def test_an_unknown_keyword_is_pythons_own_error():
    with pytest.raises(TypeError, match="unexpected keyword argument 'nonsense'"):
        _loop().simulate(3, inputs={"u": 1.0}, nonsense=1)


@pytest.mark.parametrize(("make", "arg"), [
    (lambda: Save(every=0), "every"), (lambda: Save(every=2.5), "every"), (lambda: Save(keep=3), "keep"),
    (lambda: Save(states="yes"), "states"), (lambda: Execution(engine="fast"), "engine"),
    (lambda: Execution(jobs=0), "jobs"), (lambda: Execution(chunk_runs=0), "chunk_runs"),
    (lambda: Execution(max_bytes=-1.0), "max_bytes"), (lambda: Execution(progress="f"), "progress"),
    (lambda: Execution(bound=0.0), "bound"), (lambda: Execution(bound=float("nan")), "bound"),
])
def test_policies_refuse_bad_fields_naming_them(make, arg):
    with pytest.raises((TypeError, ValueError), match=rf"\b{arg}\b"):
        make()


def test_policies_are_frozen_exported_and_checked_by_simulate():
    assert ctrl_analysis.Save is Save and ctrl_analysis.Execution is Execution
    with pytest.raises(AttributeError):
        Save().every = 3
    with pytest.raises(TypeError, match="save must be"):
        _loop().simulate(3, inputs={"u": 1.0}, save={"every": 2})
    with pytest.raises(ValueError, match="keep names unknown signal 'nope'"):
        _loop().simulate(3, inputs={"u": 1.0}, save=Save(keep=["nope"]))


def test_save_keeps_what_it_says():
    res = _loop().simulate(6, inputs={"u": 1.0}, save=Save(keep=["u"], every=3, states=False))
    full = _loop().simulate(6, inputs={"u": 1.0})
    assert list(res.signals) == ["u"] and res.x is None and np.array_equal(res.t, full.t[::3])
    assert np.array_equal(res.final_states["leak"], full.final_states["leak"])


def test_batch_x0_per_run_equals_single_runs():
    loop = _loop()
    x0 = np.array([[0.0], [1.0], [-2.0]])
    batch = resolve_batch(loop.plan, 4, inputs={"u": 1.0}, x0={"leak": x0})
    assert batch.B == 3 and batch.x0.shape == (3, 1) and np.array_equal(batch.x0, x0)
    both = loop.simulate(4, inputs={"u": 1.0}, x0={"leak": x0})
    for b in range(3):
        one = loop.simulate(4, inputs={"u": 1.0}, x0={"leak": x0[b]})
        assert np.array_equal(both["y"][:, b], one["y"][:, 0])


def test_batch_takes_per_run_x0_and_parameters_from_params():
    loop = _loop()
    batch = resolve_batch(loop.plan, 4, inputs={"u": 0.0}, params={"leak": {"x0": np.array([1.0, 2.0]),
                                                                           "a": np.array([0.5, 0.25])}})
    assert batch.B == 2 and batch.x0[:, 0].tolist() == [1.0, 2.0]
    assert batch.variants["leak"].rows.shape == (2, 1)
    part = batch.take(loop.plan, 1, 2)
    assert part["runs"] == 1 and part["x0"]["leak"].tolist() == [[2.0]]


def test_both_engines_follow_one_protocol_bit_for_bit():
    loop = _loop()
    plan = loop.plan
    batch = resolve_batch(plan, 20, inputs={"u": np.sin(np.arange(20.0))[:, None] * [1.0, 2.0]},
                          params={"leak": {"a": np.array([0.5, 0.9])}})
    compiled = select_engine(plan, batch, Execution())
    assert isinstance(compiled, CompiledEngine)
    assert isinstance(select_engine(plan, batch, Execution(engine="numpy")), NumpyEngine)
    a = NumpyEngine().run(plan, batch, Save(), Execution())
    b = compiled.run(plan, batch, Save(), Execution())
    assert np.array_equal(a["y"], b["y"]) and np.array_equal(a.x_final, b.x_final)
    # jobs > 1 is an engine too: the runs split over processes, given the loop to send them
    split = select_engine(plan, batch, Execution(jobs=2), loop=loop)
    assert isinstance(split, ProcessEngine) and split.name == "processes"
    assert isinstance(select_engine(plan, batch, Execution(jobs=2)), CompiledEngine)  # no loop: one process
    c = split.run(plan, batch, Save(), Execution(jobs=2))
    assert np.array_equal(c["y"], b["y"]) and np.array_equal(c.x_final, b.x_final)


def test_loop_response_has_no_always_none_fields():
    res = _loop().simulate(2, inputs={"u": 1.0}, seeds=[7])
    assert not hasattr(res, "u") and not hasattr(res, "y")
    assert res.seeds == [7] and res.runs == 1 and res.ok.all() and res.divergences() == []


def test_the_compiled_path_reads_no_private_attribute_of_a_loop():
    engine = Path(ctrl_analysis.__file__).parent / "engine"
    for name in ("compiled.py", "codegen.py", "engines.py", "numpy_engine.py", "batch.py"):
        text = (engine / name).read_text()
        assert "loop._" not in text and "_plan()" not in text, name


def test_a_block_changed_after_a_call_is_simulated_as_it_is_now():
    """The runner is found once per loop, but the parameters and initial states are read at every call."""
    blk = Leak(a=0.5)
    loop = Loop([place(blk, "leak")], dt=1.0)
    before = loop.simulate(3, inputs={"u": 1.0})
    blk.kernel_params, blk.x0 = np.array([0.9]), 2.0
    after = loop.simulate(3, inputs={"u": 1.0})
    fresh = Loop([place(Leak(a=0.9, x0=2.0), "leak")], dt=1.0).simulate(3, inputs={"u": 1.0})
    assert np.array_equal(after["y"], fresh["y"]) and not np.array_equal(before["y"], after["y"])
