"""Argument checks and controllability / observability / detectability tests for the Kalman modules."""

from __future__ import annotations

import warnings

import control as ct
import numpy as np

from ..._validate import check_finite, check_matrix, finite_result

__all__ = ["controllability_matrix", "observability_matrix", "controllability_rank", "observability_rank",
           "check_controllable", "check_observable", "check_detectable"]


# --------------------------------------------------------------------------------------------
# argument checks
# --------------------------------------------------------------------------------------------


def _square(name: str, value) -> np.ndarray:
    return check_matrix(name, value, square=True)


_NO_G = object()


def _system(A, C, G=_NO_G, *, names=("A", "C", "G")):
    """Validate A (n×n), C (p×n) and optional G (n×m); return float arrays.

    ``names`` are the caller's names of the three matrices (``("F", "H", "G")`` in discrete time),
    used in every error message.
    """
    a, c, g = names
    A = _square(a, A)
    n = A.shape[0]
    C = check_matrix(c, C)
    if C.shape[1] != n:
        raise ValueError(f"{c} must have {n} columns (the order of {a}), got shape {C.shape}")
    if G is _NO_G:
        return A, C
    G = check_matrix(g, G)
    if G.shape[0] != n:
        # a 1-D G given as a row is read as a column
        if G.shape == (1, n):
            G = G.T
        else:
            raise ValueError(f"{g} must have {n} rows (the order of {a}), got shape {G.shape}")
    return A, C, G


def _sym(M: np.ndarray) -> np.ndarray:
    return 0.5 * (M + M.T)


def _symb(M: np.ndarray) -> np.ndarray:
    """Symmetric part of a stack of matrices."""
    return 0.5 * (M + np.swapaxes(M, -1, -2))


def _covariance(name: str, value, size: int, *, definite: bool, per: str = "") -> np.ndarray:
    """A symmetric size×size covariance; positive definite if ``definite`` else semidefinite.

    ``per`` says where ``size`` comes from (e.g. ``"one row per output of C"``), for the message."""
    arr = np.atleast_2d(check_finite(name, value))
    per = f" ({per})" if per else ""
    if arr.shape == (1, 1) and size > 1:
        raise ValueError(f"{name} must have shape ({size}, {size}){per}, got a scalar")
    if arr.shape != (size, size):
        raise ValueError(f"{name} must have shape ({size}, {size}){per}, got {arr.shape}")
    if not np.allclose(arr, arr.T, rtol=1e-10, atol=1e-12):
        raise ValueError(f"{name} must be symmetric")
    arr = _sym(arr)
    eig = np.linalg.eigvalsh(arr)
    tol = 1e-12 * max(1.0, float(np.max(np.abs(eig))))
    shown = value if np.ndim(value) == 0 else eig.min()
    if definite and eig.min() <= 0:
        if size == 1:
            raise ValueError(f"{name} must be > 0, got {float(arr[0, 0]):g}")
        raise ValueError(f"{name} must be positive definite (> 0), smallest eigenvalue {shown:g}")
    if not definite and eig.min() < -tol:
        if size == 1:
            raise ValueError(f"{name} must be >= 0, got {float(arr[0, 0]):g}")
        raise ValueError(f"{name} must be positive semidefinite (>= 0), smallest eigenvalue {shown:g}")
    return arr


# --------------------------------------------------------------------------------------------
# controllability / observability
# --------------------------------------------------------------------------------------------


def controllability_matrix(A, B) -> np.ndarray:
    """``[B, A B, …, A^(n-1) B]``.

    Parameters
    ----------
    A : array_like, shape (n, n)
    B : array_like, shape (n, m)

    Returns
    -------
    numpy.ndarray, shape (n, n·m)
    """
    A = _square("A", A)
    B = check_matrix("B", B)
    n = A.shape[0]
    if B.shape[0] != n:
        raise ValueError(f"B must have {n} rows (the order of A), got shape {B.shape}")
    return np.asarray(ct.ctrb(A, B))


def observability_matrix(A, C) -> np.ndarray:
    """``[C; C A; …; C A^(n-1)]`` (rows ``C A^i``; note ``C A``, not ``A C``).

    Parameters
    ----------
    A : array_like, shape (n, n)
    C : array_like, shape (p, n)

    Returns
    -------
    numpy.ndarray, shape (n·p, n)
    """
    A, C = _system(A, C)
    return np.asarray(ct.obsv(A, C))


