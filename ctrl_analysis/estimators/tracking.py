"""Setpoint softening and derivative extraction: Han's ``fhan``, the tracking differentiator, and a prefilter.

Three blocks that turn a raw (possibly discontinuous) reference ``r`` into a smooth signal ``v``
together with its derivatives ``v, v', v'', ...``:

* :func:`fhan` — Han's time-optimal synthesis function of the discrete double integrator;
* :class:`TrackingDifferentiator` — Han's discrete tracking differentiator (TD) built on it,
  giving ``(v, v')`` and, through the last ``fhan`` value, ``v''``;
* the linear prefilter ``ω^m / (s + ω)^m`` is :class:`~ctrl_analysis.estimators.lowpass.LowPassFilter`,
  whose phase-variable states are exactly ``(v, v', ..., v^(m-1))``.

:func:`softened_setpoint` runs either softener over a sampled reference and returns the
derivative vector ``θ`` at every sample, ready for a differential-feedback controller.
"""

from __future__ import annotations

import control as ct
import numpy as np

from .._validate import check_array, check_finite, check_in, check_int, check_positive, finite_result
from ..engine.blocks import DiscreteBlock, StaticBlock
from ..engine.integrators import MAX_SUBSTEPS, STEPPERS
from ..engine.kernels import KernelBlock, Kernels, Layout, as_int, jitable
from .lowpass import LowPassFilter

__all__ = [
    "fhan",
    "TrackingDifferentiator",
    "softened_setpoint",
]


def fhan(x1, x2, r, h0):
    """Han's discrete time-optimal control synthesis function ``fhan(x1, x2, r, h0)``.

    The feedback that brings the discrete double integrator ``x1 <- x1 + h x2``,
    ``x2 <- x2 + h u``, ``|u| <= r`` to the origin as fast as possible (bang-bang far from the
    origin, linear in a boundary layer of width ``d = r h0²``)::

        d  = r h0²;  a0 = h0 x2;  y = x1 + a0
        a1 = sqrt(d (d + 8|y|));  a2 = a0 + sign(y) (a1 - d) / 2
        sy = (sign(y + d) - sign(y - d)) / 2
        a  = (a0 + y - a2) sy + a2
        sa = (sign(a + d) - sign(a - d)) / 2
        fhan = -r (a/d - sign(a)) sa - r sign(a)

    Parameters
    ----------
    x1, x2 : array_like
        Position and velocity errors; broadcast against each other.
    r : float
        Acceleration bound ("speed factor"), ``> 0``.
    h0 : float
        Filtering step, ``> 0`` (``h0 >= h`` filters more).

    Returns
    -------
    numpy.ndarray or float
        ``fhan`` with the broadcast shape of ``x1`` and ``x2`` (a float for scalar inputs);
        always within ``[-r, r]`` and odd: ``fhan(-x1, -x2) = -fhan(x1, x2)``.

    Raises
    ------
    ValueError
        If ``r`` or ``h0`` is not finite and ``> 0``.

    References
    ----------
    Han J., "From PID to active disturbance rejection control", IEEE Trans. Ind. Electron.
    56(3), 900-906, 2009, eq. (12) (the form coded here).

    Examples
    --------
    >>> fhan(1.0, 0.0, 1.0, 0.1)    # far from the origin: full braking
    -1.0
    >>> round(fhan(0.001, 0.0, 1.0, 0.1), 12)  # inside the linear layer
    -0.1
    """
    r = float(check_positive("r", r, scalar=True))
    h0 = float(check_positive("h0", h0, scalar=True))
    if not 1e-150 < r * h0 * h0 < 1e150:  # d = r·h0² and d² must stay inside double precision
        raise ValueError(f"r and h0 overflow double precision: r·h0² = {r * h0 * h0:g} must lie in (1e-150, 1e150)")
    out = _fhan(check_array("x1", x1), check_array("x2", x2), r, h0)
    return float(out) if out.ndim == 0 else out


@jitable
def _fhan(x1, x2, r, h0):
    """Unchecked kernel of :func:`fhan` (arrays or, in a compiled kernel, floats; ``r``, ``h0`` validated)."""
    d = r * h0 * h0
    a0 = h0 * x2
    y = x1 + a0
    a1 = np.sqrt(d * (d + 8.0 * np.abs(y)))
    a2 = a0 + np.sign(y) * (a1 - d) * 0.5
    sy = (np.sign(y + d) - np.sign(y - d)) * 0.5
    a = (a0 + y - a2) * sy + a2
    sa = (np.sign(a + d) - np.sign(a - d)) * 0.5
    sign_a = np.sign(a)
    return -r * (a / d - sign_a) * sa - r * sign_a


