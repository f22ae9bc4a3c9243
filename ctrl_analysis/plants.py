"""Plants as blocks: any SISO linear system, sampled with a zero-order hold, as a discrete block."""

from __future__ import annotations

import numpy as np

from ._validate import check_positive, check_vector, finite_result
from .engine.blocks import DiscreteBlock, signal_names
from .engine.kernels import KernelBlock, Kernels, Layout, as_int, jitable

__all__ = ["DiscreteLTI"]


#: The fixed head of a :class:`DiscreteLTI`'s kernel parameters: the order, the feedthrough switch
#: (1 when ``D != 0``) and ``D``; the arrays follow (:func:`lti_layout`).
HEAD = Layout("n", "has_D", "D")
AT = HEAD.at
_ARRAYS = HEAD.size


def lti_layout(n: int) -> Layout:
    """The kernel parameters of an ``n``-state :class:`DiscreteLTI`: :data:`HEAD`, then ``A`` (row-major), ``B``, ``C``.

    Parameters
    ----------
    n : int
        Number of states.

    Returns
    -------
    Layout
    """
    return Layout(*zip(HEAD.names, HEAD.shapes, strict=True), ("A", (n, n)), ("B", n), ("C", n))


@jitable
def _lti_at(p):
    """``(n, A, B, C)``: the order read from ``p`` and the offsets of :func:`lti_layout` ``(n)``'s arrays."""
    n = as_int(p[AT.n])
    return n, _ARRAYS, _ARRAYS + n * n, _ARRAYS + n * n + n


def lti_update(t, x, u, p, x_next):
    """``x(k+1) = A x(k) + B u(k)``, the update of :class:`DiscreteLTI`.

    Written with scalar indexing only, so it is both the compiled kernel of one run (``x`` of shape
    ``(n,)``) and, on a batch's columns, the block's batched method.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        The state ``x(k)``.
    u : numpy.ndarray
        The input ``[u(k)]``.
    p : numpy.ndarray
        :func:`lti_layout` ``(n)``.
    x_next : numpy.ndarray
        ``x(k+1)``, written in place (each row summed left to right, then ``+ B u``).
    """
    n, A, B, _ = _lti_at(p)
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc = acc + p[A + i * n + j] * x[j]
        x_next[i] = acc + u[0] * p[B + i]


def lti_output(t, x, u, p, y):
    """``y(k) = C x(k) + D u(k)`` (the ``D u`` term only when ``D != 0``), the output of :class:`DiscreteLTI`.

    Parameters
    ----------
    t, x, u, p
        As :func:`lti_update`.
    y : numpy.ndarray
        ``[y(k)]``, written in place.
    """
    n, _, _, C = _lti_at(p)
    acc = 0.0
    for j in range(n):
        acc = acc + x[j] * p[C + j]
    # a conditional expression, not an if statement: numba then prunes the arrays' reference counting
    y[0] = acc + p[AT.D] * u[0] if as_int(p[AT.has_D]) else acc


class DiscreteLTI(KernelBlock, DiscreteBlock):
    """A SISO linear system ``x(k+1) = A x(k) + B u(k)``, ``y(k) = C x(k) + D u(k)`` as a discrete block.

    A continuous-time ``control.TransferFunction`` or ``control.StateSpace`` is discretised with
    ``control.c2d(sys, dt, method="zoh")`` (exact for an input held over each sample); a
    discrete-time system is used as it is (its ``dt`` must be ``dt`` or unspecified). A delay
    ``z⁻¹`` is ``DiscreteLTI(control.tf([1], [1, 0], True), dt)``.

    Parameters
    ----------
    sys : control.TransferFunction or control.StateSpace
        A single-input single-output linear system.
    dt : float
        Sampling period (> 0).
    x0 : array_like, shape (n,), optional
        Initial state (default zeros).

    Attributes
    ----------
    A, B, C, D : numpy.ndarray
        Discrete matrices, shapes ``(n, n)``, ``(n,)``, ``(n,)`` and scalar ``D``.
    ss : control.StateSpace
        The discrete system (``dt`` set).

    Block signals: input ``u``; output ``y``; states ``x[0] .. x[n-1]``. Direct feedthrough iff ``D != 0``.

    Raises
    ------
    TypeError
        If ``sys`` is not a python-control LTI system.
    ValueError
        If ``sys`` is not SISO, ``dt`` is not > 0, or a discrete ``sys`` has another sampling period.

    Examples
    --------
    >>> import control as ct
    >>> import numpy as np
    >>> plant = DiscreteLTI(ct.tf([1], [1, 1]), dt=0.1)
    >>> y, _ = plant.run(np.ones(200))
    >>> round(float(y[-1, 0, 0]), 4)
    1.0
    """

    inputs = ("u",)
    outputs = ("y",)
    kernels = Kernels(output=lti_output, update=lti_update)

    def __init__(self, sys, dt: float, x0=None):
        import control as ct

        if not isinstance(sys, (ct.TransferFunction, ct.StateSpace)):
            raise TypeError(f"sys must be a control.TransferFunction or control.StateSpace, got {type(sys).__name__}")
        if sys.ninputs != 1 or sys.noutputs != 1:
            raise ValueError(f"sys must be SISO (1 input, 1 output), got {sys.ninputs} inputs and "
                             f"{sys.noutputs} outputs")
        self.dt = float(check_positive("dt", dt, scalar=True))
        if sys.isctime(strict=True):
            sysd = ct.c2d(ct.ss(sys), self.dt, method="zoh")
            finite_result("dt (with sys)", lambda: (sysd.A, sysd.B))
        else:
            if sys.dt is not True and sys.dt is not None and not np.isclose(sys.dt, self.dt):
                raise ValueError(f"sys is discrete with dt={sys.dt}, which must equal dt={self.dt}")
            sysd = ct.ss(sys)
            sysd = ct.ss(sysd.A, sysd.B, sysd.C, sysd.D, self.dt)
        self.ss = sysd
        self.A = np.asarray(sysd.A, dtype=float)
        self.B = np.asarray(sysd.B, dtype=float)[:, 0]
        self.C = np.asarray(sysd.C, dtype=float)[0, :]
        self.D = float(np.asarray(sysd.D)[0, 0])
        n = self.A.shape[0]
        self.states = signal_names("x", n)
        self.feedthrough = self.D != 0.0
        self._x0 = np.zeros(n) if x0 is None else check_vector("x0", x0, n, broadcast=False)
        self.kernel_params = lti_layout(n).pack(n=n, has_D=1.0 if self.feedthrough else 0.0, D=self.D, A=self.A,
                                                B=self.B, C=self.C)

    def initial_state(self) -> np.ndarray:
        return self._x0.copy()

    def __repr__(self) -> str:
        return f"DiscreteLTI(n={self.A.shape[0]}, dt={self.dt})"
