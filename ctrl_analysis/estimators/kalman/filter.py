"""Time-varying discrete Kalman filter (scalar measurement) as a discrete block batched over runs."""

from __future__ import annotations

import numpy as np

from ..._validate import check_finite, check_matrix, check_positive
from ...engine.blocks import DiscreteBlock, signal_names
from ...engine.kernels import KernelBlock, Kernels, Layout, as_int, jitable, offset, scratch
from ...engine.matrix import add_mat_mul_t, dot, mat_mul, mat_vec, matrix, scratch_matrix, sub_dot, vector

__all__ = ["DiscreteKalmanFilter"]


#: The kernel parameters of a :class:`DiscreteKalmanFilter` of any order ``n``: the order, the input
#: switch (1 with ``b``), ``R``, then ``h, F, Qd, b`` (``b`` zeros without an input; matrices row-major).
LAYOUT = Layout("n", "has_b", "R", ("h", "n"), ("F", ("n", "n")), ("Qd", ("n", "n")), ("b", "n"))
AT = LAYOUT.at


def kalman_layout(n: int) -> Layout:
    """The kernel parameters of an ``n``-state :class:`DiscreteKalmanFilter`: :data:`LAYOUT` for this ``n``.

    Parameters
    ----------
    n : int
        Number of states.

    Returns
    -------
    Layout
    """
    return LAYOUT.sized(n=n)


@jitable
def _kf_params(p):
    """``(n, h, F, Qd, b)``: the order read from ``p`` and views of :data:`LAYOUT`'s arrays."""
    n = as_int(p[AT.n])
    return (n, vector(p, offset(AT.h, n), n), matrix(p, offset(AT.F, n), n, n), matrix(p, offset(AT.Qd, n), n, n),
            vector(p, offset(AT.b, n), n))


def kalman_output(t, x, u, p, y):
    """The output of :class:`DiscreteKalmanFilter`: ``x̂(k|k) = x̂(k|k−1) + K(k) (y(k) − h x̂(k|k−1))``.

    One run in the compiled engine, the batch's columns in the batched methods
    (:mod:`ctrl_analysis.engine.matrix`). With an empty ``x`` (a static corrector placed after a
    predictor that holds the state) the state is read from ``u[0 : n + n²]`` and ``y(k)`` from
    ``u[n + n²]``.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray, shape (n + n²,) or (0,)
        ``[x̂(k|k−1), P(k|k−1) (row-major)]``.
    u : numpy.ndarray
        ``[y, (u)]``, or ``[state, y]`` when ``x`` is empty.
    p : numpy.ndarray
        :data:`LAYOUT`.
    y : numpy.ndarray, shape (n,)
        The estimate ``x̂(k|k)``, written in place.
    """
    n, h, _, _, _ = _kf_params(p)
    s, o = (x, 0) if x.shape[0] > 0 else (u, n + n * n)
    xp, P = vector(s, 0, n), matrix(s, n, n, n)  # x̂(k|k−1), P(k|k−1)
    Ph = mat_vec(P, h, y)                        # P hᵀ (in y until x̂(k|k) overwrites it)
    S = dot(h, Ph, p[AT.R])                      # S(k) = R + h P hᵀ
    r = sub_dot(u[o], h, xp)                     # innovation y(k) − h x̂(k|k−1)
    for i in range(n):
        y[i] = xp[i] + (Ph[i] / S) * r           # x̂(k|k) = x̂(k|k−1) + K r,  K = P hᵀ / S


def kalman_update(t, x, u, p, x_next):
    """The update of :class:`DiscreteKalmanFilter` (the correction, then the prediction).

    ``x̂(k+1|k) = F x̂(k|k) + b u(k)``, ``P(k+1|k) = Qd + F (P − K S Kᵀ) Fᵀ``.

    Parameters
    ----------
    t, x, u, p
        As :func:`kalman_output` (``x`` the state, ``u = [y, (u)]``).
    x_next : numpy.ndarray, shape (n + n²,)
        The next state, written in place.
    """
    n, h, F, Qd, b = _kf_params(p)
    xp, P = vector(x, 0, n), matrix(x, n, n, n)  # x̂(k|k−1), P(k|k−1)
    x_new, P_new = vector(x_next, 0, n), matrix(x_next, n, n, n)
    K, xf = scratch(n, u[0]), scratch(n, u[0])
    Pf, FPf = scratch_matrix(n, n, u[0]), scratch_matrix(n, n, u[0])
    mat_vec(P, h, K)                             # P hᵀ
    S = dot(h, K, p[AT.R])                       # S(k) = R + h P hᵀ
    r = sub_dot(u[0], h, xp)                     # innovation y(k) − h x̂(k|k−1)
    for i in range(n):
        K[i] = K[i] / S                          # K(k) = P hᵀ / S(k)
        xf[i] = xp[i] + K[i] * r                 # x̂(k|k) = x̂(k|k−1) + K r
    mat_vec(F, xf, x_new)                        # x̂(k+1|k) = F x̂(k|k) (+ b u(k))
    if as_int(p[AT.has_b]):
        for i in range(n):
            x_new[i] = x_new[i] + u[1] * b[i]
    for i in range(n):
        for j in range(n):
            Pf[i, j] = P[i, j] - K[i] * K[j] * S  # P(k|k) = P(k|k−1) − K S Kᵀ
    mat_mul(F, Pf, FPf)
    add_mat_mul_t(Qd, FPf, F, P_new)             # P(k+1|k) = Qd + F P(k|k) Fᵀ


