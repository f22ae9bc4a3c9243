"""Golden-section adaptive control with maintaining tracking and a logic integral, on a 2nd-order model."""

from __future__ import annotations

import numpy as np

from .._validate import check_finite, check_nonnegative, check_positive
from ..engine.blocks import DiscreteBlock
from ..engine.kernels import KernelBlock, Kernels, Layout, jitable

__all__ = ["GOLDEN_L1", "GOLDEN_L2", "GoldenSectionController"]

#: Golden-section coefficients ``l1 = 1 − 0.618``, ``l2 = (√5 − 1)/2 ≈ 0.618`` (as printed: 0.382, 0.618).
GOLDEN_L1 = 0.382
GOLDEN_L2 = 0.618

#: The kernel parameters of :class:`GoldenSectionController`.
LAYOUT = Layout("k_I", "c1", "c2", "mu", "l1", "l2")
AT = LAYOUT.at  # parameter offsets, a numba constant


@jitable
def _golden_step(x, u, p):
    """One run of the law with scalar branches: ``(u(k), e(k), u_i(k))``."""
    y, r, f1, f2, g0 = u[0], u[1], u[2], u[3], u[4]
    e = y - r
    e_prev, r_prev = (x[0], x[1]) if x[3] > 0.0 else (e, r)  # before the first sample: e(k−1) := e(k), r(k−1) := r(k)
    # (17) golden section u_l(k) = −(l1 f̂1 e(k) + l2 f̂2 e(k−1)) / (ĝ0 + μ)
    ul = -(p[AT.l1] * f1 * e + p[AT.l2] * f2 * e_prev) * (1.0 / (g0 + p[AT.mu]))
    # (18) maintaining tracking u_0(k) = (r(k+1) − f̂1 r(k) − f̂2 r(k−1)) / ĝ0, r(k+1) := r(k)
    u0 = (r - f1 * r - f2 * r_prev) / g0
    # (19) logic integral u_i(k) = c u_i(k−1) − k_I e(k), c = c1 if e (e − e(k−1)) > 0 else c2
    ui = (p[AT.c1] if e * (e - e_prev) > 0.0 else p[AT.c2]) * x[2] - p[AT.k_I] * e
    return u0 + ul + ui, e, ui  # (20) u = u_0 + u_l + u_i


def golden_output(t, x, u, p, y):
    """The output kernel of :class:`GoldenSectionController`: ``y = [u(k)]``, eq. (17)-(20).

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        ``[e(k−1), r(k−1), u_i(k−1), started]`` of one run.
    u : numpy.ndarray
        ``[y, r, f1, f2, g0]``.
    p : numpy.ndarray
        :data:`LAYOUT`.
    y : numpy.ndarray
        Written in place.
    """
    y[0] = _golden_step(x, u, p)[0]


def golden_update(t, x, u, p, x_next):
    """The update kernel of :class:`GoldenSectionController`: ``[e(k), r(k), u_i(k), 1]``.

    Parameters
    ----------
    t, x, u, p
        As :func:`golden_output`.
    x_next : numpy.ndarray
        Written in place.
    """
    _, e, ui = _golden_step(x, u, p)
    x_next[0] = e
    x_next[1] = u[1]
    x_next[2] = ui
    x_next[3] = 1.0


