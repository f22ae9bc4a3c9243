"""Extended state observers: linear ESO, Han's nonlinear ESO (``fal``) and the modified ESO (MESO).

Plant of order ``n`` in the canonical form

    x_i' = x_{i+1}  (i < n),   x_n' = f(known) + L(t) + b0 u,   y = x_1,

with the *extended state* ``x_{n+1} = L(t)`` (the total unknown part). The observer has ``n + 1``
states ``x_hat_1 .. x_hat_{n+1}``; with ``e = y - x_hat_1``

    x_hat_i'     = x_hat_{i+1} + L_i g_i(e)                            i = 1..n-1
    x_hat_n'     = x_hat_{n+1} + f_known + b0 u + L_n g_n(e)
    x_hat_{n+1}' = L_{n+1} g_{n+1}(e)

``g_i(e) = e`` (linear ESO) or ``g_i(e) = fal(e, alpha_i, delta)`` (Han's nonlinear ESO). A callable
``known`` supplying ``f_known`` makes it a *modified* ESO (MESO); without it the observer is the
conventional ESO, which lumps the known part into the extended state.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .._validate import (
    check_array,
    check_finite,
    check_hurwitz,
    check_int,
    check_positive,
    finite_result,
)
from ..engine.blocks import ContinuousBlock, signal_names
from ..engine.kernels import KernelBlock, Kernels, Layout, as_int, jitable
from ..polynomials import MAX_POLE_ORDER, _coefficients

__all__ = ["fal", "ExtendedStateObserver"]


def fal(e, alpha, delta):
    """Han's nonlinear gain function ``fal(e, alpha, delta)``.

    ``fal(e) = e / delta**(1 - alpha)`` for ``|e| <= delta`` and ``|e|**alpha * sign(e)`` otherwise:
    linear near the origin (which avoids the infinite slope of ``|e|**alpha`` at 0), continuous at
    ``|e| = delta`` and odd.

    Parameters
    ----------
    e : array_like
        Error(s).
    alpha : float or array_like
        Exponent(s), broadcast against ``e``.
    delta : float
        Width of the linear zone (> 0).

    Returns
    -------
    ndarray or float
        Same shape as ``broadcast(e, alpha)``.

    Raises
    ------
    ValueError
        If ``delta <= 0`` or any input is not finite.

    References
    ----------
    Han J., "From PID to active disturbance rejection control", IEEE TIE 56(3), 2009.
    Chen Z., Gao Q., "Modified extended state observer: analysis and implementation", Control
    Theory & Applications 35(8), 2018, eq. (2)-(3) (nonlinear g_i).

    Examples
    --------
    >>> round(float(fal(0.5, 0.5, 0.1)), 12)  # |e| > delta: sqrt(0.5)
    0.707106781187
    """
    delta = check_positive("delta", delta, scalar=True)
    alpha = np.asarray(check_finite("alpha", alpha), dtype=float)
    delta_pow = finite_result("alpha and delta", lambda: np.power(delta, 1.0 - alpha))
    try:
        out = _fal_array(check_array("e", e), alpha, delta, delta_pow)
    except OverflowError:
        raise ValueError("e and alpha overflow double precision (|e|**alpha is not finite)") from None
    return float(out) if out.ndim == 0 else out


# not inline="always": inlined by numba into the compiled RK4 stage loop, its two returns made numba warn
# NumbaIRAssumptionWarning ("please report"); LLVM inlines the scalar call, as fast (Example 1, B = 1000)
@jitable
def _fal(e, alpha, delta, delta_pow):
    """fal of one value (no checks; ``delta_pow = delta**(1 - alpha)``): the kernel's and :func:`fal`'s one source."""
    ae = abs(e)
    if ae <= delta:
        return e / delta_pow  # linear zone
    sgn = 1.0 if e > 0 else (-1.0 if e < 0 else e)  # numpy's sign (NaN stays NaN)
    return ae ** alpha * sgn  # |e|^alpha sign(e)


#: :func:`_fal` element by element on arrays (broadcast), for :func:`fal` and :meth:`ExtendedStateObserver.correction`.
_fal_array = np.vectorize(_fal, otypes=[float])


#: The fixed head of an ESO's kernel parameters: the switch ``linear`` (1: ``g_i(e) = e``), ``b0`` and
#: ``delta``; the arrays ``L``, ``alpha``, ``delta_pow`` (``δ^(1-α_i)``) of ``m = n + 1`` entries follow
#: (:func:`eso_layout`; ones for the linear ESO).
HEAD = Layout("linear", "b0", "delta")
AT = HEAD.at
_ARRAYS = HEAD.size


def _from_gains(cls, names: str, compute, kw):
    """``cls(gains, **kw)`` with the gains that ``names`` give; an error names them where they do not fit."""
    gains = finite_result(names, compute)
    if np.any(gains <= 0):
        raise ValueError(f"{names} underflow double precision: the gains {gains.tolist()} are not all > 0")
    try:
        return cls(gains, **kw)
    except ValueError as exc:
        raise ValueError(f"{exc} (the gains come from {names})") from None


def eso_layout(m: int) -> Layout:
    """The kernel parameters of an ESO with ``m = n + 1`` states: :data:`HEAD`, then ``L``, ``alpha``, ``delta_pow``.

    Parameters
    ----------
    m : int
        Observer order ``n + 1``.

    Returns
    -------
    Layout
    """
    return Layout(*zip(HEAD.names, HEAD.shapes, strict=True), ("L", m), ("alpha", m), ("delta_pow", m))


@jitable(inline="always")  # also called inside other kernels (meso's ESO with a model term)
def eso_rhs(t, x, u, p, dx):
    """(Nonlinear) ESO: ``x̂_i' = L_i g_i(e) + x̂_(i+1)``, ``+ b0 u`` in row n, ``e = y - x̂_1``; the ESO block's kernel.

    ``g_i(e) = e`` (linear) or Han's ``fal(e, alpha_i, delta)``. fal branches on the error (its
    linear zone), so the batched methods of a fal ESO call it run by run (``Kernels(columns=False)``);
    the linear ESO's run on the batch's columns.

    Parameters
    ----------
    t, x, u, p
        Time (unused), the observer state ``x̂`` of one run (its length is ``m``), its inputs
        ``[y, u]`` and :func:`eso_layout` ``(m)``.
    dx : numpy.ndarray
        The derivative ``x̂'``, written in place.
    """
    m = x.shape[0]
    L, alpha, dp = _ARRAYS, _ARRAYS + m, _ARRAYS + 2 * m
    e = u[0] - x[0]
    if as_int(p[AT.linear]):
        for i in range(m):
            dx[i] = p[L + i] * e + 0.0  # linear ESO: g_i(e) = e
    else:
        for i in range(m):
            dx[i] = p[L + i] * _fal(e, p[alpha + i], p[AT.delta], p[dp + i]) + 0.0  # (3) g_i(e) = fal(e, α_i, δ)
    for i in range(m - 1):
        dx[i] = dx[i] + x[i + 1]  # chain of integrators
    dx[m - 2] = dx[m - 2] + p[AT.b0] * u[1]  # + b0 u in the n-th equation


#: The ESO's kernels: the linear ESO's run on the batch's columns, fal's branch on the error (run by run).
_LINEAR_KERNELS = Kernels(rhs=eso_rhs)
_FAL_KERNELS = Kernels(rhs=eso_rhs, columns=False)


class ExtendedStateObserver(KernelBlock, ContinuousBlock):
    """Continuous extended state observer of plant order ``n`` (linear, nonlinear or modified).

    The equations are the kernel :func:`eso_rhs`; a ``known`` term (MESO) is a Python callable, so
    an observer with one has no compiled kernel and runs on the numpy engine.

    Parameters
    ----------
    gains : sequence of float, length n + 1 >= 2
        Observer gains ``L_1 .. L_{n+1}`` (> 0).
    b0 : float
        Nominal input gain of the plant (``b0 u`` enters the n-th equation).
    alpha : sequence of float, length n + 1, optional
        Exponents of Han's ``fal``; ``None`` gives the linear ESO (``g_i(e) = e``).
    delta : float, optional
        Linear-zone width of ``fal`` (> 0); required when ``alpha`` is given.
    known : callable, optional
        ``known(t, x_hat, u, params) -> f_known`` of shape ``x_hat.shape[:-1]``; it receives the same
        ``x_hat`` and observer input ``u = [y, u_control]`` as :meth:`rhs`. Present: modified ESO
        (MESO, the known part of the plant is fed into the n-th equation). Absent: conventional ESO.
    allow_unstable : bool, keyword
        Gains whose error dynamics are not Hurwitz (``s^(n+1) + L_1 s^n + ... + L_{n+1}``; for the
        ``fal`` ESO the same with the linear-zone gains ``L_i δ^(α_i - 1)``) raise ``ValueError``
        unless this is ``True`` (to study an unstable design on purpose). Same opt-out as
        ``DifferentialEstimator(allow_unstable=...)``; ``AlphaBetaFilter(require_stable=False)``.

    Block signals: inputs ``y``, ``u``; states and outputs ``xhat[0] .. xhat[n]`` (``x̂_1 .. x̂_{n+1}``).

    Attributes
    ----------
    n : int
        Plant order.
    nstates : int
        Observer order ``n + 1``.
    L : ndarray, shape (n + 1,)
        Gains.
    b0 : float
    alpha, delta, known
        As given.

    Raises
    ------
    ValueError
        Gains not finite or not > 0, fewer than two gains, error dynamics not Hurwitz (unless
        ``allow_unstable``), ``alpha`` of the wrong length, or ``delta`` missing / not > 0 when
        ``alpha`` is given.

    Notes
    -----
    Error dynamics of the linear ESO (``e_i = x_i - x_hat_i``, known part cancelled exactly):
    ``e' = (A - L C) e + E_{n+1} h`` with ``h = dx_{n+1}/dt``; characteristic polynomial
    ``s^(n+1) + L_1 s^n + ... + L_{n+1}``. With ``L_i = beta_i / eps^i`` the steady error for a
    constant ``h`` is ``e_i = L_{i-1} / L_{n+1} h ∝ eps^(n+2-i)`` (``L_0 = 1``).

    References
    ----------
    Chen Z., Gao Q., "Modified extended state observer: analysis and implementation", Control
    Theory & Applications 35(8), 2018: eq. (3) MESO, (6) ESO, (29) linear gains ``beta_i / eps^i``,
    bound (4)/(7) for the error scaling.
    Gao Z., "Scaling and bandwidth-parameterization based controller tuning", ACC 2003 (bandwidth
    form ``(s + omega_o)^(n+1)``).

    Examples
    --------
    >>> import numpy as np
    >>> obs = ExtendedStateObserver.from_bandwidth(2, 10.0, b0=1.0)
    >>> np.allclose(obs.characteristic_polynomial(), [1, 30, 300, 1000])
    True
    """

    def __init__(self, gains, b0: float = 0.0, alpha=None, delta=None,
                 known: Callable | None = None, *, allow_unstable: bool = False):
        gains = np.atleast_1d(check_finite("gains", gains)).astype(float)
        if gains.ndim != 1 or gains.size < 2:
            raise ValueError(f"gains must be a 1-D sequence of n + 1 >= 2 entries, got shape {gains.shape}")
        if np.any(gains <= 0):
            raise ValueError(f"gains must all be > 0, got {gains.tolist()}")
        self.L = gains
        self.n = gains.size - 1
        self.nstates = self.n + 1
        self.b0 = float(check_finite("b0", b0, scalar=True))
        if alpha is not None:
            alpha = np.atleast_1d(check_finite("alpha", alpha)).astype(float)
            if alpha.shape != (self.nstates,):
                raise ValueError(f"alpha must have one entry per entry of gains (n + 1 = {self.nstates}), "
                                 f"got {alpha.size}")
            if delta is None:
                raise ValueError("delta must be given (> 0) when alpha is given, got None")
            delta = float(check_positive("delta", delta, scalar=True))
        elif delta is not None:
            delta = float(check_positive("delta", delta, scalar=True))
        if known is not None and not callable(known):
            raise TypeError(f"known must be callable known(t, x_hat, u, params), got {known!r}")
        if not isinstance(allow_unstable, (bool, np.bool_)):
            raise TypeError(f"allow_unstable must be True or False, got {allow_unstable!r}")
        self.alpha = alpha
        self.delta = delta
        self._delta_pow = None if alpha is None else finite_result(
            "alpha and delta", lambda: np.power(delta, 1.0 - alpha))
        self.known = known
        self.allow_unstable = bool(allow_unstable)
        if not allow_unstable:
            # linear-zone gains: fal(e) = e / δ^(1-α) for |e| <= δ
            small_signal = gains if alpha is None else gains / self._delta_pow
            check_hurwitz("gains" if alpha is None else "gains (with alpha and delta)",
                          np.concatenate([[1.0], small_signal]),
                          polynomial="the error dynamics s^(n+1) + L_1 s^n + ... + L_(n+1)"
                          + ("" if alpha is None else " (linear zone of fal)"))
        m, linear = self.nstates, alpha is None
        self.kernel_params = eso_layout(m).pack(
            linear=1.0 if linear else 0.0, b0=self.b0, delta=1.0 if delta is None else delta, L=gains,
            alpha=np.ones(m) if linear else alpha, delta_pow=np.ones(m) if linear else self._delta_pow)

    @property
    def kernels(self) -> Kernels:
        """:func:`eso_rhs`; run by run in the batched methods when fal branches on the error."""
        return _LINEAR_KERNELS if self.alpha is None else _FAL_KERNELS

    # ------------------------------------------------------------------------------------------
    # Constructors
    # ------------------------------------------------------------------------------------------

    @classmethod
    def from_epsilon(cls, n: int, epsilon: float, beta, **kw) -> ExtendedStateObserver:
        """High-gain form ``L_i = beta_i / epsilon**i`` (paper eq. (29) with ``g_i(e) = beta_i e``).

        Parameters
        ----------
        n : int
            Plant order (>= 1).
        epsilon : float
            High-gain parameter (> 0); the observer bandwidth scales as ``1 / epsilon``.
        beta : sequence of float, length n + 1
            Normalised gains (> 0).
        **kw
            Passed to the constructor (``b0``, ``alpha``, ``delta``, ``known``).

        Returns
        -------
        ExtendedStateObserver
        """
        n = check_int("n", n, minimum=1, maximum=MAX_POLE_ORDER - 1)
        epsilon = float(check_positive("epsilon", epsilon, scalar=True))
        beta = np.atleast_1d(check_positive("beta", beta)).astype(float)
        if beta.shape != (n + 1,):
            raise ValueError(f"beta must have n + 1 = {n + 1} entries, got {beta.size}")
        i = np.arange(1, n + 2)
        return _from_gains(cls, "beta and epsilon", lambda: beta / epsilon**i, kw)

    @classmethod
    def from_bandwidth(cls, n: int, omega_o: float, **kw) -> ExtendedStateObserver:
        """Bandwidth form: all poles at ``-omega_o``, ``L_i = C(n+1, i) omega_o**i``.

        Parameters
        ----------
        n : int
            Plant order (>= 1).
        omega_o : float
            Observer bandwidth in rad/s (> 0).
        **kw
            Passed to the constructor.

        Returns
        -------
        ExtendedStateObserver
        """
        n = check_int("n", n, minimum=1, maximum=MAX_POLE_ORDER - 1)
        omega_o = float(check_positive("omega_o", omega_o, scalar=True))
        # (s + omega_o)^(n+1) = sum_i C(n+1, i) omega_o^i s^(n+1-i)
        return _from_gains(cls, "n and omega_o", lambda: _coefficients(n + 1, omega_o)[1:], kw)

    # ------------------------------------------------------------------------------------------
    # Dynamics
    # ------------------------------------------------------------------------------------------

    @property
    def is_linear(self) -> bool:
        """True for ``g_i(e) = e`` (no ``alpha``)."""
        return self.alpha is None

    def correction(self, e) -> np.ndarray:
        """The output-injection terms ``L_i g_i(e)``.

        Parameters
        ----------
        e : array_like
            Output estimation error ``y - x̂_1``.

        Returns
        -------
        numpy.ndarray, shape ``e.shape + (n + 1,)``
        """
        e = np.asarray(e, dtype=float)[..., None]
        if self.alpha is None:
            return self.L * e
        return self.L * _fal_array(e, self.alpha, self.delta, self._delta_pow)

    def kernel(self):
        """The compiled engine's kernel (:func:`eso_rhs`), or ``None`` with a ``known`` term (numpy engine).

        Returns
        -------
        Kernels or None
        """
        return None if self.known is not None else KernelBlock.kernel(self)

    def rhs(self, t, x_hat, u, params=None) -> np.ndarray:
        """Observer right-hand side in python-control's order ``(t, x, u, params)``: the kernel :func:`eso_rhs`.

        With a ``known`` term (MESO) the kernel runs without ``b0 u``, and ``b0 u + f_known`` is then
        added to the n-th equation.

        Parameters
        ----------
        t : float
        x_hat : ndarray, shape (n + 1,) or (B, n + 1)
            Observer states on the last axis.
        u : ndarray, shape (..., 2)
            Observer inputs ``[y, u_control]``.
        params : dict, optional
            python-control's ``params``: passed to ``known`` when there is one, else constructor
            arguments changed by name for this call.

        Returns
        -------
        ndarray
            ``d x_hat / dt``, shape ``x_hat.shape``.
        """
        if self.known is None:
            return self.batched("rhs", t, x_hat, u, self._vector(params))
        P = self.kernel_params.copy()
        P[..., AT.b0] = 0.0
        dx = self.batched("rhs", t, x_hat, u, P)
        # (3) n-th equation: + f_known + b0 u  (MESO)
        dx[..., self.n - 1] += self.b0 * np.asarray(u, dtype=float)[..., 1] + np.asarray(
            self.known(t, x_hat, u, params), dtype=float)
        return dx

    inputs = ("y", "u")

    @property
    def states(self) -> tuple:
        return signal_names("xhat", self.nstates)

    @property
    def outputs(self) -> tuple:
        return self.states

    # ------------------------------------------------------------------------------------------
    # Linear analysis
    # ------------------------------------------------------------------------------------------

    def _require_linear(self, what: str) -> None:
        if self.alpha is not None:
            raise ValueError(f"{what} is defined for the linear ESO only (alpha must be None)")

    def _matrices(self):
        m = self.nstates
        A = np.diag(np.ones(m - 1), 1)
        A[:, 0] -= self.L
        B = np.zeros((m, 2))
        B[:, 0] = self.L
        B[self.n - 1, 1] = self.b0
        return A, B

    @property
    def ss(self):
        """Linear ESO as :class:`control.StateSpace`: inputs ``[y, u]``, outputs ``x_hat_1..x_hat_{n+1}``.

        The ``known`` term (MESO) is not part of this linear part; it enters the n-th state equation
        as an additional input with unit gain.
        """
        import control as ct

        self._require_linear("ss")
        A, B = self._matrices()
        m = self.nstates
        return ct.ss(A, B, np.eye(m), np.zeros((m, 2)),
                     inputs=list(self.inputs), outputs=list(self.outputs), states=list(self.states))

    def characteristic_polynomial(self) -> np.ndarray:
        """Coefficients ``[1, L_1, ..., L_{n+1}]`` of ``det(sI - (A - LC))`` (highest power first).

        Returns
        -------
        numpy.ndarray, shape (n + 2,)

        Raises
        ------
        ValueError
            For a nonlinear observer (``alpha`` given).
        """
        self._require_linear("characteristic_polynomial")
        return np.concatenate([[1.0], self.L])

    @property
    def poles(self) -> np.ndarray:
        """Observer poles (roots of the characteristic polynomial)."""
        return np.roots(self.characteristic_polynomial())

    def disturbance_error_tf(self, wrt: str = "derivative") -> list:
        """Transfer functions from the total disturbance to each estimation error ``e_i = x_i - x_hat_i``.

        Parameters
        ----------
        wrt : {"derivative", "state"}
            ``"derivative"``: input ``h = dx_{n+1}/dt`` (the derivative of the extended state),
            ``E_i(s)/H(s) = (s^(i-1) + L_1 s^(i-2) + ... + L_{i-1}) / p(s)``.
            ``"state"``: input ``x_{n+1}`` itself (the former times ``s``).

        Returns
        -------
        list of control.TransferFunction
            ``n + 1`` SISO transfer functions, ``e_1 .. e_{n+1}`` (outputs ``e[0] .. e[n]``).

        References
        ----------
        Chen & Gao 2018, error bound (4)/(7).
        """
        import control as ct

        self._require_linear("disturbance_error_tf")
        if wrt not in ("derivative", "state"):
            raise ValueError(f"wrt must be 'derivative' or 'state', got {wrt!r}")
        den = self.characteristic_polynomial()
        coeff = np.concatenate([[1.0], self.L])
        out = []
        for i in range(1, self.nstates + 1):
            num = coeff[:i].copy()  # s^(i-1) + L_1 s^(i-2) + ... + L_{i-1}
            if wrt == "state":
                num = np.concatenate([num, [0.0]])
            out.append(ct.tf(num, den, inputs="h" if wrt == "derivative" else "x_ext",
                             outputs=f"e[{i - 1}]"))
        return out

    def __repr__(self) -> str:
        kind = "MESO" if self.known is not None else "ESO"
        kind = ("nonlinear " if self.alpha is not None else "linear ") + kind
        return f"ExtendedStateObserver({kind}, n={self.n}, L={self.L.tolist()}, b0={self.b0})"
