"""The characteristic-model Kalman filter (2 states, driven by identified parameters) and a full-order reference."""

from __future__ import annotations

import numpy as np

from ..._validate import check_finite, check_matrix, check_positive
from ...engine.blocks import DiscreteBlock, signal_names
from ...engine.kernels import KernelBlock, Kernels, Layout, as_int, jitable, offset
from ...engine.matrix import (
    dot,
    mat_mul,
    mat_mul_t,
    mat_mul_t_add,
    mat_vec,
    matrix,
    scratch_matrices,
    scratch_matrix,
    vector,
)

__all__ = ["CharacteristicKalmanFilter", "LinearKalmanFilter"]


def _check_covariance(name: str, value, n: int, *, definite: bool) -> np.ndarray:
    """A symmetric ``n×n`` covariance (a scalar means ``value·I``), positive (semi)definite."""
    M = np.asarray(check_finite(name, value), dtype=float)
    M = M * np.eye(n) if M.ndim == 0 else check_matrix(name, M, shape=(n, n), symmetric=True)
    eig = np.linalg.eigvalsh(0.5 * (M + M.T))
    tol = 1e-12 * max(1.0, float(np.max(np.abs(eig))))  # round-off of a rank-deficient Q = q b bᵀ
    if (definite and np.any(eig <= 0)) or np.any(eig < -tol):
        rule = "positive definite (not singular or negative)" if definite else "positive semidefinite"
        raise ValueError(f"{name} must be {rule}, got eigenvalues {eig}")
    return 0.5 * (M + M.T)


#: Kernel parameters of :class:`CharacteristicKalmanFilter`: the upper triangle of ``Q``, then ``R``.
CKF_LAYOUT = Layout("Q00", "Q01", "Q11", "R")
CKF_AT = CKF_LAYOUT.at


@jitable
def _ckf_step(x, u, p):
    """One CKF step, eq. (6), (10), (11): ``(X̂(k)[0], X̂(k)[1], P(k)[0][0], P(k)[0][1], P(k)[1][1])``.

    ``x = [X̂(k−1), P00, P01, P11]``, ``u = [y(k), u(k−1), f1, f2, g0]``, ``p`` as :data:`CKF_LAYOUT`;
    scalar indexing only, so ``x``, ``u`` may be one run's vectors or a batch's columns.
    """
    y, u_prev, f1, f2, g0 = u[0], u[1], u[2], u[3], u[4]
    P00, P01, P11 = x[2], x[3], x[4]
    R = p[CKF_AT.R]
    # (11) X̂(k|k−1) = Φ X̂(k−1) + Γ u(k−1)
    xp0 = f1 * x[0] + f2 * x[1] + g0 * u_prev
    xp1 = x[0]
    # (11) P(k|k−1) = Φ P Φᵀ + Q, Φ = [[f1, f2], [1, 0]]
    a0 = f1 * P00 + f2 * P01
    a1 = f1 * P01 + f2 * P11
    Pp00 = a0 * f1 + a1 * f2 + p[CKF_AT.Q00]
    Pp01 = a0 + p[CKF_AT.Q01]
    Pp11 = P00 + p[CKF_AT.Q11]
    # (11) K = P(k|k−1) Cᵀ (C P(k|k−1) Cᵀ + R)⁻¹
    S = Pp00 + R
    K0, K1 = Pp00 / S, Pp01 / S
    # (11) X̂(k) = X̂(k|k−1) + K (y(k) − C X̂(k|k−1))
    r = y - xp0
    xf0, xf1 = xp0 + K0 * r, xp1 + K1 * r
    # (11) P(k) = (I − K C) P(k|k−1) (I − K C)ᵀ + K R Kᵀ, I − K C = [[1 − K0, 0], [−K1, 1]]
    m0 = 1.0 - K0
    b10 = Pp01 - K1 * Pp00
    n00 = m0 * m0 * Pp00 + K0 * K0 * R
    n01 = m0 * b10 + K0 * K1 * R
    n11 = b10 * (-K1) + (Pp11 - K1 * Pp01) + K1 * K1 * R
    return xf0, xf1, n00, n01, n11


