"""The α-β-γ filter beyond constant acceleration: Singer's first-order Markov (manoeuvre) acceleration model.

Model (Singer 1970; Bar-Shalom, Li & Kirubarajan 2001, §8.2), sampled with period ``T``::

    ẍ = a,  ȧ = -a/τ_m + w(t)        (manoeuvre time constant τ_m; decay s = T/τ_m)
    x(k+1) = F(s) x(k) + Γ w(k),     F = [[1, T, T² (s - 1 + e^-s)/s²], [0, 1, T (1 - e^-s)/s], [0, 0, e^-s]]
    y(k)   = x₀(k) + v(k),           Γ = [T²/2, T, 1]ᵀ,  Λ = σ_w T² / σ_v

``F`` is the exact transition of the continuous model (``expm(A T)``); the process noise enters through the gain
``Γ`` of the discrete Wiener-process-acceleration model, so that at ``s = 0`` (``τ_m = ∞``) the model, and the
steady-state gains, are exactly :func:`~ctrl_analysis.estimators.kalman.alpha_beta.alpha_beta_gamma_gains`'.
For a large ``s`` the acceleration is nearly white from sample to sample and the filter behaves like the
constant-velocity α-β filter. The filter is the α-β-γ correction (``alpha_beta_gamma_output``) with the
prediction :func:`singer_update`.
"""

from __future__ import annotations

import numpy as np

from ..._validate import check_nonnegative, check_positive, finite_result

__all__ = ["singer_gains", "singer_transition", "singer_update"]

#: Below this decay ``s`` the transition's entries use their series (``s + expm1(-s)`` cancels in double precision:
#: a relative error of about ``2 ε_mach / s``); 10 terms leave ``s¹⁰/12!`` below it.
_SERIES_BELOW = 0.1


def _series(s: np.ndarray, first: int) -> np.ndarray:
    """``Σ_k (-s)^k / (k + first)!`` for ``k = 0..9`` (Horner): ``b`` for ``first = 1``, ``a`` for ``first = 2``."""
    import math

    out = np.zeros_like(s)
    for k in range(9, -1, -1):
        out = out * (-s) + 1.0 / math.factorial(k + first)
    return out


def singer_transition(decay):
    """The dimensionless entries ``(a, b, ρ)`` of Singer's transition ``F = [[1, T, a T²], [0, 1, b T], [0, 0, ρ]]``.

    Parameters
    ----------
    decay : float or array_like
        ``s = T/τ_m >= 0`` (0: constant acceleration, ``a = 1/2, b = 1, ρ = 1``).

    Returns
    -------
    (a, b, rho) : floats or arrays
        ``a = (s - 1 + e^-s)/s²``, ``b = (1 - e^-s)/s``, ``ρ = e^-s``, the shape of ``decay``.

    Raises
    ------
    ValueError
        If ``decay`` is not finite and >= 0.

    Examples
    --------
    >>> singer_transition(0.0)
    (0.5, 1.0, 1.0)
    """
    s = np.asarray(check_nonnegative("decay", decay), dtype=float)
    small = s < _SERIES_BELOW
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(small, _series(s, 2), (s + np.expm1(-s)) / (s * s))
        b = np.where(small, _series(s, 1), -np.expm1(-s) / s)
    rho = np.exp(-s)
    if s.ndim == 0:
        return float(a), float(b), float(rho)
    return a, b, rho


def singer_gains(Lambda, decay):
    """Steady-state α-β-γ gains of Singer's model as functions of Kalata's index ``Λ`` and the decay ``s = T/τ_m``.

    The filter-form steady-state Kalman gain ``K = [α, β/T, γ/(2T²)]`` of the model above, solved at ``T = 1`` (in the
    states ``[x, T ẋ, T² ẍ]`` the model depends on ``Λ`` and ``s`` alone) by
    :func:`~ctrl_analysis.estimators.kalman.discrete.discrete_steady_state_batch`.

    Parameters
    ----------
    Lambda : float or array_like
        Tracking index ``σ_w T²/σ_v`` (> 0).
    decay : float or array_like
        ``s = T/τ_m >= 0``, broadcast with ``Lambda``.

    Returns
    -------
    (alpha, beta, gamma) : floats or arrays
        The broadcast shape of the arguments.

    Raises
    ------
    ValueError
        If ``Lambda`` is not finite and > 0, ``decay`` not finite and >= 0, or their shapes do not broadcast.

    References
    ----------
    R. A. Singer, "Estimating optimal tracking filter performance for manned maneuvering targets", IEEE Trans. AES
    6(4), 1970, 473–483; P. R. Kalata, IEEE Trans. AES 20(2), 1984 (the tracking index).

    Examples
    --------
    >>> from ctrl_analysis.estimators.kalman.alpha_beta import alpha_beta_gamma_gains
    >>> bool(np.allclose(singer_gains(0.5, 0.0), alpha_beta_gamma_gains(0.5), rtol=1e-12))
    True
    """
    from .discrete import discrete_steady_state_batch

    lam = np.asarray(check_positive("Lambda", Lambda), dtype=float)
    s = np.asarray(check_nonnegative("decay", decay), dtype=float)
    try:
        lam, s = np.broadcast_arrays(lam, s)
    except ValueError:
        raise ValueError(f"Lambda and decay must broadcast, got shapes {lam.shape} and {s.shape}") from None
    a, b, rho = (np.atleast_1d(v).reshape(-1) for v in singer_transition(s))
    flat = lam.reshape(-1)
    F = np.zeros((flat.size, 3, 3))
    F[:, 0, 0] = F[:, 0, 1] = F[:, 1, 1] = 1.0
    F[:, 0, 2], F[:, 1, 2], F[:, 2, 2] = a, b, rho
    G = np.array([0.5, 1.0, 1.0])
    Qd = finite_result("Lambda", lambda: flat[:, None, None] ** 2 * np.outer(G, G)[None])  # σ_v = 1, σ_w = Λ, T = 1
    K = discrete_steady_state_batch(F, np.array([[1.0, 0.0, 0.0]]), Qd, 1.0).K_filter[:, :, 0]
    alpha, beta, gamma = K[:, 0], K[:, 1], 2.0 * K[:, 2]
    if lam.ndim == 0:
        return float(alpha[0]), float(beta[0]), float(gamma[0])
    return alpha.reshape(lam.shape), beta.reshape(lam.shape), gamma.reshape(lam.shape)


def singer_update(t, x, u, p, x_next):
    """Singer prediction ``x̂(k+1|k) = F x̂(k|k)`` after the α-β-γ correction (``alpha_beta_gamma_output``'s).

    Scalar-indexed: the kernel of one run and, on a batch's transposed arrays, a block's numpy method.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray, shape (3,)
        The prediction ``x̂(k|k−1)``.
    u : numpy.ndarray, shape (1,)
        ``[y(k)]``.
    p : numpy.ndarray, shape (7,)
        ``[K₀, K₁, K₂, T, a T², b T, ρ]`` (filter-form gain, sample period, :func:`singer_transition`'s entries).
    x_next : numpy.ndarray, shape (3,)
        The next prediction, written in place.
    """
    r = u[0] - x[0]  # the correction of alpha_beta_gamma_output, repeated (a compiled kernel cannot call it)
    f0, f1, f2 = x[0] + p[0] * r, x[1] + p[1] * r, x[2] + p[2] * r
    x_next[0] = f0 + p[3] * f1 + p[4] * f2
    x_next[1] = f1 + p[5] * f2
    x_next[2] = p[6] * f2
