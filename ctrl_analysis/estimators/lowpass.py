"""The low-pass / prefilter ``W(s) = ω^m / (s + ω)^m``: a continuous block and its exact digital form.

One block serves every use of this filter in the toolkit: smoothing a measured signal or identified
parameters (the digital form, exact for inputs held over each sample), and softening a setpoint
while giving its first ``m − 1`` derivatives (the states of the phase-variable realisation).
"""

from __future__ import annotations

import numpy as np

from .._validate import (
    check_array,
    check_int,
    check_positive,
    check_vector,
    finite_result,
)
from ..engine.blocks import MAX_SIGNALS, ContinuousBlock, DiscreteBlock, signal_names
from ..engine.kernels import KernelBlock, Kernels, Layout, as_int
from ..polynomials import _coefficients

__all__ = ["LowPassFilter", "DiscreteLowPass"]


#: The fixed head of a :class:`LowPassFilter`'s kernel parameters: the order ``m`` and the input gain
#: ``ω^m``; the coefficients ``c_0 .. c_(m-1)`` of ``(s + ω)^m`` follow (:func:`lowpass_layout`).
HEAD = Layout("m", "gain")
AT = HEAD.at
_COEFFS = HEAD.size


def lowpass_layout(m: int) -> Layout:
    """The kernel parameters of an order-``m`` :class:`LowPassFilter`: :data:`HEAD`, then ``coeffs`` (``m``).

    Parameters
    ----------
    m : int
        Filter order.

    Returns
    -------
    Layout
    """
    return Layout(*zip(HEAD.names, HEAD.shapes, strict=True), ("coeffs", m))


def lowpass_rhs(t, x, u, p, dx):
    """``dw/dt`` of :class:`LowPassFilter`'s phase-variable form: ``w_i' = w_(i+1)``, ``w_(m-1)' = ω^m u − Σ c_j w_j``.

    Scalar indexing only: one run in the compiled engine, the batch's columns in the batched methods.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        ``w, w', ..., w^(m-1)``.
    u : numpy.ndarray
        ``[u]``.
    p : numpy.ndarray
        :func:`lowpass_layout` ``(m)``.
    dx : numpy.ndarray
        The derivative, written in place.
    """
    m = as_int(p[AT.m])
    c = _COEFFS
    for i in range(m - 1):
        dx[i] = x[i + 1]  # w_i' = w_(i+1)
    top = p[AT.gain] * u[0]
    for j in range(m):
        top = top - p[c + j] * x[j]  # w_(m-1)' = ω^m u − Σ c_j w_j
    dx[m - 1] = top


