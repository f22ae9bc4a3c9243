"""High-order differential feedback: ``u = Σ k_i (θ_i - x̂_i)`` with a Hurwitz gain vector.

The controller needs only the plant order ``n``: the setpoint and its first ``n - 1``
derivatives ``θ = (v, v', ..., v^(n-1))`` and estimates ``x̂ = (x, x', ..., x^(n-1))`` of the
output and its derivatives (e.g. from a differential estimator), and feeds back the error vector
``ε = θ - x̂`` through ``K = [k_n, ..., k_1]``. On a chain of ``n`` integrators with exact
derivatives this places the closed-loop poles at the roots of ``s^n + k_1 s^(n-1) + ... + k_n``.
"""

from __future__ import annotations

import control as ct
import numpy as np

from .._validate import check_array, check_finite, check_int

__all__ = ["HighOrderDifferentialFeedback", "hurwitz_roots", "gains_from_poles"]


def _poly_text(n: int) -> str:
    return "s^n + k_1 s^(n-1) + ... + k_n" if n > 3 else " + ".join(
        ["s^%d" % n] + [f"k_{i} s^{n - i}" if n - i > 1 else (f"k_{i} s" if n - i == 1 else f"k_{i}")
                        for i in range(1, n + 1)])


def hurwitz_roots(K) -> np.ndarray:
    """Roots of ``s^n + k_1 s^(n-1) + ... + k_n`` for ``K = [k_n, ..., k_1]`` (the paper's order).

    Parameters
    ----------
    K : array_like, shape (n,)
        Gains in ascending powers of ``s``: ``K[0] = k_n`` multiplies ``s^0``.

    Returns
    -------
    numpy.ndarray
        The ``n`` roots, by decreasing real part.
    """
    K = np.atleast_1d(check_finite("K", K)).astype(float)
    if K.ndim != 1 or K.size < 1:
        raise ValueError(f"K must be a 1-D vector of n >= 1 gains, got shape {K.shape}")
    poly = np.concatenate(([1.0], K[::-1]))  # s^n + k_1 s^(n-1) + ... + k_n
    p = np.roots(poly)
    return p[np.lexsort((p.imag, -p.real))]


def gains_from_poles(poles) -> np.ndarray:
    """``K = [k_n, ..., k_1]`` that puts the roots of ``s^n + k_1 s^(n-1) + ... + k_n`` at ``poles``.

    Examples
    --------
    >>> gains_from_poles([-1.0, -2.0])
    array([2., 3.])
    """
    try:
        if isinstance(poles, (str, bytes)) or poles is None:
            raise TypeError
        poles = np.atleast_1d(np.asarray(poles, dtype=complex))
    except (TypeError, ValueError):
        raise TypeError(f"poles must be a sequence of real or complex numbers, got {poles!r}") from None
    if poles.ndim != 1 or poles.size < 1:
        raise ValueError(f"poles must be a 1-D sequence of n >= 1 poles, got shape {poles.shape}")
    if not np.all(np.isfinite(poles)):
        raise ValueError(f"poles must be finite, got {poles!r}")
    coeffs = np.poly(poles)  # [1, k_1, ..., k_n]
    if np.max(np.abs(coeffs.imag)) > 1e-9 * max(1.0, np.max(np.abs(coeffs.real))):
        raise ValueError("poles must be real or come in complex-conjugate pairs")
    return coeffs.real[1:][::-1].copy()


