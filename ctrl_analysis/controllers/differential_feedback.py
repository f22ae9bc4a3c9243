"""High-order differential feedback: ``u = Σ k_i (θ_i - x̂_i)`` with a Hurwitz gain vector.

The controller needs only the plant order ``n``: the setpoint and its first ``n - 1``
derivatives ``θ = (v, v', ..., v^(n-1))`` and estimates ``x̂ = (x, x', ..., x^(n-1))`` of the
output and its derivatives (e.g. from a differential estimator), and feeds back the error vector
``ε = θ - x̂`` through ``K = [k_n, ..., k_1]``. On a chain of ``n`` integrators with exact
derivatives this places the closed-loop poles at the roots of ``s^n + k_1 s^(n-1) + ... + k_n``.
The controller is a static kernel-first block (:class:`~ctrl_analysis.engine.kernels.KernelBlock`,
:class:`~ctrl_analysis.engine.blocks.StaticBlock`): no state, direct feedthrough; its kernel
:func:`feedback_output` is the batched method (on the batch's columns) and the compiled engine's
kernel, so it runs in :class:`~ctrl_analysis.engine.loop.Loop` and in ``control.interconnect``.
"""

from __future__ import annotations

import control as ct
import numpy as np

from .._validate import check_array, check_bool, check_finite
from ..engine.blocks import StaticBlock, signal_names
from ..engine.kernels import KernelBlock, Kernels, Layout

__all__ = ["HighOrderDifferentialFeedback", "gains_from_poles", "hurwitz_roots"]


def feedback_layout(n: int) -> Layout:
    """The parameters of :func:`feedback_output` for plant order ``n``: the gains ``K = [k_n, ..., k_1]``.

    Parameters
    ----------
    n : int
        Plant order (the number of gains).

    Returns
    -------
    Layout
    """
    return Layout(("K", n))


AT = feedback_layout(1).at  # offsets (the same for every n), a numba constant


def feedback_output(t, x, u, p, y):
    """Eq. (18) ``u = Σ k_i (θ_i - x̂_i)`` for one run, or for a batch's columns; ``p`` = :func:`feedback_layout`.

    Written with scalar indexing only: it is the compiled kernel of one run (``u`` of shape ``(2n,)``)
    and, called on a batch's transposed arrays (``u.T`` of shape ``(2n, B)``, ``y.T``), the block's
    batched method (:class:`~ctrl_analysis.engine.kernels.KernelBlock`), so both engines evaluate the
    same expression in the same order. The order ``n`` is the length of ``p``.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray or None
        State (unused: the block is static).
    u : numpy.ndarray, shape (2n,) or (2n, B)
        ``[θ_1..θ_n, x̂_1..x̂_n]``.
    p : numpy.ndarray, shape (n,) or (n, B)
        The gains ``K`` (one column per run on the batch's columns with per-run gains).
    y : numpy.ndarray, shape (1,) or (1, B)
        The control, written in place.
    """
    n = p.shape[0]
    # (18) u = K ε,  ε_i = θ_i - x̂_i,  K = [k_n, ..., k_1], summed left to right
    acc = p[AT.K] * (u[0] - u[n])
    for i in range(1, n):
        acc = acc + p[AT.K + i] * (u[i] - u[n + i])
    y[0] = acc


