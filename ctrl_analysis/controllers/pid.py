"""Discrete PID controller with a filtered derivative and anti-windup, a kernel-first block.

Written by following CONTRIBUTING.md's recipe "Add a block" (the block's module, its tests, a
row of the fuzz table, a docs entry): the equations are the two kernels below, once; the batched
methods, the compiled engine, ``nlsys`` and per-run parameters
(``Loop.simulate(params={"pid": {"kp": ...}})``) come from :class:`~ctrl_analysis.engine.kernels.KernelBlock`.
"""

from __future__ import annotations

import numpy as np

from .._validate import check_nonnegative, check_positive, check_real
from ..engine.blocks import DiscreteBlock
from ..engine.kernels import KernelBlock, Kernels, Layout

__all__ = ["DiscretePID"]

PID = Layout("kp", "ki", "kd", "T", "Tf", "u_min", "u_max")
AT = PID.at  # parameter offsets, a numba constant


def pid_output(t, x, u, p, y):
    """``u(k) = sat(Kp e + I + D)``, ``D(k) = a D(k-1) + b (e(k) - e(k-1))``; state ``[I, D, e_prev]``."""
    a = p[AT.Tf] / (p[AT.Tf] + p[AT.T])
    d = a * x[1] + (p[AT.kd] / (p[AT.Tf] + p[AT.T])) * (u[0] - x[2])  # backward-Euler filtered derivative
    y[0] = np.minimum(np.maximum(p[AT.kp] * u[0] + x[0] + d, p[AT.u_min]), p[AT.u_max])  # saturation


def pid_update(t, x, u, p, x_next):
    """``I(k+1) = I(k) + Ki T e(k)`` only while the output is not saturated (conditional integration)."""
    a = p[AT.Tf] / (p[AT.Tf] + p[AT.T])
    d = a * x[1] + (p[AT.kd] / (p[AT.Tf] + p[AT.T])) * (u[0] - x[2])
    v = p[AT.kp] * u[0] + x[0] + d
    free = (v >= p[AT.u_min]) * (v <= p[AT.u_max])  # 1 inside the limits, 0 when saturated
    x_next[0] = x[0] + free * (p[AT.ki] * p[AT.T]) * u[0]
    x_next[1] = d
    x_next[2] = u[0]


class DiscretePID(KernelBlock, DiscreteBlock):
    """Discrete PID ``u = sat(Kp e + Ki T Σ e + D)`` with derivative filter ``Tf`` and anti-windup.

    The integral is the forward sum ``I(k+1) = I(k) + Ki T e(k)``; the derivative is the backward
    difference through a first-order filter, ``D(k) = Tf/(Tf+T) D(k-1) + Kd/(Tf+T) (e(k) - e(k-1))``
    (``Tf = 0``: the plain difference ``Kd (e(k) - e(k-1)) / T``). The output is clipped to
    ``[u_min, u_max]`` and the integral is frozen while it is (conditional integration). Inside the
    limits the block is linear with transfer function :meth:`tf`.

    Parameters
    ----------
    kp, ki, kd : float
        Proportional, integral (1/s) and derivative (s) gains, each >= 0.
    T : float
        Sampling period (s, > 0).
    Tf : float
        Derivative filter time constant (s, >= 0).
    u_min, u_max : float
        Output limits (``u_min < u_max``; infinite: no saturation).

    Raises
    ------
    ValueError
        If a gain or ``Tf`` is negative, ``T`` is not positive, or ``u_min >= u_max``.

    Examples
    --------
    >>> import numpy as np
    >>> pid = DiscretePID(kp=2.0, ki=1.0, kd=0.0, T=0.1)
    >>> y, x = pid.run(np.ones(3))  # a unit error: Kp e + Ki T (0, 1, 2) e
    >>> y[:, 0, 0]
    array([2. , 2.1, 2.2])
    """

    inputs, outputs, states = ("e",), ("u",), ("I", "D", "e_prev")
    feedthrough = True
    kernels = Kernels(output=pid_output, update=pid_update)

    def __init__(self, kp=1.0, ki=0.0, kd=0.0, T=1.0, Tf=0.0, u_min=-np.inf, u_max=np.inf):
        self.kp, self.ki, self.kd = (check_nonnegative(n, v) for n, v in (("kp", kp), ("ki", ki), ("kd", kd)))
        self.T = check_positive("T", T, scalar=True)
        self.Tf = check_nonnegative("Tf", Tf)
        self.u_min, self.u_max = check_real("u_min", u_min), check_real("u_max", u_max)
        if not self.u_min < self.u_max:
            raise ValueError(f"u_min must be < u_max, got u_min = {u_min}, u_max = {u_max}")
        self.kernel_params = PID.pack(kp=self.kp, ki=self.ki, kd=self.kd, T=self.T, Tf=self.Tf,
                                      u_min=self.u_min, u_max=self.u_max)

    def tf(self):
        """The unsaturated controller ``E -> U`` as a discrete transfer function (period ``T``).

        ``Kp + Ki T z⁻¹/(1 - z⁻¹) + Kd/(Tf+T) (1 - z⁻¹)/(1 - Tf/(Tf+T) z⁻¹)``.

        Returns
        -------
        control.TransferFunction
        """
        import control as ct

        z = ct.tf([1.0, 0.0], [1.0], self.T)
        a = self.Tf / (self.Tf + self.T)
        return self.kp + self.ki * self.T / (z - 1) + (self.kd / (self.Tf + self.T)) * (z - 1) / (z - a)

    def __repr__(self) -> str:
        return (f"DiscretePID(kp={self.kp:g}, ki={self.ki:g}, kd={self.kd:g}, T={self.T:g}, Tf={self.Tf:g}, "
                f"u_min={self.u_min:g}, u_max={self.u_max:g})")
