"""PD control with reference feed-forward and disturbance/model compensation (the ADRC control law).

For a plant ``x^(n) = F + b0 u`` whose states ``x_1..x_n`` and total disturbance ``x_{n+1}`` are
estimated by an extended state observer, the law

    u = ( Σ_{i=1}^{n+1} k_i (ξ^(i-1) - x̂_i) - f̂ ) / b0,      k_{n+1} = 1,

cancels the estimated disturbance (``k_{n+1} = 1`` on ``x̂_{n+1}`` with ``ξ^(n)`` as feed-forward),
subtracts any known model part ``f̂`` (modified ESO), and leaves the tracking error dynamics
``e^(n) + k_n e^(n-1) + ... + k_1 e = 0``. Bandwidth tuning places all ``n`` roots at ``-ω_c``.

:class:`PDFeedforward` is a discrete block (the law is evaluated at the sample instants and held):
with ``model=True`` the known part is an identified linear model ``f̂ = XᵀΘ``,
``X = [x̂_1 .. x̂_n, u, 1]``, evaluated with the previous sample's ``x̂`` and ``u`` (the block's state)
because ``X`` contains the control being computed.
"""

from __future__ import annotations

import numpy as np

from .._validate import (
    check_array,
    check_finite,
    check_hurwitz,
    check_int,
    check_positive,
    finite_result,
)
from ..engine.blocks import DiscreteBlock, signal_names
from ..engine.kernels import KernelBlock, Kernels, Layout
from ..polynomials import MAX_POLE_ORDER, _coefficients

__all__ = ["PDFeedforward", "bandwidth_gains"]


def pd_layout(n: int) -> Layout:
    """The parameters of :class:`PDFeedforward` of order ``n``: ``b0``, then the gains ``k_1 .. k_{n+1}``."""
    return Layout("b0", ("k", n + 1))


AT = pd_layout(1).at  # offsets (the same for every n: the gains come last), a numba constant


def bandwidth_gains(n: int, omega_c: float) -> np.ndarray:
    """Gains ``k_1..k_{n+1}`` placing the tracking-error poles at ``-omega_c`` (``k_{n+1} = 1``).

    ``s^n + k_n s^(n-1) + ... + k_1 = (s + ω_c)^n`` so ``k_i = C(n, i-1) ω_c^(n-i+1)``; for ``n = 2``:
    ``k_1 = ω_c², k_2 = 2 ω_c, k_3 = 1``.

    Parameters
    ----------
    n : int
        Order of the tracked chain (>= 1).
    omega_c : float
        Controller bandwidth ω_c (> 0).

    Returns
    -------
    numpy.ndarray, shape (n + 1,)
        ``[k_1, ..., k_n, k_{n+1} = 1]``.

    References
    ----------
    Gao Z., "Scaling and bandwidth-parameterization based controller tuning", ACC 2003.
    """
    n = check_int("n", n, minimum=1, maximum=MAX_POLE_ORDER)
    omega_c = float(check_positive("omega_c", omega_c, scalar=True))
    # k_i = C(n, i-1) ω_c^(n-i+1): the coefficients of (s + ω_c)^n, lowest power first
    return finite_result("n and omega_c", lambda: _coefficients(n, omega_c))[::-1].copy()