@jitable
def _td_steps(x1, x2, v, r, h, h0, n):
    """``n`` TD steps of length ``h`` with ``v`` held: returns ``(x1, x2, fh)``, ``fh`` of the last step."""
    fh = x1 * 0.0
    for _ in range(n):
        fh = _fhan(x1 - v, x2, r, h0)
        # (37) x1(k+1) = x1(k) + h x2(k),  x2(k+1) = x2(k) + h fh
        x1, x2 = x1 + h * x2, x2 + h * fh
    return x1, x2, fh


#: Kernel parameters of :class:`TrackingDifferentiator` and :class:`TDStep`: ``r``, ``h``, ``h0``, the
#: number of substeps and the feedthrough switch (0/1).
LAYOUT = Layout("r", "h", "h0", "substeps", "feedthrough")
AT = LAYOUT.at


@jitable
def td_update(t, x, u, p, x_next):
    """Kernel update of :class:`TrackingDifferentiator`: ``substeps`` TD steps with ``v`` held.

    Scalar indexing only: one run's vectors in the compiled engine, the batch's columns in the
    block's batched methods.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        State ``(x1, x2)``.
    u : numpy.ndarray
        Input ``(v,)``.
    p : numpy.ndarray
        :data:`LAYOUT`: ``r``, ``h``, ``h0``, ``substeps``, ``feedthrough``.
    x_next : numpy.ndarray
        Next state, written in place.
    """
    x1, x2, _fh = _td_steps(x[0], x[1], u[0], p[AT.r], p[AT.h], p[AT.h0], as_int(p[AT.substeps]))
    x_next[0] = x1
    x_next[1] = x2


def td_step_output(t, x, u, p, y):
    """Kernel output of :class:`TDStep`: ``y = (x1, x2)`` after the steps, ``u = (v, x1, x2)``.

    Parameters
    ----------
    t, x : float, numpy.ndarray
        Time and (empty) state, unused.
    u : numpy.ndarray
        ``(v, x1, x2)``: the tracked signal and the TD state before the sample's steps.
    p : numpy.ndarray
        As :func:`td_update`.
    y : numpy.ndarray
        ``(x1, x2)`` after the steps, written in place.
    """
    x1, x2, _fh = _td_steps(u[1], u[2], u[0], p[AT.r], p[AT.h], p[AT.h0], as_int(p[AT.substeps]))
    y[0] = x1
    y[1] = x2


def td_output(t, x, u, p, y):
    """Kernel output of :class:`TrackingDifferentiator`: the state, or with feedthrough the state after the steps.

    Parameters
    ----------
    t, x, u, p
        As :func:`td_update`.
    y : numpy.ndarray
        Outputs ``(x1, x2)``, written in place.
    """
    if as_int(p[AT.feedthrough]):
        td_update(t, x, u, p, y)
    else:
        y[0] = x[0]
        y[1] = x[1]