def ckf_update(t, x, u, p, x_next):
    """The CKF's next state ``[X̂(k), P(k)]``: the kernel of :class:`CharacteristicKalmanFilter`.

    Scalar indexing only: the compiled kernel of one run and, on a batch's columns, the batched methods.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        ``[X̂(k−1)[0], X̂(k−1)[1], P00, P01, P11]``.
    u : numpy.ndarray
        ``[y(k), u(k−1), f1, f2, g0]``.
    p : numpy.ndarray
        :data:`CKF_LAYOUT`: ``Q00``, ``Q01``, ``Q11`` (the upper triangle of ``Q``), ``R``.
    x_next : numpy.ndarray
        Written in place.
    """
    xf0, xf1, n00, n01, n11 = _ckf_step(x, u, p)
    x_next[0] = xf0
    x_next[1] = xf1
    x_next[2] = n00
    x_next[3] = n01
    x_next[4] = n11


def ckf_output(t, x, u, p, y):
    """The filtered estimate ``X̂(k)`` after this sample (direct feedthrough); arguments as :func:`ckf_update`.

    Parameters
    ----------
    t, x, u, p
        As :func:`ckf_update`.
    y : numpy.ndarray
        ``[X̂(k)[0], X̂(k)[1]]``, written in place.
    """
    xf0, xf1, _, _, _ = _ckf_step(x, u, p)
    y[0] = xf0
    y[1] = xf1