class LowPassFilter(KernelBlock, ContinuousBlock):
    """Continuous low-pass ``W(s) = ω^m / (s + ω)^m`` of order ``m`` (unit DC gain, m-fold pole at ``-ω``).

    Phase-variable (controllable canonical) realisation with states ``w = [w_0, w_1, ..., w_(m-1)]``,
    the output and exactly its first ``m − 1`` derivatives::

        w_i' = w_(i+1),   i = 0..m-2
        w_(m-1)' = ω^m u − Σ_(j=0..m-1) C(m, j) ω^(m-j) w_j

    so a step in ``u`` gives a ``w_0`` without overshoot whose first ``m − 1`` derivatives are
    continuous (a setpoint prefilter for an ``m``-th order tracking controller).

    Parameters
    ----------
    omega : float
        Corner frequency of each pole in rad/s (> 0).
    order : int
        ``m >= 1``.

    Attributes
    ----------
    A, B, C : numpy.ndarray
        Companion matrices; ``C`` picks ``w_0``.
    tf : control.TransferFunction
        ``u -> w_0``.
    ss : control.StateSpace
        Input ``u``; states and outputs ``w[0..m-1]``.

    Block signals: input ``u``; states and outputs ``w[0] .. w[m-1]`` (``w[k]`` is the k-th derivative).

    Raises
    ------
    ValueError
        If ``order < 1`` or ``omega`` is not finite and ``> 0``.

    References
    ----------
    Ogata K., *Modern Control Engineering*, 5th ed., §9-2 (phase-variable form). Used by Chen & Gao
    (2018), §4, to smooth identified parameters (``m = 2``), by Gong & Wu (2010) as the digital
    low-pass baseline, and as the setpoint softener of Qi et al. (2004), §4 (which only asks for a
    "softened" square wave).

    Examples
    --------
    >>> import control as ct
    >>> import numpy as np
    >>> W = LowPassFilter(2.0, order=2)
    >>> np.allclose(W.tf.den[0][0], [1, 4.0, 4.0]), float(ct.dcgain(W.tf))
    (True, 1.0)
    """

    inputs = ("u",)
    kernels = Kernels(rhs=lowpass_rhs)

    def __init__(self, omega: float, order: int = 2):
        self.omega = float(check_positive("omega", omega, scalar=True))
        self.order = check_int("order", order, minimum=1, maximum=20)
        m = self.order
        # (s + ω)^m = s^m + C(m,1) ω s^(m-1) + ... + ω^m
        self.den = finite_result("omega and order", lambda: _coefficients(m, self.omega))
        self.gain = self.den[-1]  # ω^m
        #: last row of A: −[c_0, ..., c_(m-1)] with c_j the coefficient of s^j
        self.coeffs = self.den[:0:-1].copy()
        A = np.diag(np.ones(m - 1), 1)
        A[-1, :] = -self.coeffs
        self.A = A
        self.B = np.zeros((m, 1))
        self.B[-1, 0] = self.gain
        self.C = np.zeros((1, m))
        self.C[0, 0] = 1.0
        self.states = self.outputs = signal_names("w", m)
        self.kernel_params = lowpass_layout(m).pack(m=m, gain=self.gain, coeffs=self.coeffs)

    @property
    def tf(self):
        """``ω^m / (s + ω)^m`` (``u -> w[0]``)."""
        import control as ct

        return ct.tf([self.gain], self.den, inputs="u", outputs="w[0]")

    def derivative_tf(self, k: int):
        """``s^k ω^m / (s + ω)^m``: ``u -> w[k]``, ``0 <= k <= m`` (a state for ``k < m``).

        Parameters
        ----------
        k : int
            Derivative order, ``0 <= k <= m``.

        Returns
        -------
        control.TransferFunction
        """
        import control as ct

        k = check_int("k", k, minimum=0, maximum=self.order)
        num = np.zeros(k + 1)
        num[0] = self.gain
        return ct.tf(num, self.den, inputs="u", outputs=f"w[{k}]")

    @property
    def ss(self):
        """Phase-variable state space: input ``u``; states and outputs ``w[0..m-1]``."""
        import control as ct

        names = list(self.states)
        return ct.ss(self.A, self.B, np.eye(self.order), np.zeros((self.order, 1)), inputs="u", states=names,
                     outputs=names)

    def discretize(self, h: float):
        """Exact zero-order-hold discretisation ``x(k+1) = Ad x(k) + Bd u(k)`` for sample period ``h``.

        Parameters
        ----------
        h : float
            Sample period (> 0).

        Returns
        -------
        Ad : numpy.ndarray, shape (m, m)
        Bd : numpy.ndarray, shape (m,)
        """
        import control as ct

        h = float(check_positive("h", h, scalar=True))
        sysd = ct.c2d(ct.ss(self.A, self.B, np.eye(self.order), 0), h, method="zoh")
        return (finite_result("h (with omega)", lambda: np.asarray(sysd.A)),
                finite_result("h (with omega)", lambda: np.asarray(sysd.B)[:, 0]))

    def digital(self, h: float, channels: int = 1, initial=None) -> DiscreteLowPass:
        """A :class:`DiscreteLowPass` with sample period ``h`` filtering ``channels`` signals.

        Parameters
        ----------
        h : float
            Sample period (> 0).
        channels : int
            Number of filtered signals (>= 1).
        initial : float or array_like, shape (channels,), optional
            Initial output (default 0).

        Returns
        -------
        DiscreteLowPass
        """
        return DiscreteLowPass(self, h, channels=channels, initial=initial)

    def __repr__(self) -> str:
        return f"LowPassFilter(omega={self.omega}, order={self.order})"


#: The fixed head of a :class:`DiscreteLowPass`'s kernel parameters: the order ``m``; ``Ad`` (row-major)
#: and ``Bd`` follow (:func:`digital_layout`).
DIGITAL_HEAD = Layout("m")
DIGITAL_AT = DIGITAL_HEAD.at
_DIGITAL_ARRAYS = DIGITAL_HEAD.size


def digital_layout(m: int) -> Layout:
    """The kernel parameters of an order-``m`` :class:`DiscreteLowPass`: :data:`DIGITAL_HEAD`, then ``Ad``, ``Bd``.

    Parameters
    ----------
    m : int
        Filter order.

    Returns
    -------
    Layout
    """
    return Layout(*zip(DIGITAL_HEAD.names, DIGITAL_HEAD.shapes, strict=True), ("Ad", (m, m)), ("Bd", m))


