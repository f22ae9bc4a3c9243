"""Levant's robust exact differentiator (arbitrary order), a discrete block with a compiled kernel.

The order-``n`` differentiator (Levant 2003, the non-recursive form) driven by the measured signal
``f`` with a known bound ``L >= |f^(n+1)|``::

    z_0' = v_0,   v_0 = -λ_n L^(1/(n+1)) |z_0 - f|^(n/(n+1)) sign(z_0 - f) + z_1
    z_i' = v_i,   v_i = -λ_(n-i) L^(1/(n+1-i)) |z_i - v_(i-1)|^((n-i)/(n+1-i)) sign(z_i - v_(i-1)) + z_(i+1)
    z_n' = -λ_0 L sign(z_n - v_(n-1))

Without noise ``z_i = f^(i)`` after a finite time, exactly (hence *exact*); with noise of bound ``ε``
the error of ``z_i`` is of order ``L^(i/(n+1)) ε^((n+1-i)/(n+1))``: for the first derivative of a
first-order differentiator ``√(εL)``, the order of the lower bound ``2√(εL)`` that no causal estimator
beats. Discretised here by explicit Euler with step ``h`` (``substeps`` steps per sample, the input
held), the usual implementation; without noise its error is then of order ``L h^(n+1-i)``.
"""

from __future__ import annotations

import numpy as np

from .._validate import check_finite, check_int, check_positive
from ..engine.blocks import DiscreteBlock, signal_names
from ..engine.integrators import MAX_SUBSTEPS
from ..engine.kernels import KernelBlock, Kernels, as_int, jitable

__all__ = ["LEVANT_GAINS", "MAX_ORDER", "LevantDifferentiator", "levant_output", "levant_update"]

#: Levant's gains λ_0, λ_1, ... (Levant 2003, sec. 7): the order-``n`` differentiator uses ``λ_0 .. λ_n``.
LEVANT_GAINS = (1.1, 1.5, 2.0, 3.0, 5.0, 8.0)
#: The highest order with published gains.
MAX_ORDER = len(LEVANT_GAINS) - 1


@jitable
def levant_update(t, x, u, p, x_next):
    """Kernel update of :class:`LevantDifferentiator`: ``substeps`` Euler steps of length ``h``, ``f`` held.

    Scalar indexing only: one run's vectors in the compiled engine, the batch's columns in the block's
    batched methods. The order is the state's length minus one.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        State ``z_0 .. z_n``.
    u : numpy.ndarray
        Input ``(f,)``.
    p : numpy.ndarray
        ``L``, ``h``, ``substeps``, then ``λ_n, λ_(n-1), ..., λ_0`` (the gain of ``z_0``'s equation first).
    x_next : numpy.ndarray
        Next state, written in place.
    """
    n = x.shape[0] - 1
    L, h = p[0], p[1]
    for i in range(n + 1):
        x_next[i] = x[i]
    for _ in range(as_int(p[2])):
        prev = u[0]
        # in place, i ascending: v_i reads z_i, z_(i+1) of the step's start (z_(i+1) is not yet moved) and v_(i-1)
        for i in range(n):
            k = n + 1 - i
            e = x_next[i] - prev
            v = -p[3 + i] * L ** (1.0 / k) * np.abs(e) ** ((k - 1.0) / k) * np.sign(e) + x_next[i + 1]
            x_next[i] = x_next[i] + h * v
            prev = v
        x_next[n] = x_next[n] - h * p[3 + n] * L * np.sign(x_next[n] - prev)


@jitable
def levant_output(t, x, u, p, y):
    """Kernel output of :class:`LevantDifferentiator`: the state ``z_0 .. z_n``.

    The state was reached with the inputs up to the previous sample (no feedthrough).

    Parameters
    ----------
    t, x, u, p
        As :func:`levant_update`.
    y : numpy.ndarray
        Outputs, written in place.
    """
    for i in range(x.shape[0]):
        y[i] = x[i]


class LevantDifferentiator(KernelBlock, DiscreteBlock):
    """Levant's robust exact differentiator of order ``n``: ``z_i`` estimates ``f^(i)``, ``i = 0 .. n``.

    Block signals: input ``f``; states and outputs ``z[0] .. z[n]``. The output at sample ``k`` is the
    state reached with the inputs up to ``k - 1`` (no feedthrough), like the other discrete estimators.

    Parameters
    ----------
    order : int
        ``n``, from 1 (the super-twisting differentiator: ``f`` and ``f'``) to :data:`MAX_ORDER`.
    L : float
        Bound on ``|f^(n+1)|``, ``> 0`` (Lipschitz constant of the highest derivative estimated).
    h : float
        Euler step, ``> 0``.
    substeps : int
        Euler steps per sample (1 to :data:`~ctrl_analysis.engine.integrators.MAX_SUBSTEPS`); a sample spans
        ``substeps * h``.
    gains : array_like, shape (order + 1,), optional
        ``λ_0 .. λ_n`` (default :data:`LEVANT_GAINS`), each ``> 0``.
    x0 : array_like, shape (order + 1,), optional
        Initial ``z`` (default zero).

    Raises
    ------
    ValueError
        ``order`` outside ``[1, MAX_ORDER]``, ``L``, ``h`` or a gain not finite and ``> 0``, ``substeps`` outside its
        range, or ``gains`` / ``x0`` of the wrong length.

    References
    ----------
    Levant A., "Higher-order sliding modes, differentiation and output-feedback control", Int. J. Control
    76(9-10), 924-941, 2003 (the differentiator, eq. (7), and its gains); Levant A., "Robust exact
    differentiation via sliding mode technique", Automatica 34(3), 379-384, 1998 (first order).

    Examples
    --------
    >>> import numpy as np
    >>> h = 0.001
    >>> t = h * np.arange(3000)
    >>> d = LevantDifferentiator(1, L=4.0, h=h)
    >>> y, _ = d.run(t ** 2)          # f' = 2t, |f''| = 2 <= L
    >>> bool(abs(y[-1, 0, 1] - 2 * t[-2]) < 0.02)   # exact up to the Euler step's chattering
    True
    """

    inputs = ("f",)
    feedthrough = False
    kernels = Kernels(output=levant_output, update=levant_update)

    def __init__(self, order: int, L: float, h: float, substeps: int = 1, gains=None, x0=None):
        self.order = check_int("order", order, minimum=1, maximum=MAX_ORDER)
        self.L = float(check_positive("L", L, scalar=True))
        self.h = float(check_positive("h", h, scalar=True))
        self.substeps = check_int("substeps", substeps, minimum=1, maximum=MAX_SUBSTEPS)
        n = self.order
        lam = np.array(LEVANT_GAINS[:n + 1] if gains is None else check_finite("gains", np.ravel(gains),
                                                                                 shape=(n + 1,)), dtype=float)
        check_positive("gains", lam)
        self.gains = lam
        self.x0 = np.zeros(n + 1) if x0 is None else check_finite("x0", np.ravel(x0), shape=(n + 1,))
        self.states = self.outputs = signal_names("z", n + 1)
        self.kernel_params = np.concatenate([[self.L, self.h, float(self.substeps)], lam[::-1]])

    def initial_state(self) -> np.ndarray:
        return np.array(self.x0, dtype=float)

    def __repr__(self) -> str:
        return f"LevantDifferentiator(order={self.order}, L={self.L}, h={self.h}, substeps={self.substeps})"