class CharacteristicKalmanFilter(KernelBlock, DiscreteBlock):
    """Kalman filter on the 2nd-order characteristic model, its transition built from identified parameters.

    Model (characteristic model in state-space form)::

        X(k) = [x(k), x(k−1)]ᵀ,  Φ(k) = [[f1, f2], [1, 0]],  Γ(k) = [g0, 0]ᵀ,  C = [1, 0]
        X(k) = Φ(k) X(k−1) + Γ(k) u(k−1) + w,    y(k) = C X(k) + v,   cov w = Q, cov v = R

    One sample, with ``f1, f2, g0`` the current estimates (inputs)::

        X̂(k|k−1) = Φ X̂(k−1) + Γ u(k−1)
        P(k|k−1) = Φ P(k−1) Φᵀ + Q
        K(k)     = P(k|k−1) Cᵀ (C P(k|k−1) Cᵀ + R)⁻¹
        X̂(k)     = X̂(k|k−1) + K (y(k) − C X̂(k|k−1))
        P(k)     = (I − K C) P(k|k−1) (I − K C)ᵀ + K R Kᵀ       (Joseph form)

    Every 2×2 product is written out element-wise (no matrix product on the batch axis), so a
    run is bit-identical whatever the batch size.

    ``f1, f2, g0`` usually come from an online identification
    (:class:`~ctrl_analysis.identification.ArxRegressor` into
    :class:`~ctrl_analysis.identification.RecursiveLeastSquaresBlock`) and ``u(k−1)`` from a
    :class:`~ctrl_analysis.engine.blocks.UnitDelay`. Identify from ``y`` and ``u`` passed through one
    low-pass, not from the noisy ``y`` the filter reads: least squares on noisy regressors is biased
    (see :class:`~ctrl_analysis.identification.ArxRegressor`), and a CKF driven by the biased model
    does worse than the raw measurement.

    Parameters
    ----------
    Q : float or array_like, shape (2, 2)
        Process-noise covariance (symmetric, >= 0; a scalar means ``Q·I``).
    R : float
        Measurement-noise variance (> 0).
    P0 : float or array_like, shape (2, 2)
        Initial covariance (symmetric positive definite; a scalar means ``P0·I``).
    x0 : array_like, shape (2,), optional
        Initial estimate ``X̂(0)`` (default zeros).

    Block signals: inputs ``y`` (the measurement ``y(k)``), ``u`` (the input ``u(k−1)`` applied over
    the last sample), ``f1, f2, g0``; states ``xhat[0], xhat[1]`` (``X̂(k−1)``) and ``P[0][0], P[0][1],
    P[1][1]``; outputs ``xhat[0], xhat[1]`` = ``X̂(k)`` (direct feedthrough from ``y`` and the
    parameters).

    Raises
    ------
    ValueError
        ``R <= 0``, ``Q`` not symmetric positive semidefinite, ``P0`` not symmetric positive definite.

    References
    ----------
    Gong Y., Wu H., "Characteristic-model-based Kalman filter for high-order linear systems with
    unknown parameters", Aerospace Control and Application 36(6), 2010, eq. (6), (10), (11); the
    extracted text keeps only the Joseph-form covariance line, the others are the standard
    Kalman filter (Anderson & Moore, *Optimal Filtering*, 1979, ch. 3). Departure: ``u(k−1)`` is an
    input, so a loop must delay the control by one sample (this also avoids an algebraic loop).

    Examples
    --------
    >>> import numpy as np
    >>> ckf = CharacteristicKalmanFilter(Q=1e-4, R=1.0, P0=10.0)
    >>> u = np.column_stack([np.full(300, 5.0), np.zeros(300), np.full(300, 1.9), np.full(300, -0.9),
    ...                      np.full(300, 0.05)])          # y = 5 measured, u = 0, a stable model
    >>> y, _ = ckf.run(u)
    >>> bool(abs(y[-1, 0, 0] - 5.0) < 0.5)
    True
    """

    inputs = ("y", "u", "f1", "f2", "g0")
    outputs = ("xhat[0]", "xhat[1]")
    states = ("xhat[0]", "xhat[1]", "P[0][0]", "P[0][1]", "P[1][1]")
    feedthrough = True
    kernels = Kernels(output=ckf_output, update=ckf_update)

    def __init__(self, Q=1e-4, R=1.0, P0=1.0, x0=None):
        self.Q = _check_covariance("Q", Q, 2, definite=False)
        self.R = float(check_positive("R", R, scalar=True))
        self.P0 = _check_covariance("P0", P0, 2, definite=True)
        self.x0 = np.zeros(2) if x0 is None else check_finite("x0", np.ravel(x0), shape=(2,))
        self.kernel_params = CKF_LAYOUT.pack(Q00=self.Q[0, 0], Q01=self.Q[0, 1], Q11=self.Q[1, 1], R=self.R)

    def initial_state(self) -> np.ndarray:
        return np.array([self.x0[0], self.x0[1], self.P0[0, 0], self.P0[0, 1], self.P0[1, 1]])

    def __repr__(self) -> str:
        return f"CharacteristicKalmanFilter(R={self.R:g})"


#: The kernel parameters of a :class:`LinearKalmanFilter` of any order ``n``: ``n, R``, then ``F, G, H, Q``.
LKF_LAYOUT = Layout("n", "R", ("F", ("n", "n")), ("G", "n"), ("H", "n"), ("Q", ("n", "n")))
LKF_AT = LKF_LAYOUT.at


def lkf_layout(n: int) -> Layout:
    """The kernel parameters of an ``n``-state :class:`LinearKalmanFilter`: :data:`LKF_LAYOUT` for this ``n``.

    Parameters
    ----------
    n : int
        Number of model states.

    Returns
    -------
    Layout
    """
    return LKF_LAYOUT.sized(n=n)


@jitable
def _lkf_params(p):
    """``(n, F, G, H, Q)``: the order read from ``p`` and views of :data:`LKF_LAYOUT`'s arrays."""
    n = as_int(p[LKF_AT.n])
    return (n, matrix(p, offset(LKF_AT.F, n), n, n), vector(p, offset(LKF_AT.G, n), n),
            vector(p, offset(LKF_AT.H, n), n), matrix(p, offset(LKF_AT.Q, n), n, n))


