"""Offline (non-causal) smoothers of a whole record: the arena's answer to "what is the derivative of my record".

A causal estimator's error at ``t`` can only use the samples up to ``t``; a smoother of a recorded signal uses
every sample, before and after. On a record the price of causality is the ratio of the two best errors. Three
families from well-kept code, each tuned like the causal ones (:mod:`.tuning`):

* ``sg`` — the centred Savitzky–Golay fit (:func:`scipy.signal.savgol_filter`, ``mode="interp"``: the first and
  last half-windows from the fit of the edge window), window and degree tuned;
* ``spline`` — the smoothing spline (:func:`scipy.interpolate.make_smoothing_spline`: minimises
  ``Σ (y_k - s(t_k))² + λ ∫ s''(t)² dt``), ``λ`` tuned; its derivatives are the spline's;
* ``rts`` — the Rauch–Tung–Striebel smoother of the constant-velocity Kalman filter (white acceleration), in
  steady state: the forward filter is the α-β filter of Kalata's index ``Λ`` (the arena's ``kalman`` family), the
  backward pass its steady RTS gain; ``Λ`` tuned.

Each returns the estimates of ``f``, ``f'`` (and ``f''`` where it has one) at every sample, one record per column.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rts_smoother", "savgol_smoother", "spline_smoother"]


def savgol_smoother(y: np.ndarray, window: np.ndarray, degree: np.ndarray, dt: float) -> np.ndarray:
    """Centred Savitzky–Golay estimates of ``f, f', f''`` of every record (column) of ``y``.

    Parameters
    ----------
    y : numpy.ndarray, shape (N, B)
    window, degree : numpy.ndarray, shape (B,)
        Samples in the window (made odd, at least ``degree + 2``, at most ``N`` or ``N - 1``) and the polynomial
        degree (2 to 4), per record.
    dt : float

    Returns
    -------
    numpy.ndarray, shape (N, B, 3)
    """
    import scipy.signal

    N, B = y.shape
    out = np.empty((N, B, 3))
    for b in range(B):
        d = int(degree[b])
        w = int(window[b]) | 1  # odd
        w = max(w, d + 2 + (d % 2 == 0))
        w = min(w, N if N % 2 else N - 1)
        if w <= d:  # a record shorter than the degree allows: a plain fit of its samples
            d = max(0, w - 1)
        for k in range(3):
            out[:, b, k] = scipy.signal.savgol_filter(y[:, b], w, d, deriv=k, delta=dt, mode="interp") \
                if k <= d else 0.0
    return out


def spline_smoother(y: np.ndarray, lam: np.ndarray, dt: float) -> np.ndarray:
    """Smoothing-spline estimates of ``f, f', f''`` of every record (column) of ``y``.

    Parameters
    ----------
    y : numpy.ndarray, shape (N, B)
    lam : numpy.ndarray, shape (B,)
        The penalty ``λ`` of ``∫ s''²`` per record (> 0), in the units of ``t³``.
    dt : float

    Returns
    -------
    numpy.ndarray, shape (N, B, 3)
    """
    from scipy.interpolate import make_smoothing_spline

    N, B = y.shape
    t = dt * np.arange(N)
    out = np.empty((N, B, 3))
    for b in range(B):
        s = make_smoothing_spline(t, y[:, b], lam=float(lam[b]))
        out[:, b, 0] = s(t)
        out[:, b, 1] = s.derivative(1)(t)
        out[:, b, 2] = s.derivative(2)(t)
    return out


def _rts_gains(lam: float, dt: float) -> tuple:
    """Steady-state Kalman gain ``K``, predicted covariance and RTS gain of the constant-velocity model whose
    tracking index is ``Λ = σ_w dt² / σ_v`` (unit measurement noise)."""
    import scipy.linalg

    F = np.array([[1.0, dt], [0.0, 1.0]])
    H = np.array([[1.0, 0.0]])
    g = np.array([[dt * dt / 2.0], [dt]])
    q = (lam / (dt * dt)) ** 2  # σ_w² with σ_v = 1
    Q = q * (g @ g.T)
    P = scipy.linalg.solve_discrete_are(F.T, H.T, Q, np.eye(1))  # predicted covariance
    K = P @ H.T / (H @ P @ H.T + 1.0)
    Pf = (np.eye(2) - K @ H) @ P
    C = Pf @ F.T @ np.linalg.inv(P)
    return F, K[:, 0], C


def rts_smoother(y: np.ndarray, lam: np.ndarray, dt: float) -> np.ndarray:
    """Steady-state RTS estimates of ``f, f'`` of every record (column) of ``y`` (constant-velocity model).

    The forward pass is the steady α-β filter of index ``Λ``, started from a line fitted to the first ``2/√Λ``
    samples; the backward pass ``x_s(k) = x_f(k) + C (x_s(k+1) - F x_f(k))``.

    Parameters
    ----------
    y : numpy.ndarray, shape (N, B)
    lam : numpy.ndarray, shape (B,)
        Kalata's tracking index ``Λ`` per record (> 0).
    dt : float

    Returns
    -------
    numpy.ndarray, shape (N, B, 2)
    """
    N, B = y.shape
    out = np.empty((N, B, 2))
    for value in np.unique(lam):
        cols = np.flatnonzero(lam == value)
        F, K, C = _rts_gains(float(value), dt)
        yy = y[:, cols]
        xf = np.empty((N, 2, cols.size))
        # started from a line fitted to the first samples (about the filter's memory, 2/√Λ): a steady-state filter
        # has no diffuse prior, and a zero slope would bias the start of the smoothed record
        w = int(min(N, max(2, round(2.0 / np.sqrt(float(value))))))
        slope, icpt = np.polyfit(dt * np.arange(w), yy[:w], 1) if N > 1 else (np.zeros(cols.size), yy[0])
        xp = np.array([icpt, slope])
        for k in range(N):
            x = xp + K[:, None] * (yy[k] - xp[0])
            xf[k] = x
            xp = F @ x
        xs = xf[-1]
        out[-1, cols, :] = xs.T
        for k in range(N - 2, -1, -1):
            xs = xf[k] + C @ (xs - F @ xf[k])
            out[k, cols, :] = xs.T
    return out
