"""The scalar random-walk steady-state Kalman gain K∞(Q/R)."""

from __future__ import annotations

import numpy as np

from ..._validate import check_finite, check_positive

__all__ = ["random_walk_gain"]


# --------------------------------------------------------------------------------------------
# scalar random walk
# --------------------------------------------------------------------------------------------


def random_walk_gain(Q, R):
    """Steady-state Kalman gain of the scalar random walk ``x(k+1) = x(k) + w``, ``y = x + v``.

    The recursion ``P⁻ = P + Q``, ``K = P⁻ / (P⁻ + R)``, ``P = (1 − K) P⁻`` has the fixed point
    ``P⁻ = (Q + √(Q² + 4 Q R)) / 2``, hence, with ``q = Q / R``,

        K∞ = (−q + √(q² + 4q)) / 2,

    a function of ``Q/R`` only (derived in
    :func:`ctrl_analysis.symbolic.riccati.derive_random_walk_gain`, numeric
    :func:`ctrl_analysis.symbolic.riccati.random_walk_gain_closed_form`).

    Parameters
    ----------
    Q : float or array_like, >= 0
        Process-noise variance.
    R : float or array_like, > 0
        Measurement-noise variance.

    Returns
    -------
    float or numpy.ndarray
        ``K∞`` in ``[0, 1)``.

    Raises
    ------
    ValueError
        ``Q must be >= 0`` / ``R must be > 0``.
    """
    Q = check_finite("Q", Q)
    if np.any(np.asarray(Q) < 0):
        raise ValueError(f"Q must be >= 0, got {Q!r}")
    R = check_positive("R", R)
    q = np.asarray(Q / R, dtype=float)
    # K∞ = (−q + √(q² + 4q)) / 2, written as 2 / (1 + √(1 + 4/q)): no cancellation for large q and no
    # overflow of q² (the textbook form gives 0 for q > 1e154)
    with np.errstate(divide="ignore"):
        k = np.where(q > 0, 2.0 / (1.0 + np.sqrt(1.0 + 4.0 / np.where(q > 0, q, 1.0))), 0.0)
    return float(k) if k.ndim == 0 else k
