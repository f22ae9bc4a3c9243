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

    Block signals: inputs ``y`` (and ``u``); states ``xpred[i]``, ``P[i][j]``; outputs ``xhat[i]``.

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
        self.states = signal_names("xpred", n) + tuple(f"P[{i}][{j}]" for i in range(n) for j in range(n))
        # kernel parameters: [n, has b, R, h, F (row-major), Qd (row-major), b]
        self._p = np.concatenate([[n, 0.0 if self.b is None else 1.0, self.R], self.h, self.F.ravel(),
                                  self.Qd.ravel(), np.zeros(n) if self.b is None else self.b]).astype(float)

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

    def kernel(self):
        """The compiled engine's kernel: :func:`kalman_output`, :func:`kalman_update` (twins of the numpy methods).

        Returns
        -------
        ctrl_analysis._kernels.BlockKernel
        """
        from ..._kernels import BlockKernel

        return BlockKernel(output=kalman_output, params=self._p, update=kalman_update)

    def __repr__(self) -> str:
        return f"DiscreteKalmanFilter(n={self.n}, R={self.R:g})"


def kalman_output(t, x, u, p, y):
    """Compiled twin of :meth:`DiscreteKalmanFilter.output` for one run: ``x̂(k|k) = x̂(k|k−1) + K(k) (y(k) − h x̂(k|k−1))``.

    The same products and sums in the same order as the numpy method (bit for bit; held equal by
    ``tests/lib/test_fuzzy.py``). With an empty ``x`` (a static corrector placed after a predictor
    that holds the state) the state is read from ``u[0 : n + n²]`` and ``y(k)`` from ``u[n + n²]``.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray, shape (n + n²,) or (0,)
        ``[x̂(k|k−1), P(k|k−1) (row-major)]``.
    u : numpy.ndarray
        ``[y, (u)]``, or ``[state, y]`` when ``x`` is empty.
    p : numpy.ndarray
        ``[n, has b, R, h, F (row-major), Qd (row-major), b]``.
    y : numpy.ndarray, shape (n,)
        The estimate ``x̂(k|k)``, written in place.
    """
    n = int(p[0])
    s, o = (x, 0) if x.shape[0] > 0 else (u, n + n * n)
    S = p[2]  # S(k) = h P hᵀ + R
    for i in range(n):
        ph = 0.0
        for j in range(n):
            ph = ph + s[n + i * n + j] * p[3 + j]
        S = S + p[3 + i] * ph
    r = u[o]  # innovation y(k) − h x̂(k|k−1)
    for i in range(n):
        r = r - p[3 + i] * s[i]
    for i in range(n):
        ph = 0.0
        for j in range(n):
            ph = ph + s[n + i * n + j] * p[3 + j]
        y[i] = s[i] + (ph / S) * r  # K(k) = P hᵀ / S(k)


def kalman_update(t, x, u, p, x_next):
    """Compiled twin of :meth:`DiscreteKalmanFilter.update` for one run (the correction, then the prediction).

    ``x̂(k+1|k) = F x̂(k|k) + b u(k)``, ``P(k+1|k) = F (P − K S Kᵀ) Fᵀ + Qd``.

    The gain and the innovation (those of :func:`kalman_output`, which a compiled kernel cannot
    call) are recomputed where needed instead of being stored: no scratch space, the numpy
    method's operation order (bit for bit).

    Parameters
    ----------
    t, x, u, p
        As :func:`kalman_output` (``x`` the state, ``u = [y, (u)]``).
    x_next : numpy.ndarray, shape (n + n²,)
        The next state, written in place.
    """
    n = int(p[0])
    oF, oQ = 3 + n, 3 + n + n * n
    S = p[2]
    for i in range(n):
        ph = 0.0
        for j in range(n):
            ph = ph + x[n + i * n + j] * p[3 + j]
        S = S + p[3 + i] * ph
    r = u[0]
    for i in range(n):
        r = r - p[3 + i] * x[i]
    for i in range(n):  # x̂(k+1|k) = F x̂(k|k) + b u(k)
        acc = 0.0
        for j in range(n):
            ph = 0.0
            for m in range(n):
                ph = ph + x[n + j * n + m] * p[3 + m]
            acc = acc + p[oF + i * n + j] * (x[j] + (ph / S) * r)
        x_next[i] = acc + u[1] * p[oQ + n * n + i] if p[1] != 0.0 else acc
    for i in range(n):  # P(k+1|k) = F P(k|k) Fᵀ + Qd, P(k|k) = P − K S Kᵀ
        for j in range(n):
            acc = 0.0 + p[oQ + i * n + j]
            for k in range(n):
                fp = 0.0
                for m in range(n):
                    km, kk = 0.0, 0.0
                    for q in range(n):
                        km = km + x[n + m * n + q] * p[3 + q]
                        kk = kk + x[n + k * n + q] * p[3 + q]
                    fp = fp + p[oF + i * n + m] * (x[n + m * n + k] - (km / S) * (kk / S) * S)
                acc = acc + fp * p[oF + j * n + k]
            x_next[n + i * n + j] = acc