def _rank(M: np.ndarray) -> int:
    s = np.linalg.svd(M, compute_uv=False)
    if s.size == 0:
        return 0
    return int(np.sum(s > max(M.shape) * np.finfo(float).eps * max(s[0], 1.0)))


def controllability_rank(A, B) -> int:
    """Rank of the controllability matrix of ``(A, B)``.

    Parameters
    ----------
    A, B : array_like
        As in :func:`controllability_matrix`.

    Returns
    -------
    int
        Numerical rank of ``[B, A B, …, A^(n-1) B]`` (SVD, tolerance scaled by the largest
        singular value).
    """
    return _rank(controllability_matrix(A, B))


def observability_rank(A, C) -> int:
    """Rank of the observability matrix of ``(A, C)``.

    Parameters
    ----------
    A, C : array_like
        As in :func:`observability_matrix`; by duality the result equals
        ``controllability_rank(A.T, C.T)``.

    Returns
    -------
    int
    """
    return _rank(observability_matrix(A, C))


def check_controllable(A, B, *, names=("A", "B")) -> int:
    """Return ``n`` if ``(A, B)`` is controllable, else raise.

    Parameters
    ----------
    A : array_like, shape (n, n)
    B : array_like, shape (n, m)
    names : tuple of str
        Names of the two matrices in the error message.

    Returns
    -------
    int
        The rank of the controllability matrix, equal to ``n``.

    Raises
    ------
    ValueError
        ``(A, B) must be controllable: rank [B, AB, …] = r < n``.
    """
    r = controllability_rank(A, B)
    n = np.atleast_2d(A).shape[0]
    if r < n:
        raise ValueError(
            f"({names[0]}, {names[1]}) must be controllable: rank [{names[1]}, {names[0]}{names[1]}, ...] "
            f"= {r} < n = {n}"
        )
    return r


def check_observable(A, C, *, names=("A", "C")) -> int:
    """Return ``n`` if ``(A, C)`` is observable, else raise.

    The dual of :func:`check_controllable`: ``(A, C)`` is observable iff ``(Aᵀ, Cᵀ)`` is
    controllable.

    Parameters
    ----------
    A, C : array_like
        Shapes ``(n, n)`` and ``(p, n)``.
    names : tuple of str
        What the error message calls ``A`` and ``C``.

    Returns
    -------
    n : int
        The order of ``A`` (the rank of ``[C; C A; …]``).

    Raises
    ------
    ValueError
        ``(A, C) must be observable: rank [C; CA; …] = r < n``.
    """
    A, C = _system(A, C, names=(names[0], names[1], "G"))
    r = observability_rank(A, C)
    n = A.shape[0]
    if r < n:
        raise ValueError(
            f"({names[0]}, {names[1]}) must be observable: rank [{names[1]}; {names[1]}{names[0]}; ...] "
            f"= {r} < n = {n}"
        )
    return r


def _unobservable_bad_modes(A: np.ndarray, C: np.ndarray, discrete: bool) -> list:
    """Eigenvalues of A that are unobservable from C (PBH test) and not strictly stable."""
    n = A.shape[0]
    bad = []
    for lam in np.linalg.eigvals(A):
        stable = abs(lam) < 1 - 1e-12 if discrete else lam.real < -1e-12
        if stable:
            continue
        M = np.vstack([A - lam * np.eye(n), C])
        if _rank(M) < n and not any(abs(lam - b) < 1e-9 for b in bad):
            bad.append(complex(lam))
    return bad


