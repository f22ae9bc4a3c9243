"""A plain Python function as a static block: :class:`FunctionBlock`, ``y = fn(t, u)``.

The wrapper for a sum, a saturation or a reference generator written as a function or a lambda. It
runs on the numpy engine only (a function has no kernel); a static block that should compile is a
class, ``(KernelBlock, StaticBlock)`` with an output kernel (CONTRIBUTING.md, "Add a block"), or a
:class:`~ctrl_analysis.engine.blocks.StaticGain` for a sum, a difference or a selection.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .._validate import check_names
from .blocks import StaticBlock

__all__ = ["FunctionBlock"]


class FunctionBlock(StaticBlock):
    """A memoryless block ``y = fn(t, u)`` made from a Python function (a sum, a gain, a reference generator).

    Parameters
    ----------
    fn : callable
        ``fn(t, u) -> (B, p)`` with ``u`` of shape ``(B, m)``.
    inputs, outputs : sequence of str
        Signal names (at least one output). Without inputs the block has no feedthrough.

    Raises
    ------
    TypeError
        If ``fn`` is not callable.
    ValueError
        If ``outputs`` is empty or a name is not a valid signal name.

    Examples
    --------
    >>> import numpy as np
    >>> add = FunctionBlock(lambda t, u: u[:, :1] + u[:, 1:], inputs=("y", "v"), outputs=("y_meas",))
    >>> add.output(0.0, np.zeros((2, 0)), np.array([[1.0, 0.5], [2.0, -1.0]]))
    array([[1.5],
           [1. ]])
    """

    def __init__(self, fn: Callable, inputs, outputs):
        if not callable(fn):
            raise TypeError(f"fn must be callable, got {type(fn).__name__}")
        self.fn = fn
        self.inputs = check_names("inputs", inputs)
        self.outputs = check_names("outputs", outputs)
        if not self.outputs:
            raise ValueError("outputs must name at least one signal")
        self.feedthrough = bool(self.inputs)

    def output(self, t, x, u, params=None) -> np.ndarray:
        return self.fn(t, u)
