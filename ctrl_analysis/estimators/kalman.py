"""Steady-state Kalman filtering: continuous and discrete gains, Riccati equations, α-β filters.

Building blocks, independent of any paper:

* controllability / observability ranks and checks (with errors that name the argument);
* the continuous steady-state Kalman–Bucy gain ``K = P Cᵀ R⁻¹`` from the filter algebraic
  Riccati equation (ARE) ``A P + P Aᵀ − P Cᵀ R⁻¹ C P + G Q Gᵀ = 0``;
* the Riccati differential equation ``Ṗ = A P + P Aᵀ − P Cᵀ R⁻¹ C P + G Q Gᵀ`` integrated from
  any ``P(0)`` (it converges to the ARE solution ``P̄``, not to zero);
* the discrete steady-state gain in **filter form** (``K``, the update gain of ``x̂(k|k)``) and in
  **predictor form** (``L = F K``, the gain of ``x̂(k+1|k)`` that ``control.dlqe`` returns);
* sampled-data noise discretisation (Van Loan);
* α-β gains from a 2-state filter gain, Kalata's tracking index and closed forms;
* a constant-gain discrete α-β filter block with ``reset()`` / ``step(y)`` over a batch axis;
* the scalar random-walk steady-state gain ``K∞(Q/R)``.

Conventions
-----------
Continuous model: ``ẋ = A x + B u + G w``, ``y = C x + v``, ``E[w wᵀ] = Q δ``, ``E[v vᵀ] = R δ``.
Discrete model: ``x(k+1) = F x(k) + G w(k)``, ``y(k) = H x(k) + v(k)``, ``cov w = Q``, ``cov v = R``.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.integrate
import scipy.linalg

from .._validate import check_finite, check_matrix, check_positive

__all__ = [
    "controllability_matrix",
    "observability_matrix",
    "controllability_rank",
    "observability_rank",
    "check_controllable",
    "check_observable",
    "check_detectable",
    "ContinuousSteadyState",
    "continuous_steady_state",
    "continuous_steady_state_gain",
    "care_residual",
    "riccati_rhs",
    "riccati_trajectory",
    "DiscreteSteadyState",
    "discrete_steady_state",
    "discrete_steady_state_batch",
    "dare_residual",
    "discretize_noise",
    "alpha_beta_from_gain",
    "gain_from_alpha_beta",
    "tracking_index",
    "tracking_index_from_gains",
    "kalata_gains",
    "alpha_beta_stable",
    "AlphaBetaFilter",
    "random_walk_gain",
]


# --------------------------------------------------------------------------------------------
# argument checks
# --------------------------------------------------------------------------------------------


def _square(name: str, value) -> np.ndarray:
    return check_matrix(name, value, square=True)


def _system(A, C, G=None):
    """Validate A (n×n), C (p×n) and optional G (n×m); return float arrays."""
    A = _square("A", A)
    n = A.shape[0]
    C = check_matrix("C", C)
    if C.shape[1] != n:
        raise ValueError(f"C must have {n} columns (the order of A), got shape {C.shape}")
    if G is None:
        return A, C
    G = check_matrix("G", G)
    if G.shape[0] != n:
        # a 1-D G given as a row is read as a column
        if G.shape == (1, n):
            G = G.T
        else:
            raise ValueError(f"G must have {n} rows (the order of A), got shape {G.shape}")
    return A, C, G


def _sym(M: np.ndarray) -> np.ndarray:
    return 0.5 * (M + M.T)


def _symb(M: np.ndarray) -> np.ndarray:
    """Symmetric part of a stack of matrices."""
    return 0.5 * (M + np.swapaxes(M, -1, -2))


def _covariance(name: str, value, size: int, *, definite: bool) -> np.ndarray:
    """A symmetric size×size covariance; positive definite if ``definite`` else semidefinite."""
    arr = np.atleast_2d(check_finite(name, value))
    if arr.shape == (1, 1) and size > 1:
        raise ValueError(f"{name} must have shape ({size}, {size}), got a scalar")
    if arr.shape != (size, size):
        raise ValueError(f"{name} must have shape ({size}, {size}), got {arr.shape}")
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
    """Rank of the controllability matrix of ``(A, B)``."""
    return _rank(controllability_matrix(A, B))


def observability_rank(A, C) -> int:
    """Rank of the observability matrix of ``(A, C)``."""
    return _rank(observability_matrix(A, C))


def check_controllable(A, B, *, names=("A", "B")) -> int:
    """Return ``n`` if ``(A, B)`` is controllable, else raise.

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

    Raises
    ------
    ValueError
        ``(A, C) must be observable: rank [C; CA; …] = r < n``.
    """
    r = observability_rank(A, C)
    n = np.atleast_2d(A).shape[0]
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

    Raises
    ------
    ValueError
        ``(A, C) must be detectable: mode λ of A is unobservable from C and not stable``.
    """
    A, C = _system(A, C)
    bad = _unobservable_bad_modes(A, C, discrete)
    if bad:
        region = "inside the unit circle" if discrete else "in the open left half-plane"
        raise ValueError(
            f"({names[0]}, {names[1]}) must be detectable (every mode not {region} observable), "
            f"but mode(s) {[complex(round(b.real, 12), round(b.imag, 12)) for b in bad]} of {names[0]} "
            f"are unobservable from {names[1]} (PBH rank test; the pair is unobservable)"
        )


