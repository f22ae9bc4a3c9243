"""Polynomials shared by several blocks: the repeated-pole (bandwidth) polynomial ``(s + ω)^m``."""

from __future__ import annotations

from math import comb

import numpy as np

from ._validate import check_int, check_positive, finite_result

__all__ = ["MAX_POLE_ORDER", "repeated_pole_coefficients"]

#: Highest power ``m`` of ``(s + ω)^m`` (its binomial coefficients near 1e300 beyond it overflow double precision).
MAX_POLE_ORDER = 1000


def repeated_pole_coefficients(m: int, omega: float) -> np.ndarray:
    """Coefficients of ``(s + ω)^m``, highest power first: ``[1, C(m,1) ω, C(m,2) ω², ..., ω^m]``.

    The one place the binomial expansion is coded: the low-pass / prefilter ``ω^m / (s + ω)^m``,
    the bandwidth-parameterised ESO gains (``L_i = C(n+1, i) ω_o^i``) and the bandwidth PD gains
    all use it.

    Parameters
    ----------
    m : int
        Multiplicity of the pole (>= 0).
    omega : float
        Pole at ``-ω`` (> 0), in rad/s.

    Returns
    -------
    numpy.ndarray, shape (m + 1,)

    Examples
    --------
    >>> repeated_pole_coefficients(3, 2.0)
    array([ 1.,  6., 12.,  8.])
    """
    m = check_int("m", m, minimum=0, maximum=MAX_POLE_ORDER)
    omega = float(check_positive("omega", omega, scalar=True))
    return finite_result("m and omega", lambda: _coefficients(m, omega))


def _coefficients(m: int, omega: float) -> np.ndarray:
    """The coefficients of ``(s + ω)^m``, unchecked (an ``OverflowError`` or inf where they overflow)."""
    return np.array([comb(m, i) * omega**i for i in range(m + 1)], dtype=float)
