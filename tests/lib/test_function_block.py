"""Tests of the static-block protocol (StaticBlock) and the function wrapper (ctrl_analysis.engine.function_block)."""

import numpy as np
import pytest

import ctrl_analysis
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.blocks import StaticBlock, StaticGain
from ctrl_analysis.engine.function_block import FunctionBlock
from ctrl_analysis.engine.loop import Loop, place


def test_function_block_wraps_a_function_and_runs_in_a_loop_like_the_gain():
    diff = FunctionBlock(lambda t, u: u[:, :1] - u[:, 1:], inputs=("r", "y"), outputs=("e",))
    assert isinstance(diff, StaticBlock) and diff.feedthrough and diff.states == ()
    np.testing.assert_array_equal(diff.output(0.0, np.zeros((2, 0)), np.array([[1.0, 0.25], [0.0, 2.0]])),
                                  [[0.75], [-2.0]])
    r, y = np.linspace(0.0, 1.0, 6), np.cos(np.arange(6.0))
    via_fn = Loop([place(diff, "e")], 0.1).simulate(6, inputs={"r": r, "y": y},
                                                  execution=Execution(engine="numpy"))
    gain = StaticGain([[1.0, -1.0]], ("r", "y"), ("e",))
    via_gain = Loop([place(gain, "e")], 0.1).simulate(6, inputs={"r": r, "y": y})
    np.testing.assert_array_equal(via_fn["e"], via_gain["e"])
    # a source (no inputs) has no feedthrough; its nlsys is python-control's static system
    src = FunctionBlock(lambda t, u: np.full((u.shape[0], 1), 2.0), (), ("c",))
    assert not src.feedthrough
    assert repr(src) == "FunctionBlock(inputs=(), outputs=('c',))"
    assert ctrl_analysis.FunctionBlock is FunctionBlock


def test_static_block_is_a_protocol_and_says_where_the_function_wrapper_went():
    with pytest.raises(TypeError, match=r"FunctionBlock\(fn, inputs, outputs\)"):
        StaticBlock(lambda t, u: u, inputs=("a",), outputs=("b",))
    with pytest.raises(TypeError, match="FunctionBlock"):
        StaticBlock(lambda t, u: u, ("a",), ("b",))

    class Double(StaticBlock):  # the protocol: a class with its signals and an output
        inputs, outputs = ("u",), ("y",)

        def output(self, t, x, u, params=None):
            return 2.0 * u

    block = Double()
    assert block.feedthrough and block.states == ()
    np.testing.assert_array_equal(block.output(0.0, np.zeros((1, 0)), np.array([[1.5]])), [[3.0]])
    sys = block.nlsys(name="double")
    assert sys.ninputs == 1 and sys.noutputs == 1 and sys.nstates == 0


@pytest.mark.parametrize("kw, error, fragment", [
    (dict(fn=3.0), TypeError, "fn must be callable"),
    (dict(outputs=()), ValueError, "outputs must name at least one signal"),
    (dict(inputs=["a", 3]), (TypeError, ValueError), "inputs"),
])
def test_function_block_refuses_bad_arguments(kw, error, fragment):
    args = dict(fn=lambda t, u: u, inputs=("a",), outputs=("b",)) | kw
    with pytest.raises(error, match=fragment):
        FunctionBlock(**args)
