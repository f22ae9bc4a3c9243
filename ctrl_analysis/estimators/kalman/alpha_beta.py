"""α-β gains, Kalata's tracking index and a constant-gain α-β filter."""

from __future__ import annotations

import numpy as np

from ..._validate import check_bool, check_finite, check_matrix, check_positive, finite_result
from ...engine.blocks import DiscreteBlock
from ...engine.kernels import KernelBlock, Kernels, Layout, as_int, jitable

__all__ = ["alpha_beta_from_gain", "gain_from_alpha_beta", "tracking_index", "tracking_index_from_gains",
           "kalata_gains", "alpha_beta_stable", "AlphaBetaFilter"]


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
    T = check_positive("T", T, scalar=True)
    return float(K[0]), float(T * K[1])


def gain_from_alpha_beta(alpha, beta, T) -> np.ndarray:
    """Filter-form gain ``[α, β/T]`` of an α-β filter; inverse of :func:`alpha_beta_from_gain`.

    Parameters
    ----------
    alpha, beta : float
        Dimensionless gains.
    T : float, > 0
        Sampling period (s).

    Returns
    -------
    numpy.ndarray, shape (2,)
    """
    alpha = check_finite("alpha", alpha, scalar=True)
    beta = check_finite("beta", beta, scalar=True)
    T = check_positive("T", T, scalar=True)
    return np.array([alpha, beta / T], dtype=float)


def tracking_index(sigma_w, sigma_v, T):
    """Kalata's tracking index ``Λ = σ_w T² / σ_v``.

    ``σ_w`` is the standard deviation of the (piecewise-constant) acceleration noise of the
    discrete white-noise-acceleration model ``x(k+1) = [[1, T], [0, 1]] x(k) + [T²/2, T]ᵀ w(k)``,
    ``σ_v`` that of the position measurement noise.

    Parameters
    ----------
    sigma_w : float or array_like, >= 0
        Standard deviation of the acceleration noise.
    sigma_v : float, > 0
        Standard deviation of the position measurement noise.
    T : float, > 0
        Sampling period (s).

    Returns
    -------
    float or numpy.ndarray
        ``Λ`` (dimensionless).

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
    return finite_result("sigma_w, sigma_v and T", lambda: sigma_w * T**2 / sigma_v)


def tracking_index_from_gains(alpha, beta):
    """Tracking index implied by steady-state α-β gains: ``Λ = β / √(1 − α)`` (Kalata 1984, ``Λ² = β²/(1−α)``).

    Valid for ``0 < α < 1``. A pair that is not on the steady-state locus
    ``β = 2(2 − α) − 4√(1 − α)`` still yields a number, but it is not the Λ of any Kalman filter.

    Parameters
    ----------
    alpha : float or array_like, in (0, 1)
    beta : float or array_like

    Returns
    -------
    float or numpy.ndarray
        ``Λ``.
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
    :func:`ctrl_analysis.symbolic.riccati.derive_kalata_gains` (numeric:
    :func:`ctrl_analysis.symbolic.riccati.kalata_gains_closed_form`).

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
    with np.errstate(over="ignore", invalid="ignore"):
        r = np.sqrt(L * L + 8.0 * L)
        alpha = -(L * L + 8.0 * L - (L + 4.0) * r) / 8.0
        beta = (L * L + 4.0 * L - L * r) / 4.0
    finite_result("Lambda", lambda: (alpha, beta))
    return alpha, beta


def alpha_beta_stable(alpha, beta) -> bool:
    """Whether the classical α-β filter (``F = [[1, T], [0, 1]]``) is stable: ``0 < α < 2``, ``0 < β < 4 − 2α``.

    Jury's test on ``z² + (α + β − 2) z + (1 − α)`` (independent of ``T``).

    Parameters
    ----------
    alpha, beta : float
        Dimensionless gains.

    Returns
    -------
    bool
    """
    alpha = float(check_finite("alpha", alpha, scalar=True))
    beta = float(check_finite("beta", beta, scalar=True))
    return bool(0 < alpha < 2 and 0 < beta < 4 - 2 * alpha)


