"""A causal algebraic (Savitzky–Golay / Jacobi-type) differentiator: the arena's yardstick from outside the papers.

At every sample the last ``W`` samples are fitted, in the least-squares sense, by a polynomial of
degree ``d`` in time; its value, slope and curvature **at the newest sample** are the estimates of
``f``, ``f'`` and ``f''``. The fit is linear in the samples, so each estimate is an FIR filter whose
``W`` weights are a row of the pseudo-inverse of the Vandermonde matrix (a delay-free algebraic
differentiator in the sense of Mboup, Join & Fliess 2009: the projection on Legendre/Jacobi
polynomials of the window is the same least-squares fit).
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import check_finite, check_in, check_int, check_positive
from .recordcheck import MAX_ROWS

__all__ = ["MAX_WINDOW", "algebraic_derivative", "algebraic_weights"]

#: The longest window (samples): a record's most rows (:data:`~ctrl_analysis.arena.recordcheck.MAX_ROWS`).
MAX_WINDOW = MAX_ROWS


def algebraic_weights(window: int, degree: int, dt: float) -> np.ndarray:
    """FIR weights of the causal least-squares polynomial differentiator.

    Parameters
    ----------
    window : int
        Samples in the window, ``degree + 1 <= W <=`` :data:`MAX_WINDOW`.
    degree : int
        Polynomial degree ``d``, 1 or 2.
    dt : float
        Sample period (> 0), not so small that the weights ``1/dt`` and ``2/dt²`` overflow double precision.

    Returns
    -------
    numpy.ndarray, shape (3, W)
        Rows: weights of ``f̂``, ``f̂'``, ``f̂''`` (zero for ``d = 1``); column ``j`` multiplies
        ``y_(k-j)``.

    Raises
    ------
    ValueError
        If ``degree`` is not 1 or 2, ``window`` is outside ``[degree + 1, MAX_WINDOW]``, ``dt <= 0``, or ``dt`` so
        small that the weights overflow.

    References
    ----------
    A. Savitzky, M. J. E. Golay, Anal. Chem. 36(8), 1964 (least-squares polynomial smoothing and
    differentiation); M. Mboup, C. Join, M. Fliess, "Numerical differentiation with annihilators in
    noisy environment", Numer. Algorithms 50(4), 2009 (the causal algebraic form). Departure: evaluated
    at the newest sample (no delay), not at a Jacobi-root delay.

    Examples
    --------
    >>> w = algebraic_weights(3, 2, 1.0)           # (3 y_k - 4 y_(k-1) + y_(k-2)) / 2
    >>> np.round(w[1], 12).tolist()
    [1.5, -2.0, 0.5]
    """
    degree = check_int("degree", degree, minimum=1, maximum=2)
    window = check_int("window", window, minimum=degree + 1, maximum=MAX_WINDOW)
    dt = float(check_positive("dt", dt, scalar=True))
    tau = -np.arange(window, dtype=float)  # time of y_(k-j) relative to t_k, in samples
    V = np.vander(tau, degree + 1, increasing=True)  # columns 1, τ, τ²
    pinv = np.linalg.pinv(V)  # coefficients c = pinv y: p(τ) = c0 + c1 τ + c2 τ²
    w = np.zeros((3, window))
    w[0] = pinv[0]
    with np.errstate(over="ignore", divide="ignore"):
        w[1] = pinv[1] / dt  # p'(0) = c1, per sample -> per second
        if degree == 2:
            w[2] = 2.0 * pinv[2] / _square(dt)  # p''(0) = 2 c2
    if not np.all(np.isfinite(w)):
        raise ValueError(f"dt = {dt!r} s is too small for double precision: the weights 1/dt and 2/dt² of a "
                         "window's samples overflow; express the record in another unit of time")
    return w


def _square(dt: float) -> float:
    """``dt**2``, ``inf`` past the float range (whose weights ``2 c2/dt²`` are then 0 to double precision)."""
    try:
        return dt**2
    except OverflowError:
        return math.inf


def algebraic_derivative(y, windows, degrees, dt: float, *, before: str = "first") -> np.ndarray:
    """Run the causal algebraic differentiator over records ``y``, one window and degree per run.

    Before the first sample the record is taken as constant (``y_(-j) = y_0``), or as zero.

    Parameters
    ----------
    y : array_like, shape (N, B)
        Measured samples, one record per run.
    windows, degrees : array_like of int, shape (B,)
        Window ``W`` (at most :data:`MAX_WINDOW`) and degree ``d`` of each run (``W`` raised to ``d + 1`` when
        smaller).
    dt : float
        Sample period (> 0).
    before : {"first", "zero"}
        What the window sees before the first sample: ``y_0`` (default, the filter at rest on the first sample)
        or 0.

    Returns
    -------
    numpy.ndarray, shape (N, B, 3)
        ``f̂, f̂', f̂''`` at every sample.

    Raises
    ------
    TypeError, ValueError
        If ``y`` is not a finite (N, B) array, ``windows``/``degrees`` are not integers (windows 1 to
        :data:`MAX_WINDOW`, degrees 1 or 2) of one value or ``B`` values, ``dt`` is not as
        :func:`algebraic_weights` needs it, ``before`` is unknown, or the magnitudes of ``y`` and ``dt`` make an
        estimate overflow.

    Examples
    --------
    >>> t = 0.1 * np.arange(10)
    >>> est = algebraic_derivative((t**2)[:, None], [4], [2], 0.1)
    >>> round(float(est[-1, 0, 1]), 9), round(float(est[-1, 0, 2]), 9)   # 2 t and 2 at t = 0.9
    (1.8, 2.0)
    """
    y = np.asarray(check_finite("y", y))
    if y.ndim != 2:
        raise ValueError(f"y must have shape (N, B), got {y.shape}")
    N, B = y.shape
    dt = float(check_positive("dt", dt, scalar=True))
    windows = _integers("windows", windows, B, minimum=1, maximum=MAX_WINDOW)
    degrees = _integers("degrees", degrees, B, minimum=1, maximum=2)
    check_in("before", before, ("first", "zero"))
    windows = np.maximum(windows, degrees + 1)
    out = np.empty((N, B, 3))
    for W, d in {(int(a), int(b)) for a, b in zip(windows, degrees, strict=True)}:
        cols = np.flatnonzero((windows == W) & (degrees == d))
        w = algebraic_weights(W, d, dt)
        head = y[:1, cols] if before == "first" else np.zeros((1, cols.size))
        padded = np.concatenate([np.repeat(head, W - 1, axis=0), y[:, cols]])
        # sliding windows: view[k, b, j] = padded[k + j, b]; newest sample last, so reverse the weights
        view = np.lib.stride_tricks.sliding_window_view(padded, W, axis=0)
        out[:, cols, :] = np.einsum("kbj,rj->kbr", view, w[:, ::-1])
    if not np.all(np.isfinite(out)):
        raise ValueError("y and dt overflow double precision (an estimate is not finite): express the record in "
                         "other units of the signal or of time")
    return out


def _integers(name: str, value, size: int, *, minimum: int, maximum: int | None = None) -> np.ndarray:
    """``value`` (one integer or ``size`` of them) as an int array of shape ``(size,)``; errors name ``name``."""
    arr = np.asarray(check_finite(name, value))
    if arr.ndim > 1 or (arr.ndim == 1 and arr.shape != (size,)):
        raise ValueError(f"{name} must be one integer or {size} of them (one per run), got shape {arr.shape}")
    if np.any(arr != np.round(arr)):
        raise ValueError(f"{name} must be integers, got {value!r}")
    if np.any(arr < minimum) or (maximum is not None and np.any(arr > maximum)):
        rule = f">= {minimum}" if maximum is None else f"in [{minimum}, {maximum}]"
        raise ValueError(f"{name} must be {rule}, got {value!r}")
    return np.broadcast_to(arr.astype(int), (size,))