def check_detectable(A, C, *, discrete: bool = False, names=("A", "C")) -> None:
    """Raise unless every unstable (or marginal) mode of ``A`` is observable from ``C`` (PBH test).

    Detectability of ``(A, C)`` is what a stabilising Riccati solution needs; observability
    (:func:`check_observable`) is the stronger condition of the Kalman–Bucy stability theorem.

    Parameters
    ----------
    A : array_like, shape (n, n)
    C : array_like, shape (p, n)
    discrete : bool
        Stability region: the open unit disc (``True``) or the open left half-plane (``False``).
    names : tuple of str
        Names of the two matrices in the error message.

    Raises
    ------
    ValueError
        ``(A, C) must be detectable: mode λ of A is unobservable from C and not stable``.
    """
    A, C = _system(A, C, names=(names[0], names[1], "G"))
    bad = _unobservable_bad_modes(A, C, discrete)
    if bad:
        region = "inside the unit circle" if discrete else "in the open left half-plane"
        raise ValueError(
            f"({names[0]}, {names[1]}) must be detectable (every mode not {region} observable), "
            f"but mode(s) {[complex(round(b.real, 12), round(b.imag, 12)) for b in bad]} of {names[0]} "
            f"are unobservable from {names[1]} (PBH rank test; the pair is unobservable)"
        )


def _check_noise_reaches_marginal_modes(A, GQ, discrete: bool, names=("A", "G")) -> None:
    """(A, G Q^½) must have no uncontrollable mode on the stability boundary."""
    a, g = names
    n = A.shape[0]
    for lam in np.linalg.eigvals(A):
        on_boundary = abs(abs(lam) - 1) < 1e-9 if discrete else abs(lam.real) < 1e-9
        if on_boundary and _rank(np.hstack([A - lam * np.eye(n), GQ])) < n:
            where = "on the unit circle" if discrete else "on the imaginary axis"
            raise ValueError(
                f"({a}, {g}·Q^½) must have no uncontrollable mode {where}; mode {complex(lam):g} of {a} "
                f"is not excited by the process noise {g} w (check {g} and Q)"
            )


def _prepare(A, C, G, Q, R, discrete: bool, require: str, names=("A", "C", "G")):
    if require not in ("detectable", "observable"):
        raise ValueError(f"require must be one of ['detectable', 'observable'], got {require!r}")
    A, C, G = _system(A, C, G, names=names)
    Q = _covariance("Q", Q, G.shape[1], definite=False, per=f"one row per column of {names[2]}")
    R = _covariance("R", R, C.shape[0], definite=True, per=f"one row per output of {names[1]}")
    _check_scaling(C, G, Q, R, names)
    if require == "observable":
        check_observable(A, C, names=names[:2])
    else:
        check_detectable(A, C, discrete=discrete, names=names[:2])
    w, V = np.linalg.eigh(Q)
    GQ = G @ V @ np.diag(np.sqrt(np.clip(w, 0.0, None)))
    _check_noise_reaches_marginal_modes(A, GQ, discrete, names=(names[0], names[2]))
    return A, C, G, Q, R




def _check_scaling(C, G, Q, R, names) -> None:
    """The Riccati equation's terms G Q Gᵀ and Cᵀ R⁻¹ C must be finite (no overflow of double precision)."""
    finite_result(f"{names[2]} and Q", lambda: G @ Q @ G.T)
    finite_result(f"{names[1]} and R", lambda: C.T @ np.linalg.solve(R, C))


def _riccati_solution(primary, unbalanced, solved, equation: str, names=("A", "C", "G")):
    """The stabilising solution of a filter Riccati equation, verified.

    ``primary()`` (python-control) returns ``(gain, P, poles)``; when it fails or ``solved(P)`` is
    False (scipy's balancing can spoil a badly scaled problem, e.g. an entry of 1e-200), ``P`` is
    recomputed by ``unbalanced()``. Returns ``(gain, P, poles)`` of the primary solver, or
    ``(None, P, None)`` after the fallback (the caller then derives gain and poles from ``P``).
    """
    a, c, g = names
    try:
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # the result is verified below
            gain, P, poles = primary()
        P = _sym(np.asarray(P, dtype=float))
        if solved(P):
            return gain, P, poles
    except np.linalg.LinAlgError:
        pass
    try:
        P = _sym(np.asarray(unbalanced(), dtype=float))
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(f"the filter {equation} has no stabilising solution in double precision ({exc}); "
                         f"({a}, {c}) or ({a}, {g}·Q^½) is numerically close to losing detectability / "
                         "stabilisability, or Q and R are of extreme magnitude") from None
    if not solved(P):
        raise ValueError(f"the filter {equation} could not be solved accurately in double precision (residual "
                         f"too large); check the scaling of {a}, {c}, {g}, Q and R")
    return None, P, None
