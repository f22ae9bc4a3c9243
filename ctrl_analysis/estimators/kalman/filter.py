"""Time-varying discrete Kalman filter (scalar measurement) as a discrete block batched over runs."""

from __future__ import annotations

import numpy as np

from ..._validate import check_finite, check_matrix, check_positive
from ...blocks import DiscreteBlock, signal_names

__all__ = ["DiscreteKalmanFilter"]


class DiscreteKalmanFilter(DiscreteBlock):
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

    Products are written out element by element (``n`` is small), so a run is bit-identical
    whatever the batch size. As ``k`` grows, ``K(k)`` tends to the filter-form steady-state gain
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

    Block signals: inputs ``y`` (and ``u``); states ``xpred[i]``, ``P[i,j]``; outputs ``xhat[i]``.

    References
    ----------
    R. E. Kalman, "A new approach to linear filtering and prediction problems", 1960; Bar-Shalom,
    Li & Kirubarajan, *Estimation with Applications to Tracking and Navigation*, 2001, §5.2.
    """

    feedthrough = True

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
        self.states = signal_names("xpred", n) + tuple(f"P[{i},{j}]" for i in range(n) for j in range(n))

    def initial_state(self) -> np.ndarray:
        return np.concatenate([self.x0, self.P0.ravel()])

    def _gain(self, x):
        """``(K, S)`` of the state ``x`` (B, n + n²): ``K = P hᵀ / (h P hᵀ + R)``."""
        n, h = self.n, self.h
        P = x[:, n:].reshape(-1, n, n)
        Ph = np.zeros((x.shape[0], n))
        for j in range(n):
            Ph += P[:, :, j] * h[j]
        S = self.R
        for i in range(n):
            S = S + h[i] * Ph[:, i]
        return Ph / S[:, None], S, P

    def output(self, t, x, u, params=None) -> np.ndarray:
        n = self.n
        K, _, _ = self._gain(x)
        xp = x[:, :n]
        r = u[:, 0]
        for i in range(n):
            r = r - self.h[i] * xp[:, i]
        return xp + K * r[:, None]  # x̂(k|k) = x̂(k|k−1) + K(k) (y(k) − h x̂(k|k−1))

    def update(self, t, x, u, params=None) -> np.ndarray:
        n, F = self.n, self.F
        K, S, P = self._gain(x)
        xf = self.output(t, x, u, params)
        Pf = P - K[:, :, None] * K[:, None, :] * S[:, None, None]  # P(k|k) = P − K S Kᵀ
        x_next = np.zeros_like(x)
        for i in range(n):  # x̂(k+1|k) = F x̂(k|k) + b u(k)
            for j in range(n):
                x_next[:, i] += F[i, j] * xf[:, j]
        if self.b is not None:
            x_next[:, :n] += u[:, 1:2] * self.b
        FP = np.zeros_like(Pf)  # F P(k|k)
        for k in range(n):
            FP += F[None, :, k, None] * Pf[:, None, k, :]
        Pn = np.zeros_like(Pf) + self.Qd  # P(k+1|k) = F P(k|k) Fᵀ + Qd
        for k in range(n):
            Pn += FP[:, :, k, None] * F[None, None, :, k]
        x_next[:, n:] = Pn.reshape(-1, n * n)
        return x_next

    def __repr__(self) -> str:
        return f"DiscreteKalmanFilter(n={self.n}, R={self.R:g})"
