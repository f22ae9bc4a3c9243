"""Sympy derivations of steady-state Kalman gains: 2-state continuous filter, scalar random walk, α-β (Kalata).

Each derivation solves the steady-state Riccati equations symbolically, selects the stabilising
root by a check (not by position in sympy's solution list), and returns the sympy expressions
together with a plain numeric function (``sympy.lambdify``). The numeric counterparts in
:mod:`ctrl_analysis.estimators.kalman` are tested against these.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import sympy as sp

from .._validate import check_finite, finite_result

__all__ = [
    "DEFAULT_SAMPLES",
    "A21",
    "QR",
    "LAMBDA",
    "SecondOrderGainDerivation",
    "derive_second_order_gain",
    "second_order_gain",
    "RandomWalkDerivation",
    "derive_random_walk_gain",
    "random_walk_gain_closed_form",
    "KalataDerivation",
    "derive_kalata_gains",
    "kalata_gains_closed_form",
]

#: Symbols: a21 (real), q = Q/R (> 0), Λ (Kalata's tracking index, > 0).
A21 = sp.Symbol("a21", real=True)
QR = sp.Symbol("q", positive=True)
LAMBDA = sp.Symbol("Lambda", positive=True)


# --------------------------------------------------------------------------------------------
# continuous 2-state problem A = [[0, 1], [a21, 0]], C = [1, 0], Γ = [0, 1]ᵀ
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SecondOrderGainDerivation:
    """Steady-state Kalman–Bucy filter of ``ẋ = [[0, 1], [a21, 0]] x + [0, 1]ᵀ w``, ``y = x1 + v``.

    With ``R`` factored out (``P = R·p``, ``q = Q/R``) the ARE
    ``A P + P Aᵀ − P Cᵀ R⁻¹ C P + Γ Q Γᵀ = 0`` becomes three scalar equations in
    ``p11, p12, p22``:

    * (1,1): ``2 p12 − p11² = 0``
    * (1,2): ``p22 + a21 p11 − p11 p12 = 0``
    * (2,2): ``2 a21 p12 − p12² + q = 0``

    and ``K = P Cᵀ R⁻¹ = [p11, p12]ᵀ`` depends on ``a21`` and ``q`` only.

    Attributes
    ----------
    equations : tuple of sympy.Expr
        The three scalar equations (each ``= 0``).
    solutions : tuple of dict
        Every solution sympy finds.
    p : sympy.Matrix
        The stabilising, positive-definite solution ``P/R`` (2×2).
    k1, k2 : sympy.Expr
        Gain entries as derived (``k1 = p11``, ``k2 = p12``).
    k1_simple, k2_simple : sympy.Expr
        Simplified forms ``k2 = a21 + √(a21² + q)``, ``k1 = √(2 k2)`` (checked equal to ``k1, k2``).
    numeric : callable
        ``numeric(a21, q) -> ndarray (..., 2)`` of ``[k1, k2]``.
    numeric_P : callable
        ``numeric_P(a21, q, R) -> ndarray (..., 2, 2)`` of ``P̄ = R·p``.
    """

    equations: tuple
    solutions: tuple
    p: sp.Matrix
    k1: sp.Expr
    k2: sp.Expr
    k1_simple: sp.Expr
    k2_simple: sp.Expr
    numeric: Callable
    numeric_P: Callable


def _is_stabilising(sol: dict, p11, p12, p22, samples) -> bool:
    """P positive definite and A − K C Hurwitz at every sample point (a21, q)."""
    f = sp.lambdify((A21, QR), (sol[p11], sol[p12], sol[p22]), "cmath")
    for a, q in samples:
        try:
            v11, v12, v22 = (complex(v) for v in f(a, q))
        except (TypeError, ValueError, ZeroDivisionError):
            return False
        P = np.array([[v11, v12], [v12, v22]])
        if np.max(np.abs(P.imag)) > 1e-9:
            return False
        P = P.real
        if np.min(np.linalg.eigvalsh(P)) <= 0:
            return False
        Acl = np.array([[0.0, 1.0], [a, 0.0]]) - np.array([[P[0, 0]], [P[0, 1]]]) @ np.array([[1.0, 0.0]])
        if np.max(np.linalg.eigvals(Acl).real) >= 0:
            return False
    return True


#: Points ``(a21, q)`` at which a root is checked to be stabilising (stable, neutral and unstable a21).
DEFAULT_SAMPLES = ((-1.0, 0.5), (0.0, 1.0), (1.0, 2.0), (10.0, 2.0), (1.0, 100.0))


@lru_cache(maxsize=8)
def derive_second_order_gain(samples=DEFAULT_SAMPLES) -> SecondOrderGainDerivation:
    """Solve the 2-state filter ARE symbolically and return the stabilising gain ``K(a21, q)``.

    Parameters
    ----------
    samples : tuple of (float, float)
        Points ``(a21, q)``, ``q > 0``, at which the chosen root must give a positive-definite ``P``
        and a Hurwitz ``A − K C`` (a caller adds the points it uses; exactly one root must pass).

    Returns
    -------
    SecondOrderGainDerivation

    References
    ----------
    Kalman & Bucy (1961), filter Riccati equation.

    Examples
    --------
    >>> d = derive_second_order_gain()
    >>> d.k2_simple
    a21 + sqrt(a21**2 + q)
    """
    p11, p12, p22 = sp.symbols("p11 p12 p22", real=True)
    a, q = A21, QR
    A = sp.Matrix([[0, 1], [a, 0]])
    C = sp.Matrix([[1, 0]])
    Gm = sp.Matrix([[0], [1]])
    P = sp.Matrix([[p11, p12], [p12, p22]])
    # ARE / R:  A p + p Aᵀ − p Cᵀ C p + Γ q Γᵀ = 0
    E = A * P + P * A.T - P * C.T * C * P + Gm * q * Gm.T
    equations = (sp.expand(E[0, 0]), sp.expand(E[0, 1]), sp.expand(E[1, 1]))
    # eliminate: (2,2) is a quadratic in p12 alone, then (1,1) gives p11, then (1,2) gives p22
    solutions = []
    for r12 in sp.solve(equations[2], p12):
        for r11 in sp.solve(equations[0].subs(p12, r12), p11):
            for r22 in sp.solve(equations[1].subs({p11: r11, p12: r12}), p22):
                solutions.append({p11: r11, p12: r12, p22: r22})
    solutions = tuple(solutions)
    samples = tuple((float(a_), float(q_)) for a_, q_ in samples)
    if not samples or any(q_ <= 0 for _, q_ in samples):
        raise ValueError(f"samples must be a non-empty tuple of (a21, q) with q > 0, got {samples!r}")
    chosen = [s for s in solutions if _is_stabilising(s, p11, p12, p22, samples)]
    if len(chosen) != 1:  # pragma: no cover - a sympy change would show up here
        raise RuntimeError(f"expected one stabilising ARE root, found {len(chosen)}")
    s = chosen[0]
    p = sp.Matrix([[s[p11], s[p12]], [s[p12], s[p22]]])
    k1, k2 = s[p11], s[p12]
    k2_simple = a + sp.sqrt(a**2 + q)
    k1_simple = sp.sqrt(2 * k2_simple)
    f = sp.lambdify((a, q), (k1_simple, k2_simple), "numpy")
    fp = sp.lambdify((a, q), (p[0, 0], p[0, 1], p[1, 1]), "numpy")

    def numeric(a21, q):
        """``[k1, k2]`` of the steady-state gain for ``a21`` and ``q = Q/R > 0``."""
        a21 = check_finite("a21", a21)
        q = check_finite("q", q)
        if np.any(np.asarray(q) <= 0):
            raise ValueError(f"q must be > 0, got {q!r}")
        k1v, k2v = f(np.asarray(a21, dtype=float), np.asarray(q, dtype=float))
        return np.stack(np.broadcast_arrays(k1v, k2v), axis=-1)

    def numeric_P(a21, q, R):
        """``P̄ = R·p(a21, q)``."""
        a21 = np.asarray(check_finite("a21", a21), dtype=float)
        q = np.asarray(check_finite("q", q), dtype=float)
        R = np.asarray(check_finite("R", R), dtype=float)
        if np.any(q <= 0):
            raise ValueError(f"q must be > 0, got {q!r}")
        if np.any(R <= 0):
            raise ValueError(f"R must be > 0, got {R!r}")
        # p11 = k1, p12 = k2, p22 = k1 (k2 − a21) from the (1,2) equation, in the stable simplified form
        k1v, k2v = f(a21, q)
        p11v, p12v, p22v = np.broadcast_arrays(k1v, k2v, k1v * (k2v - a21))
        out = np.stack([np.stack([p11v, p12v], -1), np.stack([p12v, p22v], -1)], -2)
        return out * R[..., None, None]

    numeric_P.derived = fp  # the unsimplified sympy root, for cross-checks
    return SecondOrderGainDerivation(
        equations=equations, solutions=solutions, p=p, k1=k1, k2=k2,
        k1_simple=k1_simple, k2_simple=k2_simple, numeric=numeric, numeric_P=numeric_P,
    )


def second_order_gain(a21, q) -> np.ndarray:
    """Closed-form steady-state gain ``[k1, k2]`` of the 2-state problem (see :func:`derive_second_order_gain`).

    ``k2 = a21 + √(a21² + q)``, ``k1 = √(2 k2)``, ``q = Q/R``.

    Parameters
    ----------
    a21 : float or array_like
        The entry ``a21`` of the system matrix.
    q : float or array_like, >= 0
        Noise ratio ``Q/R``.

    Returns
    -------
    numpy.ndarray
        ``[k1, k2]`` (last axis) for each ``(a21, q)``.
    """
    return finite_result("a21 and q", lambda: derive_second_order_gain().numeric(a21, q))


# --------------------------------------------------------------------------------------------
# scalar random walk
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class RandomWalkDerivation:
    """Fixed point of the scalar random-walk Kalman recursion.

    ``P⁻ = P + Q``, ``K = P⁻/(P⁻ + R)``, ``P = (1 − K) P⁻`` ⇒ ``P⁻² − Q P⁻ − Q R = 0``.

    Attributes
    ----------
    Q, R : sympy.Symbol
    fixed_point_equation : sympy.Expr
        ``P⁻² − Q P⁻ − Q R`` (= 0).
    P_prior : sympy.Expr
        Positive root ``(Q + √(Q² + 4 Q R)) / 2``.
    K : sympy.Expr
        ``K∞`` in terms of ``Q`` and ``R``.
    K_of_q : sympy.Expr
        ``K∞`` after substituting ``Q = q R`` and simplifying: ``R`` cancels, so it is a
        function of ``q`` alone.
    K_canonical : sympy.Expr
        The canonical form ``(√(q² + 4q) − q)/2`` (checked equal to ``K_of_q``).
    numeric : callable
        ``numeric(q) -> K∞``.
    """

    Q: sp.Symbol
    R: sp.Symbol
    fixed_point_equation: sp.Expr
    P_prior: sp.Expr
    K: sp.Expr
    K_of_q: sp.Expr
    K_canonical: sp.Expr
    numeric: Callable


@lru_cache(maxsize=1)
def derive_random_walk_gain() -> RandomWalkDerivation:
    """Derive ``K∞`` of the scalar random walk and show it depends on ``q = Q/R`` only.

    References
    ----------
    Standard scalar Kalman filter; used by the IKF of Lu & Hou (2022) (its eq. (13) gain).

    Examples
    --------
    >>> d = derive_random_walk_gain()
    >>> d.K_of_q.free_symbols == {QR}
    True
    """
    Q, R = sp.symbols("Q R", positive=True)
    Pm = sp.Symbol("P_prior", positive=True)
    K = Pm / (Pm + R)  # K = P⁻ / (P⁻ + R)
    P_post = (1 - K) * Pm  # P = (1 − K) P⁻
    # fixed point P⁻ = P + Q, numerator of (P + Q − P⁻)
    eq = sp.factor(sp.numer(sp.together(P_post + Q - Pm)))
    eq = sp.expand(-eq) if sp.Poly(eq, Pm).LC() < 0 else sp.expand(eq)
    roots = sp.solve(eq, Pm)
    pos = [r for r in roots if r.subs({Q: 1, R: 1}).is_positive]
    if len(pos) != 1:  # pragma: no cover
        raise RuntimeError(f"expected one positive root, found {pos}")
    P_prior = pos[0]
    K_QR = sp.simplify(K.subs(Pm, P_prior))
    K_q = sp.simplify(K_QR.subs(Q, QR * R))
    if R in K_q.free_symbols:  # pragma: no cover - would contradict the claim
        raise RuntimeError(f"K∞ still depends on R after Q = qR: {K_q}")
    # the canonical form (√(q² + 4q) − q)/2, checked equal
    canonical = (sp.sqrt(QR**2 + 4 * QR) - QR) / 2
    if sp.simplify(sp.radsimp(K_q - canonical)) != 0:
        # fall back on a numeric check at a few points
        for v in (0.01, 0.5, 2.0, 37.0):
            if abs(float(K_q.subs(QR, v)) - float(canonical.subs(QR, v))) > 1e-12:  # pragma: no cover
                raise RuntimeError("random-walk closed form does not match the canonical form")
    f = sp.lambdify(QR, canonical, "numpy")

    def numeric(q):
        """``K∞(q)`` for ``q = Q/R >= 0``."""
        q = np.asarray(check_finite("q", q), dtype=float)
        if np.any(q < 0):
            raise ValueError(f"q must be >= 0, got {q!r}")
        out = f(q)
        return float(out) if np.ndim(out) == 0 else out

    return RandomWalkDerivation(Q=Q, R=R, fixed_point_equation=eq, P_prior=P_prior, K=K_QR,
                                K_of_q=K_q, K_canonical=canonical, numeric=numeric)


def random_walk_gain_closed_form(q):
    """``K∞ = (√(q² + 4q) − q)/2`` of the scalar random walk, ``q = Q/R``.

    Parameters
    ----------
    q : float or array_like, >= 0
        Noise ratio ``Q/R``.

    Returns
    -------
    float or numpy.ndarray
        The steady-state gain ``K∞``.
    """
    return finite_result("q", lambda: derive_random_walk_gain().numeric(q))


# --------------------------------------------------------------------------------------------
# discrete α-β (Kalata)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class KalataDerivation:
    """Steady-state α-β gains of the discrete white-noise-acceleration model, from its DARE.

    Model: ``x(k+1) = [[1, T], [0, 1]] x(k) + [T²/2, T]ᵀ w(k)``, ``y = x1 + v``,
    ``var w = σ_w²``, ``var v = σ_v²``. Scaling position by ``σ_v`` and velocity by ``σ_v/T``
    leaves the single parameter ``Λ = σ_w T²/σ_v`` (the tracking index), so the derivation takes
    ``T = 1``, ``σ_v = 1``, ``σ_w = Λ``. With the a-priori covariance ``M``, the filter-form gain
    is ``[α, β/T] = M Hᵀ/(m11 + 1)``.

    Attributes
    ----------
    equations : tuple of sympy.Expr
        Numerators of ``F (I − K H) M Fᵀ + Λ² g gᵀ − M`` (entries 11, 12, 22).
    M : sympy.Matrix
        The positive-definite a-priori solution (in units of σ_v², T = 1).
    alpha, beta : sympy.Expr
        Gains as derived from the DARE.
    alpha_kalata, beta_kalata : sympy.Expr
        Kalata's published forms ``α = −(Λ² + 8Λ − (Λ+4)√(Λ² + 8Λ))/8``,
        ``β = (Λ² + 4Λ − Λ√(Λ² + 8Λ))/4`` (checked equal to ``alpha``, ``beta`` numerically).
    numeric : callable
        ``numeric(Lambda) -> (alpha, beta)``.
    """

    equations: tuple
    M: sp.Matrix
    alpha: sp.Expr
    beta: sp.Expr
    alpha_kalata: sp.Expr
    beta_kalata: sp.Expr
    numeric: Callable


@lru_cache(maxsize=1)
def derive_kalata_gains() -> KalataDerivation:
    """Solve the α-β DARE symbolically in Λ and select the stabilising root.

    References
    ----------
    P. R. Kalata, "The tracking index: a generalized parameter for α-β and α-β-γ target
    trackers", IEEE Trans. AES 20(2), 1984; Bar-Shalom, Li & Kirubarajan, *Estimation with
    Applications to Tracking and Navigation*, Wiley 2001, §6.5.3.
    """
    L = LAMBDA
    m11, m12, m22 = sp.symbols("m11 m12 m22", real=True)
    M = sp.Matrix([[m11, m12], [m12, m22]])
    H = sp.Matrix([[1, 0]])
    F = sp.Matrix([[1, 1], [0, 1]])
    g = sp.Matrix([sp.Rational(1, 2), 1])
    K = M * H.T / (m11 + 1)  # filter-form gain, σ_v = 1
    P = (sp.eye(2) - K * H) * M  # a-posteriori covariance
    E = F * P * F.T + L**2 * g * g.T - M  # DARE residual (a-priori form)
    equations = tuple(sp.expand(sp.numer(sp.together(E[i, j]))) for i, j in ((0, 0), (0, 1), (1, 1)))
    # eliminate: (2,2) is linear in m11, then (1,2) is linear in m22, then (1,1) is a polynomial in m12
    solutions = []
    for r11 in sp.solve(equations[2], m11):
        e12 = sp.factor(sp.numer(sp.together(equations[1].subs(m11, r11))))
        for r22 in sp.solve(e12, m22):
            e11 = sp.factor(sp.numer(sp.together(equations[0].subs({m11: r11, m22: r22}))))
            for r12 in sp.solve(e11, m12):
                solutions.append({m12: r12, m11: r11.subs(m12, r12), m22: r22.subs(m12, r12)})
    chosen = []
    for s in solutions:
        if any(e.has(sp.zoo, sp.oo, sp.nan) for e in s.values()):
            continue  # m11 = −1 (m12 = 0) makes the gain's denominator vanish
        ok = True
        f = sp.lambdify(L, (s[m11], s[m12], s[m22]), "cmath")
        for v in (0.1, 1.0, 7.0):
            v11, v12, v22 = (complex(x) for x in f(v))
            Mv = np.array([[v11, v12], [v12, v22]])
            if np.max(np.abs(Mv.imag)) > 1e-9 or np.min(np.linalg.eigvalsh(Mv.real)) <= 0:
                ok = False
                break
        if ok:
            chosen.append(s)
    if len(chosen) != 1:  # pragma: no cover
        raise RuntimeError(f"expected one positive-definite DARE root, found {len(chosen)}")
    s = chosen[0]
    Msol = sp.Matrix([[s[m11], s[m12]], [s[m12], s[m22]]])
    # α = m11/(m11 + 1) = 1 − Λ²/m12², using (2,2): m11 + 1 = m12²/Λ²
    if sp.simplify(s[m11] + 1 - s[m12] ** 2 / L**2) != 0:  # pragma: no cover
        raise RuntimeError("the (2,2) equation m11 + 1 = m12²/Λ² does not hold at the chosen root")
    alpha = sp.expand(1 - sp.radsimp(L**2 / s[m12] ** 2))
    beta = sp.radsimp(sp.cancel(s[m12] / (s[m11] + 1)))  # β = T·k2 with T = 1
    r = sp.sqrt(L**2 + 8 * L)
    alpha_k = -(L**2 + 8 * L - (L + 4) * r) / 8
    beta_k = (L**2 + 4 * L - L * r) / 4
    for v in (0.01, 0.3, 1.0, 4.0, 50.0):
        if abs(complex(alpha.subs(L, v)) - float(alpha_k.subs(L, v))) > 1e-10 or abs(
            complex(beta.subs(L, v)) - float(beta_k.subs(L, v))
        ) > 1e-10:  # pragma: no cover
            raise RuntimeError("DARE root does not match Kalata's closed form")
    f = sp.lambdify(L, (alpha_k, beta_k), "numpy")

    def numeric(Lambda):
        """``(α, β)`` for tracking index ``Λ >= 0``."""
        Lv = np.asarray(check_finite("Lambda", Lambda), dtype=float)
        if np.any(Lv < 0):
            raise ValueError(f"Lambda must be >= 0, got {Lambda!r}")
        a_, b_ = f(Lv)
        if np.ndim(a_) == 0:
            return float(a_), float(b_)
        return np.asarray(a_), np.asarray(b_)

    return KalataDerivation(equations=equations, M=Msol, alpha=alpha, beta=beta,
                            alpha_kalata=alpha_k, beta_kalata=beta_k, numeric=numeric)


def kalata_gains_closed_form(Lambda):
    """``(α, β)`` of the steady-state α-β filter for tracking index ``Λ`` (Kalata 1984).

    Parameters
    ----------
    Lambda : float or array_like, >= 0
        Tracking index.

    Returns
    -------
    (alpha, beta) : floats or arrays
    """
    return finite_result("Lambda", lambda: derive_kalata_gains().numeric(Lambda))
