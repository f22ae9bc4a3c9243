"""Time-varying discrete Kalman filter (scalar measurement) as a discrete block batched over runs."""

from __future__ import annotations

import numpy as np

from ..._validate import check_finite, check_matrix, check_positive
from ...engine.blocks import DiscreteBlock, signal_names
from ...engine.kernels import KernelBlock, Kernels, Layout, as_int, jitable

__all__ = ["DiscreteKalmanFilter"]


#: The fixed head of a :class:`DiscreteKalmanFilter`'s kernel parameters: the order, the input
#: switch (1 with ``b``) and ``R``; the arrays follow (:func:`kalman_layout`).
HEAD = Layout("n", "has_b", "R")
AT = HEAD.at
_ARRAYS = HEAD.size


def kalman_layout(n: int) -> Layout:
    """The kernel parameters of an ``n``-state :class:`DiscreteKalmanFilter`: :data:`HEAD`, then ``h, F, Qd, b``.

    The matrices are row-major; ``b`` is zeros without an input. A kernel reads ``n`` and finds the
    arrays with :func:`_kf_at`.

    Parameters
    ----------
    n : int
        Number of states.

    Returns
    -------
    Layout
    """
    return Layout(*zip(HEAD.names, HEAD.shapes), ("h", n), ("F", (n, n)), ("Qd", (n, n)), ("b", n))


@jitable
def _kf_at(p):
    """``(n, h, F, Qd, b)``: the order read from ``p`` and the offsets of :func:`kalman_layout` ``(n)``'s arrays."""
    n = as_int(p[AT.n])
    return n, _ARRAYS, _ARRAYS + n, _ARRAYS + n + n * n, _ARRAYS + n + 2 * n * n


def kalman_output(t, x, u, p, y):
    """The output of :class:`DiscreteKalmanFilter`: ``x̂(k|k) = x̂(k|k−1) + K(k) (y(k) − h x̂(k|k−1))``.

    Scalar indexing only: one run in the compiled engine, the batch's columns in the batched methods.
    With an empty ``x`` (a static corrector placed after a predictor that holds the state) the
    state is read from ``u[0 : n + n²]`` and ``y(k)`` from ``u[n + n²]``.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray, shape (n + n²,) or (0,)
        ``[x̂(k|k−1), P(k|k−1) (row-major)]``.
    u : numpy.ndarray
        ``[y, (u)]``, or ``[state, y]`` when ``x`` is empty.
    p : numpy.ndarray
        :func:`kalman_layout` ``(n)``.
    y : numpy.ndarray, shape (n,)
        The estimate ``x̂(k|k)``, written in place.
    """
    n, h, _, _, _ = _kf_at(p)
    s, o = (x, 0) if x.shape[0] > 0 else (u, n + n * n)
    S = p[AT.R]  # S(k) = h P hᵀ + R
    for i in range(n):
        ph = 0.0
        for j in range(n):
            ph = ph + s[n + i * n + j] * p[h + j]
        S = S + p[h + i] * ph
    r = u[o]  # innovation y(k) − h x̂(k|k−1)
    for i in range(n):
        r = r - p[h + i] * s[i]
    for i in range(n):
        ph = 0.0
        for j in range(n):
            ph = ph + s[n + i * n + j] * p[h + j]
        y[i] = s[i] + (ph / S) * r  # K(k) = P hᵀ / S(k)


def kalman_update(t, x, u, p, x_next):
    """The update of :class:`DiscreteKalmanFilter` (the correction, then the prediction).

    ``x̂(k+1|k) = F x̂(k|k) + b u(k)``, ``P(k+1|k) = F (P − K S Kᵀ) Fᵀ + Qd``.

    The gain and the innovation (those of :func:`kalman_output`) are recomputed where needed
    instead of being stored: no scratch space.

    Parameters
    ----------
    t, x, u, p
        As :func:`kalman_output` (``x`` the state, ``u = [y, (u)]``).
    x_next : numpy.ndarray, shape (n + n²,)
        The next state, written in place.
    """
    n, h, oF, oQ, ob = _kf_at(p)
    S = p[AT.R]
    for i in range(n):
        ph = 0.0
        for j in range(n):
            ph = ph + x[n + i * n + j] * p[h + j]
        S = S + p[h + i] * ph
    r = u[0]
    for i in range(n):
        r = r - p[h + i] * x[i]
    for i in range(n):  # x̂(k+1|k) = F x̂(k|k) + b u(k)
        acc = 0.0
        for j in range(n):
            ph = 0.0
            for m in range(n):
                ph = ph + x[n + j * n + m] * p[h + m]
            acc = acc + p[oF + i * n + j] * (x[j] + (ph / S) * r)
        x_next[i] = acc + u[1] * p[ob + i] if as_int(p[AT.has_b]) else acc
    for i in range(n):  # P(k+1|k) = F P(k|k) Fᵀ + Qd, P(k|k) = P − K S Kᵀ
        for j in range(n):
            acc = 0.0 + p[oQ + i * n + j]
            for k in range(n):
                fp = 0.0
                for m in range(n):
                    km, kk = 0.0, 0.0
                    for q in range(n):
                        km = km + x[n + m * n + q] * p[h + q]
                        kk = kk + x[n + k * n + q] * p[h + q]
                    fp = fp + p[oF + i * n + m] * (x[n + m * n + k] - (km / S) * (kk / S) * S)
                acc = acc + fp * p[oF + j * n + k]
            x_next[n + i * n + j] = acc


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

    The kernels :func:`kalman_output` and :func:`kalman_update` write the products out element by
    element (``n`` is small), so a run is bit-identical whatever the batch size. As ``k`` grows, ``K(k)`` tends to the filter-form steady-state gain
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
        if not np.allclose(self.Qd, self.Qd.T) or np.min(np.linalg.eigvalsh(self.Qd)) < -1e-12 * max(1.0, np.abs(self.Qd).max()):
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
        self.kernel_params = kalman_layout(n).pack(n=n, has_b=0.0 if self.b is None else 1.0, R=self.R, h=self.h,
                                                   F=self.F, Qd=self.Qd, b=np.zeros(n) if self.b is None else self.b)

    def initial_state(self) -> np.ndarray:
        return np.concatenate([self.x0, self.P0.ravel()])

    def __repr__(self) -> str:
        return f"DiscreteKalmanFilter(n={self.n}, R={self.R:g})"
