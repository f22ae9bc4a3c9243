"""Offline (non-causal) smoothers of a whole record: the arena's answer to "what is the derivative of my record".

A causal estimator's error at ``t`` can only use the samples up to ``t``; a smoother of a recorded signal uses
every sample, before and after. On a record the price of causality is the ratio of the two best errors. Four
families from well-kept code, each tuned like the causal ones (:mod:`.tuning`):

* ``sg`` — the centred Savitzky–Golay fit (:func:`scipy.signal.savgol_filter`, ``mode="interp"``: the first and
  last half-windows from the fit of the edge window), window and degree tuned;
* ``spline`` — the smoothing spline (:func:`scipy.interpolate.make_smoothing_spline`: minimises
  ``Σ (y_k - s(t_k))² + λ ∫ s''(t)² dt``), ``λ`` tuned; its derivatives are the spline's;
* ``rts`` — the Rauch–Tung–Striebel smoother of the constant-velocity Kalman filter (white acceleration), in
  steady state: the forward filter is the α-β filter of Kalata's index ``Λ`` (the arena's ``kalman`` family), the
  backward pass its steady RTS gain; ``Λ`` tuned;
* ``rts3`` — the same of the constant-acceleration model (the arena's ``abg`` family forward), which also
  estimates ``f''``.

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


def _rts_gains(lam: float, order: int) -> tuple:
    """Transition ``F``, steady-state filter gain ``K`` and RTS gain ``C = P(k|k) Fᵀ P(k+1|k)⁻¹`` of the order-2
    (constant-velocity) or order-3 (constant-acceleration) model of tracking index ``Λ``, in the scaled states
    ``[x, T ẋ, T² ẍ]`` (``T = 1``: the model depends on ``Λ`` alone), by the library's steady-state DARE."""
    from ..estimators.kalman.discrete import discrete_steady_state_batch

    if order == 2:
        F, g = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([0.5, 1.0])
    else:
        F, g = np.array([[1.0, 1.0, 0.5], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]]), np.array([0.5, 1.0, 1.0])
    ss = discrete_steady_state_batch(F[None], np.eye(1, order), (lam**2 * np.outer(g, g))[None], 1.0)
    C = ss.P_post[0] @ F.T @ np.linalg.inv(ss.P_prior[0])
    return F, ss.K_filter[0, :, 0], C


def rts_smoother(y: np.ndarray, lam: np.ndarray, dt: float, order: int = 2) -> np.ndarray:
    """Steady-state RTS estimates of ``f, f'`` (and ``f''`` at order 3) of every record (column) of ``y``.

    The forward pass is the steady α-β (order 2, constant velocity: the arena's ``kalman`` family) or α-β-γ filter
    (order 3, constant acceleration: its ``abg`` family) of index ``Λ``, started from a polynomial of degree
    ``order - 1`` fitted to the first ``2/Λ^(1/order)`` samples (about the filter's memory); the backward pass
    ``x_s(k) = x_f(k) + C (x_s(k+1) - F x_f(k))``.

    Parameters
    ----------
    y : numpy.ndarray, shape (N, B)
    lam : numpy.ndarray, shape (B,)
        Kalata's tracking index ``Λ`` per record (> 0).
    dt : float
    order : {2, 3}
        States of the model.

    Returns
    -------
    numpy.ndarray, shape (N, B, order)
    """
    N, B = y.shape
    out = np.empty((N, B, order))
    scale = dt ** -np.arange(order)  # scaled state [x, T ẋ, T² ẍ] -> [x, ẋ, ẍ]
    for value in np.unique(lam):
        cols = np.flatnonzero(lam == value)
        F, K, C = _rts_gains(float(value), order)
        yy = y[:, cols]
        xf = np.empty((N, order, cols.size))
        # started from a fit to the first samples: a steady-state filter has no diffuse prior, and a zero slope
        # would bias the start of the smoothed record
        w = int(min(N, max(order, round(2.0 / float(value) ** (1.0 / order)))))
        deg = min(order - 1, w - 1)
        c = np.polyfit(np.arange(w, dtype=float), yy[:w], deg)[::-1] if N > 1 else yy[:1]  # c0 + c1 k + c2 k²
        xp = np.zeros((order, cols.size))
        xp[:deg + 1] = c * np.array([1.0, 1.0, 2.0])[:deg + 1, None]  # [x, T ẋ, T² ẍ] at k = 0
        for k in range(N):
            x = xp + K[:, None] * (yy[k] - xp[0])
            xf[k] = x
            xp = F @ x
        xs = xf[-1]
        out[-1, cols, :] = xs.T * scale
        for k in range(N - 2, -1, -1):
            xs = xf[k] + C @ (xs - F @ xf[k])
            out[k, cols, :] = xs.T * scale
    return out