class TrackingDifferentiator(KernelBlock, DiscreteBlock):
    """Han's discrete tracking differentiator as a discrete block: ``x1`` tracks ``v``, ``x2`` its derivative.

    One sample runs ``substeps`` steps of the discrete TD with integration step ``h``, the input
    ``v`` held::

        fh = fhan(x1 - v, x2, r, h0)
        x1 <- x1 + h x2
        x2 <- x2 + h fh

    so one sample spans ``dt = substeps * h`` of the TD's own time. ``fh`` of the last sub-step
    (:meth:`acceleration`) is the acceleration of ``x1``: an estimate of ``v''``.

    Block signals: input ``v``; states and outputs ``x[0]``, ``x[1]`` (``x1``, ``x2``). Without feedthrough (default)
    the output at sample ``k`` is the state reached with the inputs up to ``k - 1``; with
    ``feedthrough=True`` it is the state after this sample's steps, driven by ``v(k)`` too.

    Parameters
    ----------
    r : float
        Speed factor (acceleration bound), ``> 0``: larger tracks faster.
    h : float
        Integration step of the TD, ``> 0``.
    h0 : float, optional
        Filtering factor of :func:`fhan`, ``> 0``; default ``h`` (Han's choice without extra
        filtering).
    substeps : int
        TD steps (each of length ``h``) per sample, from 1 to :data:`~ctrl_analysis.engine.integrators.MAX_SUBSTEPS`.
    x0 : array_like, shape (2,), optional
        Initial ``(x1, x2)`` (default zero).
    feedthrough : bool
        Output the state after the sample's steps (``True``) or before them (``False``).

    Attributes
    ----------
    dt : float
        TD time covered by one sample, ``substeps * h``.

    Raises
    ------
    ValueError
        If ``r``, ``h`` or ``h0`` is not finite and ``> 0``, or ``substeps`` is outside ``[1, MAX_SUBSTEPS]``.
    TypeError
        If ``feedthrough`` is not a bool.

    References
    ----------
    Han J., "From PID to active disturbance rejection control", IEEE Trans. Ind. Electron.
    56(3), 2009, eq. (11)-(12); Lu & Hou (2022), eq. (37) (one TD step per sample as printed;
    how many steps run per control sample is a parameter here).

    Examples
    --------
    >>> import numpy as np
    >>> td = TrackingDifferentiator(r=50.0, h=0.01)
    >>> y, x = td.run(np.ones(300))
    >>> round(float(x[-1, 0, 0]), 6), abs(round(float(x[-1, 0, 1]), 6))  # abs: a rounded 0 may carry a sign
    (1.0, 0.0)
    """

    inputs = ("v",)
    states = ("x[0]", "x[1]")
    outputs = ("x[0]", "x[1]")
    feedthrough = False
    kernels = Kernels(output=td_output, update=td_update)

    def __init__(self, r: float, h: float, h0: float | None = None, substeps: int = 1, x0=None,
                 feedthrough: bool = False):
        if not isinstance(feedthrough, (bool, np.bool_)):
            raise TypeError(f"feedthrough must be a bool, got {type(feedthrough).__name__}")
        self.feedthrough = bool(feedthrough)
        self.r = float(check_positive("r", r, scalar=True))
        self.h = float(check_positive("h", h, scalar=True))
        self.h0 = self.h if h0 is None else float(check_positive("h0", h0, scalar=True))
        self.substeps = check_int("substeps", substeps, minimum=1, maximum=MAX_SUBSTEPS)
        self.dt = self.h * self.substeps
        self.x0 = np.zeros(2) if x0 is None else check_finite("x0", np.ravel(x0), shape=(2,))
        self.kernel_params = LAYOUT.pack(r=self.r, h=self.h, h0=self.h0, substeps=self.substeps,
                                         feedthrough=float(self.feedthrough))

    def initial_state(self) -> np.ndarray:
        return self.x0.copy()

    def step_block(self):
        """The sample's steps as a static block (inputs ``v``, ``x[0]``, ``x[1]``; outputs ``x[0]``, ``x[1]`` after).

        With two :class:`~ctrl_analysis.engine.blocks.UnitDelay` blocks holding its outputs it is
        this TD with feedthrough, computing the steps once per sample where the block's output and
        update compute them twice (same numbers).

        Returns
        -------
        TDStep
        """
        return TDStep(self)

    def acceleration(self, x, u) -> np.ndarray:
        """The acceleration ``fh`` applied in the last sub-step of a sample.

        Parameters
        ----------
        x : numpy.ndarray, shape (B, 2)
            TD states ``(x1, x2)`` at the start of the sample.
        u : numpy.ndarray, shape (B, 1)
            The tracked signal ``v``, held over the sample.

        Returns
        -------
        numpy.ndarray, shape (B,)
            ``fhan`` of the last sub-step.
        """
        return _td_steps(x[:, 0], x[:, 1], u[:, 0], self.r, self.h, self.h0, self.substeps)[2]

    def __repr__(self) -> str:
        return (f"TrackingDifferentiator(r={self.r}, h={self.h}, h0={self.h0}, "
                f"substeps={self.substeps})")