@jitable
def _lkf_filter(x, u, p, M, V):
    """Prediction, gain and correction of :class:`LinearKalmanFilter` into the scratch ``M``, ``V``.

    ``M[0] = F P``, ``M[1] = P(k|k−1)``; ``V[0] = K(k)``, ``V[1] = x̂(k)``.
    """
    n, F, G, H, Q = _lkf_params(p)
    xh, P = vector(x, 0, n), matrix(x, n, n, n)  # x̂(k−1), P(k−1)
    FP, Pp, K, xf = M[0], M[1], V[0], V[1]
    mat_vec(F, xh, xf)                           # x̂(k|k−1) = F x̂(k−1) + G u(k−1)
    for i in range(n):
        xf[i] = xf[i] + u[1] * G[i]
    mat_mul(F, P, FP)
    mat_mul_t_add(FP, F, Q, Pp)                  # P(k|k−1) = F P Fᵀ + Q
    mat_vec(Pp, H, K)                            # P(k|k−1) Hᵀ
    S = dot(K, H, 0.0)                           # H P(k|k−1) Hᵀ
    yp = dot(xf, H, 0.0)                         # H x̂(k|k−1)
    for i in range(n):
        K[i] = K[i] / (S + p[LKF_AT.R])          # K = P(k|k−1) Hᵀ / (H P(k|k−1) Hᵀ + R)
        xf[i] = xf[i] + K[i] * (u[0] - yp)       # x̂(k) = x̂(k|k−1) + K (y − H x̂(k|k−1))


def lkf_update(t, x, u, p, x_next):
    """The update of :class:`LinearKalmanFilter`: ``[x̂(k), P(k)]``, P(k) in Joseph form.

    One run in the compiled engine, the batch's columns in the batched methods
    (:mod:`ctrl_analysis.engine.matrix`; the scratch takes the shape of a per-run value, ``u[0]``).

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        ``[x̂(k−1), P(k−1) row by row]`` of one run.
    u : numpy.ndarray
        ``[y(k), u(k−1)]``.
    p : numpy.ndarray
        :data:`LKF_LAYOUT`: ``n, R, F, G, H, Q`` (matrices row-major).
    x_next : numpy.ndarray
        Written in place.
    """
    n, _, _, H, _ = _lkf_params(p)
    M, V = scratch_matrices(4, n, n, u[0]), scratch_matrix(2, n, u[0])  # two allocations for the intermediates
    _lkf_filter(x, u, p, M, V)
    Pp, IKH, IKHP, K, xf = M[1], M[2], M[3], V[0], V[1]
    for i in range(n):
        x_next[i] = xf[i]
        for j in range(n):
            IKH[i, j] = (1.0 if i == j else 0.0) - K[i] * H[j]  # I − K H
    mat_mul(IKH, Pp, IKHP)
    P_new = mat_mul_t(IKHP, IKH, matrix(x_next, n, n, n))      # P(k) = (I − K H) P(k|k−1) (I − K H)ᵀ
    for i in range(n):
        for j in range(n):
            P_new[i, j] = P_new[i, j] + p[LKF_AT.R] * K[i] * K[j]  # + K R Kᵀ


def lkf_output(t, x, u, p, y):
    """The output of :class:`LinearKalmanFilter`: ``ŷ = H x̂(k)``; arguments as :func:`lkf_update`.

    Parameters
    ----------
    t, x, u, p
        As :func:`lkf_update`.
    y : numpy.ndarray
        ``[ŷ]``, written in place.
    """
    n, _, _, H, _ = _lkf_params(p)
    V = scratch_matrix(2, n, u[0])
    _lkf_filter(x, u, p, scratch_matrices(2, n, n, u[0]), V)
    y[0] = dot(V[1], H, 0.0)                     # ŷ = H x̂(k)