def _check_noise_reaches_marginal_modes(A, GQ, discrete: bool) -> None:
    """(A, G Q^½) must have no uncontrollable mode on the stability boundary."""
    n = A.shape[0]
    for lam in np.linalg.eigvals(A):
        on_boundary = abs(abs(lam) - 1) < 1e-9 if discrete else abs(lam.real) < 1e-9
        if on_boundary and _rank(np.hstack([A - lam * np.eye(n), GQ])) < n:
            where = "on the unit circle" if discrete else "on the imaginary axis"
            raise ValueError(
                f"(A, G·Q^½) must have no uncontrollable mode {where}; mode {complex(lam):g} of A "
                "is not excited by the process noise G w (check G and Q)"
            )


def _prepare(A, C, G, Q, R, discrete: bool, require: str):
    A, C, G = _system(A, C, G)
    Q = _covariance("Q", Q, G.shape[1], definite=False)
    R = _covariance("R", R, C.shape[0], definite=True)
    if require == "observable":
        check_observable(A, C)
    elif require == "detectable":
        check_detectable(A, C, discrete=discrete)
    else:
        raise ValueError(f"require must be one of ['detectable', 'observable'], got {require!r}")
    w, V = np.linalg.eigh(Q)
    GQ = G @ V @ np.diag(np.sqrt(np.clip(w, 0.0, None)))
    _check_noise_reaches_marginal_modes(A, GQ, discrete)
    return A, C, G, Q, R


# --------------------------------------------------------------------------------------------
# continuous time
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ContinuousSteadyState:
    """Steady state of the Kalman–Bucy filter.

    Attributes
    ----------
    K : numpy.ndarray, shape (n, p)
        Steady-state gain ``K = P̄ Cᵀ R⁻¹`` of ``x̂' = A x̂ + B u + K (y − C x̂)``.
    P : numpy.ndarray, shape (n, n)
        Stabilising solution ``P̄`` of ``A P + P Aᵀ − P Cᵀ R⁻¹ C P + G Q Gᵀ = 0``.
    poles : numpy.ndarray, shape (n,)
        Eigenvalues of ``A − K C`` (all in the open left half-plane).
    """

    K: np.ndarray
    P: np.ndarray
    poles: np.ndarray


