"""Sympy derivations for the differential estimator Σ: coefficients, breakaway point and gain.

The estimator Σ of order ``n0`` has the open loop (all ``n0 - 1`` zeros at ``-a``)

    G(s) = K (s + a)^(n0-1) / s^n0

and the closed loop y -> z_1

    Φ(s) = K (s + a)^(n0-1) / (s^n0 + K (s + a)^(n0-1)).

This module derives, for general ``n0`` and ``a``, the coefficients ``a_i`` of Φ, the real-axis
breakaway point of the root locus of G and the gain there, and returns each result both as a sympy
expression and as a plain numeric function.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import sympy as sp

from .._validate import check_int, check_positive, finite_result

__all__ = [
    "S",
    "A",
    "KGAIN",
    "MAX_ORDER",
    "N0",
    "I",
    "BreakawayDerivation",
    "derive_breakaway",
    "breakaway_point",
    "breakaway_gain",
    "locus_gain",
    "coefficient_formula",
    "coefficients_from_zeros",
    "differential_coefficients",
]

#: Symbols shared by every expression of this module: s, a, K, n0, i.
S = sp.Symbol("s")
A = sp.Symbol("a", positive=True)
KGAIN = sp.Symbol("K", positive=True)
N0 = sp.Symbol("n0", integer=True, positive=True)
I = sp.Symbol("i", integer=True, positive=True)


@dataclass(frozen=True)
class BreakawayDerivation:
    """The root-locus derivation of Σ, every step a sympy expression in ``s``, ``n0``, ``a``.

    Attributes
    ----------
    locus_gain : sympy.Expr
        ``K(s) = -s^n0 / (s + a)^(n0-1)``, the gain that puts a closed-loop pole at ``s``
        (from the characteristic equation ``s^n0 + K (s + a)^(n0-1) = 0``).
    dK_ds : sympy.Expr
        ``dK/ds`` as differentiated (unsimplified).
    dK_ds_reduced : sympy.Expr
        ``dK/ds · (s + a)^n0 / s^(n0-1)``, which simplifies to ``-(s + n0 a)``; the removed factor
        vanishes only at ``s = 0`` (the ``n0``-fold open-loop pole, where ``K = 0``).
    critical_points : tuple of sympy.Expr
        All roots of ``dK/ds = 0``: ``0`` (the start of the locus, ``K = 0``) and the breakaway point.
    breakaway : sympy.Expr
        The breakaway point with ``K > 0``: ``-n0 a``. Strictly a break-in point: ``K(s)`` has a
        minimum there on the real axis, two complex branches arrive and leave along the axis.
    gain : sympy.Expr
        ``K`` at the breakaway point: ``n0^n0 a / (n0 - 1)^(n0-1)``.
    second_derivative : sympy.Expr
        ``d²K/ds²`` at the breakaway point; non-zero, so exactly two branches meet there (a double,
        not a triple, closed-loop pole).
    """

    locus_gain: sp.Expr
    dK_ds: sp.Expr
    dK_ds_reduced: sp.Expr
    critical_points: tuple
    breakaway: sp.Expr
    gain: sp.Expr
    second_derivative: sp.Expr


def _simplify_integer_powers(expr: sp.Expr) -> sp.Expr:
    """Simplify powers of negative bases with the integer exponent ``n0`` (written ``n0 = m + 1``)."""
    m = sp.Symbol("m", integer=True, positive=True)  # n0 >= 2  <=>  m = n0 - 1 >= 1
    e = expr.subs(N0, m + 1)
    # (-x)^m = (-1)^m x^m is exact for integer m, so force=True is safe here.
    e = sp.simplify(sp.powsimp(sp.expand_power_base(e, force=True), force=True))
    return sp.simplify(e.subs(m, N0 - 1))


@lru_cache(maxsize=1)
def derive_breakaway() -> BreakawayDerivation:
    """Derive the real-axis breakaway point of G(s) = K (s+a)^(n0-1)/s^n0 and the gain there.

    Returns
    -------
    BreakawayDerivation
        Each step of the derivation as a sympy expression (cached: derived once per process).

    References
    ----------
    Qi, Chen, Xue & Yuan (2004), eq. (4), (6)-(9): the paper states the breakaway point ``-n0 a``
    and prints the gain as eq. (9); this function derives both from ``dK/ds = 0``.

    Examples
    --------
    >>> from ctrl_analysis.symbolic.differential import derive_breakaway
    >>> d = derive_breakaway()
    >>> d.breakaway, d.gain
    (-a*n0, a*n0**n0*(n0 - 1)**(1 - n0))
    """
    # characteristic equation s^n0 + K (s + a)^(n0-1) = 0  =>  K(s) = -s^n0 / (s + a)^(n0-1)
    k_s = -(S**N0) / (S + A) ** (N0 - 1)
    dk = sp.diff(k_s, S)
    # divide out s^(n0-1) / (s + a)^n0, non-zero away from s = 0
    reduced = sp.simplify(sp.powsimp(sp.expand(dk * (S + A) ** N0 / S ** (N0 - 1)), force=True))
    roots = sp.solve(sp.Eq(reduced, 0), S)
    if len(roots) != 1:
        raise RuntimeError(f"expected one breakaway point off the origin, sympy found {roots}")
    s_b = sp.simplify(roots[0])
    gain = _simplify_integer_powers(k_s.subs(S, s_b))
    d2 = _simplify_integer_powers(sp.diff(k_s, S, 2).subs(S, s_b))
    return BreakawayDerivation(
        locus_gain=k_s,
        dK_ds=dk,
        dK_ds_reduced=reduced,
        critical_points=(sp.Integer(0), s_b),
        breakaway=s_b,
        gain=gain,
        second_derivative=d2,
    )


@lru_cache(maxsize=1)
def _numeric_functions():
    d = derive_breakaway()
    point = sp.lambdify((N0, A), d.breakaway, modules="numpy")
    gain = sp.lambdify((N0, A), d.gain, modules="numpy")
    locus = sp.lambdify((S, N0, A), d.locus_gain, modules="numpy")
    return point, gain, locus


#: Largest order n0 accepted. The design gain n0^n0 a / (n0-1)^(n0-1) overflows the generated
#: code near n0 = 170, and well before that the closed-loop poles computed from the coefficients
#: (a repeated pole at -n0 a, coefficients spanning many decades) lose their accuracy; no practical
#: estimator needs more than 30 integrators.
MAX_ORDER = 30


def _check_n0_a(n0_value, a_value) -> tuple[int, float]:
    return (check_int("n0", n0_value, minimum=2, maximum=MAX_ORDER),
            check_positive("a", a_value, scalar=True))


def breakaway_point(n0: int, a: float) -> float:
    """Real-axis breakaway point of the root locus of Σ (derived: ``-n0 a``).

    Parameters
    ----------
    n0 : int
        Order of Σ, ``>= 2``.
    a : float
        Position of the ``n0 - 1`` open-loop zeros at ``-a``; ``> 0`` and finite.

    Returns
    -------
    float
        The breakaway point in 1/s.

    Raises
    ------
    TypeError, ValueError
        If ``n0`` is not an integer ``>= 2`` or ``a`` is not finite and ``> 0``.

    References
    ----------
    Qi, Chen, Xue & Yuan (2004), text above eq. (8).

    Examples
    --------
    >>> breakaway_point(5, 2.0)
    -10.0
    """
    n0_value, a_value = _check_n0_a(n0, a)
    return float(_numeric_functions()[0](float(n0_value), a_value))


def breakaway_gain(n0: int, a: float) -> float:
    """Gain ``K`` that puts a double closed-loop pole at the breakaway point: ``n0^n0 a / (n0-1)^(n0-1)``.

    Parameters
    ----------
    n0 : int
        Order of Σ, ``>= 2``.
    a : float
        Position of the open-loop zeros at ``-a``; ``> 0`` and finite.

    Returns
    -------
    float
        The design gain, in 1/s (it scales linearly with ``a``).

    Raises
    ------
    TypeError, ValueError
        If ``n0`` is not an integer ``>= 2`` or ``a`` is not finite and ``> 0``.

    References
    ----------
    Qi, Chen, Xue & Yuan (2004), eq. (8)-(9); the printed eq. (9) has the exponent ``n`` where
    the derivation gives ``n0``.

    Examples
    --------
    >>> breakaway_gain(5, 2.0)
    24.4140625
    """
    n0_value, a_value = _check_n0_a(n0, a)
    # floats: n0**n0 overflows int64 from n0 = 16 on
    return float(_numeric_functions()[1](float(n0_value), a_value))


def locus_gain(s_value, n0: int, a: float):
    """``K(s) = -s^n0 / (s + a)^(n0-1)``: the gain that places a closed-loop pole at ``s_value``.

    Real and positive on the real-axis branches of the locus; ``s_value`` may be an array.

    Parameters
    ----------
    s_value : complex or array_like
        Point(s) of the s-plane.
    n0 : int
        Estimator order (>= 2).
    a : float
        Zero location parameter (> 0).

    Returns
    -------
    complex or numpy.ndarray
        ``K(s)`` at each point.
    """
    n0_value, a_value = _check_n0_a(n0, a)
    s_arr = None if isinstance(s_value, (str, bytes)) or s_value is None else np.asarray(s_value)
    if s_arr is None or s_arr.dtype.kind not in "iufc":
        raise TypeError(f"s_value must be a number or an array of numbers, got {s_value!r}")
    if not np.all(np.isfinite(s_arr)):
        raise ValueError(f"s_value must be finite (no NaN or inf), got {s_value!r}")
    return finite_result("s_value (with n0 and a)", lambda: _numeric_functions()[2](s_arr, float(n0_value), a_value))


def coefficient_formula() -> sp.Expr:
    """Closed form of the ``i``-th coefficient of Φ: ``a_i = K C(n0-1, i-1) a^(i-1)``.

    Follows from the binomial expansion of ``K (s + a)^(n0-1)`` (eq. 5 with eq. 6); see
    :func:`coefficients_from_zeros` for the expansion with general zeros.

    Returns
    -------
    sympy.Expr
        ``a_i`` in the symbols ``K``, ``n0``, ``i``, ``a``.

    References
    ----------
    Qi, Chen, Xue & Yuan (2004), eq. (3)-(6).
    """
    return KGAIN * sp.binomial(N0 - 1, I - 1) * A ** (I - 1)


def _sym_or_number(name: str, value):
    """A sympy expression, or a finite real or complex number."""
    if isinstance(value, sp.Basic):
        return value
    if isinstance(value, (bool, np.bool_, str, bytes)) or not isinstance(value, (numbers.Number, np.number)):
        raise TypeError(f"{name} must hold numbers or sympy expressions, got {value!r}")
    if not np.isfinite(complex(value)):
        raise ValueError(f"{name} must be finite (no NaN or inf), got {value!r}")
    return value


def coefficients_from_zeros(zeros, gain=KGAIN) -> list:
    """Coefficients ``a_1..a_n0`` of Φ for open-loop zeros ``zeros`` (sympy, by expansion).

    ``K ∏(s - z_j) = a_1 s^(n0-1) + ... + a_n0`` with ``n0 = len(zeros) + 1``; by Vieta,
    ``a_i = (-1)^(i-1) K e_(i-1)(z)``, ``e_k`` the elementary symmetric polynomials, so
    ``a_n0 = (-1)^(n0-1) K ∏ z_j``.

    Parameters
    ----------
    zeros : sequence of sympy expressions or numbers
        The ``n0 - 1`` open-loop zeros ``z_j``.
    gain : sympy expression, optional
        The gain ``K`` (default: the symbol ``K``).

    Returns
    -------
    list of sympy.Expr
        ``[a_1, ..., a_n0]``.

    References
    ----------
    Qi, Chen, Xue & Yuan (2004), eq. (4)-(5).
    """
    if isinstance(zeros, (str, bytes)) or not hasattr(zeros, "__iter__"):
        raise TypeError(f"zeros must be a sequence of numbers or sympy expressions, got {zeros!r}")
    zeros = [_sym_or_number("zeros", z) for z in zeros]
    gain = _sym_or_number("gain", gain)
    if len(zeros) < 1:
        raise ValueError(f"zeros must hold at least one zero (n0 >= 2), got {len(zeros)}")
    if len(zeros) > MAX_ORDER - 1:
        raise ValueError(f"zeros must hold at most MAX_ORDER - 1 = {MAX_ORDER - 1} zeros (n0 <= {MAX_ORDER}), "
                         f"got {len(zeros)}")
    # (4) numerator K ∏ (s - z_j), read off its coefficients (eq. 5)
    poly = sp.Poly(sp.expand(gain * sp.prod([S - z for z in zeros])), S)
    return poly.all_coeffs()  # already expanded, canonical


def differential_coefficients(n0: int, a: float, K: float) -> np.ndarray:
    """Numeric coefficients ``a_1..a_n0 = K C(n0-1, i-1) a^(i-1)`` of Σ.

    Parameters
    ----------
    n0 : int
        Order of Σ, ``>= 2``.
    a : float
        Zero position, ``> 0``.
    K : float
        Open-loop gain, ``> 0``.

    Returns
    -------
    numpy.ndarray
        Shape ``(n0,)``.

    References
    ----------
    Qi, Chen, Xue & Yuan (2004), eq. (5)-(6).

    Examples
    --------
    >>> differential_coefficients(3, 2.0, 1.0)
    array([1., 4., 4.])
    """
    n0_value, a_value = _check_n0_a(n0, a)
    k_value = check_positive("K", K, scalar=True)
    # (5)+(6) a_i = K C(n0-1, i-1) a^(i-1), i = 1..n0
    return finite_result("a and K", lambda: np.array([k_value * math.comb(n0_value - 1, j) * a_value**j
                                                      for j in range(n0_value)]))