def pd_step(t, x, u, p, out):
    """The law (30)/(12) of one sample, written into the last entry of ``out`` (output or next state).

    ``u = (Σ_{i=1}^{n+1} k_i (ξ^(i-1) − x̂_i) − f̂) / b0`` with, when ``model``, ``f̂ = Σ_l θ_l
    x̂_l(k−1) + θ_{n+1} u(k−1) + θ_{n+2}`` from the state ``x = [x̂_1(k−1) .. x̂_n(k−1), u(k−1)]``.
    Called with the block's output (one entry) it writes ``u``; with the next state (``n + 1``
    entries, ``model`` only) it also stores this sample's ``x̂_1..x̂_n`` before ``u``; with an empty
    next state (no model) it writes nothing. The order ``n`` and ``model`` are read from the shapes
    (``model``: the block has a state, ``n + 1`` entries; without it the inputs are ``2 n + 2``), so
    the kernel has no branch on a value and also runs on a batch's columns.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        The block's state (empty without ``model``).
    u : numpy.ndarray
        Inputs ``[ξ .. ξ^(n), x̂_1 .. x̂_{n+1}, θ_1 .. θ_{n+2} (model)]``.
    p : numpy.ndarray
        Packed by :func:`pd_layout`: ``b0``, ``k_1 .. k_{n+1}``.
    out : numpy.ndarray
        The output (1 entry) or the next state (``n + 1`` or 0 entries), written in place.
    """
    last = out.shape[0] - 1
    if last < 0:
        return
    model = x.shape[0] > 0
    n = x.shape[0] - 1 if model else u.shape[0] // 2 - 1
    # Σ_{i=1}^{n+1} k_i (ξ^(i-1) - x̂_i), summed left to right
    acc = p[AT.k] * (u[0] - u[n + 1])
    for i in range(1, n + 1):
        acc = acc + p[AT.k + i] * (u[i] - u[n + 1 + i])
    if model:
        th = 2 * n + 2  # first column of Θ in u
        # (12) XᵀΘ with the previous sample: Σ_l θ_l x̂_l(k-1) + θ_{n+1} u(k-1) + θ_{n+2}
        f = u[th] * x[0]
        for i in range(1, n + 1):
            f = f + u[th + i] * x[i]
        f = f + u[th + n + 1]
        acc = acc - f
    for i in range(last):
        # the next state holds this sample's x̂_1..x̂_n for the next sample's model term (12)
        out[i] = u[n + 1 + i]
    # (30) u = (Σ k_i (ξ^(i-1) - x̂_i) - XᵀΘ) / b0
    out[last] = acc / p[AT.b0]