def continuous_steady_state(A, C, G, Q, R, *, require: str = "detectable") -> ContinuousSteadyState:
    """Steady-state Kalman–Bucy filter: ARE solution, gain and filter poles.

    Solves the filter algebraic Riccati equation

        A P + P Aᵀ − P Cᵀ R⁻¹ C P + G Q Gᵀ = 0

    for its stabilising solution with :func:`control.lqe`, and returns ``K = P Cᵀ R⁻¹``.

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix.
    C : array_like, shape (p, n)
        Output matrix.
    G : array_like, shape (n, m)
        Process-noise input matrix (Γ).
    Q : float or array_like, shape (m, m)
        Process-noise intensity (>= 0).
    R : float or array_like, shape (p, p)
        Measurement-noise intensity (> 0).
    require : {'detectable', 'observable'}
        Condition imposed on ``(A, C)``: detectability suffices for a stabilising solution;
        ``'observable'`` is the Kalman–Bucy stability theorem's condition.

    Returns
    -------
    ContinuousSteadyState

    Raises
    ------
    ValueError
        On a NaN/inf entry, wrong shapes, ``Q`` not >= 0, ``R`` not > 0, an undetectable
        (or, with ``require='observable'``, unobservable) pair ``(A, C)``, or a marginal mode
        that the noise does not excite.

    References
    ----------
    R. E. Kalman and R. S. Bucy, "New results in linear filtering and prediction theory",
    J. Basic Eng. 83 (1961) 95–108: the filter Riccati equation and ``K = P Cᵀ R⁻¹``.

    Examples
    --------
    >>> import numpy as np
    >>> ss = continuous_steady_state([[0, 1], [0, 0]], [[1, 0]], [[0], [1]], 1.0, 1.0)
    >>> np.round(ss.K.ravel(), 4)
    array([1.4142, 1.    ])
    """
    import control as ct

    A, C, G, Q, R = _prepare(A, C, G, Q, R, discrete=False, require=require)
    GQGt = _sym(G @ Q @ G.T)  # exactly symmetric (python-control checks symmetry strictly)
    # python-control: lqe(A, G, C, QN, RN) -> L = P Cᵀ R⁻¹, P, eig(A − L C)
    K, P, E = ct.lqe(A, np.eye(A.shape[0]), C, GQGt, R)
    K = np.asarray(K, dtype=float)
    P = np.asarray(P, dtype=float)
    P = 0.5 * (P + P.T)
    return ContinuousSteadyState(K=K, P=P, poles=np.asarray(E))


def continuous_steady_state_gain(A, C, G, Q, R, *, require: str = "detectable") -> np.ndarray:
    """Steady-state Kalman–Bucy gain ``K = P̄ Cᵀ R⁻¹`` (shape (n, p)); see :func:`continuous_steady_state`."""
    return continuous_steady_state(A, C, G, Q, R, require=require).K


def care_residual(A, C, G, Q, R, P) -> np.ndarray:
    """Residual ``A P + P Aᵀ − P Cᵀ R⁻¹ C P + G Q Gᵀ`` of the filter ARE (zero at a solution).

    This is also the right-hand side ``Ṗ`` of the Riccati differential equation.
    """
    A, C, G = _system(A, C, G)
    n = A.shape[0]
    Q = _covariance("Q", Q, G.shape[1], definite=False)
    R = _covariance("R", R, C.shape[0], definite=True)
    P = check_matrix("P", P, shape=(n, n))
    PCt = P @ C.T
    return A @ P + P @ A.T - PCt @ np.linalg.solve(R, PCt.T) + G @ Q @ G.T


def riccati_rhs(t, p, A, C, GQGt, Rinv, iu) -> np.ndarray:
    """Right-hand side of the Riccati ODE on the vector of upper-triangular entries of ``P``.

    ``Ṗ = A P + P Aᵀ − P Cᵀ R⁻¹ C P + G Q Gᵀ`` in python-control's ``(t, x, …)`` order; ``iu`` are
    the upper-triangular indices (``numpy.triu_indices(n)``); ``GQGt`` and ``Rinv`` are
    precomputed. Used by :func:`riccati_trajectory`.
    """
    n = A.shape[0]
    P = np.empty((n, n))
    P[iu] = p
    P.T[iu] = p
    PCt = P @ C.T
    dP = A @ P + P @ A.T - PCt @ Rinv @ PCt.T + GQGt
    return dP[iu]