def _poly_text(n: int) -> str:
    return "s^n + k_1 s^(n-1) + ... + k_n" if n > 3 else " + ".join(
        [f"s^{n}"] + [f"k_{i} s^{n - i}" if n - i > 1 else (f"k_{i} s" if n - i == 1 else f"k_{i}")
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


def gains_from_poles(poles, *, allow_unstable: bool = False) -> np.ndarray:
    """``K = [k_n, ..., k_1]`` that puts the roots of ``s^n + k_1 s^(n-1) + ... + k_n`` at ``poles``.

    Parameters
    ----------
    poles : array_like of complex
        The ``n`` desired roots (finite; complex ones in conjugate pairs; in the open left
        half-plane, as :class:`HighOrderDifferentialFeedback` requires).
    allow_unstable : bool
        Accept poles with a real part >= 0 (default ``False``: such gains make the closed loop
        unstable, and the feedback block refuses them).

    Returns
    -------
    numpy.ndarray, shape (n,)
        Real gains in the paper's order ``[k_n, ..., k_1]``.

    Raises
    ------
    ValueError
        If a pole is not finite, a complex pole has no conjugate, or (without ``allow_unstable``)
        a pole has a real part >= 0.

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
    if not check_bool("allow_unstable", allow_unstable) and np.max(poles.real) >= 0:
        raise ValueError(f"poles must lie in the open left half-plane (Re < 0; allow_unstable=True to accept "
                         f"others), got {complex(poles[np.argmax(poles.real)]):.4g}")
    coeffs = np.poly(poles)  # [1, k_1, ..., k_n]
    if np.max(np.abs(coeffs.imag)) > 1e-9 * max(1.0, np.max(np.abs(coeffs.real))):
        raise ValueError("poles must be real or come in complex-conjugate pairs")
    return coeffs.real[1:][::-1].copy()


class HighOrderDifferentialFeedback(KernelBlock, StaticBlock):
    """Model-free high-order differential feedback ``u = K ε``, ``ε_i = θ_i - x̂_i``: a static block.

    Stateless with direct feedthrough; inputs ``theta[0..n-1]`` (the setpoint and its first
    ``n - 1`` derivatives) then ``xhat[0..n-1]`` (estimates of the output and its derivatives),
    output ``u``. Kernel :func:`feedback_output`; gains per run are given to the simulation:
    ``Loop.simulate(params={"ctrl": {"K": (B, n) gains}})``.

    Parameters
    ----------
    K : array_like, shape (n,)
        Gains in the paper's order ``[k_n, k_(n-1), ..., k_1]``, i.e. ``u = k_n ε_1 + ... + k_1 ε_n``
        (``K[i]`` multiplies the ``i``-th derivative of the error); ``n = len(K)`` is the plant
        order. ``s^n + k_1 s^(n-1) + ... + k_n`` must be Hurwitz.

    Attributes
    ----------
    K : numpy.ndarray, shape (n,)
        The gains ``[k_n, ..., k_1]``.
    n : int
        Plant order.
    poles : numpy.ndarray
        Roots of ``s^n + k_1 s^(n-1) + ... + k_n`` (the closed-loop poles on a chain of
        integrators with exact derivatives).

    Raises
    ------
    ValueError
        If ``K`` is not a finite 1-D vector or does not make ``s^n + k_1 s^(n-1) + ... + k_n``
        Hurwitz (every root with a negative real part).

    References
    ----------
    Qi Guoyuan, Chen Zengqiang, Xue Wei, Yuan Zhuzhi, "A new differential state estimator and
    controller for nonlinear stochastic system", Acta Electronica Sinica 32(4), 2004, eq. (18)
    and the Hurwitz condition below it. The paper's example prints ``K`` with an extra trailing
    entry 1 (the coefficient of ``s^n``); reading that vector is the study's business, this block
    takes the ``n`` gains only.

    Examples
    --------
    >>> import numpy as np
    >>> ctrl = HighOrderDifferentialFeedback([6.0, 11.0, 6.0])
    >>> np.round(ctrl.poles.real, 9)
    array([-1., -2., -3.])
    >>> ctrl.inputs
    ('theta[0]', 'theta[1]', 'theta[2]', 'xhat[0]', 'xhat[1]', 'xhat[2]')
    >>> float(ctrl.u([1.0, 0.0, 0.0], [0.0, 0.0, 0.0]))
    6.0
    """

    kernels = Kernels(output=feedback_output)

    def __init__(self, K):
        K = np.atleast_1d(check_finite("K", K)).astype(float)
        if K.ndim != 1:
            raise ValueError(f"K must be a 1-D gain vector, got shape {K.shape}")
        n = K.size
        poles = hurwitz_roots(K)
        if not np.all(poles.real < 0):
            raise ValueError(
                f"K must make {_poly_text(n)} Hurwitz (all roots with negative real part), "
                f"got K = {K.tolist()} with roots {np.round(poles, 6).tolist()}"
            )
        K.setflags(write=False)
        self.K = K
        self.n = n
        self.poles = poles
        self.inputs, self.outputs = signal_names("theta", n) + signal_names("xhat", n), ("u",)
        self.kernel_params = feedback_layout(n).pack(K=K)

    @property
    def characteristic_polynomial(self) -> np.ndarray:
        """``[1, k_1, ..., k_n]`` (highest power first)."""
        return np.concatenate(([1.0], self.K[::-1]))

    @property
    def gain_matrix(self) -> np.ndarray:
        """State-feedback row ``(1, n)``: ``u = -gain_matrix @ x̂`` when ``θ = 0``."""
        return self.K.reshape(1, -1).copy()

    def u(self, theta, x_hat) -> np.ndarray:
        """Control ``u = K (θ - x̂)`` (eq. 18) for arrays outside a loop, batched on leading axes.

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

        Raises
        ------
        ValueError
            If ``theta`` does not have ``n`` entries or ``x_hat`` fewer than ``n`` on the last axis.
        """
        theta = check_array("theta", theta)
        x_hat = check_array("x_hat", x_hat)
        if theta.ndim < 1 or theta.shape[-1] != self.n:
            raise ValueError(f"theta must have n = {self.n} entries on its last axis, got {theta.shape}")
        if x_hat.ndim < 1 or x_hat.shape[-1] < self.n:
            raise ValueError(f"x_hat must have at least n = {self.n} entries on its last axis, got {x_hat.shape}")
        lead = np.broadcast_shapes(theta.shape[:-1], x_hat.shape[:-1])
        th = np.broadcast_to(theta, lead + (self.n,)).reshape(-1, self.n)
        xh = np.broadcast_to(x_hat[..., : self.n], lead + (self.n,)).reshape(-1, self.n)
        out = self.batched("output", 0.0, None, np.concatenate([th, xh], axis=1), self.kernel_params)
        return out[:, 0].reshape(lead)

    def closed_loop_chain(self) -> ct.StateSpace:
        """Closed loop of the chain of ``n`` integrators ``x^(n) = u`` under exact state feedback.

        Input ``v`` (a constant setpoint entering as ``θ = (v, 0, ..., 0)``), output ``x``; its
        poles are :attr:`poles` and its DC gain is 1.

        Returns
        -------
        control.StateSpace
            The ``n``-state closed loop ``v -> x``.
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