#: Kernel parameters of :class:`AlphaBetaFilter`: the input switch (1 with ``b``), the filter-form gain
#: ``[α, β/T]``, ``F`` (row-major) and ``b`` (zeros without it).
LAYOUT = Layout("has_b", ("K", 2), ("F", (2, 2)), ("b", 2))
AT = LAYOUT.at


@jitable
def _correct(s, y, p):
    """``x̂(k|k) = x̂(k|k−1) + [α, β/T] r(k)`` from the prediction ``s[0:2]`` and the measurement ``y``."""
    r = y - s[0]  # innovation r(k) = y(k) − H x̂(k|k−1)
    return s[0] + r * p[AT.K], s[1] + r * p[AT.K + 1]


def alpha_beta_output(t, x, u, p, y):
    """α-β correction ``x̂(k|k) = x̂(k|k−1) + [α, β/T] (y(k) − x̂(k|k−1)[0])`` (the output; :class:`AlphaBetaFilter`).

    Scalar-indexed: the kernel of one run and, on a batch's transposed arrays, the block's numpy
    method. With an empty ``x`` (a static corrector placed after a predictor that holds the
    state, see ``analysis/pendulum/blocks.split_filter``) the prediction is read from ``u[0:2]`` and
    ``y(k)`` from ``u[2]``.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray, shape (2,) or (0,)
        The prediction ``x̂(k|k−1)``.
    u : numpy.ndarray
        ``[y, (u)]``, or ``[x̂(k|k−1), y]`` when ``x`` is empty.
    p : numpy.ndarray
        :data:`LAYOUT`: ``has_b``, ``K = [α, β/T]``, ``F`` (row-major), ``b``.
    y : numpy.ndarray, shape (2,)
        The estimate ``x̂(k|k)``, written in place.
    """
    if x.shape[0] > 0:
        y[0], y[1] = _correct(x, u[0], p)
    else:
        y[0], y[1] = _correct(u, u[2], p)


def alpha_beta_update(t, x, u, p, x_next):
    """α-β prediction ``x̂(k+1|k) = F x̂(k|k) + b u(k)`` (the state update; :class:`AlphaBetaFilter`).

    Written out (2×2), so a run is bit-identical whatever the batch size; scalar-indexed like
    :func:`alpha_beta_output`.

    Parameters
    ----------
    t, x, u, p
        As :func:`alpha_beta_output` (``x`` the prediction, ``u = [y, (u)]``).
    x_next : numpy.ndarray, shape (2,)
        The next prediction, written in place.
    """
    xf0, xf1 = _correct(x, u[0], p)  # x̂(k|k), the output
    x_next[0] = p[AT.F] * xf0 + p[AT.F + 1] * xf1
    x_next[1] = p[AT.F + 2] * xf0 + p[AT.F + 3] * xf1
    if as_int(p[AT.has_b]):
        x_next[0] = x_next[0] + u[1] * p[AT.b]
        x_next[1] = x_next[1] + u[1] * p[AT.b + 1]


