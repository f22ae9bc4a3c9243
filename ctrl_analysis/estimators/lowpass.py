"""Low-pass filters ``W(s) = ω_f^m / (s + ω_f)^m`` (m = 1, 2): continuous block and exact digital form.

The same filter serves as a continuous block (:attr:`LowPassFilter.ss`, :attr:`LowPassFilter.tf`,
:meth:`LowPassFilter.rhs`) and as a digital filter for a signal or a parameter vector sampled with a
fixed period and held between samples (:meth:`LowPassFilter.discretize` gives the exact
zero-order-hold discretisation; :class:`DiscreteLowPass` steps it over any number of channels and
batch runs).
"""

from __future__ import annotations

from math import comb

import numpy as np

from .._validate import check_array, check_finite, check_int, check_positive

__all__ = ["LowPassFilter", "DiscreteLowPass"]


class LowPassFilter:
    """Continuous low-pass ``W(s) = ω_f^m / (s + ω_f)^m`` of order ``m`` (unit DC gain, m-fold pole).

    Controllable canonical realisation with states ``[w, w', ..., w^(m-1)]``::

        w^(m) = ω_f^m (u - w) - Σ_{i=1}^{m-1} C(m, i) ω_f^i w^(m-i)

    Parameters
    ----------
    omega_f : float
        Corner frequency of each pole in rad/s (> 0).
    order : int
        1 or 2.

    References
    ----------
    Chen Z., Gao Q., "Modified extended state observer: analysis and implementation", Control
    Theory & Applications 35(8), 2018, section 4: ``W(s) = ω_f² / (s + ω_f)²`` smooths the
    identified parameters before they enter the observer and the controller.

    Examples
    --------
    >>> import numpy as np
    >>> W = LowPassFilter(2.0)
    >>> np.allclose(W.tf.den[0][0], [1, 4.0, 4.0])
    True
    """

    def __init__(self, omega_f: float, order: int = 2):
        self.omega_f = float(check_positive("omega_f", omega_f, scalar=True))
        self.order = check_int("order", order, minimum=1, maximum=2)
        m, w = self.order, self.omega_f
        # characteristic polynomial (s + ω_f)^m = s^m + Σ C(m, i) ω_f^i s^(m-i)
        self._den = np.array([comb(m, i) * w**i for i in range(m + 1)], dtype=float)
        A = np.zeros((m, m))
        A[:-1, 1:] = np.eye(m - 1)
        A[-1, :] = -self._den[:0:-1]
        self.A = A
        self.B = np.zeros((m, 1))
        self.B[-1, 0] = w**m
        self.C = np.zeros((1, m))
        self.C[0, 0] = 1.0

    @property
    def ss(self):
        """The filter as :class:`control.StateSpace` (input ``u``, output ``w``)."""
        import control as ct

        return ct.ss(self.A, self.B, self.C, np.zeros((1, 1)), inputs="u", outputs="w")

    @property
    def tf(self):
        """The filter as :class:`control.TransferFunction`: ``ω_f^m / (s + ω_f)^m``."""
        import control as ct

        return ct.tf([self.omega_f**self.order], self._den, inputs="u", outputs="w")

    def rhs(self, t, x, u, params=None) -> np.ndarray:
        """``dx/dt`` with ``x`` of shape (..., m) and ``u`` of shape (..., 1) (python-control order)."""
        x = np.asarray(x, dtype=float)
        u = np.asarray(u, dtype=float)[..., 0]
        return x @ self.A.T + u[..., None] * self.B[:, 0]

    def discretize(self, h: float):
        """Exact zero-order-hold discretisation ``x(k+1) = Ad x(k) + Bd u(k)`` for sample period ``h``.

        Returns ``(Ad, Bd)`` with ``Bd`` of shape (m,).
        """
        import control as ct

        h = float(check_positive("h", h, scalar=True))
        sysd = ct.c2d(ct.ss(self.A, self.B, np.eye(self.order), 0), h, method="zoh")
        return np.asarray(sysd.A), np.asarray(sysd.B)[:, 0]

    def digital(self, h: float, shape=(), initial=None) -> "DiscreteLowPass":
        """A :class:`DiscreteLowPass` for sample period ``h`` over signals of ``shape``."""
        return DiscreteLowPass(self, h, shape=shape, initial=initial)


class DiscreteLowPass:
    """Digital form of a :class:`LowPassFilter` (exact for inputs held over each sample period).

    Filters every entry of an array of ``shape`` (e.g. ``(B, p)`` for ``B`` runs of a
    ``p``-parameter vector) independently.

    Parameters
    ----------
    lowpass : LowPassFilter
    h : float
        Sample period (> 0).
    shape : tuple
        Shape of the filtered signal.
    initial : array_like, optional
        Initial output (the filter starts at rest at this value; default 0).

    Attributes
    ----------
    x : ndarray, shape shape + (m,)
        Filter state ``[w, w', ...]``.
    Ad, Bd : ndarray
        Discretised matrices.
    """

    def __init__(self, lowpass: LowPassFilter, h: float, shape=(), initial=None):
        if not isinstance(lowpass, LowPassFilter):
            raise TypeError(f"lowpass must be a LowPassFilter, got {type(lowpass).__name__}")
        self.lowpass = lowpass
        self.h = float(check_positive("h", h, scalar=True))
        if isinstance(shape, (int, np.integer)):
            shape = (shape,)
        if not isinstance(shape, (tuple, list)):
            raise TypeError(f"shape must be a tuple of sizes (the batch shape), got {shape!r}")
        self.shape = tuple(check_int("shape", n, minimum=1) for n in shape)
        self.Ad, self.Bd = lowpass.discretize(self.h)
        if initial is not None:
            initial = np.asarray(check_finite("initial", initial), dtype=float)
            if initial.shape not in ((), self.shape):
                raise ValueError(f"initial must be a scalar or have shape {self.shape}, got {initial.shape}")
        self.initial = None if initial is None else np.broadcast_to(initial, self.shape).copy()
        self.reset()

    def reset(self) -> None:
        """Back to rest at the initial output."""
        self.x = np.zeros(self.shape + (self.lowpass.order,))
        if self.initial is not None:
            self.x[..., 0] = self.initial

    @property
    def output(self) -> np.ndarray:
        """Current filter output ``w`` (shape ``shape``)."""
        return self.x[..., 0].copy()

    def step(self, u) -> np.ndarray:
        """Advance one sample with input ``u`` (held over the period); return the new output.

        ``u`` is a scalar or has the batch ``shape``; NaN passes through (a diverged run stays NaN
        in its own entry).
        """
        u = check_array("u", u)
        if u.shape not in ((), self.shape):
            raise ValueError(f"u must be a scalar or have shape {self.shape}, got {u.shape}")
        # x(k+1) = Ad x(k) + Bd u(k)   (exact ZOH discretisation of W(s))
        self.x = self.x @ self.Ad.T + u[..., None] * self.Bd
        return self.x[..., 0].copy()

    def filter(self, u) -> np.ndarray:
        """Filter a whole record ``u`` of shape (N,) + shape; returns the outputs after each step."""
        u = np.asarray(u, dtype=float)
        out = np.empty_like(u)
        for k in range(u.shape[0]):
            out[k] = self.step(u[k])
        return out
