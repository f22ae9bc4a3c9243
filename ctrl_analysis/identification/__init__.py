"""Parameter identification: batch least squares with identifiability checks, recursive least squares.

Linear regression ``z = H θ + v`` with ``H`` the regression matrix (one row ``hᵀ`` per sample).

* :func:`identifiability` reports the rank and condition number of ``H``. ``θ`` is identifiable
  from a batch iff ``H`` has full column rank (``HᵀH`` invertible); a large condition number means
  the columns are nearly collinear and ``θ`` is poorly determined by the data.
* :func:`batch_least_squares` solves the batch problem (``θ = (HᵀH)⁻¹ Hᵀ z``, computed by an
  SVD-based solver), warns with :class:`IdentifiabilityWarning` when the problem is ill-conditioned
  and, in ``strict`` mode, raises when it is rank-deficient.
* :class:`RecursiveLeastSquaresBlock`: the recursive form (forgetting, box projection), a discrete
  block for a :class:`~ctrl_analysis.engine.loop.Loop`, fed by :class:`ArxRegressor`'s delayed signals;
  :class:`RecursiveLeastSquares`: its equations as an estimator object (``step(h, z)``, ``run(H, z)``).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from .._validate import check_bool, check_finite, check_int, check_positive, check_vector, finite_result
from ..engine.blocks import MAX_SIGNALS, DiscreteBlock, signal_names
from ..engine.kernels import KernelBlock, Kernels
from . import kernels as kern

__all__ = [
    "ArxRegressor",
    "IdentifiabilityReport",
    "IdentifiabilityWarning",
    "LeastSquaresResult",
    "RecursiveLeastSquares",
    "RecursiveLeastSquaresBlock",
    "batch_least_squares",
    "identifiability",
]

#: Most parameters a recursive least squares estimates (its covariance is n_params² floats).
MAX_PARAMS = 1000

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
        """Whether the regressor has full column rank and a scaled condition number within the threshold."""
        return self.full_rank and self.cond_scaled <= self.threshold

    def as_dict(self) -> dict:
        """The report as a JSON-ready dict (for results.json).

        Returns
        -------
        dict
            The fields by name, singular values as a list.
        """
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
    finite_result("H", lambda: np.linalg.norm(H, axis=0))  # its column norms (and H^T H) must not overflow
    if z is _NO_Z:
        return H
    z = np.atleast_1d(check_finite("z", z))
    if z.shape != (H.shape[0],):
        raise ValueError(f"z must have shape ({H.shape[0]},) to match H's rows, got {z.shape}")
    finite_result("z", lambda: np.linalg.norm(z))
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


class RecursiveLeastSquaresBlock(KernelBlock, DiscreteBlock):
    """Recursive least squares with exponential forgetting and optional box projection, as a discrete block.

    For each new sample ``z(k) = h(k)ᵀ θ + v(k)``::

        D(k) = R(k-1) h(k) [hᵀ(k) R(k-1) h(k) + λ]⁻¹
        θ(k) = Π[θ(k-1) + D(k) (z(k) - hᵀ(k) θ(k-1))]
        R(k) = [I - D(k) hᵀ(k)] R(k-1) / λ

    with ``Π`` the projection onto the box ``lower <= θ <= upper`` (the identity without bounds).
    The gain is called ``D`` and the covariance ``R`` in the characteristic-model literature;
    here (state names, and :class:`RecursiveLeastSquares`' attributes) they are ``K`` and ``P``.

    The block protocol (batched, for :class:`ctrl_analysis.engine.loop.Loop` and
    ``control.interconnect``): inputs ``z, h[0..p-1]``; states ``theta[0..p-1]`` and the
    covariance row by row ``P[i][j]``; outputs ``theta[0..p-1]`` = ``θ(k)`` *after* the update
    with the current sample (direct feedthrough, as :class:`~ctrl_analysis.estimators.lowpass.DiscreteLowPass`),
    or the previous estimate ``θ(k−1)`` with ``feedthrough=False``. Its :meth:`run` is the
    protocol's open-loop runner (``u`` of shape ``(N, 1 + p)``: ``z`` then ``h``). To feed samples
    or a record to an estimator that keeps its state, use :class:`RecursiveLeastSquares`, which
    steps this block's equations (one implementation).

    Parameters
    ----------
    n_params : int
        Number of parameters ``p`` (>= 1).
    forgetting : float
        Forgetting factor ``λ`` in ``(0, 1]``; ``1`` is ordinary RLS, smaller values track changes
        with an effective memory of about ``1 / (1 - λ)`` samples.
    P0 : float or array_like, shape (p, p)
        Initial covariance (a scalar means ``P0 * I``; symmetric positive definite).
    theta0 : array_like, shape (p,), optional
        Initial estimate (default zeros; inside the bounds when given).
    lower, upper : array_like, shape (p,), optional
        Box bounds of the projection (``-inf`` / ``inf`` entries leave a parameter free).
    max_trace : float, optional
        Anti-windup: after each update, ``R(k)`` is scaled down so that ``trace R(k) <= max_trace``
        (with forgetting and weak excitation ``R`` otherwise grows like ``λ⁻ᵏ``, and the estimate
        bursts). ``None`` (default) leaves ``R`` unbounded.
    feedthrough : bool
        ``True`` (default) outputs ``θ(k)``, the estimate after the update with the current
        sample; ``False`` outputs the stored ``θ(k−1)`` (no direct feedthrough: a loop may then
        feed the estimate back into the regression without an algebraic loop, and the output
        costs nothing).

    Raises
    ------
    ValueError
        ``forgetting`` outside ``(0, 1]``, ``P0`` not symmetric positive definite, shapes that do
        not match ``p``, ``lower > upper`` or ``theta0`` outside the bounds.

    References
    ----------
    Ljung L., System Identification, 2nd ed., 1999, section 11.2 (RLS with forgetting);
    Goodwin G. C., Sin K. S., Adaptive Filtering, Prediction and Control, 1984, §3.3 (projection).
    Gong & Wu 2010, eq. (9) (the ``D(k)`` line; the others are the standard form).

    Examples
    --------
    Open loop, the samples ``z(k) = 3 sin k − 2`` with ``h(k) = [sin k, 1]`` as the input ``[z, h]``:

    >>> import numpy as np
    >>> k = np.arange(20.0)
    >>> y, _ = RecursiveLeastSquaresBlock(2, forgetting=1.0, P0=1e6).run(
    ...     np.column_stack([3 * np.sin(k) - 2, np.sin(k), np.ones(20)]))
    >>> y[-1, 0].round(6)
    array([ 3., -2.])
    """

    def __init__(self, n_params: int, forgetting: float = 1.0, P0=1e6, theta0=None, *, lower=None, upper=None,
                 max_trace: float | None = None, feedthrough: bool = True):
        self.feedthrough = check_bool("feedthrough", feedthrough)
        self.max_trace = None if max_trace is None else float(check_positive("max_trace", max_trace, scalar=True))
        self.n_params = check_int("n_params", n_params, minimum=1, maximum=MAX_PARAMS)
        forgetting = float(check_finite("forgetting", forgetting, scalar=True))
        if not 0.0 < forgetting <= 1.0:
            raise ValueError(f"forgetting must be in (0, 1], got {forgetting}")
        self.forgetting = forgetting
        p = self.n_params
        P0 = check_finite("P0", P0)
        if np.ndim(P0) == 0:
            if P0 <= 0:
                raise ValueError(f"P0 must be > 0 (a covariance), got {P0}")
            P0 = P0 * np.eye(p)
        else:
            P0 = np.asarray(P0, dtype=float)
            if P0.shape != (p, p):
                raise ValueError(f"P0 must be a scalar or have shape ({p}, {p}), got {P0.shape}")
            if not np.allclose(P0, P0.T):
                raise ValueError("P0 must be symmetric")
            eig = np.linalg.eigvalsh(P0)
            if np.any(eig <= 0):
                raise ValueError(f"P0 must be positive definite (not singular or negative), got eigenvalues {eig}")
        self.P0 = P0
        lower = np.full(p, -np.inf) if lower is None else check_vector("lower", lower, p, allow_inf=True)
        upper = np.full(p, np.inf) if upper is None else check_vector("upper", upper, p, allow_inf=True)
        if np.any(np.isnan(lower)) or np.any(np.isnan(upper)) or np.any(lower > upper):
            raise ValueError(f"lower must be <= upper element-wise (no NaN), got lower={lower}, upper={upper}")
        if np.any(lower == np.inf) or np.any(upper == -np.inf):
            raise ValueError(f"lower must be < inf and upper > -inf (an infinite bound is on its own side), got "
                             f"lower={lower}, upper={upper}")
        self.lower, self.upper = lower.copy(), upper.copy()
        self.projected = bool(np.any(np.isfinite(lower)) or np.any(np.isfinite(upper)))
        if theta0 is None:
            theta0 = np.clip(np.zeros(p), lower, upper)
        theta0 = np.atleast_1d(check_finite("theta0", theta0)).astype(float)
        if theta0.shape != (p,):
            raise ValueError(f"theta0 must have shape ({p},), got {theta0.shape}")
        if np.any(theta0 < lower) or np.any(theta0 > upper):
            raise ValueError(f"theta0 must lie within [lower, upper], got {theta0}")
        self.theta0 = theta0
        self.inputs = ("z",) + signal_names("h", p)
        self.outputs = signal_names("theta", p)
        self.states = self.outputs + tuple(f"P[{i}][{j}]" for i in range(p) for j in range(p))
        self.kernel_params = kern.rls_layout(p).pack(n=p, forgetting=forgetting, max_trace=self.max_trace or 0.0,
                                                     projected=float(self.projected), lower=lower, upper=upper)

    # ------------------------------------------------------------------ block protocol
    def initial_state(self) -> np.ndarray:
        return np.concatenate([self.theta0, self.P0.reshape(-1)])

    @property
    def kernels(self) -> Kernels:
        """The RLS kernels: ``rls_update`` and ``rls_output`` (``rls_hold_output`` without feedthrough).

        In :mod:`ctrl_analysis.identification.kernels`; run by run in the batched methods (the
        projection and the trace cap branch per value).
        """
        return _RLS_KERNELS if self.feedthrough else _RLS_HOLD_KERNELS

    def __repr__(self) -> str:
        return f"RecursiveLeastSquaresBlock(n_params={self.n_params}, forgetting={self.forgetting})"


_RLS_KERNELS = Kernels(output=kern.rls_output, update=kern.rls_update, columns=False)
_RLS_HOLD_KERNELS = Kernels(output=kern.rls_hold_output, update=kern.rls_update, columns=False)


class RecursiveLeastSquares:
    """Recursive least squares as an estimator object that keeps its state: :meth:`step` a sample, :meth:`run` a record.

    The equations are :class:`RecursiveLeastSquaresBlock`'s, stepped by its own per-sample code:
    this object holds a block and its state ``[θ, vec R]``. In a :class:`~ctrl_analysis.engine.loop.Loop`,
    place the block.

    Parameters
    ----------
    n_params, forgetting, P0, theta0, lower, upper, max_trace
        As :class:`RecursiveLeastSquaresBlock`.
    batch : int, optional
        Number of independent runs ``B`` stepped side by side; ``None`` for a single run (arrays
        without a batch axis).

    Attributes
    ----------
    block : RecursiveLeastSquaresBlock
        The equations and their settings (``block.n_params``, ``block.forgetting``, ...).
    theta, P, K : ndarray, shapes (p,), (p, p), (p,) (with a leading B for a batch)
        The estimate after the last sample (``theta0`` before the first), the covariance
        ``R(k)`` and the last gain ``D(k)`` (zeros before the first sample).

    Raises
    ------
    ValueError
        As :class:`RecursiveLeastSquaresBlock`, or ``batch`` not an integer ``>= 1``.

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

    def __init__(self, n_params: int, forgetting: float = 1.0, P0=1e6, theta0=None, batch: int | None = None,
                 lower=None, upper=None, max_trace: float | None = None):
        self.block = RecursiveLeastSquaresBlock(n_params, forgetting, P0, theta0, lower=lower, upper=upper,
                                                max_trace=max_trace)
        self.batch = None if batch is None else check_int("batch", batch, minimum=1, maximum=MAX_SIGNALS)
        self.reset()

    def reset(self) -> None:
        """Return to ``theta0`` and ``P0``."""
        B = 1 if self.batch is None else self.batch
        self._x = np.tile(self.block.initial_state(), (B, 1))
        self.K = np.zeros((B, self.block.n_params))
        self._sync()

    def _sync(self):
        p = self.block.n_params
        theta = self._x[:, :p].copy()
        P = self._x[:, p:].reshape(-1, p, p).copy()
        if self.batch is None:
            theta, P, self.K = theta[0], P[0], self.K[0]
        self.theta, self.P = theta, P

    def step(self, h, z) -> np.ndarray:
        """Update with one sample.

        Parameters
        ----------
        h : array_like, shape (p,) or (B, p)
            Regressor ``h(k)``.
        z : float or array_like, shape (B,)
            Measurement ``z(k)``.

        Returns
        -------
        numpy.ndarray, shape (p,) or (B, p)
            The new estimate ``θ(k)`` (also in :attr:`theta`).

        Raises
        ------
        ValueError
            ``h`` or ``z`` with NaN/inf (one bad sample would make θ NaN for good) or of the wrong
            shape; the estimator state is left unchanged.
        """
        h = np.asarray(check_finite("h", h), dtype=float)
        z = np.asarray(check_finite("z", z), dtype=float)
        p = self.block.n_params
        if self.batch is None:
            if h.shape != (p,):
                raise ValueError(f"h must have shape ({p},), got {h.shape}")
            if z.size != 1:
                raise ValueError(f"z must be a scalar, got shape {z.shape}")
            B = 1
        else:
            B = self.batch
        h = np.broadcast_to(h, (B, p))
        z = np.broadcast_to(z.reshape(-1) if z.ndim else z, (B,))
        u = np.concatenate([z[:, None], h], axis=1)
        P = self.block.kernel_params
        D = np.empty((B, p))
        for b in range(B):  # D(k) = R(k-1) h(k) / (hᵀ R(k-1) h + λ), the kernels' own gain
            den, _ = kern.rls_gain(self._x[b], u[b], P, D[b])
            D[b] /= den
        self._x = self.block.batched("update", 0.0, self._x, u, P)  # the block's equations, one step
        self.K = D
        self._sync()
        return self.theta

    def run(self, H, z) -> np.ndarray:
        """Feed a whole record sample by sample through :meth:`step`.

        Parameters
        ----------
        H : array_like, shape (N, p) or (N, B, p)
            Regressors, one row per sample.
        z : array_like, shape (N,) or (N, B)
            Measurements.

        Returns
        -------
        numpy.ndarray, shape (N, p) or (N, B, p)
            The estimate after each sample.

        Raises
        ------
        ValueError
            If ``H`` and ``z`` have different numbers of samples.
        """
        H = np.atleast_2d(check_finite("H", H))
        z = np.atleast_1d(check_finite("z", z))
        if H.ndim > 3 or z.ndim != H.ndim - 1:
            raise ValueError(f"H and z must have shapes (N, p) and (N,), or (N, B, p) and (N, B), got {H.shape} "
                             f"and {z.shape}")
        if H.shape[0] != z.shape[0]:
            raise ValueError(f"H and z must have the same number of samples, got {H.shape[0]} and {z.shape[0]}")
        out = np.empty(H.shape[:1] + np.shape(self.theta))
        for k in range(H.shape[0]):
            out[k] = self.step(H[k], z[k])
        return out

    def __repr__(self) -> str:
        return f"RecursiveLeastSquares({self.block!r}, batch={self.batch})"


class ArxRegressor(KernelBlock, DiscreteBlock):
    """Tapped delay lines forming the ARX regression ``z = s(k−d)``, ``h = [s(k−d−1..k−d−na), u(k−d−1..k−d−nb)]``.

    Feeds :class:`RecursiveLeastSquaresBlock` with the model
    ``s(k) = a_1 s(k−1) + ... + a_na s(k−na) + b_1 u(k−1) + ... + b_nb u(k−nb)``. With ``lag`` ``d = 0``
    the target is the current sample (direct feedthrough from ``s``); with ``d >= 1`` the whole
    regression is ``d`` samples old and comes from the state only, so an estimator whose output is
    ``s`` can be identified inside its own loop without an algebraic loop.

    Parameters
    ----------
    na, nb : int
        Numbers of output lags (>= 0) and input lags (>= 0); ``na + nb >= 1``.
    lag : int
        Age ``d`` of the regression (>= 0).

    Block signals: inputs ``s, u``; outputs ``z, h[0..na+nb-1]``; states ``s_prev[0..na+d-1]``
    (``s_prev[i] = s(k−1−i)``) and ``u_prev[0..nb+d-1]`` (``u(k−1−i)``).

    Raises
    ------
    ValueError
        Negative orders or lag, or no regressor at all.

    Notes
    -----
    **Never feed it a noisy measurement.** Least squares assumes noise-free regressors; with a
    measurement ``s = y + v`` in ``h`` (*errors in variables*) it converges to ``(R_hh + Σ)⁻¹ R_hh θ``,
    not ``θ`` (``R_hh`` the noise-free regressors' second moment, ``Σ`` the noise's), and no test
    inside the estimator can tell. Sampled fast, the ``a_i`` are carried by the sample-to-sample change
    of ``y``, much smaller than the noise's, and the fit describes the noise (the user guide's
    second-order plant: ``a_1 = 0.53, a_2 = 0.45`` for ``1.93, −0.93``). Filter ``s`` *and* ``u`` with one low-pass
    first, ``LowPassFilter(ω, order=na + 1).digital(h, channels=2)`` with ``ω`` near the plant's
    bandwidth: a linear filter commutes with the model, so the filtered pair obeys it with the same
    ``θ``, and the noise leaves the regression (``docs/guide.rst``, "Online characteristic-model
    identification with the CKF").

    Examples
    --------
    >>> import numpy as np
    >>> reg = ArxRegressor(2, 1, lag=0)
    >>> y, _ = reg.run(np.column_stack([np.arange(4.0), 10 + np.arange(4.0)]))
    >>> y[-1, 0]          # z = s(3); h = [s(2), s(1), u(2)]
    array([ 3.,  2.,  1., 12.])
    """

    inputs = ("s", "u")
    kernels = Kernels(output=kern.arx_output, update=kern.arx_update)

    def __init__(self, na: int, nb: int, lag: int = 0):
        self.na = check_int("na", na, minimum=0, maximum=MAX_SIGNALS)
        self.nb = check_int("nb", nb, minimum=0, maximum=MAX_SIGNALS)
        self.lag = check_int("lag", lag, minimum=0, maximum=MAX_SIGNALS)
        if self.na + self.nb < 1:
            raise ValueError(f"na + nb must be >= 1, got na={na}, nb={nb}")
        self.ns, self.nu = self.na + self.lag, self.nb + self.lag
        self.states = signal_names("s_prev", self.ns) + signal_names("u_prev", self.nu)
        self.outputs = ("z",) + signal_names("h", self.na + self.nb)
        self.feedthrough = self.lag == 0
        self.kernel_params = kern.ARX.pack(na=self.na, nb=self.nb, lag=self.lag)
