"""Setpoint softening and derivative extraction: Han's ``fhan``, the tracking differentiator, and a prefilter.

Three blocks that turn a raw (possibly discontinuous) reference ``r`` into a smooth signal ``v``
together with its derivatives ``v, v', v'', ...``:

* :func:`fhan` — Han's time-optimal synthesis function of the discrete double integrator;
* :class:`TrackingDifferentiator` — Han's discrete tracking differentiator (TD) built on it,
  giving ``(v, v')`` and, through the last ``fhan`` value, ``v''``;
* :class:`SetpointPrefilter` — the linear prefilter ``ω^m / (s + ω)^m`` in phase-variable form,
  whose states are exactly ``(v, v', ..., v^(m-1))``.

:func:`softened_setpoint` runs either softener over a sampled reference and returns the
derivative vector ``θ`` at every sample, ready for a differential-feedback controller.
"""

from __future__ import annotations

from math import comb

import control as ct
import numpy as np

from .._validate import check_array, check_finite, check_in, check_int, check_positive

__all__ = [
    "fhan",
    "TrackingDifferentiator",
    "SetpointPrefilter",
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
    x1 = check_array("x1", x1)
    x2 = check_array("x2", x2)
    d = r * h0 * h0
    a0 = h0 * x2
    y = x1 + a0
    a1 = np.sqrt(d * (d + 8.0 * np.abs(y)))
    a2 = a0 + np.sign(y) * (a1 - d) * 0.5
    sy = (np.sign(y + d) - np.sign(y - d)) * 0.5
    a = (a0 + y - a2) * sy + a2
    sa = (np.sign(a + d) - np.sign(a - d)) * 0.5
    sign_a = np.sign(a)
    out = -r * (a / d - sign_a) * sa - r * sign_a
    return float(out) if out.ndim == 0 else out


class TrackingDifferentiator:
    """Han's discrete tracking differentiator: ``x1`` tracks the input ``v``, ``x2`` its derivative.

    Per sample (``substeps`` times with step ``h / substeps``)::

        fh = fhan(x1 - v, x2, r, h0)
        x1 <- x1 + h x2
        x2 <- x2 + h fh

    ``fh`` (kept in :attr:`fh`) is the acceleration of ``x1`` over the step: an estimate of ``v''``.

    Parameters
    ----------
    r : float
        Speed factor (acceleration bound), ``> 0``: larger tracks faster.
    h : float
        Sampling step, ``> 0``.
    h0 : float, optional
        Filtering factor of :func:`fhan`, ``> 0``; default ``h`` (Han's choice without extra
        filtering).
    substeps : int
        Integration steps per sample (``>= 1``); each uses ``h / substeps``.

    Attributes
    ----------
    x1, x2 : float or numpy.ndarray
        Tracking signal and its derivative (scalars, or shape ``(B,)`` once stepped with arrays).
    fh : float or numpy.ndarray
        Last value of ``fhan``: the acceleration applied over the last step.

    Raises
    ------
    ValueError
        If ``r``, ``h`` or ``h0`` is not finite and ``> 0``, or ``substeps < 1``.

    References
    ----------
    Han J., "From PID to active disturbance rejection control", IEEE Trans. Ind. Electron.
    56(3), 2009, eq. (11)-(12).

    Examples
    --------
    >>> td = TrackingDifferentiator(r=50.0, h=0.01)
    >>> for _ in range(300):
    ...     x1, x2 = td.step(1.0)
    >>> round(float(x1), 6), round(float(x2), 6)
    (1.0, 0.0)
    """

    def __init__(self, r: float, h: float, h0: float | None = None, substeps: int = 1):
        self.r = float(check_positive("r", r, scalar=True))
        self.h = float(check_positive("h", h, scalar=True))
        self.h0 = self.h if h0 is None else float(check_positive("h0", h0, scalar=True))
        self.substeps = check_int("substeps", substeps, minimum=1)
        self.reset()

    def reset(self, x1=0.0, x2=0.0) -> None:
        """Set the state (scalars, or arrays of shape ``(B,)`` for a batch)."""
        self.x1 = check_finite("x1", x1)
        self.x2 = check_finite("x2", x2)
        self.fh = 0.0 * (np.asarray(self.x1) + np.asarray(self.x2))

    def step(self, v):
        """Advance one sample with input ``v`` (scalar or ``(B,)``); return ``(x1, x2)``."""
        v = np.asarray(check_finite("v", v), dtype=float)
        dt = self.h / self.substeps
        x1, x2 = self.x1, self.x2
        for _ in range(self.substeps):
            fh = fhan(x1 - v, x2, self.r, self.h0)
            # (11) x1 <- x1 + h x2,  x2 <- x2 + h fhan(x1 - v, x2, r, h0)
            x1, x2 = x1 + dt * x2, x2 + dt * fh
        self.x1, self.x2, self.fh = x1, x2, fh
        return x1, x2

    def __repr__(self) -> str:
        return (f"TrackingDifferentiator(r={self.r}, h={self.h}, h0={self.h0}, "
                f"substeps={self.substeps})")


class SetpointPrefilter:
    """Linear setpoint prefilter ``ω^m / (s + ω)^m`` in phase-variable form.

    States ``q = (v, v', ..., v^(m-1))``::

        q_i' = q_(i+1),   i = 1..m-1
        q_m' = ω^m r - Σ_(j=0..m-1) C(m, j) ω^(m-j) q_(j+1)

    so the states are the softened setpoint and exactly its first ``m - 1`` derivatives; a step
    in ``r`` gives a ``v`` without overshoot whose first ``m - 1`` derivatives are continuous.

    Parameters
    ----------
    order : int
        ``m >= 1``; ``m = n`` gives ``v`` and the ``n - 1`` derivatives an ``n``-th order
        differential-feedback controller needs.
    omega : float
        Corner frequency ``ω`` in rad/s, ``> 0`` (an ``m``-fold pole at ``-ω``).

    Attributes
    ----------
    tf : control.TransferFunction
        ``r -> v``.
    ss : control.StateSpace
        Input ``r``; states and outputs ``v, v', ...``.
    A, B : numpy.ndarray
        Companion matrices of the phase-variable form.

    Raises
    ------
    ValueError
        If ``order < 1`` or ``omega`` is not finite and ``> 0``.

    References
    ----------
    Ogata K., *Modern Control Engineering*, 5th ed., §9-2 (phase-variable / controllable
    canonical form). A common setpoint softener in two-degree-of-freedom designs; Qi, Chen, Xue
    & Yuan (2004), section 4, only ask for a "softened" square wave without saying how.

    Examples
    --------
    >>> import control as ct
    >>> pf = SetpointPrefilter(3, 2.0)
    >>> float(ct.dcgain(pf.tf))
    1.0
    """

    def __init__(self, order: int, omega: float):
        self.order = check_int("order", order, minimum=1)
        self.omega = float(check_positive("omega", omega, scalar=True))
        m, w = self.order, self.omega
        # (s + ω)^m = s^m + Σ_j C(m, j) ω^(m-j) s^j  ->  last row -[c_0, ..., c_(m-1)]
        self.coeffs = np.array([comb(m, j) * w ** (m - j) for j in range(m)])
        self.gain = w**m
        A = np.diag(np.ones(m - 1), 1)
        A[-1, :] = -self.coeffs
        self.A = A
        self.B = np.zeros((m, 1))
        self.B[-1, 0] = self.gain

    @property
    def tf(self) -> ct.TransferFunction:
        """``ω^m / (s + ω)^m`` (``r -> v``)."""
        den = np.concatenate(([1.0], self.coeffs[::-1]))
        return ct.tf([self.gain], den, inputs="r", outputs="v")

    def derivative_tf(self, k: int) -> ct.TransferFunction:
        """``s^k ω^m / (s + ω)^m``: ``r -> v^(k)``, ``0 <= k <= m`` (the states for ``k < m``)."""
        k = check_int("k", k, minimum=0, maximum=self.order)
        num = np.zeros(k + 1)
        num[0] = self.gain
        den = np.concatenate(([1.0], self.coeffs[::-1]))
        return ct.tf(num, den, inputs="r", outputs=f"v^({k})")

    @property
    def ss(self) -> ct.StateSpace:
        """Phase-variable state space; outputs are the states ``v, v', ..., v^(m-1)``."""
        names = self.output_names()
        return ct.ss(self.A, self.B, np.eye(self.order), np.zeros((self.order, 1)),
                     inputs="r", states=names, outputs=names)

    def output_names(self) -> list[str]:
        """``["v", "v'", "v''", ...]``."""
        return ["v" + "'" * k for k in range(self.order)]

    def rhs(self, t, q, r, params=None) -> np.ndarray:
        """Right-hand side in python-control's ``(t, x, u, params)`` order.

        Parameters
        ----------
        t : float
            Time (unused).
        q : array_like, shape (m,) or (B, m)
            Prefilter states.
        r : array_like
            Raw reference: scalar, ``(1,)``, ``(B,)`` or ``(B, 1)``.

        Returns
        -------
        numpy.ndarray
            ``dq/dt`` with the shape of ``q`` (broadcast with ``r``).
        """
        q = np.asarray(q, dtype=float)
        r = np.asarray(r, dtype=float)
        if r.ndim >= 1 and r.shape[-1] == 1:
            r = r[..., 0]
        dq = np.empty(np.broadcast_shapes(q.shape, r.shape + (1,)))
        # q_i' = q_(i+1)
        dq[..., :-1] = q[..., 1:]
        # q_m' = ω^m r - Σ c_j q_(j+1)
        dq[..., -1] = self.gain * r - q @ self.coeffs
        return dq

    def outputs(self, q, r=None) -> np.ndarray:
        """``(v, v', ..., v^(m-1))`` — the states themselves; with ``r`` also ``v^(m)`` appended."""
        q = np.asarray(q, dtype=float)
        if r is None:
            return q.copy()
        top = self.rhs(0.0, q, r)[..., -1:]
        return np.concatenate([q, top], axis=-1)

    def __repr__(self) -> str:
        return f"SetpointPrefilter(order={self.order}, omega={self.omega})"


def softened_setpoint(softener, r, h: float, *, method: str = "zoh") -> np.ndarray:
    """Soften a sampled reference and return ``θ = (v, v', v'', ...)`` at every sample.

    Parameters
    ----------
    softener : SetpointPrefilter or TrackingDifferentiator
        A :class:`SetpointPrefilter` of order ``m`` gives its ``m`` states with ``r`` held over
        each step (zero-order hold). A
        :class:`TrackingDifferentiator` (its ``h`` must equal ``h``) gives
        ``(x1, x2, fh)``: the tracking signal, its derivative and the acceleration applied over
        the next step; it is reset to zero first.
    r : array_like, shape (N,)
        Raw reference at the sample instants ``t_k = k h``.
    h : float
        Sampling step, ``> 0``.
    method : {"zoh", "rk4", "euler"}
        Prefilter only: ``"zoh"`` (default) propagates the exact zero-order-hold discretisation
        (:func:`control.c2d`, :func:`control.forced_response`); ``"rk4"``/``"euler"`` integrate
        :meth:`SetpointPrefilter.rhs` with the engine's fixed step instead.

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
        If ``r`` is not a finite 1-D array, or the TD's step differs from ``h``.
    """
    from ..simulate import simulate_sampled

    h = float(check_positive("h", h, scalar=True))
    r = np.asarray(check_finite("r", r), dtype=float)
    if r.ndim != 1 or r.size < 1:
        raise ValueError(f"r must be a non-empty 1-D array of samples, got shape {r.shape}")
    check_in("method", method, ("zoh", "rk4", "euler"))
    if isinstance(softener, SetpointPrefilter):
        if method == "zoh":
            # exact for r held over each step: q_(k+1) = e^(A h) q_k + ∫ e^(A s) ds B r_k
            sysd = ct.c2d(softener.ss, h, method="zoh")
            resp = ct.forced_response(sysd, T=h * np.arange(r.size), U=r)
            return np.asarray(resp.states).T.reshape(r.size, softener.order).copy()
        res = simulate_sampled(lambda t, q, u, p: softener.rhs(t, q, u), np.zeros(softener.order),
                               h, r.size, noise=r[:, None, None], method=method)
        return res.x[:-1, 0, :]
    if isinstance(softener, TrackingDifferentiator):
        if not np.isclose(softener.h, h, rtol=1e-12, atol=0.0):
            raise ValueError(f"softener.h must equal h={h}, got {softener.h}")
        softener.reset()
        theta = np.empty((r.size, 3))
        for k, rk in enumerate(r):
            theta[k, 0], theta[k, 1] = softener.x1, softener.x2
            softener.step(rk)
            # with substeps > 1, fh is the last sub-step's acceleration
            theta[k, 2] = softener.fh
        return theta
    raise TypeError(
        f"softener must be a SetpointPrefilter or a TrackingDifferentiator, got {type(softener).__name__}"
    )
