"""Parameter identification: batch least squares with identifiability checks, recursive least squares.

Linear regression ``z = H θ + v`` with ``H`` the regression matrix (one row ``hᵀ`` per sample).

* :func:`identifiability` reports the rank and condition number of ``H``. ``θ`` is identifiable
  from a batch iff ``H`` has full column rank (``HᵀH`` invertible); a large condition number means
  the columns are nearly collinear and ``θ`` is poorly determined by the data.
* :func:`batch_least_squares` solves the batch problem (``θ = (HᵀH)⁻¹ Hᵀ z``, computed by an
  SVD-based solver), warns with :class:`IdentifiabilityWarning` when the problem is ill-conditioned
  and, in ``strict`` mode, raises when it is rank-deficient.
* :class:`RecursiveLeastSquares` is the recursive form with exponential forgetting, batched over
  independent runs.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ._validate import check_bool, check_finite, check_int, check_positive

__all__ = [
    "IdentifiabilityWarning",
    "IdentifiabilityReport",
    "LeastSquaresResult",
    "identifiability",
    "batch_least_squares",
    "RecursiveLeastSquares",
]

#: Default threshold on the (column-scaled) condition number above which a batch is ill-conditioned.
DEFAULT_COND_THRESHOLD = 1e6


class IdentifiabilityWarning(UserWarning):
    """The regression matrix of a least-squares problem is ill-conditioned or rank-deficient."""


@dataclass(frozen=True)
class IdentifiabilityReport:
    """Rank and conditioning of a regression matrix ``H`` (rows = samples, columns = parameters).

    Attributes
    ----------
    n_rows, n_params : int
        Shape of ``H``.
    rank : int
        Numerical rank (singular values above ``max(shape) * eps * s_max``).
    cond : float
        2-norm condition number ``s_max / s_min`` of ``H`` as given (``inf`` if ``s_min = 0``).
    cond_scaled : float
        Condition number after scaling every column to unit 2-norm: insensitive to the units of the
        parameters, so it measures collinearity alone.
    singular_values : tuple of float
        Singular values of the column-scaled ``H``.
    threshold : float
        The ``cond_scaled`` above which the batch is called ill-conditioned.
    """

    n_rows: int
    n_params: int
    rank: int
    cond: float
    cond_scaled: float
    singular_values: tuple
    threshold: float

    @property
    def full_rank(self) -> bool:
        """Theorem: ``HᵀH`` is invertible iff the columns of ``H`` are linearly independent."""
        return self.rank == self.n_params

    @property
    def well_conditioned(self) -> bool:
        return self.full_rank and self.cond_scaled <= self.threshold

    def as_dict(self) -> dict:
        return {
            "n_rows": self.n_rows,
            "n_params": self.n_params,
            "rank": self.rank,
            "cond": self.cond,
            "cond_scaled": self.cond_scaled,
            "full_rank": self.full_rank,
            "well_conditioned": self.well_conditioned,
        }


@dataclass(frozen=True)
class LeastSquaresResult:
    """Solution of a batch least-squares problem.

    Attributes
    ----------
    theta : ndarray, shape (p,)
        Estimated parameters (minimum-norm solution when rank-deficient).
    residual_rms : float
        ``sqrt(mean((z - H theta)^2))``.
    report : IdentifiabilityReport
    """

    theta: np.ndarray
    residual_rms: float
    report: IdentifiabilityReport


_NO_Z = object()


def _check_regression(H, z=_NO_Z):
    H = np.asarray(check_finite("H", H))
    if H.ndim != 2:
        raise ValueError(f"H must be a 2-D regression matrix (samples x parameters), got ndim={H.ndim}")
    if H.shape[0] < 1 or H.shape[1] < 1:
        raise ValueError(f"H must have at least one row and one column, got shape {H.shape}")
    if z is _NO_Z:
        return H
    z = np.atleast_1d(check_finite("z", z))
    if z.shape != (H.shape[0],):
        raise ValueError(f"z must have shape ({H.shape[0]},) to match H's rows, got {z.shape}")
    return H, z


def identifiability(H, *, cond_threshold: float = DEFAULT_COND_THRESHOLD) -> IdentifiabilityReport:
    """Rank and condition number of a regression matrix (the full-column-rank test).

    Parameters
    ----------
    H : array_like, shape (N, p)
        Regression matrix.
    cond_threshold : float
        Column-scaled condition number above which the batch is reported as ill-conditioned.

    Returns
    -------
    IdentifiabilityReport

    References
    ----------
    Chen Z., Gao Q., "Modified extended state observer: analysis and implementation", Control
    Theory & Applications 35(8), 2018, Theorem 1 and eq. (24)-(26): ``AᵀA`` is invertible iff the
    columns of ``A`` are linearly independent.
    """
    H = _check_regression(H)
    cond_threshold = check_positive("cond_threshold", cond_threshold, scalar=True)
    N, p = H.shape
    s = np.linalg.svd(H, compute_uv=False)
    tol = max(N, p) * np.finfo(float).eps * (s[0] if s.size else 0.0)
    rank = int(np.sum(s > tol)) if s.size else 0
    cond = float(s[0] / s[-1]) if s.size == p and s[-1] > 0 else np.inf
    norms = np.linalg.norm(H, axis=0)
    if np.any(norms == 0):
        ss = np.zeros(p)
        cond_scaled = np.inf
    else:
        ss = np.linalg.svd(H / norms, compute_uv=False)
        cond_scaled = float(ss[0] / ss[-1]) if ss.size == p and ss[-1] > 0 else np.inf
    if N < p:
        rank = min(rank, N)
        cond = cond_scaled = np.inf
    return IdentifiabilityReport(n_rows=N, n_params=p, rank=rank, cond=cond, cond_scaled=cond_scaled,
                                 singular_values=tuple(float(v) for v in ss), threshold=float(cond_threshold))


def batch_least_squares(H, z, *, strict: bool = False, cond_threshold: float = DEFAULT_COND_THRESHOLD,
                        warn: bool = True) -> LeastSquaresResult:
    """Batch least squares ``theta = argmin ||z - H theta||`` with an identifiability report.

    Parameters
    ----------
    H : array_like, shape (N, p)
        Regression matrix, one sample per row.
    z : array_like, shape (N,)
        Regressand.
    strict : bool
        Raise :class:`ValueError` when ``H`` is rank-deficient (otherwise return the minimum-norm
        solution and warn).
    cond_threshold : float
        Column-scaled condition number above which :class:`IdentifiabilityWarning` is issued.
    warn : bool
        Issue :class:`IdentifiabilityWarning` for ill-conditioned or rank-deficient batches
        (set ``False`` when the caller collects the reports itself).

    Returns
    -------
    LeastSquaresResult

    Raises
    ------
    ValueError
        Non-finite data, shapes that do not match, or (``strict``) a rank-deficient ``H``.

    References
    ----------
    Chen & Gao 2018, eq. (17) and (23) (``(XᵀX)⁻¹ Xᵀ B``) and Theorem 1.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 50)
    >>> H = np.column_stack([t, np.ones_like(t)])
    >>> batch_least_squares(H, 2 * t + 1).theta.round(12)
    array([2., 1.])
    """
    H, z = _check_regression(H, z)
    strict = check_bool("strict", strict)
    warn = check_bool("warn", warn)
    report = identifiability(H, cond_threshold=cond_threshold)
    if not report.full_rank:
        msg = (f"H is rank-deficient: rank {report.rank} < {report.n_params} parameters "
               f"(columns linearly dependent), so the parameters are not identifiable from this batch")
        if strict:
            raise ValueError(msg)
        if warn:
            warnings.warn(msg + "; returning the minimum-norm solution", IdentifiabilityWarning, stacklevel=2)
    elif warn and report.cond_scaled > report.threshold:
        warnings.warn(
            f"H is ill-conditioned: column-scaled condition number {report.cond_scaled:.3g} > "
            f"{report.threshold:.3g}; the parameters are poorly determined by this batch",
            IdentifiabilityWarning, stacklevel=2)
    theta, *_ = np.linalg.lstsq(H, z, rcond=None)
    resid = z - H @ theta
    return LeastSquaresResult(theta=theta, residual_rms=float(np.sqrt(np.mean(resid**2))), report=report)


class RecursiveLeastSquares:
    """Recursive least squares with exponential forgetting, batched over independent runs.

    For each new sample ``z(k) = h(k)ᵀ θ + v(k)``::

        K(k)     = P(k-1) h / (λ + hᵀ P(k-1) h)
        θ(k)     = θ(k-1) + K(k) (z(k) - hᵀ θ(k-1))
        P(k)     = [I - K(k) hᵀ] P(k-1) / λ

    Parameters
    ----------
    n_params : int
        Number of parameters ``p`` (>= 1).
    forgetting : float
        Forgetting factor ``λ`` in ``(0, 1]``; ``1`` is ordinary RLS, smaller values track changes
        with an effective memory of about ``1 / (1 - λ)`` samples.
    P0 : float or array_like, shape (p, p)
        Initial covariance (a scalar means ``P0 * I``; > 0).
    theta0 : array_like, shape (p,), optional
        Initial estimate (default zeros).
    batch : int, optional
        Number of independent runs ``B``; ``None`` for a single run (arrays without a batch axis).

    Attributes
    ----------
    theta : ndarray, shape (p,) or (B, p)
    P : ndarray, shape (p, p) or (B, p, p)
    K : ndarray, shape (p,) or (B, p)
        Last gain.

    References
    ----------
    Ljung L., System Identification, 2nd ed., 1999, section 11.2 (RLS with forgetting).

    Examples
    --------
    >>> import numpy as np
    >>> rls = RecursiveLeastSquares(2, forgetting=1.0, P0=1e6)
    >>> for k in range(20):
    ...     h = np.array([np.sin(k), 1.0])
    ...     _ = rls.step(h, 3 * np.sin(k) - 2)
    >>> rls.theta.round(6)
    array([ 3., -2.])
    """

    def __init__(self, n_params: int, forgetting: float = 1.0, P0=1e6, theta0=None, batch: int | None = None):
        self.n_params = check_int("n_params", n_params, minimum=1)
        forgetting = float(check_finite("forgetting", forgetting, scalar=True))
        if not 0.0 < forgetting <= 1.0:
            raise ValueError(f"forgetting must be in (0, 1], got {forgetting}")
        self.forgetting = forgetting
        p = self.n_params
        P0 = check_finite("P0", P0)
        if np.ndim(P0) == 0:
            if P0 <= 0:
                raise ValueError(f"P0 must be > 0, got {P0}")
            P0 = P0 * np.eye(p)
        else:
            P0 = np.asarray(P0, dtype=float)
            if P0.shape != (p, p):
                raise ValueError(f"P0 must be a scalar or have shape ({p}, {p}), got {P0.shape}")
            if not np.allclose(P0, P0.T) or np.any(np.linalg.eigvalsh(P0) <= 0):
                raise ValueError("P0 must be symmetric positive definite")
        self.P0 = P0
        if theta0 is None:
            theta0 = np.zeros(p)
        theta0 = np.atleast_1d(check_finite("theta0", theta0)).astype(float)
        if theta0.shape != (p,):
            raise ValueError(f"theta0 must have shape ({p},), got {theta0.shape}")
        self.theta0 = theta0
        self.batch = None if batch is None else check_int("batch", batch, minimum=1)
        self.reset()

    def reset(self) -> None:
        """Return to ``theta0`` and ``P0``."""
        if self.batch is None:
            self.theta = self.theta0.copy()
            self.P = self.P0.copy()
            self.K = np.zeros(self.n_params)
        else:
            self.theta = np.tile(self.theta0, (self.batch, 1))
            self.P = np.tile(self.P0, (self.batch, 1, 1))
            self.K = np.zeros((self.batch, self.n_params))

    def step(self, h, z) -> np.ndarray:
        """Update with one sample: regressor ``h`` (shape (p,) or (B, p)) and measurement ``z``.

        Returns the new ``theta``.

        Raises
        ------
        ValueError
            ``h`` or ``z`` with NaN/inf (one bad sample would make θ NaN for good) or of the wrong
            shape; the estimator state is left unchanged.
        """
        h = np.asarray(check_finite("h", h), dtype=float)
        z = np.asarray(check_finite("z", z), dtype=float)
        p = self.n_params
        if self.batch is None:
            if h.shape != (p,):
                raise ValueError(f"h must have shape ({p},), got {h.shape}")
            if z.size != 1:
                raise ValueError(f"z must be a scalar, got shape {z.shape}")
            z = float(z)
            Ph = self.P @ h
            # K(k) = P h / (λ + hᵀ P h)
            self.K = Ph / (self.forgetting + h @ Ph)
            # θ(k) = θ(k-1) + K (z - hᵀ θ(k-1))
            self.theta = self.theta + self.K * (z - h @ self.theta)
            # P(k) = [I - K hᵀ] P / λ
            self.P = (self.P - np.outer(self.K, Ph)) / self.forgetting
        else:
            B = self.batch
            if h.shape not in ((p,), (B, p)):
                raise ValueError(f"h must have shape ({p},) or ({B}, {p}), got {h.shape}")
            if z.size not in (1, B):
                raise ValueError(f"z must be a scalar or have {B} entries (one per run), got shape {z.shape}")
            h = np.broadcast_to(h, (B, p))
            z = np.broadcast_to(z.reshape(-1), (B,))
            Ph = np.einsum("bij,bj->bi", self.P, h)
            self.K = Ph / (self.forgetting + np.einsum("bi,bi->b", h, Ph))[:, None]
            self.theta = self.theta + self.K * (z - np.einsum("bi,bi->b", h, self.theta))[:, None]
            self.P = (self.P - self.K[:, :, None] * Ph[:, None, :]) / self.forgetting
        # keep P symmetric against round-off
        self.P = 0.5 * (self.P + np.swapaxes(self.P, -1, -2))
        return self.theta

    def run(self, H, z) -> np.ndarray:
        """Feed a whole record (``H`` of shape (N, p) or (N, B, p), ``z`` of shape (N,) or (N, B)).

        Returns the estimate history, shape (N, p) or (N, B, p).
        """
        H = np.atleast_2d(check_finite("H", H))
        z = np.atleast_1d(check_finite("z", z))
        if H.shape[0] != z.shape[0]:
            raise ValueError(f"H and z must have the same number of samples, got {H.shape[0]} and {z.shape[0]}")
        out = np.empty(H.shape[:1] + np.shape(self.theta))
        for k in range(H.shape[0]):
            out[k] = self.step(H[k], z[k])
        return out