class HighOrderDifferentialFeedback:
    """Model-free high-order differential feedback ``u = K ε``, ``ε_i = θ_i - x̂_i``.

    Parameters
    ----------
    K : array_like
        Gains in the paper's order ``[k_n, k_(n-1), ..., k_1]``, i.e. ``u = k_n ε_1 + ... + k_1 ε_n``
        (``K[i]`` multiplies the ``i``-th derivative of the error). ``s^n + k_1 s^(n-1) + ... + k_n``
        must be Hurwitz. A vector of length ``n + 1`` whose last entry is ``1`` is read as the
        full coefficient list of that monic polynomial in ascending powers (``[k_n, ..., k_1, 1]``):
        the trailing 1 is the coefficient of ``s^n``, not a gain, and is dropped. This needs ``n``.
    n : int, optional
        Plant order; default ``len(K)``. With ``len(K) == n + 1`` the last entry must be 1.

    Attributes
    ----------
    K : numpy.ndarray, shape (n,)
        The gains ``[k_n, ..., k_1]`` actually applied.
    n : int
        Plant order.
    poles : numpy.ndarray
        Roots of ``s^n + k_1 s^(n-1) + ... + k_n`` (the closed-loop poles on a chain of
        integrators with exact derivatives).

    Raises
    ------
    ValueError
        If ``K`` is not finite, has the wrong length, has a trailing entry other than 1 when of
        length ``n + 1``, or does not make ``s^n + k_1 s^(n-1) + ... + k_n`` Hurwitz (every root
        with a negative real part).

    References
    ----------
    Qi Guoyuan, Chen Zengqiang, Xue Wei, Yuan Zhuzhi, "A new differential state estimator and
    controller for nonlinear stochastic system", Acta Electronica Sinica 32(4), 2004, eq. (18)
    and the Hurwitz condition below it; the paper's example prints ``K`` with ``n + 1`` entries.

    Examples
    --------
    >>> import numpy as np
    >>> ctrl = HighOrderDifferentialFeedback([6.0, 11.0, 6.0])
    >>> np.round(ctrl.poles.real, 9)
    array([-1., -2., -3.])
    >>> float(ctrl.u([1.0, 0.0, 0.0], [0.0, 0.0, 0.0]))
    6.0
    """

    def __init__(self, K, n: int | None = None):
        K = np.atleast_1d(check_finite("K", K)).astype(float)
        if K.ndim != 1:
            raise ValueError(f"K must be a 1-D gain vector, got shape {K.shape}")
        if n is None:
            n = K.size
        n = check_int("n", n, minimum=1)
        if K.size == n + 1:
            if K[-1] != 1.0:
                raise ValueError(
                    f"K of length n + 1 = {n + 1} must end with the leading coefficient 1 of the monic "
                    f"polynomial s^n + k_1 s^(n-1) + ... + k_n, got K[-1] = {K[-1]}"
                )
            K = K[:-1]
        elif K.size != n:
            raise ValueError(f"K must have n = {n} gains (or n + 1 ending in 1), got {K.size}")
        poles = hurwitz_roots(K)
        if not np.all(poles.real < 0):
            raise ValueError(
                f"K must make {_poly_text(n)} Hurwitz (all roots with negative real part), "
                f"got K = {K.tolist()} with roots {np.round(poles, 6).tolist()}"
            )
        self.K = K
        self.n = n
        self.poles = poles

    @property
    def characteristic_polynomial(self) -> np.ndarray:
        """``[1, k_1, ..., k_n]`` (highest power first)."""
        return np.concatenate(([1.0], self.K[::-1]))

    @property
    def gain_matrix(self) -> np.ndarray:
        """State-feedback row ``(1, n)``: ``u = -gain_matrix @ x̂`` when ``θ = 0``."""
        return self.K.reshape(1, -1).copy()

    def u(self, theta, x_hat) -> np.ndarray:
        """Control ``u = K (θ - x̂)`` (eq. 18), batched.

        Parameters
        ----------
        theta : array_like, shape (..., n)
            Setpoint and its derivatives ``(v, v', ..., v^(n-1))``.
        x_hat : array_like, shape (..., m), m >= n
            Estimates of the output and its derivatives; only the first ``n`` are used (so the
            states of a higher-order estimator may be passed as they are).

        Returns
        -------
        numpy.ndarray, shape (...)
            The control; a 0-d array for 1-D inputs.
        """
        theta = check_array("theta", theta)
        x_hat = check_array("x_hat", x_hat)
        if theta.ndim < 1 or theta.shape[-1] != self.n:
            raise ValueError(f"theta must have n = {self.n} entries on its last axis, got {theta.shape}")
        if x_hat.ndim < 1 or x_hat.shape[-1] < self.n:
            raise ValueError(f"x_hat must have at least n = {self.n} entries on its last axis, got {x_hat.shape}")
        # (18) u = K ε,  ε_i = θ_i - x̂_i,  K = [k_n, ..., k_1]
        return (theta - x_hat[..., : self.n]) @ self.K

    def closed_loop_chain(self) -> ct.StateSpace:
        """Closed loop of the chain of ``n`` integrators ``x^(n) = u`` under exact state feedback.

        Input ``v`` (a constant setpoint entering as ``θ = (v, 0, ..., 0)``), output ``x``; its
        poles are :attr:`poles` and its DC gain is 1.
        """
        n = self.n
        A = np.diag(np.ones(n - 1), 1)
        B = np.zeros((n, 1))
        B[-1, 0] = 1.0
        C = np.zeros((1, n))
        C[0, 0] = 1.0
        Acl = A - B @ self.gain_matrix
        Bcl = B * self.K[0]
        return ct.ss(Acl, Bcl, C, 0.0, inputs="v", outputs="x")

    def __repr__(self) -> str:
        return f"HighOrderDifferentialFeedback(K={self.K.tolist()}, poles={np.round(self.poles, 6).tolist()})"