class TDStep(KernelBlock, StaticBlock):
    """The steps of one sample of a :class:`TrackingDifferentiator`, a static block with a compiled kernel.

    Block signals: inputs ``v``, ``x[0]``, ``x[1]`` (the TD state ``x1``, ``x2`` before the steps); outputs
    ``x[0]``, ``x[1]`` after them. Made by :meth:`TrackingDifferentiator.step_block`.

    Parameters
    ----------
    td : TrackingDifferentiator
        Whose ``r``, ``h``, ``h0`` and ``substeps`` are used.
    """

    inputs = ("v", "x[0]", "x[1]")
    outputs = ("x[0]", "x[1]")
    feedthrough = True
    kernels = Kernels(output=td_step_output)

    def __init__(self, td: TrackingDifferentiator):
        if not isinstance(td, TrackingDifferentiator):
            raise TypeError(f"td must be a TrackingDifferentiator, got {type(td).__name__}")
        self.kernel_params = td.kernel_params


def softened_setpoint(softener, r, h: float, *, method: str = "zoh") -> np.ndarray:
    """Soften a sampled reference and return ``θ = (v, v', v'', ...)`` at every sample.

    Parameters
    ----------
    softener : LowPassFilter or TrackingDifferentiator
        A :class:`~ctrl_analysis.estimators.lowpass.LowPassFilter` of order ``m`` (the prefilter
        ``ω^m / (s + ω)^m``) gives its ``m`` states with ``r`` held over
        each step (zero-order hold). A
        :class:`TrackingDifferentiator` (its sample period ``dt = substeps * h`` must equal
        ``h``) gives ``(x1, x2, fh)``: the tracking signal, its derivative and the acceleration
        applied over the next step, from a zero initial state.
    r : array_like, shape (N,)
        Raw reference at the sample instants ``t_k = k h``.
    h : float
        Sampling step, ``> 0``.
    method : {"zoh", "rk4", "euler"}
        Prefilter only: ``"zoh"`` (default) propagates the exact zero-order-hold discretisation
        (:func:`control.c2d`, :func:`control.forced_response`); ``"rk4"``/``"euler"`` integrate
        :meth:`LowPassFilter.rhs` with the engine's fixed step instead.

    Returns
    -------
    numpy.ndarray, shape (N, m)
        ``θ_k`` at ``t_k`` (before the step driven by ``r_k``); ``m`` is the prefilter order, or
        3 for the TD.

    Raises
    ------
    TypeError
        If ``softener`` is neither block.
    ValueError
        If ``r`` is not a finite 1-D array, or the TD's sample period differs from ``h``.
    """
    h = float(check_positive("h", h, scalar=True))
    r = np.asarray(check_finite("r", r), dtype=float)
    if r.ndim != 1 or r.size < 1:
        raise ValueError(f"r must be a non-empty 1-D array of samples, got shape {r.shape}")
    check_in("method", method, ("zoh", "rk4", "euler"))
    if isinstance(softener, LowPassFilter):
        if method == "zoh":
            # exact for r held over each step: q_(k+1) = e^(A h) q_k + ∫ e^(A s) ds B r_k
            sysd = ct.c2d(softener.ss, h, method="zoh")
            finite_result("h (with the softener's omega)", lambda: (sysd.A, sysd.B))
            resp = ct.forced_response(sysd, T=h * np.arange(r.size), U=r)
            return np.asarray(resp.states).T.reshape(r.size, softener.order).copy()
        # the fixed-step recursion q_(k+1) = step(q_k, r_k), r_k held over the step (one run; the engine's
        # integrators, so the same numbers as a Loop of the block: tests/lib/test_lowpass.py)
        step, q = STEPPERS[method], np.zeros((1, softener.order))
        theta = np.empty((r.size, softener.order))
        for k in range(r.size):
            theta[k] = q[0]
            q = step(softener.rhs, k * h, q, r[k:k + 1, None], h)
        return theta
    if isinstance(softener, TrackingDifferentiator):
        if not np.isclose(softener.dt, h, rtol=1e-12, atol=0.0):
            raise ValueError(f"softener.dt (substeps * h) must equal h={h}, got {softener.dt}")
        _, x = softener.run(r, x0=np.zeros(2))
        theta = np.empty((r.size, 3))
        theta[:, :2] = x[:-1, 0, :]
        # the acceleration applied over each sample (the last sub-step's with substeps > 1)
        theta[:, 2] = softener.acceleration(x[:-1, 0, :], r[:, None])
        return theta
    raise TypeError(
        f"softener must be a LowPassFilter or a TrackingDifferentiator, got {type(softener).__name__}"
    )