class AlphaBetaFilter(KernelBlock, DiscreteBlock):
    """Constant-gain (steady-state) discrete α-β filter, a discrete block batched over runs.

    The block's state is the prediction ``x̂(k|k−1)``; at each sample it corrects with the
    measurement ``y`` of the first state and outputs the estimate, then predicts::

        r(k)      = y(k) − x̂(k|k−1)[0]                 innovation
        x̂(k|k)    = x̂(k|k−1) + [α, β/T] r(k)          output (direct feedthrough from y)
        x̂(k+1|k)  = F x̂(k|k) + b u(k)                 update

    With the default ``F = [[1, T], [0, 1]]`` this is the classical α-β tracker (Kalata 1984);
    any other 2×2 ``F`` (e.g. ``expm(A T)`` of a sampled plant) gives a constant-gain Kalman filter.

    Parameters
    ----------
    alpha, beta : float
        Dimensionless gains (filter form; ``β = T·k2``).
    T : float, > 0
        Sampling period (s).
    F : array_like, shape (2, 2), optional
        State transition; default ``[[1, T], [0, 1]]``.
    b : array_like, shape (2,), optional
        Discrete input vector of the prediction; when given the block has a second input ``u``.
    x0 : array_like, shape (2,), optional
        Initial prediction ``x̂(0|−1)`` (default zero).
    require_stable : bool
        Raise if the error dynamics ``(I − K H) F`` are not strictly stable.

    Attributes
    ----------
    K : numpy.ndarray, shape (2,)
        Filter-form gain ``[α, β/T]``.

    Block signals: inputs ``y`` (and ``u`` with ``b``); states ``xpred[0]``, ``xpred[1]``; outputs
    ``xhat[0]``, ``xhat[1]``.

    References
    ----------
    Kalata (1984); Bar-Shalom, Li & Kirubarajan (2001), §6.5.

    Examples
    --------
    >>> import numpy as np
    >>> f = AlphaBetaFilter(0.5, 0.2, T=0.1)
    >>> y, _ = f.run(2.0 * 0.1 * np.arange(200))     # a ramp of slope 2
    >>> round(float(y[-1, 0, 1]), 6)
    2.0
    """

    states = ("xpred[0]", "xpred[1]")
    outputs = ("xhat[0]", "xhat[1]")
    feedthrough = True
    kernels = Kernels(output=alpha_beta_output, update=alpha_beta_update)

    def __init__(self, alpha, beta, T, *, F=None, b=None, x0=None, require_stable: bool = True):
        self.alpha = float(check_finite("alpha", alpha, scalar=True))
        self.beta = float(check_finite("beta", beta, scalar=True))
        self.T = float(check_positive("T", T, scalar=True))
        if F is None:
            F = [[1.0, self.T], [0.0, 1.0]]
        self.F = check_matrix("F", F, shape=(2, 2))
        require_stable = check_bool("require_stable", require_stable)
        self.b = None if b is None else check_finite("b", np.ravel(b), shape=(2,))
        self.inputs = ("y",) if self.b is None else ("y", "u")
        self.K = gain_from_alpha_beta(self.alpha, self.beta, self.T)
        if require_stable and not np.all(np.abs(self.poles) < 1.0):
            raise ValueError(
                f"alpha, beta must give a stable filter (|eig((I − K H) F)| < 1), got alpha={self.alpha:g}, "
                f"beta={self.beta:g}, spectral radius {np.max(np.abs(self.poles)):.4g}"
            )
        self.x0 = np.zeros(2) if x0 is None else check_finite("x0", np.ravel(x0), shape=(2,))
        self.kernel_params = LAYOUT.pack(has_b=0.0 if self.b is None else 1.0, K=self.K, F=self.F,
                                         b=np.zeros(2) if self.b is None else self.b)

    @property
    def poles(self) -> np.ndarray:
        """Eigenvalues of the estimation-error dynamics ``(I − K H) F``."""
        H = np.array([[1.0, 0.0]])
        return np.linalg.eigvals((np.eye(2) - self.K[:, None] @ H) @ self.F)

    def initial_state(self) -> np.ndarray:
        return self.x0.copy()

    def __repr__(self) -> str:
        return f"AlphaBetaFilter(alpha={self.alpha:g}, beta={self.beta:g}, T={self.T:g})"


# --------------------------------------------------------------------------------------------
# α-β-γ (constant-acceleration) steady-state gains and constant-gain kernels
# --------------------------------------------------------------------------------------------