class GoldenSectionController(KernelBlock, DiscreteBlock):
    """``u = u_0 + u_l + u_i`` for the characteristic model ``x(k+1) = f1 x(k) + f2 x(k−1) + g0 u(k)``.

    With ``e(k) = y(k) − r(k)`` and the current estimates ``f̂1, f̂2, ĝ0`` (inputs)::

        u_l(k) = −(l1 f̂1 e(k) + l2 f̂2 e(k−1)) / (ĝ0 + μ)              golden-section feedback
        u_0(k) = (r(k+1) − f̂1 r(k) − f̂2 r(k−1)) / ĝ0                  maintaining tracking
        u_i(k) = c u_i(k−1) − k_I e(k),  c = c1 if e(k) (e(k) − e(k−1)) > 0 else c2   logic integral
        u(k)   = u_0(k) + u_l(k) + u_i(k)

    ``r(k+1)`` is not known to a block fed ``r(k)``; it is taken as ``r(k)`` (exact for a constant
    or piecewise-constant reference except at its jumps).

    Parameters
    ----------
    k_I : float
        Integral gain (>= 0).
    c2 : float
        Leak of the integral while the error shrinks, ``0 < c2 <= c1``.
    c1 : float
        Integral factor while the error grows (``0 < c1 <= 1``; 1 in the literature).
    mu : float
        Regularisation of ``1/ĝ0`` in the golden-section term: ``1/(ĝ0 + μ)`` (>= 0), as in Wu's
        golden-section law. ``u_0`` divides by ``ĝ0`` itself (so that it holds exactly the
        steady state of the identified model); the caller must keep ``ĝ0`` away from zero (e.g. by
        projecting the identification onto ``ĝ0 >= g0_min``).
    l1, l2 : float
        Golden-section coefficients (default 0.382, 0.618).

    Block signals: inputs ``y, r, f1, f2, g0``; output ``u``; states ``e_prev`` (``e(k−1)``),
    ``r_prev`` (``r(k−1)``), ``ui_prev`` (``u_i(k−1)``), ``started`` (0 before the first sample, when
    ``r(k−1) := r(k)`` and ``e(k−1) := e(k)``, then 1). Direct feedthrough.

    Raises
    ------
    ValueError
        ``k_I < 0``, ``mu < 0``, or ``c1, c2`` not with ``0 < c2 <= c1 <= 1``.

    References
    ----------
    Wu H., Liu Y., Liu Z., et al., "Characteristic modeling and the control of flexible
    structures", Science in China (E) 31(2), 2001 (the golden-section law, maintaining tracking,
    logic integral); Gong & Wu 2010, eq. (16)-(20), whose formulas were lost in extraction: the
    forms above are the standard ones. Departure: ``r(k+1) := r(k)``.

    Examples
    --------
    >>> import numpy as np
    >>> ctrl = GoldenSectionController(k_I=0.0, c2=0.9, mu=0.0)
    >>> u = ctrl.output(0.0, ctrl.initial_state()[None, :], np.array([[0.0, 1.0, 1.9, -0.9, 0.1]]))
    >>> round(float(u[0, 0]), 6)    # e = e(k−1) = −1: u_0 = 0, u_l = (0.382·1.9 − 0.618·0.9)/0.1
    1.696
    """

    inputs = ("y", "r", "f1", "f2", "g0")
    outputs = ("u",)
    states = ("e_prev", "r_prev", "ui_prev", "started")
    feedthrough = True
    kernels = Kernels(output=golden_output, update=golden_update, columns=False)  # branches per value

    def __init__(self, k_I: float = 0.0, c2: float = 0.9, c1: float = 1.0, mu: float = 0.0,
                 l1: float = GOLDEN_L1, l2: float = GOLDEN_L2):
        self.k_I = float(check_nonnegative("k_I", k_I, scalar=True))
        self.c1 = float(check_finite("c1", c1, scalar=True))
        self.c2 = float(check_finite("c2", c2, scalar=True))
        if not 0.0 < self.c2 <= self.c1 <= 1.0:
            raise ValueError(f"c1, c2 must satisfy 0 < c2 <= c1 <= 1, got c1={self.c1}, c2={self.c2}")
        self.mu = float(check_nonnegative("mu", mu, scalar=True))
        self.l1 = float(check_positive("l1", l1, scalar=True))
        self.l2 = float(check_positive("l2", l2, scalar=True))
        self.kernel_params = LAYOUT.pack(k_I=self.k_I, c1=self.c1, c2=self.c2, mu=self.mu, l1=self.l1, l2=self.l2)

    def initial_state(self) -> np.ndarray:
        return np.zeros(4)

    def __repr__(self) -> str:
        return f"GoldenSectionController(k_I={self.k_I:g}, c2={self.c2:g}, mu={self.mu:g})"