class DiscreteKalmanFilter(KernelBlock, DiscreteBlock):
    """Time-varying discrete Kalman filter for ``x(k+1) = F x(k) + b u(k) + w(k)``, ``y(k) = h x(k) + v(k)``.

    The block's state is the prediction ``x̂(k|k−1)`` and its covariance ``P(k|k−1)`` (row-major);
    at each sample it corrects with the scalar measurement ``y`` and outputs the estimate, then
    predicts::

        S(k)      = h P(k|k−1) hᵀ + R                innovation variance
        K(k)      = P(k|k−1) hᵀ / S(k)               filter-form gain
        x̂(k|k)    = x̂(k|k−1) + K(k) (y(k) − h x̂(k|k−1))   output (feedthrough from y)
        P(k|k)    = P(k|k−1) − K(k) S(k) K(k)ᵀ
        x̂(k+1|k)  = F x̂(k|k) + b u(k)
        P(k+1|k)  = F P(k|k) Fᵀ + Qd                 update

    The kernels :func:`kalman_output` and :func:`kalman_update` write these lines with the loops of
    :mod:`ctrl_analysis.engine.matrix` (``n`` is small), so a run is bit-identical whatever the batch size. As ``k``
    grows, ``K(k)`` tends to the filter-form steady-state gain
    of :func:`~ctrl_analysis.estimators.kalman.discrete_steady_state`.

    Parameters
    ----------
    F : array_like, shape (n, n)
    h : array_like, shape (n,)
        Measurement row.
    Qd : array_like, shape (n, n)
        Covariance of ``w(k)`` (symmetric, positive semidefinite).
    R : float, > 0
        Variance of ``v(k)``.
    b : array_like, shape (n,), optional
        Input vector; when given the block has a second input ``u``.
    x0 : array_like, shape (n,), optional
        Initial prediction (default zero).
    P0 : array_like, shape (n, n), optional
        Initial prediction covariance (default identity).

    Block signals: inputs ``y`` (and ``u``); states ``xpred[i]``, ``P[i][j]``; outputs ``xhat[i]``.

    References
    ----------
    R. E. Kalman, "A new approach to linear filtering and prediction problems", 1960; Bar-Shalom,
    Li & Kirubarajan, *Estimation with Applications to Tracking and Navigation*, 2001, §5.2.
    """

    feedthrough = True
    kernels = Kernels(output=kalman_output, update=kalman_update)

    def __init__(self, F, h, Qd, R, *, b=None, x0=None, P0=None):
        self.F = check_matrix("F", F)
        n = self.F.shape[0]
        if self.F.shape != (n, n):
            raise ValueError(f"F must be square, got shape {self.F.shape}")
        self.n = n
        self.h = np.ravel(check_finite("h", h))
        if self.h.shape != (n,):
            raise ValueError(f"h must have {n} entries to match F ({n}×{n}), got shape {np.shape(h)}")
        self.Qd = check_matrix("Qd", Qd, shape=(n, n))
        tol = -1e-12 * max(1.0, np.abs(self.Qd).max())
        if not np.allclose(self.Qd, self.Qd.T) or np.min(np.linalg.eigvalsh(self.Qd)) < tol:
            raise ValueError(f"Qd must be symmetric positive semidefinite, got {self.Qd.tolist()}")
        self.R = check_positive("R", R, scalar=True)
        self.b = None if b is None else check_finite("b", np.ravel(b), shape=(n,))
        self.inputs = ("y",) if self.b is None else ("y", "u")
        self.x0 = np.zeros(n) if x0 is None else check_finite("x0", np.ravel(x0), shape=(n,))
        self.P0 = np.eye(n) if P0 is None else check_matrix("P0", P0, shape=(n, n), symmetric=True)
        if np.min(np.linalg.eigvalsh(self.P0)) < -1e-12 * max(1.0, np.abs(self.P0).max()):
            raise ValueError(f"P0 must be positive semidefinite (a covariance), got {self.P0.tolist()}")
        self.outputs = signal_names("xhat", n)
        self.states = signal_names("xpred", n) + tuple(f"P[{i}][{j}]" for i in range(n) for j in range(n))
        self.kernel_params = LAYOUT.pack(n=n, has_b=0.0 if self.b is None else 1.0, R=self.R, h=self.h,
                                                   F=self.F, Qd=self.Qd, b=np.zeros(n) if self.b is None else self.b)

    def initial_state(self) -> np.ndarray:
        return np.concatenate([self.x0, self.P0.ravel()])

    def __repr__(self) -> str:
        return f"DiscreteKalmanFilter(n={self.n}, R={self.R:g})"