def riccati_trajectory(A, C, G, Q, R, P0, t, *, rtol: float = 1e-8, atol: float | None = None) -> np.ndarray:
    """Integrate the filter Riccati differential equation from ``P(t[0]) = P0``.

    ``Ṗ = A P + P Aᵀ − P Cᵀ R⁻¹ C P + G Q Gᵀ`` is integrated with :func:`scipy.integrate.solve_ivp`
    on the ``n(n+1)/2`` independent entries of the symmetric ``P``. For a detectable ``(A, C)`` and
    ``(A, G Q^½)`` stabilisable, ``P(t)`` converges to the stabilising ARE solution ``P̄`` from any
    ``P0 >= 0`` (it does **not** converge to zero unless ``G Q Gᵀ = 0`` and ``A`` is stable).

    Parameters
    ----------
    A, C, G, Q, R
        As in :func:`continuous_steady_state`.
    P0 : array_like, shape (n, n)
        Initial error covariance (symmetric, >= 0).
    t : array_like, shape (N,)
        Strictly increasing output times; integration starts at ``t[0]``.
    rtol, atol : float
        Tolerances of ``solve_ivp`` (``atol`` defaults to ``1e-10 · max(1, ‖P0‖, ‖G Q Gᵀ‖)``).

    Returns
    -------
    numpy.ndarray, shape (N, n, n)
        ``P(t[i])``.

    Raises
    ------
    ValueError
        On bad shapes, NaN, ``Q`` not >= 0, ``R`` not > 0, ``P0`` not symmetric >= 0, ``t`` not
        strictly increasing, or a failed integration.

    References
    ----------
    Kalman and Bucy (1961), the variance equation; B. D. O. Anderson and J. B. Moore,
    *Optimal Filtering*, Prentice-Hall 1979, ch. 4 (convergence of the Riccati equation).
    """
    A, C, G = _system(A, C, G)
    n = A.shape[0]
    Q = _covariance("Q", Q, G.shape[1], definite=False)
    R = _covariance("R", R, C.shape[0], definite=True)
    P0 = _covariance("P0", P0, n, definite=False)
    t = check_finite("t", t)
    t = np.atleast_1d(t)
    if t.ndim != 1 or t.size < 1:
        raise ValueError(f"t must be a 1-D array of times, got shape {t.shape}")
    if t.size > 1 and np.any(np.diff(t) <= 0):
        raise ValueError("t must be strictly increasing")
    GQGt = G @ Q @ G.T
    Rinv = np.linalg.inv(R)
    iu = np.triu_indices(n)
    if t.size == 1:
        return P0[None].copy()
    if atol is None:
        atol = 1e-10 * max(1.0, float(np.abs(P0).max()), float(np.abs(GQGt).max()))
    sol = scipy.integrate.solve_ivp(
        riccati_rhs, (t[0], t[-1]), P0[iu], t_eval=t, args=(A, C, GQGt, Rinv, iu),
        rtol=rtol, atol=atol, method="RK45",
    )
    if not sol.success:
        raise ValueError(f"Riccati ODE integration failed: {sol.message}")
    out = np.empty((t.size, n, n))
    for k in range(t.size):
        out[k][iu] = sol.y[:, k]
        out[k].T[iu] = sol.y[:, k]
    return out


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

    F, H, G, Q, R = _prepare(F, H, G, Q, R, discrete=True, require=require)
    GQGt = _sym(G @ Q @ G.T)  # exactly symmetric (python-control checks symmetry strictly)
    # python-control: dlqe(F, G, H, Q, R) -> L (predictor form), P⁻ (DARE solution), eig(F − L H)
    L, P, E = ct.dlqe(F, np.eye(F.shape[0]), H, GQGt, R)
    P = np.asarray(P, dtype=float)
    P = 0.5 * (P + P.T)
    S = H @ P @ H.T + R  # innovation covariance
    K = np.linalg.solve(S, H @ P).T  # K = P⁻ Hᵀ S⁻¹ (filter form)
    P_post = P - K @ H @ P  # P(k|k) = (I − K H) P⁻
    return DiscreteSteadyState(
        K_filter=K,
        L_predictor=np.asarray(L, dtype=float),
        P_prior=P,
        P_post=0.5 * (P_post + P_post.T),
        poles=np.asarray(E),
    )


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
        Relative change of ``H_k`` at which to stop.
    max_iter : int

    Returns
    -------
    DiscreteSteadyState
        Fields with a leading batch axis.

    Raises
    ------
    ValueError
        On NaN/inf, inconsistent shapes, ``R`` not > 0, or no convergence in ``max_iter``.

    References
    ----------
    E. K.-W. Chu, H.-Y. Fan, W.-W. Lin, C.-S. Wang, "Structure-preserving algorithms for periodic
    discrete-time algebraic Riccati equations", Int. J. Control 77(8), 2004; W.-W. Lin and
    S.-F. Xu, "Convergence analysis of structure-preserving doubling algorithms for Riccati-type
    matrix equations", SIAM J. Matrix Anal. Appl. 28(1), 2006.
    """
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
        raise ValueError(f"R must have shape (B, {p}, {p}), ({p}, {p}), (B,) or be a scalar, got {R.shape}")
    R = np.broadcast_to(R, (nb, p, p))
    if np.any(np.linalg.eigvalsh(_symb(R)).min(axis=-1) <= 0):
        raise ValueError(f"R must be > 0 (positive definite), got smallest eigenvalue "
                         f"{np.linalg.eigvalsh(_symb(R)).min():g}")
    Ht = np.swapaxes(H, -1, -2)
    Ak = np.swapaxes(F, -1, -2).copy()
    Gk = Ht @ np.linalg.solve(R, H)
    Hk = _symb(Qd).copy()
    eye = np.eye(n)
    for _ in range(int(max_iter)):
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
                         f"(largest relative change {change.max():.2e}); check detectability of (F, H)")
    P = Hk
    S = H @ P @ Ht + R
    K = np.swapaxes(np.linalg.solve(S, H @ P), -1, -2)  # K = P⁻ Hᵀ S⁻¹
    L = F @ K  # predictor form
    P_post = _symb(P - K @ H @ P)
    return DiscreteSteadyState(K_filter=K, L_predictor=L, P_prior=P, P_post=P_post,
                               poles=np.linalg.eigvals(F - L @ H))


def dare_residual(F, H, G, Q, R, P_prior) -> np.ndarray:
    """Residual ``F P Fᵀ − F P Hᵀ (H P Hᵀ + R)⁻¹ H P Fᵀ + G Q Gᵀ − P`` of the filter DARE (a-priori ``P``)."""
    F, H, G = _system(F, H, G)
    n = F.shape[0]
    Q = _covariance("Q", Q, G.shape[1], definite=False)
    R = _covariance("R", R, H.shape[0], definite=True)
    P = check_matrix("P_prior", P_prior, shape=(n, n))
    FPHt = F @ P @ H.T
    return F @ P @ F.T - FPHt @ np.linalg.solve(H @ P @ H.T + R, FPHt.T) + G @ Q @ G.T - P


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
    Q = _covariance("Q", Q, G.shape[1], definite=False)
    T = check_positive("T", T)
    M = np.zeros((2 * n, 2 * n))
    M[:n, :n] = -A
    M[:n, n:] = G @ Q @ G.T
    M[n:, n:] = A.T
    E = scipy.linalg.expm(M * T)
    F = E[n:, n:].T
    Qd = F @ E[:n, n:]
    return F, 0.5 * (Qd + Qd.T)


# --------------------------------------------------------------------------------------------
# α-β filters
# --------------------------------------------------------------------------------------------


def alpha_beta_from_gain(K, T):
    """α-β gains of a 2-state (position, velocity) **filter-form** gain ``K = [k1, k2]``.

    Convention (Kalata 1984; Bar-Shalom et al. 2001, §6.5): the update is
    ``x̂ = x̂⁻ + α r``, ``v̂ = v̂⁻ + (β/T) r``, so ``α = k1`` and ``β = T·k2`` (both dimensionless).
    Do not pass the predictor-form gain ``L = F K`` from :func:`control.dlqe`.

    Parameters
    ----------
    K : array_like, shape (2,) or (2, 1)
        Filter-form gain.
    T : float, > 0
        Sampling period (s).

    Returns
    -------
    (alpha, beta) : tuple of float
    """
    K = np.ravel(check_finite("K", K))
    if K.shape != (2,):
        raise ValueError(f"K must have 2 entries (position, velocity), got shape {np.shape(K)}")
    T = check_positive("T", T)
    return float(K[0]), float(T * K[1])


def gain_from_alpha_beta(alpha, beta, T) -> np.ndarray:
    """Filter-form gain ``[α, β/T]`` (shape (2,)) of an α-β filter; inverse of :func:`alpha_beta_from_gain`."""
    alpha = check_finite("alpha", alpha)
    beta = check_finite("beta", beta)
    T = check_positive("T", T)
    return np.array([alpha, beta / T], dtype=float)


def tracking_index(sigma_w, sigma_v, T):
    """Kalata's tracking index ``Λ = σ_w T² / σ_v``.

    ``σ_w`` is the standard deviation of the (piecewise-constant) acceleration noise of the
    discrete white-noise-acceleration model ``x(k+1) = [[1, T], [0, 1]] x(k) + [T²/2, T]ᵀ w(k)``,
    ``σ_v`` that of the position measurement noise.

    References
    ----------
    P. R. Kalata, "The tracking index: a generalized parameter for α-β and α-β-γ target trackers",
    IEEE Trans. AES 20(2), 1984, 174–182.
    """
    sigma_w = check_finite("sigma_w", sigma_w)
    if np.any(np.asarray(sigma_w) < 0):
        raise ValueError(f"sigma_w must be >= 0, got {sigma_w!r}")
    sigma_v = check_positive("sigma_v", sigma_v)
    T = check_positive("T", T)
    return sigma_w * T**2 / sigma_v


def tracking_index_from_gains(alpha, beta):
    """Tracking index implied by steady-state α-β gains: ``Λ = β / √(1 − α)`` (Kalata 1984, ``Λ² = β²/(1−α)``).

    Valid for ``0 < α < 1``. A pair that is not on the steady-state locus
    ``β = 2(2 − α) − 4√(1 − α)`` still yields a number, but it is not the Λ of any Kalman filter.
    """
    alpha = check_finite("alpha", alpha)
    beta = check_finite("beta", beta)
    a = np.asarray(alpha)
    if np.any((a <= 0) | (a >= 1)):
        raise ValueError(f"alpha must be in (0, 1) for a steady-state α-β filter, got {alpha!r}")
    return beta / np.sqrt(1.0 - alpha)


def kalata_gains(Lambda):
    """Steady-state α-β gains as functions of Kalata's tracking index Λ.

    ``α = −(Λ² + 8Λ − (Λ + 4)√(Λ² + 8Λ)) / 8``, ``β = (Λ² + 4Λ − Λ√(Λ² + 8Λ)) / 4``.
    They are the filter-form steady-state Kalman gains ``[α, β/T]`` of the discrete
    white-noise-acceleration model (see :func:`tracking_index`) and satisfy
    ``β²/(1 − α) = Λ²`` and ``(α + β/2)² = 2β``. Derived in
    :func:`ctrl_analysis.symbolic.riccati.kalata_closed_form`.

    Parameters
    ----------
    Lambda : float or array_like, >= 0

    Returns
    -------
    (alpha, beta) : floats or arrays

    References
    ----------
    Kalata (1984), eqs. for the α-β tracker; Y. Bar-Shalom, X. R. Li, T. Kirubarajan,
    *Estimation with Applications to Tracking and Navigation*, Wiley 2001, §6.5.3.
    """
    L = check_finite("Lambda", Lambda)
    if np.any(np.asarray(L) < 0):
        raise ValueError(f"Lambda must be >= 0, got {Lambda!r}")
    r = np.sqrt(L * L + 8.0 * L)
    alpha = -(L * L + 8.0 * L - (L + 4.0) * r) / 8.0
    beta = (L * L + 4.0 * L - L * r) / 4.0
    return alpha, beta


def alpha_beta_stable(alpha, beta) -> bool:
    """Whether the classical α-β filter (``F = [[1, T], [0, 1]]``) is stable: ``0 < α < 2``, ``0 < β < 4 − 2α``.

    Jury's test on ``z² + (α + β − 2) z + (1 − α)`` (independent of ``T``).
    """
    alpha = float(check_finite("alpha", alpha))
    beta = float(check_finite("beta", beta))
    return bool(0 < alpha < 2 and 0 < beta < 4 - 2 * alpha)


class AlphaBetaFilter:
    """Constant-gain (steady-state) discrete α-β filter over a batch axis.

    Each step predicts ``x̂⁻ = F x̂ + b u`` and corrects with the measurement ``y`` of the first
    state: ``r = y − x̂⁻[0]``, ``x̂ = x̂⁻ + [α, β/T] r``. With the default
    ``F = [[1, T], [0, 1]]`` this is the classical α-β tracker (Kalata 1984); any other
    2×2 ``F`` (e.g. ``expm(A T)`` of a sampled plant) gives a constant-gain Kalman filter.

    Parameters
    ----------
    alpha, beta : float
        Dimensionless gains (filter form; ``β = T·k2``).
    T : float, > 0
        Sampling period (s).
    F : array_like, shape (2, 2), optional
        State transition; default ``[[1, T], [0, 1]]``.
    b : array_like, shape (2,), optional
        Discrete input vector of the prediction (default zero).
    x0 : array_like, shape (2,) or (B, 2), optional
        Initial estimate (default zero).
    require_stable : bool
        Raise if the error dynamics ``(I − K H) F`` are not strictly stable.

    Attributes
    ----------
    x_hat : numpy.ndarray, shape (2,) or (B, 2)
        Current estimate ``x̂(k|k)``.
    K : numpy.ndarray, shape (2,)
        Filter-form gain ``[α, β/T]``.
    innovation : float or numpy.ndarray, shape (B,)
        Last ``r = y − x̂⁻[0]``.

    References
    ----------
    Kalata (1984); Bar-Shalom, Li & Kirubarajan (2001), §6.5.

    Examples
    --------
    >>> f = AlphaBetaFilter(0.5, 0.2, T=0.1)
    >>> for k in range(200):
    ...     x = f.step(2.0 * 0.1 * k)        # a ramp of slope 2
    >>> round(float(x[1]), 6)
    2.0
    """

    def __init__(self, alpha, beta, T, *, F=None, b=None, x0=None, require_stable: bool = True):
        self.alpha = float(check_finite("alpha", alpha))
        self.beta = float(check_finite("beta", beta))
        self.T = float(check_positive("T", T))
        if F is None:
            F = [[1.0, self.T], [0.0, 1.0]]
        self.F = check_matrix("F", F, shape=(2, 2))
        self.b = np.zeros(2) if b is None else check_finite("b", np.ravel(b), shape=(2,))
        self.K = gain_from_alpha_beta(self.alpha, self.beta, self.T)
        if require_stable and not np.all(np.abs(self.poles) < 1.0):
            raise ValueError(
                f"alpha, beta must give a stable filter (|eig((I − K H) F)| < 1), got alpha={self.alpha:g}, "
                f"beta={self.beta:g}, spectral radius {np.max(np.abs(self.poles)):.4g}"
            )
        self._x0 = None if x0 is None else check_finite("x0", x0)
        if self._x0 is not None and np.shape(self._x0)[-1:] != (2,):
            raise ValueError(f"x0 must have shape (2,) or (B, 2), got {np.shape(self._x0)}")
        self.reset()

    @property
    def poles(self) -> np.ndarray:
        """Eigenvalues of the estimation-error dynamics ``(I − K H) F``."""
        H = np.array([[1.0, 0.0]])
        return np.linalg.eigvals((np.eye(2) - self.K[:, None] @ H) @ self.F)

    def reset(self, x0=None) -> None:
        """Restore the initial estimate (``x0`` overrides the one given at construction)."""
        if x0 is not None:
            x0 = check_finite("x0", x0)
            if np.shape(x0)[-1:] != (2,):
                raise ValueError(f"x0 must have shape (2,) or (B, 2), got {np.shape(x0)}")
            self._x0 = x0
        self.x_hat = np.zeros(2) if self._x0 is None else np.array(self._x0, dtype=float)
        self.innovation = 0.0

    def step(self, y, u=0.0) -> np.ndarray:
        """One predict/correct step with measurement ``y`` (scalar or shape (B,)) and input ``u``.

        Returns
        -------
        numpy.ndarray, shape (2,) or (B, 2)
            The updated estimate ``x̂(k|k)`` (a copy).
        """
        y = np.asarray(y, dtype=float)
        if y.ndim > 1:
            raise ValueError(f"y must be a scalar or have shape (B,), got {y.shape}")
        if not np.all(np.isfinite(y)):
            raise ValueError("y must be finite (no NaN or inf)")
        u = np.asarray(u, dtype=float)
        # prediction  x̂⁻(k) = F x̂(k−1) + b u(k−1)
        x_pred = self.x_hat @ self.F.T + u[..., None] * self.b
        # innovation  r(k) = y(k) − H x̂⁻(k)
        r = y - x_pred[..., 0]
        # correction  x̂(k) = x̂⁻(k) + [α, β/T] r(k)
        self.x_hat = x_pred + r[..., None] * self.K
        self.innovation = r
        return self.x_hat.copy()


# --------------------------------------------------------------------------------------------
# scalar random walk
# --------------------------------------------------------------------------------------------


def random_walk_gain(Q, R):
    """Steady-state Kalman gain of the scalar random walk ``x(k+1) = x(k) + w``, ``y = x + v``.

    The recursion ``P⁻ = P + Q``, ``K = P⁻ / (P⁻ + R)``, ``P = (1 − K) P⁻`` has the fixed point
    ``P⁻ = (Q + √(Q² + 4 Q R)) / 2``, hence, with ``q = Q / R``,

        K∞ = (−q + √(q² + 4q)) / 2,

    a function of ``Q/R`` only (derived in
    :func:`ctrl_analysis.symbolic.riccati.random_walk_closed_form`).

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
    # K∞ = (−q + √(q² + 4q)) / 2, written as 2q / (q + √(q² + 4q)) to avoid cancellation for large q
    s = np.sqrt(q * q + 4.0 * q)
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.where(q > 0, 2.0 * q / (q + s), 0.0)
    return float(k) if k.ndim == 0 else k
