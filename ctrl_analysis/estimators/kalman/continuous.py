"""Continuous-time steady-state Kalman–Bucy gain, the filter ARE residual and the Riccati ODE."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.integrate
import scipy.linalg

from ..._validate import check_finite, check_matrix, check_positive, finite_result
from ._checks import _covariance, _prepare, _riccati_solution, _sym, _system

__all__ = ["ContinuousSteadyState", "continuous_steady_state", "continuous_steady_state_gain", "care_residual",
           "riccati_rhs", "riccati_trajectory"]


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
    # python-control: lqe(A, G, C, QN, RN) -> L = P Cᵀ R⁻¹, P, eig(A − L C); verified, else solved unbalanced
    K, P, E = _riccati_solution(lambda: ct.lqe(A, np.eye(A.shape[0]), C, GQGt, R),
                                lambda: scipy.linalg.solve_continuous_are(A.T, C.T, GQGt, R, balanced=False),
                                lambda P: _care_solved(A, C, GQGt, R, P), "ARE")
    if K is None:
        K = P @ C.T @ np.linalg.inv(R)  # K = P Cᵀ R⁻¹
        E = np.linalg.eigvals(A - K @ C)
    K = np.asarray(K, dtype=float)
    return ContinuousSteadyState(K=K, P=P, poles=np.asarray(E))


def _care_solved(A, C, GQGt, R, P) -> bool:
    """Whether ``P`` satisfies the filter ARE to a relative accuracy of 1e-8."""
    scale = max(1.0, np.abs(A @ P).max(), np.abs(P @ C.T).max() ** 2 / np.abs(R).max(), np.abs(GQGt).max())
    return bool(np.all(np.isfinite(P)) and np.abs(_care_residual(A, C, GQGt, R, P)).max() <= 1e-8 * scale)


def _care_residual(A, C, GQGt, R, P) -> np.ndarray:
    """Unchecked kernel of :func:`care_residual`."""
    PCt = P @ C.T
    return A @ P + P @ A.T - PCt @ np.linalg.solve(R, PCt.T) + GQGt


def continuous_steady_state_gain(A, C, G, Q, R, *, require: str = "detectable") -> np.ndarray:
    """Steady-state Kalman–Bucy gain ``K = P̄ Cᵀ R⁻¹``; see :func:`continuous_steady_state`.

    Parameters
    ----------
    A, C, G, Q, R, require
        As in :func:`continuous_steady_state`.

    Returns
    -------
    numpy.ndarray, shape (n, p)
        The gain ``K``.
    """
    return continuous_steady_state(A, C, G, Q, R, require=require).K


def care_residual(A, C, G, Q, R, P) -> np.ndarray:
    """Residual ``A P + P Aᵀ − P Cᵀ R⁻¹ C P + G Q Gᵀ`` of the filter ARE (zero at a solution).

    This is also the right-hand side ``Ṗ`` of the Riccati differential equation.

    Parameters
    ----------
    A : array_like, shape (n, n)
    C : array_like, shape (p, n)
    G : array_like, shape (n, m)
    Q : array_like, shape (m, m)
        Process-noise intensity (symmetric, positive semidefinite).
    R : array_like, shape (p, p)
        Measurement-noise intensity (symmetric, positive definite).
    P : array_like, shape (n, n)
        Candidate solution.

    Returns
    -------
    numpy.ndarray, shape (n, n)
        The residual.
    """
    A, C, G = _system(A, C, G)
    n = A.shape[0]
    Q = _covariance("Q", Q, G.shape[1], definite=False, per="one row per column of G")
    R = _covariance("R", R, C.shape[0], definite=True, per="one row per output of C")
    P = check_matrix("P", P, shape=(n, n))
    return finite_result("A, C, G, Q, R and P", lambda: _care_residual(A, C, G @ Q @ G.T, R, P))


def riccati_rhs(t, p, A, C, GQGt, Rinv, iu) -> np.ndarray:
    """Right-hand side of the Riccati ODE on the vector of upper-triangular entries of ``P``.

    ``Ṗ = A P + P Aᵀ − P Cᵀ R⁻¹ C P + G Q Gᵀ`` in python-control's ``(t, x, …)`` order; ``iu`` are
    the upper-triangular indices (``numpy.triu_indices(n)``); ``GQGt`` and ``Rinv`` are
    precomputed. Used by :func:`riccati_trajectory`.

    Parameters
    ----------
    t : float
        Time (unused; the equation is time invariant).
    p : numpy.ndarray, shape (n (n+1) / 2,)
        Upper-triangular entries of ``P``.
    A, C : numpy.ndarray
        System matrices.
    GQGt, Rinv : numpy.ndarray
        ``G Q Gᵀ`` and ``R⁻¹``.
    iu : tuple of numpy.ndarray
        ``numpy.triu_indices(n)``.

    Returns
    -------
    numpy.ndarray, shape (n (n+1) / 2,)
        Upper-triangular entries of ``Ṗ``.
    """
    n = A.shape[0]
    P = np.empty((n, n))
    P[iu] = p
    P.T[iu] = p
    PCt = P @ C.T
    dP = A @ P + P @ A.T - PCt @ Rinv @ PCt.T + GQGt
    return dP[iu]


#: Most steps :func:`riccati_trajectory` takes (a stiffer problem is refused instead of running for hours).
MAX_RICCATI_STEPS = 100_000


class _TooManySteps(Exception):
    pass


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
        strictly increasing, ``rtol`` / ``atol`` not finite and > 0, or a failed integration.

    References
    ----------
    Kalman and Bucy (1961), the variance equation; B. D. O. Anderson and J. B. Moore,
    *Optimal Filtering*, Prentice-Hall 1979, ch. 4 (convergence of the Riccati equation).
    """
    A, C, G = _system(A, C, G)
    n = A.shape[0]
    Q = _covariance("Q", Q, G.shape[1], definite=False, per="one row per column of G")
    R = _covariance("R", R, C.shape[0], definite=True, per="one row per output of C")
    P0 = _covariance("P0", P0, n, definite=False)
    rtol = check_positive("rtol", rtol, scalar=True)
    if atol is not None:
        atol = check_positive("atol", atol, scalar=True)
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
    # the equation's fastest rate: an explicit solver needs steps of about 1/rate over t's span
    with np.errstate(over="ignore"):
        CRC = np.linalg.norm(C.T @ Rinv @ C)
        rate = np.linalg.norm(A) + np.sqrt(np.linalg.norm(GQGt) * CRC) + CRC * np.linalg.norm(P0)
    if not rate * (t[-1] - t[0]) <= MAX_RICCATI_STEPS:
        raise ValueError(f"the Riccati ODE for these A, C, G, Q, R, P0 and t is too stiff: its rates (about "
                         f"{rate:.3g}/s over {t[-1] - t[0]:g} s) would take more than {MAX_RICCATI_STEPS} steps")
    steps = iter(range(MAX_RICCATI_STEPS))

    def budget(*_):  # called once per accepted step: a bound on the work, never a root
        if next(steps, None) is None:
            raise _TooManySteps
        return 1.0

    try:
        with np.errstate(over="ignore", invalid="ignore"):
            sol = scipy.integrate.solve_ivp(
                riccati_rhs, (t[0], t[-1]), P0[iu], t_eval=t, args=(A, C, GQGt, Rinv, iu),
                rtol=rtol, atol=atol, method="RK45", events=budget,
            )
    except _TooManySteps:
        raise ValueError(f"the Riccati ODE for these A, C, G, Q, R, P0 and t needs more than {MAX_RICCATI_STEPS} "
                         f"steps (too stiff: G Q Gᵀ or Cᵀ R⁻¹ C of extreme magnitude)") from None
    if not sol.success or not np.all(np.isfinite(sol.y)):
        raise ValueError(f"the Riccati ODE for these A, C, G, Q, R, P0 and t failed: {sol.message}")
    out = np.empty((t.size, n, n))
    for k in range(t.size):
        out[k][iu] = sol.y[:, k]
        out[k].T[iu] = sol.y[:, k]
    return out