class PDFeedforward(KernelBlock, DiscreteBlock):
    """PD (state-feedback) law with feed-forward and model compensation: a discrete block, batched.

    ``u(k) = ( Σ_{i=1}^{n+1} k_i (ξ^(i-1)(t_k) − x̂_i(k)) − f̂(k) ) / b0``, held over the sample.

    Parameters
    ----------
    b0 : float
        Nominal input gain (non-zero).
    omega_c : float, optional
        Controller bandwidth (rad/s); gives ``k`` by :func:`bandwidth_gains`.
    gains : sequence of float, optional
        ``k_1..k_n`` (or ``k_1..k_{n+1}`` with ``k_{n+1}`` given explicitly) instead of ``omega_c``;
        ``s^n + k_n s^(n-1) + ... + k_1`` must be Hurwitz.
    order : int
        Plant order ``n`` (default 2); used with ``omega_c``.
    model : bool
        ``False`` (default): ``f̂ = 0`` (conventional ESO). ``True``: ``f̂ = Θᵀ [x̂_1(k-1) .. x̂_n(k-1),
        u(k-1), 1]`` with ``Θ`` (``n + 2`` parameters) an input, the previous sample's estimates and
        control held in the block's state (eq. (12); zero before the first sample).

    Block signals: inputs ``r[0] .. r[n]`` (``ξ, ξ', .., ξ^(n)``), ``xhat[0] .. xhat[n]`` and, with
    ``model``, ``theta[0] .. theta[n+1]``; output ``u``; states (``model`` only)
    ``xhat_prev[0] .. xhat_prev[n-1]``, ``u_prev``. Direct feedthrough.

    Attributes
    ----------
    k : ndarray, shape (n + 1,)
        ``k_1..k_{n+1}``.
    n : int
    b0 : float
    model : bool

    Raises
    ------
    ValueError
        ``b0 = 0``, both or neither of ``omega_c`` / ``gains``, a non-Hurwitz gain vector.

    References
    ----------
    Chen Z., Gao Q., "Modified extended state observer: analysis and implementation", Control
    Theory & Applications 35(8), 2018, eq. (12) (model term with the previous sample) and (30).
    Zheng Q., Gao L. Q., Gao Z., "On stability analysis of active disturbance rejection control for
    nonlinear time-varying plants with unknown dynamics", CDC 2007.

    Examples
    --------
    >>> import numpy as np
    >>> pd = PDFeedforward(b0=2.0, omega_c=10.0)
    >>> pd.k.tolist()
    [100.0, 20.0, 1.0]
    >>> float(pd.control([1.0, 0.0, 0.0], [0.0, 0.0, 0.0]))
    50.0
    >>> pd.output(0.0, np.zeros((1, 0)), np.array([[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]]))
    array([[50.]])
    """

    feedthrough = True
    kernels = Kernels(output=pd_step, update=pd_step)

    def __init__(self, b0: float, omega_c: float | None = None, gains=None, order: int = 2,
                 model: bool = False):
        b0 = float(check_finite("b0", b0, scalar=True))
        if b0 == 0:
            raise ValueError("b0 must be non-zero, got 0")
        self.b0 = b0
        order = check_int("order", order, minimum=1, maximum=MAX_POLE_ORDER)
        if (omega_c is None) == (gains is None):
            raise ValueError(f"give exactly one of omega_c or gains, got omega_c={omega_c!r}, gains={gains!r}")
        if omega_c is not None:
            self.k = bandwidth_gains(order, omega_c)
            self.omega_c = float(omega_c)
        else:
            g = np.atleast_1d(check_finite("gains", gains)).astype(float)
            if g.ndim != 1 or g.size < 1:
                raise ValueError(f"gains must be a 1-D sequence, got shape {g.shape}")
            if g.size == order + 1 and g[-1] != 1.0:
                raise ValueError(f"gains: k_(n+1) must be 1 (it cancels the extended state), got {g[-1]!r}")
            if g.size == order:
                g = np.concatenate([g, [1.0]])
            elif g.size != order + 1:
                raise ValueError(f"gains must have n = order = {order} or n + 1 = {order + 1} entries, got {g.size}")
            check_hurwitz("gains", np.concatenate([[1.0], g[order - 1::-1]]),
                          polynomial="s^n + k_n s^(n-1) + ... + k_1")
            self.k = g
            self.omega_c = None
        self.n = self.k.size - 1
        if not isinstance(model, (bool, np.bool_)):
            raise TypeError(f"model must be True or False, got {model!r}")
        self.model = bool(model)
        n = self.n
        self.inputs = (signal_names("r", n + 1) + signal_names("xhat", n + 1)
                       + (signal_names("theta", n + 2) if self.model else ()))
        self.outputs = ("u",)
        self.states = signal_names("xhat_prev", n) + ("u_prev",) if self.model else ()
        self.kernel_params = pd_layout(n).pack(b0=self.b0, k=self.k)

    def tracking_poly(self) -> np.ndarray:
        """Coefficients of the tracking-error polynomial ``s^n + k_n s^(n-1) + ... + k_1``.

        Returns
        -------
        numpy.ndarray, shape (n + 1,)
            Highest power first (``numpy.roots`` order).
        """
        return np.concatenate([[1.0], self.k[self.n - 1::-1]])

    @property
    def tracking_tf(self):
        """Ideal closed loop ``ξ -> x_1`` with perfect estimation: ``k_1 / (s^n + ... + k_1)``."""
        import control as ct

        return ct.tf([self.k[0]], self.tracking_poly())

    def control(self, ref, x_hat, f_hat=0.0) -> np.ndarray:
        """The control ``u`` for reference derivatives ``ref`` and estimates ``x_hat`` (no state).

        Parameters
        ----------
        ref : array_like, shape (..., n + 1)
            ``[ξ, ξ', ..., ξ^(n)]``.
        x_hat : array_like, shape (..., n + 1)
            ``[x̂_1, ..., x̂_{n+1}]`` (``x̂_{n+1}`` the extended state).
        f_hat : array_like, shape (...,)
            Known / identified model part to cancel (0 for the conventional ESO).

        Returns
        -------
        ndarray, shape (...,)

        Raises
        ------
        ValueError
            ``ref`` or ``x_hat`` without ``n + 1`` entries on the last axis, or shapes that do not
            broadcast. NaN passes through (the control of a diverged run is NaN, in that run only).
        TypeError
            A string or ``None`` for ``ref``, ``x_hat`` or ``f_hat``.
        """
        ref = check_array("ref", ref)
        x_hat = check_array("x_hat", x_hat)
        f_hat = check_array("f_hat", f_hat)
        m = self.n + 1
        for name, arr in (("ref", ref), ("x_hat", x_hat)):
            if arr.ndim < 1 or arr.shape[-1] != m:
                raise ValueError(f"{name} must have n + 1 = {m} entries on its last axis, got shape {arr.shape}")
        try:
            np.broadcast_shapes(ref.shape[:-1], x_hat.shape[:-1], np.shape(f_hat))
        except ValueError:
            raise ValueError(f"ref, x_hat and f_hat must broadcast over the batch, got shapes {ref.shape}, "
                             f"{x_hat.shape} and {np.shape(f_hat)}") from None
        # (30) u = (Σ k_i (ξ^(i-1) - x̂_i) - XᵀΘ) / b0
        return (np.sum(self.k * (ref - x_hat), axis=-1) - f_hat) / self.b0

    def __repr__(self) -> str:
        return f"PDFeedforward(b0={self.b0}, k={self.k.tolist()}, model={self.model})"
