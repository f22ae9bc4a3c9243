"""Discrete-time steady-state Kalman gains (filter and predictor form), DARE residual, Van Loan noise discretisation."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.integrate
import scipy.linalg

from ..._validate import (
    check_finite,
    check_int,
    check_matrix,
    check_positive,
    finite_result,
)
from ._checks import (
    _covariance,
    _prepare,
    _riccati_solution,
    _square,
    _sym,
    _symb,
    _system,
)

__all__ = ["DiscreteSteadyState", "discrete_steady_state", "discrete_steady_state_batch", "dare_residual",
           "discretize_noise"]


# --------------------------------------------------------------------------------------------
# discrete time
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class DiscreteSteadyState:
    """Steady state of the discrete Kalman filter, in both of its usual forms.

    Attributes
    ----------
    K_filter : numpy.ndarray, shape (n, p)
        **Filter-form** gain ``K = P⁻ Hᵀ (H P⁻ Hᵀ + R)⁻¹`` of the measurement update
        ``x̂(k|k) = x̂(k|k−1) + K (y(k) − H x̂(k|k−1))``. For a 2-state position/velocity model
        these are the α-β gains ``[α, β/T]``.
    L_predictor : numpy.ndarray, shape (n, p)
        **Predictor-form** gain ``L = F K`` of the one-step predictor
        ``x̂(k+1|k) = F x̂(k|k−1) + L (y(k) − H x̂(k|k−1))``; this is what
        :func:`control.dlqe` returns.
    P_prior : numpy.ndarray, shape (n, n)
        A-priori covariance ``P⁻ = P(k|k−1)``, the solution of the filter DARE.
    P_post : numpy.ndarray, shape (n, n)
        A-posteriori covariance ``P(k|k) = (I − K H) P⁻``.
    poles : numpy.ndarray, shape (n,)
        Eigenvalues of ``F − L H`` (= those of ``(I − K H) F``), inside the unit circle.
    """

    K_filter: np.ndarray
    L_predictor: np.ndarray
    P_prior: np.ndarray
    P_post: np.ndarray
    poles: np.ndarray


def discrete_steady_state(F, H, G, Q, R, *, require: str = "detectable") -> DiscreteSteadyState:
    """Steady-state discrete Kalman filter: filter-form and predictor-form gains and covariances.

    The a-priori covariance solves the filter discrete ARE

        P⁻ = F P⁻ Fᵀ − F P⁻ Hᵀ (H P⁻ Hᵀ + R)⁻¹ H P⁻ Fᵀ + G Q Gᵀ,

    solved with :func:`control.dlqe` (which returns the predictor gain ``L = F P⁻ Hᵀ (H P⁻ Hᵀ + R)⁻¹``).
    The filter-form gain is ``K = P⁻ Hᵀ (H P⁻ Hᵀ + R)⁻¹`` so that ``L = F K``.

    Parameters
    ----------
    F : array_like, shape (n, n)
        State-transition matrix.
    H : array_like, shape (p, n)
        Measurement matrix.
    G : array_like, shape (n, m)
        Process-noise input matrix.
    Q : float or array_like, shape (m, m)
        Covariance of ``w(k)`` (>= 0).
    R : float or array_like, shape (p, p)
        Covariance of ``v(k)`` (> 0).
    require : {'detectable', 'observable'}
        Condition imposed on ``(F, H)``.

    Returns
    -------
    DiscreteSteadyState

    Raises
    ------
    ValueError
        As :func:`continuous_steady_state`.

    References
    ----------
    R. E. Kalman, "A new approach to linear filtering and prediction problems", J. Basic Eng. 82
    (1960) 35–45; B. D. O. Anderson and J. B. Moore, *Optimal Filtering* (1979), ch. 3–4
    (filter vs one-step-predictor forms).

    Examples
    --------
    >>> ss = discrete_steady_state([[1, 1], [0, 1]], [[1, 0]], [[0.5], [1]], 1.0, 1.0)
    >>> np.allclose(ss.L_predictor, np.array([[1, 1], [0, 1]]) @ ss.K_filter)
    True
    """
    import control as ct

    F, H, G, Q, R = _prepare(F, H, G, Q, R, discrete=True, require=require, names=("F", "H", "G"))
    GQGt = _sym(G @ Q @ G.T)  # exactly symmetric (python-control checks symmetry strictly)
    # python-control: dlqe(F, G, H, Q, R) -> L (predictor form), P⁻ (DARE solution), eig(F − L H);
    # verified, else solved unbalanced
    L, P, E = _riccati_solution(lambda: ct.dlqe(F, np.eye(F.shape[0]), H, GQGt, R),
                                lambda: scipy.linalg.solve_discrete_are(F.T, H.T, GQGt, R, balanced=False),
                                lambda P: _dare_solved(F, H, GQGt, R, P), "DARE", names=("F", "H", "G"))
    S = H @ P @ H.T + R  # innovation covariance
    K = np.linalg.solve(S, H @ P).T  # K = P⁻ Hᵀ S⁻¹ (filter form)
    if L is None:
        L = F @ K  # predictor form
        E = np.linalg.eigvals(F - L @ H)
    P_post = P - K @ H @ P  # P(k|k) = (I − K H) P⁻
    return DiscreteSteadyState(
        K_filter=K,
        L_predictor=np.asarray(L, dtype=float),
        P_prior=P,
        P_post=0.5 * (P_post + P_post.T),
        poles=np.asarray(E),
    )


def _dare_solved(F, H, GQGt, R, P) -> bool:
    """Whether ``P`` (a-priori) satisfies the filter DARE to a relative accuracy of 1e-8."""
    scale = max(1.0, np.abs(F @ P @ F.T).max(), np.abs(P).max(), np.abs(GQGt).max())
    return bool(np.all(np.isfinite(P)) and np.abs(_dare_residual(F, H, GQGt, R, P)).max() <= 1e-8 * scale)


def _dare_residual(F, H, GQGt, R, P) -> np.ndarray:
    """Unchecked kernel of :func:`dare_residual`."""
    FPHt = F @ P @ H.T
    return F @ P @ F.T - FPHt @ np.linalg.solve(H @ P @ H.T + R, FPHt.T) + GQGt - P


def discrete_steady_state_batch(F, H, Qd, R, *, tol: float = 1e-12, max_iter: int = 100) -> DiscreteSteadyState:
    """Many small filter DAREs at once (leading batch axis) by the structured doubling algorithm.

    Solves ``P⁻ = F P⁻ Fᵀ − F P⁻ Hᵀ (H P⁻ Hᵀ + R)⁻¹ H P⁻ Fᵀ + Q_d`` for every element of a batch
    (e.g. a sweep over sampling periods) with stacked 2-D linear algebra only, which is much
    faster than one :func:`control.dlqe` call per element. Same outputs as
    :func:`discrete_steady_state` (with ``G = I``), each with a leading batch axis.

    The doubling iteration (dual/filter form, ``A₀ = Fᵀ``, ``G₀ = Hᵀ R⁻¹ H``, ``H₀ = Q_d``)::

        W  = I + G_k H_k
        A_{k+1} = A_k W⁻¹ A_k
        G_{k+1} = G_k + A_k W⁻¹ G_k A_kᵀ
        H_{k+1} = H_k + A_kᵀ H_k W⁻¹ A_k      →  P⁻

    converges quadratically when ``(F, H)`` is detectable and ``(F, Q_d^½)`` stabilisable (not
    checked element by element here; use :func:`discrete_steady_state` for one system with
    full checks).

    Parameters
    ----------
    F : array_like, shape (B, n, n)
    H : array_like, shape (B, p, n) or (p, n)
    Qd : array_like, shape (B, n, n) or (n, n)
        Process-noise covariance (``G Q Gᵀ``), symmetric >= 0.
    R : array_like, shape (B, p, p), (p, p), (B,) or scalar
        Measurement-noise covariance, > 0 (the last two forms for ``p = 1``).
    tol : float
        Relative change of ``H_k`` at which to stop (finite, > 0).
    max_iter : int
        Largest number of doubling steps (>= 1).

    Returns
    -------
    DiscreteSteadyState
        Fields with a leading batch axis.

    Raises
    ------
    ValueError
        On NaN/inf, inconsistent shapes, ``R`` not > 0, ``tol`` not > 0, ``max_iter < 1``, or no
        convergence in ``max_iter``.
    TypeError
        ``tol`` not a real number or ``max_iter`` not an integer.

    References
    ----------
    E. K.-W. Chu, H.-Y. Fan, W.-W. Lin, C.-S. Wang, "Structure-preserving algorithms for periodic
    discrete-time algebraic Riccati equations", Int. J. Control 77(8), 2004; W.-W. Lin and
    S.-F. Xu, "Convergence analysis of structure-preserving doubling algorithms for Riccati-type
    matrix equations", SIAM J. Matrix Anal. Appl. 28(1), 2006.
    """
    tol = check_positive("tol", tol, scalar=True)
    max_iter = check_int("max_iter", max_iter, minimum=1)
    F = np.asarray(check_finite("F", F), dtype=float)
    if F.ndim != 3 or F.shape[1] != F.shape[2]:
        raise ValueError(f"F must have shape (B, n, n), got {F.shape}")
    nb, n = F.shape[0], F.shape[1]
    H = np.asarray(check_finite("H", H), dtype=float)
    H = np.broadcast_to(H, (nb,) + H.shape[-2:]) if H.ndim in (2, 3) else H
    if H.ndim != 3 or H.shape[2] != n:
        raise ValueError(f"H must have shape (B, p, {n}) or (p, {n}), got {np.shape(H)}")
    p = H.shape[1]
    Qd = np.asarray(check_finite("Qd", Qd), dtype=float)
    if Qd.shape[-2:] != (n, n):
        raise ValueError(f"Qd must have shape (B, {n}, {n}) or ({n}, {n}), got {Qd.shape}")
    Qd = np.broadcast_to(Qd, (nb, n, n))
    if np.any(np.linalg.eigvalsh(_symb(Qd)).min(axis=-1) < -1e-12 * np.abs(Qd).max(axis=(-2, -1))):
        raise ValueError("Qd must be positive semidefinite (>= 0)")
    R = np.asarray(check_finite("R", R), dtype=float)
    if R.ndim < 2:  # a scalar, or one scalar per batch element (p = 1)
        R = R.reshape(R.shape + (1, 1))
    if R.shape[-2:] != (p, p) or R.ndim > 3 or (R.ndim == 3 and R.shape[0] not in (1, nb)):
        raise ValueError(f"R must have shape (B, {p}, {p}), ({p}, {p}), (B,) or be a scalar (p = {p} rows of H), "
                         f"got {R.shape}")
    R = np.broadcast_to(R, (nb, p, p))
    if np.any(np.linalg.eigvalsh(_symb(R)).min(axis=-1) <= 0):
        raise ValueError(f"R must be > 0 (positive definite), got smallest eigenvalue "
                         f"{np.linalg.eigvalsh(_symb(R)).min():g}")
    Ht = np.swapaxes(H, -1, -2)
    Ak = np.swapaxes(F, -1, -2).copy()
    Gk = Ht @ np.linalg.solve(R, H)
    Hk = _symb(Qd).copy()
    eye = np.eye(n)
    for _ in range(max_iter):
        W = eye + Gk @ Hk
        WA = np.linalg.solve(W, Ak)
        WG = np.linalg.solve(W, Gk)
        AkT = np.swapaxes(Ak, -1, -2)
        H_new = _symb(Hk + AkT @ Hk @ WA)
        Gk = _symb(Gk + Ak @ WG @ AkT)
        Ak = Ak @ WA
        change = np.abs(H_new - Hk).max(axis=(-2, -1)) / np.maximum(np.abs(H_new).max(axis=(-2, -1)), 1e-300)
        Hk = H_new
        if np.all(change <= tol):
            break
    else:
        raise ValueError(f"doubling iteration did not converge in max_iter={max_iter} steps "
                         f"(largest relative change {change.max():.2e}); check detectability of (F, H) and the scaling "
                         f"of Qd and R")
    P = Hk
    S = H @ P @ Ht + R
    K = np.swapaxes(np.linalg.solve(S, H @ P), -1, -2)  # K = P⁻ Hᵀ S⁻¹
    L = F @ K  # predictor form
    P_post = _symb(P - K @ H @ P)
    return DiscreteSteadyState(K_filter=K, L_predictor=L, P_prior=P, P_post=P_post,
                               poles=np.linalg.eigvals(F - L @ H))


def dare_residual(F, H, G, Q, R, P_prior) -> np.ndarray:
    """Residual ``F P Fᵀ − F P Hᵀ (H P Hᵀ + R)⁻¹ H P Fᵀ + G Q Gᵀ − P`` of the filter DARE (a-priori ``P``).

    Parameters
    ----------
    F, H, G : array_like
        Transition ``(n, n)``, measurement ``(p, n)`` and process-noise input ``(n, m)`` matrices.
    Q, R : array_like
        Process- and measurement-noise covariances, ``(m, m)`` positive semidefinite and
        ``(p, p)`` positive definite.
    P_prior : array_like, shape (n, n)
        Candidate a-priori covariance.

    Returns
    -------
    numpy.ndarray, shape (n, n)
        The residual (zero at a solution).
    """
    F, H, G = _system(F, H, G, names=("F", "H", "G"))
    n = F.shape[0]
    Q = _covariance("Q", Q, G.shape[1], definite=False, per="one row per column of G")
    R = _covariance("R", R, H.shape[0], definite=True, per="one row per output of H")
    P = check_matrix("P_prior", P_prior, shape=(n, n))
    return finite_result("F, H, G, Q, R and P_prior", lambda: _dare_residual(F, H, G @ Q @ G.T, R, P))


def discretize_noise(A, G, Q, T):
    """Exact sampling of ``ẋ = A x + G w`` (white ``w`` of intensity ``Q``) with period ``T``.

    Van Loan's method: with ``M = [[−A, G Q Gᵀ], [0, Aᵀ]] T`` and ``e^M = [[·, M12], [0, M22]]``,
    ``F = M22ᵀ = e^{A T}`` and ``Q_d = F M12 = ∫₀ᵀ e^{Aτ} G Q Gᵀ e^{Aᵀτ} dτ``. The matching
    discrete measurement-noise covariance of a continuous white ``v`` of intensity ``R``,
    averaged over a sample, is ``R / T`` (not computed here).

    Parameters
    ----------
    A : array_like, shape (n, n)
    G : array_like, shape (n, m)
    Q : float or array_like, shape (m, m), >= 0
    T : float, > 0
        Sampling period (s).

    Returns
    -------
    F : numpy.ndarray, shape (n, n)
    Qd : numpy.ndarray, shape (n, n)
        Covariance of the discrete process noise (use with ``G = I`` in :func:`discrete_steady_state`).

    References
    ----------
    C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE TAC 23(3), 1978.
    """
    A = _square("A", A)
    n = A.shape[0]
    G = check_matrix("G", G)
    if G.shape[0] != n:
        raise ValueError(f"G must have {n} rows (the order of A), got shape {G.shape}")
    Q = _covariance("Q", Q, G.shape[1], definite=False, per="one row per column of G")
    T = check_positive("T", T, scalar=True)
    M = np.zeros((2 * n, 2 * n))
    M[:n, :n] = -A
    M[:n, n:] = G @ Q @ G.T
    M[n:, n:] = A.T
    with np.errstate(over="ignore", invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the result is checked below
        E = finite_result("A, G, Q and T", lambda: scipy.linalg.expm(M * T))
    F = E[n:, n:].T
    Qd = finite_result("A, G, Q and T", lambda: F @ E[:n, n:])
    return F, 0.5 * (Qd + Qd.T)


