"""Sympy derivations for the linear extended state observer with gains ``L_i = beta_i / eps^i``.

For a plant of order ``n`` the linear ESO has the characteristic polynomial

    p(s) = s^(n+1) + Σ_{i=1}^{n+1} (beta_i / eps^i) s^(n+1-i),

its estimation errors ``e_i = x_i - x̂_i`` respond to the derivative ``h`` of the extended state by

    E_i(s) / H(s) = (s^(i-1) + L_1 s^(i-2) + ... + L_{i-1}) / p(s),

whose DC gains ``(beta_{i-1} / beta_{n+1}) eps^(n+2-i)`` (``beta_0 = 1``) are the ``eps^(n+2-i)``
error-scaling law, and the design is a bandwidth form ``(s + ω_o)^(n+1)`` iff
``beta_i = C(n+1, i) c^i`` for one constant ``c``, in which case ``ω_o = c / eps``.
Each result is a sympy expression and, where useful, a plain numeric function.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
import sympy as sp

from .._validate import check_bool, check_int, check_positive

__all__ = [
    "S",
    "EPS",
    "MAX_ORDER",
    "MAX_TRANSFER_ORDER",
    "beta_symbols",
    "gain_symbols",
    "characteristic_polynomial",
    "characteristic_coefficients",
    "observer_matrices",
    "error_transfer_functions",
    "error_dc_gains",
    "error_scaling_exponents",
    "BandwidthMatch",
    "bandwidth_match",
    "bandwidth_polynomial",
]

#: Largest plant order ``n`` of the symbolic ESO helpers (polynomials, symbols, matrices): beyond it
#: sympy's expressions grow for minutes, and no practical observer needs more.
MAX_ORDER = 30
#: Largest ``n`` of :func:`error_transfer_functions`, :func:`error_dc_gains` and
#: :func:`error_scaling_exponents`: the symbolic solve of ``(sI - A) E = e`` grows steeply
#: (about 2 s at n = 7, 40 s at n = 10, minutes beyond).
MAX_TRANSFER_ORDER = 6


def _order(n, maximum: int = MAX_ORDER) -> int:
    """The plant order ``n``: an integer in ``[1, maximum]`` (the limit named in the message)."""
    n = check_int("n", n, minimum=1)
    if n > maximum:
        which = "MAX_ORDER" if maximum == MAX_ORDER else "MAX_TRANSFER_ORDER"
        raise ValueError(f"n must be <= {maximum} ({which}: the symbolic computation would run for minutes), "
                         f"got {n}")
    return n


#: Laplace variable and high-gain parameter.
S = sp.Symbol("s")
EPS = sp.Symbol("epsilon", positive=True)


def beta_symbols(n: int) -> tuple:
    """``beta_1 .. beta_{n+1}`` (positive).

    Parameters
    ----------
    n : int
        Plant order (>= 1); the extended observer has ``n + 1`` states.

    Returns
    -------
    tuple of sympy.Symbol
    """
    n = _order(n)
    return sp.symbols(f"beta1:{n + 2}", positive=True)


def gain_symbols(n: int) -> tuple:
    """``L_1 .. L_{n+1}`` (positive): the observer gains as free symbols.

    Parameters
    ----------
    n : int
        Plant order, as in :func:`beta_symbols`.

    Returns
    -------
    tuple of sympy.Symbol
        ``(L1, ..., L{n+1})``.
    """
    n = _order(n)
    return sp.symbols(f"L1:{n + 2}", positive=True)


def characteristic_polynomial(n: int, high_gain: bool = True) -> sp.Expr:
    """``det(sI - (A - L C))`` of the linear ESO of plant order ``n``.

    With ``high_gain`` the gains are ``L_i = beta_i / eps^i`` (paper eq. (29)); otherwise the
    symbols ``L_i``.

    Parameters
    ----------
    n : int
        Plant order (>= 1); the observer has ``n + 1`` states.
    high_gain : bool
        Gains ``beta_i / eps^i`` (True) or free symbols ``L_i`` (False).

    Returns
    -------
    sympy.Expr
        The monic polynomial of degree ``n + 1`` in ``s``.

    References
    ----------
    Chen Z., Gao Q., "Modified extended state observer: analysis and implementation", Control
    Theory & Applications 35(8), 2018, eq. (3), (6), (29).
    """
    return _characteristic_polynomial(_order(n), check_bool("high_gain", high_gain))


@cache
def _characteristic_polynomial(n: int, high_gain: bool) -> sp.Expr:
    A, _, _ = observer_matrices(n, high_gain)
    return sp.expand(sp.Matrix(A).charpoly(S).as_expr())


def characteristic_coefficients(n: int):
    """Numeric function ``(epsilon, beta) -> [1, beta_1/eps, ..., beta_{n+1}/eps^(n+1)]``.

    Parameters
    ----------
    n : int
        Plant order (>= 1).

    Returns
    -------
    callable
        ``numeric(epsilon, beta) -> numpy.ndarray`` of shape ``(n + 2,)``, checking its arguments
        (``epsilon > 0``, ``n + 1`` positive ``beta``).
    """
    n = _order(n)
    betas = beta_symbols(n)
    coeffs = sp.Poly(characteristic_polynomial(n), S).all_coeffs()
    f = sp.lambdify((EPS, betas), coeffs, "numpy")

    def numeric(epsilon, beta):
        epsilon = check_positive("epsilon", epsilon, scalar=True)
        beta = np.atleast_1d(check_positive("beta", beta))
        if beta.shape != (n + 1,):
            raise ValueError(f"beta must have n + 1 = {n + 1} entries, got {beta.size}")
        return np.array(f(epsilon, tuple(beta)), dtype=float)

    return numeric


def observer_matrices(n: int, high_gain: bool = True):
    """Symbolic error-dynamics matrices ``(A - L C, E, C)``: ``e' = (A - L C) e + E h``.

    ``E`` is the unit vector on the extended state; ``C = [1, 0, ..., 0]``.

    Parameters
    ----------
    n : int
        Plant order; the matrices have ``n + 1`` rows.
    high_gain : bool
        ``L_i = beta_i / eps^i`` (``True``) or free symbols ``L_i``.

    Returns
    -------
    (A_LC, E, C) : tuple of sympy.Matrix
        Shapes ``(n+1, n+1)``, ``(n+1, 1)``, ``(1, n+1)``.
    """
    n = _order(n)
    high_gain = check_bool("high_gain", high_gain)
    m = n + 1
    if high_gain:
        L = [b / EPS**i for i, b in enumerate(beta_symbols(n), start=1)]
    else:
        L = list(gain_symbols(n))
    A = sp.zeros(m, m)
    for i in range(m - 1):
        A[i, i + 1] = 1
    for i in range(m):
        A[i, 0] = -L[i]
    E = sp.zeros(m, 1)
    E[m - 1, 0] = 1
    C = sp.zeros(1, m)
    C[0, 0] = 1
    return A, E, C


def error_transfer_functions(n: int, high_gain: bool = False) -> tuple:
    """``E_i(s) / H(s)`` for ``i = 1..n+1``, solved from ``(sI - (A - LC)) E = e_{n+1} H``.

    Parameters
    ----------
    n : int
        Plant order (>= 1).
    high_gain : bool
        As in :func:`characteristic_polynomial`.

    Returns
    -------
    tuple of sympy.Expr
        ``n + 1`` simplified rational expressions in ``s`` (and ``L_i`` or ``beta_i, eps``).

    References
    ----------
    Chen & Gao 2018, bound (4)/(7).
    """
    return _error_transfer_functions(_order(n, MAX_TRANSFER_ORDER), check_bool("high_gain", high_gain))


@cache
def _error_transfer_functions(n: int, high_gain: bool) -> tuple:
    A, E, _ = observer_matrices(n, high_gain)
    m = n + 1
    sol = (S * sp.eye(m) - A).LUsolve(E)
    # factor_terms, not factor: numerator and denominator are irreducible apart from a power of eps, so both
    # give the same expressions for every n <= MAX_TRANSFER_ORDER; factor's multivariate (Wang) algorithm
    # draws random evaluation points from sympy's process-wide generator and, for about 2 % of its states,
    # ran for many minutes at n = 4 (a suite once hung on it)
    return tuple(sp.factor_terms(sp.cancel(sp.together(e))) for e in sol)


def error_dc_gains(n: int) -> tuple:
    """DC gains of ``E_i / H`` with ``L_i = beta_i / eps^i``: ``(beta_{i-1}/beta_{n+1}) eps^(n+2-i)``.

    Parameters
    ----------
    n : int
        Plant order (>= 1); the limits ``s -> 0`` of :func:`error_transfer_functions` are taken.

    Returns
    -------
    tuple of sympy.Expr
        One DC gain per observer state, ``n + 1`` in all.
    """
    return _error_dc_gains(_order(n, MAX_TRANSFER_ORDER))


@cache
def _error_dc_gains(n: int) -> tuple:
    return tuple(sp.simplify(sp.limit(g, S, 0)) for g in error_transfer_functions(n, high_gain=True))


def error_scaling_exponents(n: int) -> tuple:
    """Exponent ``k_i`` of ``eps`` in the steady error of ``x̂_i`` for a constant ``h``: ``n + 2 - i``.

    Derived from :func:`error_dc_gains` (the degree of ``eps`` in each DC gain), not assumed.

    Parameters
    ----------
    n : int
        Plant order, one exponent per observer state (``n + 1`` in all).

    Returns
    -------
    tuple of int
        ``k_1 .. k_{n+1}``.
    """
    out = []
    for g in error_dc_gains(_order(n, MAX_TRANSFER_ORDER)):
        num, den = sp.fraction(sp.together(g))
        out.append(int(sp.degree(num, EPS) - sp.degree(den, EPS)))
    return tuple(out)


@dataclass(frozen=True)
class BandwidthMatch:
    """Result of :func:`bandwidth_match`.

    Attributes
    ----------
    is_bandwidth : bool
        ``beta_i = C(n+1, i) c^i`` for all ``i`` (exact, in rational arithmetic).
    c : sympy.Expr or None
        The constant ``c`` (then ``ω_o = c / eps``).
    omega_o : sympy.Expr or None
        ``c / eps`` (a number when ``epsilon`` is given).
    """

    is_bandwidth: bool
    c: object
    omega_o: object


def bandwidth_polynomial(n: int, omega_o=None) -> sp.Expr:
    """``(s + omega_o)^(n+1)`` expanded (``omega_o`` a symbol when not given).

    Parameters
    ----------
    n : int
        Plant order; the polynomial has degree ``n + 1``.
    omega_o : number, optional
        Observer bandwidth (rad/s); a positive symbol when omitted.

    Returns
    -------
    sympy.Expr
    """
    n = _order(n)
    w = (sp.Symbol("omega_o", positive=True) if omega_o is None
         else sp.nsimplify(check_positive("omega_o", omega_o, scalar=True)))
    return sp.expand((S + w) ** (n + 1))


def bandwidth_match(beta, epsilon=None) -> BandwidthMatch:
    """Is ``s^(n+1) + Σ beta_i/eps^i s^(n+1-i)`` exactly ``(s + ω_o)^(n+1)``? If so, which ``ω_o``?

    Matching coefficients of ``(s + ω)^(n+1) = Σ C(n+1, i) ω^i s^(n+1-i)`` gives
    ``beta_i / eps^i = C(n+1, i) ω^i``, i.e. ``beta_i = C(n+1, i) c^i`` with ``c = eps ω``.

    Parameters
    ----------
    beta : sequence of numbers, length n + 1
        Converted to exact rationals with :func:`sympy.nsimplify`.
    epsilon : number, optional
        When given, ``omega_o`` is returned as a number.

    Returns
    -------
    BandwidthMatch

    Examples
    --------
    >>> m = bandwidth_match((3, 3, 1), epsilon=0.1)
    >>> m.is_bandwidth, m.c, m.omega_o
    (True, 1, 10)
    """
    beta_arr = np.atleast_1d(check_positive("beta", beta))
    if beta_arr.ndim != 1 or beta_arr.size < 2:
        raise ValueError(f"beta must have n + 1 >= 2 positive entries, got {beta!r}")
    if beta_arr.size > MAX_ORDER + 1:
        raise ValueError(f"beta must have at most MAX_ORDER + 1 = {MAX_ORDER + 1} entries (the exact comparison "
                         f"would run for minutes), got {beta_arr.size}")
    beta = [sp.nsimplify(b, rational=True) for b in (beta if isinstance(beta, (list, tuple)) else beta_arr)]
    eps = None if epsilon is None else sp.nsimplify(check_positive("epsilon", epsilon, scalar=True), rational=True)
    m = len(beta)
    c = beta[0] / m  # from beta_1 = C(n+1, 1) c
    ok = all(sp.simplify(beta[i - 1] - sp.binomial(m, i) * c**i) == 0 for i in range(1, m + 1))
    if not ok:
        return BandwidthMatch(False, None, None)
    if eps is None:
        return BandwidthMatch(True, c, c / EPS)
    return BandwidthMatch(True, c, sp.nsimplify(c / eps))