class LinearKalmanFilter(KernelBlock, DiscreteBlock):
    """Time-varying Kalman filter of a known ``n``-state SISO model (Joseph form), a discrete block.

    ``x(k) = F x(k−1) + G u(k−1) + w``, ``y(k) = H x(k) + v`` with ``F, G, H`` known and fixed: the
    reference a characteristic-model filter replaces when the plant is unknown. Its cost per step
    grows as ``n³`` (the covariance propagation), against a constant for the 2-state
    :class:`CharacteristicKalmanFilter`. One sample (the kernels :func:`lkf_output` /
    :func:`lkf_update` write these lines with the loops of :mod:`ctrl_analysis.engine.matrix`)::

        x̂(k|k−1) = F x̂(k−1) + G u(k−1)
        P(k|k−1) = F P(k−1) Fᵀ + Q
        K(k)     = P(k|k−1) Hᵀ / (H P(k|k−1) Hᵀ + R)
        x̂(k)     = x̂(k|k−1) + K(k) (y(k) − H x̂(k|k−1))
        P(k)     = (I − K H) P(k|k−1) (I − K H)ᵀ + K R Kᵀ       (Joseph form)
        ŷ(k)     = H x̂(k)                                        output

    Parameters
    ----------
    F : array_like, shape (n, n)
    G : array_like, shape (n,)
        Input vector.
    H : array_like, shape (n,)
        Output row.
    Q : float or array_like, shape (n, n)
        Process-noise covariance (symmetric, >= 0).
    R : float
        Measurement-noise variance (> 0).
    P0 : float or array_like, shape (n, n)
        Initial covariance (symmetric positive definite).
    x0 : array_like, shape (n,), optional

    Block signals: inputs ``y`` (``y(k)``), ``u`` (``u(k−1)``); states ``xhat[0..n-1]`` then ``P`` row
    by row; output ``yhat = H x̂(k)``.

    Raises
    ------
    ValueError
        Shapes that do not match, ``R <= 0``, ``Q`` or ``P0`` not a covariance.

    References
    ----------
    Anderson B. D. O., Moore J. B., *Optimal Filtering*, 1979, ch. 3; Bucy R. S., Joseph P. D.,
    *Filtering for Stochastic Processes*, 1968 (the Joseph form).
    """

    inputs = ("y", "u")
    outputs = ("yhat",)
    feedthrough = True
    kernels = Kernels(output=lkf_output, update=lkf_update)

    def __init__(self, F, G, H, Q, R, P0=1.0, x0=None):
        self.F = check_matrix("F", F, square=True)
        n = self.F.shape[0]
        self.G, self.H = np.ravel(check_finite("G", G)), np.ravel(check_finite("H", H))
        for name, vec in (("G", self.G), ("H", self.H)):
            if vec.shape != (n,):
                raise ValueError(f"{name} must have {n} entries to match F ({n}×{n}), got {vec.size}")
        self.Q = _check_covariance("Q", Q, n, definite=False)
        self.R = float(check_positive("R", R, scalar=True))
        self.P0 = _check_covariance("P0", P0, n, definite=True)
        self.x0 = np.zeros(n) if x0 is None else check_finite("x0", np.ravel(x0), shape=(n,))
        self.n = n
        self.kernel_params = LKF_LAYOUT.pack(n=n, R=self.R, F=self.F, G=self.G, H=self.H, Q=self.Q)
        self.states = signal_names("xhat", n) + tuple(f"P[{i}][{j}]" for i in range(n) for j in range(n))

    def initial_state(self) -> np.ndarray:
        return np.concatenate([self.x0, self.P0.reshape(-1)])

    def __repr__(self) -> str:
        return f"LinearKalmanFilter(n={self.n}, R={self.R:g})"
