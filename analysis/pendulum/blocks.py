"""The `pendulum` study's own blocks, kernel-first: the cart–pendulum, the backward difference, a split filter.

:class:`CartPendulum` (linear or ``sin φ``), :class:`BackwardDifference` (the rate the fuzzy controller gets
without a filter) and :func:`split_filter`, which places a filter with feedthrough of ``y`` as a predictor and
a static corrector so that a controller may read its estimate. Every block has compiled kernels.
"""

from __future__ import annotations

import numpy as np

from ctrl_analysis.engine.blocks import (
    ContinuousBlock,
    DiscreteBlock,
    StaticBlock,
)
from ctrl_analysis.engine.kernels import (
    KernelBlock,
    Kernels,
    Layout,
    as_int,
    copy_output,
)
from ctrl_analysis.engine.loop import place

__all__ = ["BackwardDifference", "CartPendulum", "split_filter"]

PENDULUM = Layout("a21", "b", "nonlinear")
AT = PENDULUM.at  # parameter offsets, a numba constant


def pendulum_rhs(t, x, u, p, dx):
    """``φ'' = a21 φ + b u + w`` (§3.1, ``ẋ = A x + B u + Γ w``) or, flag set, ``a21 sin φ + b cos φ · u + w``.

    The kernel of :class:`CartPendulum`: ``p`` is :data:`PENDULUM`, ``u = [u, w]``.
    """
    dx[0] = x[1]
    if as_int(p[AT.nonlinear]):
        dx[1] = p[AT.a21] * np.sin(x[0]) + p[AT.b] * np.cos(x[0]) * u[0] + u[1]
    else:
        dx[1] = p[AT.a21] * x[0] + p[AT.b] * u[0] + u[1]


class CartPendulum(KernelBlock, ContinuousBlock):
    """Pendulum on a cart driven by the cart acceleration (§3.1): ``φ'' = a21 φ + b u + w``.

    With ``nonlinear=True``: ``φ'' = a21 sin φ + b cos φ · u + w`` (the model before linearisation,
    ``φ'' = 3g/(4l) sin φ + 3/(4l) cos φ · u`` with ``a21 = 3g/(4l)``, ``b = 3/(4l)``).

    Inputs ``u`` (m/s²), ``w`` (rad/s²); states and outputs ``phi`` (rad), ``dphi`` (rad/s).
    """

    inputs = ("u", "w")
    outputs = ("phi", "dphi")
    states = ("phi", "dphi")
    kernels = Kernels(rhs=pendulum_rhs)

    def __init__(self, a21: float, b: float, nonlinear: bool = False):
        self.a21, self.b, self.nonlinear = float(a21), float(b), bool(nonlinear)
        self.kernel_params = PENDULUM.pack(a21=self.a21, b=self.b, nonlinear=1.0 if self.nonlinear else 0.0)


DIFFERENCE = Layout("T")
DT = DIFFERENCE.at  # parameter offsets, a numba constant


def difference_output(t, x, u, p, y):
    """``ec(k) = (e(k) − e(k−1)) / T``, ``p`` = :data:`DIFFERENCE`."""
    y[0] = (u[0] - x[0]) / p[DT.T]


def difference_update(t, x, u, p, x_next):
    """``e_prev(k+1) = e(k)``."""
    x_next[0] = u[0]


class BackwardDifference(KernelBlock, DiscreteBlock):
    """``ec(k) = (e(k) − e(k−1)) / T``: the rate the fuzzy controller gets without a filter (state ``e(k−1)``)."""

    inputs = ("e",)
    outputs = ("ec",)
    states = ("e_prev",)
    feedthrough = True
    kernels = Kernels(output=difference_output, update=difference_update)

    def __init__(self, T: float):
        self.T = float(T)
        self.kernel_params = DIFFERENCE.pack(T=self.T)


class _Predictor(KernelBlock, DiscreteBlock):
    """A filter block's prediction half: the filter's state and update kernel, output = its state (no feedthrough)."""

    feedthrough = False

    def __init__(self, filt: KernelBlock, prefix: str):
        self.filt = filt
        self.inputs, self.states = filt.inputs, filt.states
        self.outputs = tuple(f"{prefix}.{s}" for s in filt.states)
        self.kernel_params = filt.kernel_params

    @property
    def kernels(self) -> Kernels:
        """The filter's update kernel; output = state (:func:`~ctrl_analysis.engine.kernels.copy_output`)."""
        k = self.filt.kernels
        return Kernels(output=copy_output, update=k.update, columns=k.columns)

    def initial_state(self):
        return self.filt.initial_state()


class _Corrector(KernelBlock, StaticBlock):
    """A filter block's correction half: its output kernel on ``(predictor state, y)``, a static block.

    The filter's output kernel reads the state from its inputs when the block has no state (the
    filters' kernels document this layout), on the batch's columns as in the compiled engine.
    """

    def __init__(self, filt: KernelBlock, pred: _Predictor):
        self.filt = filt
        self.inputs, self.outputs = pred.outputs + ("y",), tuple(filt.outputs)
        self.kernel_params = filt.kernel_params

    @property
    def kernels(self) -> Kernels:
        """The filter's output kernel (state read from the inputs)."""
        k = self.filt.kernels
        return Kernels(output=k.output, columns=k.columns)


def split_filter(filt: DiscreteBlock, name: str) -> list:
    """Place a filter whose output needs ``y(k)`` but not ``u(k)`` in a loop where ``u(k)`` depends on that output.

    :class:`~ctrl_analysis.engine.loop.Loop` treats feedthrough per block, so a filter with inputs
    ``(y, u)`` and direct feedthrough closes an algebraic loop with a controller that reads its
    estimate. The filter (a :class:`~ctrl_analysis.engine.kernels.KernelBlock`) is placed as two
    blocks that reuse its own kernels: a predictor (its state and update kernel, output = state, no
    feedthrough) and a static corrector (its output kernel evaluated on the predictor's state and ``y``).
    """
    if not isinstance(filt, KernelBlock):
        raise TypeError(f"filt must be a kernel-first filter block (KernelBlock), got {type(filt).__name__}")
    pred = _Predictor(filt, name)
    corr = _Corrector(filt, pred)
    return [place(pred, f"{name}.pred"), place(corr, f"{name}.corr")]