def alpha_beta_gamma_gains(Lambda):
    """Steady-state α-β-γ gains of the constant-acceleration model as functions of Kalata's tracking index Λ.

    Model (discrete Wiener-process acceleration; Bar-Shalom, Li & Kirubarajan 2001, §6.3.3)::

        x(k+1) = F x(k) + Γ w(k),  F = [[1, T, T²/2], [0, 1, T], [0, 0, 1]],  Γ = [T²/2, T, 1]ᵀ
        y(k)   = x₀(k) + v(k),     Λ = σ_w T² / σ_v

    The gains are the filter-form steady-state Kalman gain ``K = [α, β/T, γ/(2T²)]`` of that model,
    solved by :func:`~ctrl_analysis.estimators.kalman.discrete.discrete_steady_state_batch` at ``T = 1``
    (in the states ``[x, T ẋ, T² ẍ]`` the model depends on Λ alone, so the dimensionless gains do
    too). They satisfy Kalata's relations ``β = 2(2 − α) − 4√(1 − α)``, ``γ = β²/α`` and
    ``Λ² = γ²/(4(1 − α))``.

    Parameters
    ----------
    Lambda : float or array_like, > 0
        Tracking index.

    Returns
    -------
    (alpha, beta, gamma) : floats or arrays
        Dimensionless gains, the shape of ``Lambda``.

    Raises
    ------
    ValueError
        If ``Lambda`` is not finite and > 0.

    References
    ----------
    P. R. Kalata, "The tracking index: a generalized parameter for α-β and α-β-γ target trackers",
    IEEE Trans. AES 20(2), 1984, 174–182; Bar-Shalom, Li & Kirubarajan (2001), §6.5.

    Examples
    --------
    >>> a, b, g = alpha_beta_gamma_gains(1.0)
    >>> bool(abs(b - (2 * (2 - a) - 4 * np.sqrt(1 - a))) < 1e-12), bool(abs(g - b * b / a) < 1e-12)
    (True, True)
    """
    from .discrete import discrete_steady_state_batch

    lam = np.asarray(check_positive("Lambda", Lambda), dtype=float)
    flat = lam.reshape(-1)
    F = np.array([[1.0, 1.0, 0.5], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]])
    G = np.array([0.5, 1.0, 1.0])
    Qd = finite_result("Lambda", lambda: flat[:, None, None] ** 2 * np.outer(G, G)[None])  # σ_v = 1, σ_w = Λ, T = 1
    K = discrete_steady_state_batch(np.broadcast_to(F, (flat.size, 3, 3)), np.array([[1.0, 0.0, 0.0]]), Qd,
                                    1.0).K_filter[:, :, 0]
    alpha, beta, gamma = K[:, 0], K[:, 1], 2.0 * K[:, 2]
    if lam.ndim == 0:
        return float(alpha[0]), float(beta[0]), float(gamma[0])
    return alpha.reshape(lam.shape), beta.reshape(lam.shape), gamma.reshape(lam.shape)


def alpha_beta_gamma_output(t, x, u, p, y):
    """α-β-γ correction ``x̂(k|k) = x̂(k|k−1) + K (y(k) − x̂(k|k−1)[0])``, ``K = [α, β/T, γ/(2T²)]``.

    Scalar-indexed: the kernel of one run and, on a batch's transposed arrays, a block's numpy
    method (:class:`~ctrl_analysis.engine.kernels.KernelBlock`'s batched methods).

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray, shape (3,)
        The prediction ``x̂(k|k−1)`` (position, velocity, acceleration).
    u : numpy.ndarray, shape (1,)
        ``[y(k)]``.
    p : numpy.ndarray, shape (4,)
        ``[K₀, K₁, K₂, T]`` (filter-form gain, sample period).
    y : numpy.ndarray, shape (3,)
        The estimate ``x̂(k|k)``, written in place.
    """
    r = u[0] - x[0]  # innovation
    y[0] = x[0] + p[0] * r
    y[1] = x[1] + p[1] * r
    y[2] = x[2] + p[2] * r


def alpha_beta_gamma_update(t, x, u, p, x_next):
    """α-β-γ prediction ``x̂(k+1|k) = F x̂(k|k)`` with ``F = [[1, T, T²/2], [0, 1, T], [0, 0, 1]]``.

    Parameters
    ----------
    t, x, u, p
        As :func:`alpha_beta_gamma_output`.
    x_next : numpy.ndarray, shape (3,)
        The next prediction, written in place.
    """
    r = u[0] - x[0]  # the correction of alpha_beta_gamma_output, repeated (a compiled kernel cannot call it)
    f0, f1, f2 = x[0] + p[0] * r, x[1] + p[1] * r, x[2] + p[2] * r
    x_next[0] = f0 + p[3] * f1 + 0.5 * p[3] * p[3] * f2
    x_next[1] = f1 + p[3] * f2
    x_next[2] = f2


__all__ += ["alpha_beta_gamma_gains", "alpha_beta_gamma_output", "alpha_beta_gamma_update"]