def lowpass_update(t, x, u, p, x_next):
    """Discrete W(s), every channel: ``x(k+1) = Ad x(k) + Bd u(k)`` (exact ZOH), the update of :class:`DiscreteLowPass`.

    Written with scalar indexing only, so it is both the compiled kernel of one run (``x`` of shape
    ``(channels·m,)``) and, on a batch's columns, the block's batched method.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        Filter states, channel-major: ``x[c·m + j]``.
    u : numpy.ndarray
        One input per channel.
    p : numpy.ndarray
        :func:`digital_layout` ``(m)``: ``m, Ad (m·m, row-major), Bd (m)``.
    x_next : numpy.ndarray
        Next states, written in place.
    """
    m = as_int(p[DIGITAL_AT.m])
    Ad, Bd = _DIGITAL_ARRAYS, _DIGITAL_ARRAYS + m * m
    for c in range(u.shape[0]):
        for i in range(m):
            acc = p[Bd + i] * u[c]
            for j in range(m):
                acc = acc + p[Ad + i * m + j] * x[c * m + j]
            x_next[c * m + i] = acc


def lowpass_output(t, x, u, p, y):
    """The filtered value after this sample: the first row of :func:`lowpass_update` (direct feedthrough).

    Parameters
    ----------
    t, x, u, p
        As :func:`lowpass_update`.
    y : numpy.ndarray
        One output per channel, written in place.
    """
    m = as_int(p[DIGITAL_AT.m])
    Ad, Bd = _DIGITAL_ARRAYS, _DIGITAL_ARRAYS + m * m
    for c in range(u.shape[0]):
        acc = p[Bd] * u[c]
        for j in range(m):
            acc = acc + p[Ad + j] * x[c * m + j]
        y[c] = acc


class DiscreteLowPass(KernelBlock, DiscreteBlock):
    """Digital form of a :class:`LowPassFilter` (exact for inputs held over each sample), a discrete block.

    Filters ``channels`` signals independently (e.g. a ``p``-parameter vector). The block's state
    holds, channel after channel, the ``m`` filter states ``[w, w', ...]``; its output is the
    filtered value of each channel *after* the update with the current input, ``w(k+1)``, so that
    a loop reading it sees the newest filtered sample (direct feedthrough).

    Parameters
    ----------
    lowpass : LowPassFilter
    h : float
        Sample period (> 0).
    channels : int
        Number of filtered signals (>= 1).
    initial : float or array_like, shape (channels,), optional
        Initial output (the filter starts at rest at this value; default 0).

    Attributes
    ----------
    Ad, Bd : numpy.ndarray
        Discretised matrices, shapes ``(m, m)`` and ``(m,)``.

    Block signals: inputs ``u[0..channels-1]``; outputs ``w[0..channels-1]``.

    Examples
    --------
    >>> import numpy as np
    >>> f = LowPassFilter(5.0, order=2).digital(0.01)
    >>> y, _ = f.run(np.ones(400))          # 4 s of a unit step
    >>> round(float(y[-1, 0, 0]), 6)
    1.0
    """

    feedthrough = True
    kernels = Kernels(output=lowpass_output, update=lowpass_update)

    def __init__(self, lowpass: LowPassFilter, h: float, channels: int = 1, initial=None):
        if not isinstance(lowpass, LowPassFilter):
            raise TypeError(f"lowpass must be a LowPassFilter, got {type(lowpass).__name__}")
        self.lowpass = lowpass
        self.h = float(check_positive("h", h, scalar=True))
        self.channels = check_int("channels", channels, minimum=1, maximum=MAX_SIGNALS)
        self.Ad, self.Bd = lowpass.discretize(self.h)
        m = lowpass.order
        init = np.zeros(self.channels) if initial is None else check_vector("initial", initial, self.channels)
        self._x0 = np.zeros((self.channels, m))
        self._x0[:, 0] = init
        self.inputs = signal_names("u", self.channels)
        self.outputs = signal_names("w", self.channels)
        self.states = tuple(f"w[{c}][{j}]" for c in range(self.channels) for j in range(m))
        self.kernel_params = digital_layout(m).pack(m=m, Ad=self.Ad, Bd=self.Bd)

    def initial_state(self) -> np.ndarray:
        return self._x0.reshape(-1).copy()

    def filter(self, u) -> np.ndarray:
        """Filter a whole record ``u`` of shape ``(N,)``, ``(N, channels)`` or ``(N, B, channels)``.

        Parameters
        ----------
        u : array_like, shape (N,), (N, channels) or (N, B, channels)
            Input record, one row per sample.

        Returns
        -------
        numpy.ndarray
            The filtered values after each sample, with the shape of ``u``.
        """
        u = np.asarray(check_array("u", u), dtype=float)
        shape = u.shape
        if u.ndim == 1 and self.channels == 1:
            u = u[:, None]
        y, _ = self.run(u)
        return y.reshape(shape)

    def __repr__(self) -> str:
        return f"DiscreteLowPass({self.lowpass!r}, h={self.h}, channels={self.channels})"
