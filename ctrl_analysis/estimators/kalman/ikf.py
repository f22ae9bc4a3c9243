"""The improved Kalman filter (IKF): a scalar Kalman filter whose prediction is a data model, as a discrete block."""

from __future__ import annotations

import numpy as np

from ..._validate import check_finite, check_nonnegative, check_positive
from ...engine.blocks import DiscreteBlock
from ...engine.kernels import KernelBlock, Kernels, Layout, jitable
from .scalar import random_walk_gain

__all__ = ["ImprovedKalmanFilter"]


#: The kernel parameters: the variances ``Q`` and ``R`` (one row per run when either differs per run).
LAYOUT = Layout("Q", "R")
AT = LAYOUT.at


@jitable
def _ikf_step(y_hat, P, y_m, delta, Q, R):
    """One IKF step, eq. (11)-(15): returns ``(ŷ(k|k), K(k), P(k|k))`` (scalars or arrays alike)."""
    y_prior = y_hat + delta                          # (11) ŷ(k|k−1) = ŷ(k−1|k−1) + δ(k)
    P_prior = P + Q                                  # (12) P(k|k−1) = P(k−1|k−1) + Q
    K = P_prior / (P_prior + R)                      # (13) K(k) = P(k|k−1) / (P(k|k−1) + R)
    y_post = y_prior + K * (y_m - y_prior)           # (14) ŷ(k|k) = ŷ(k|k−1) + K (y_m(k) − ŷ(k|k−1))
    return y_post, K, (1.0 - K) * P_prior            # (15) P(k|k) = (1 − K) P(k|k−1)


def ikf_output(t, x, u, p, y):
    """Kernel output of :class:`ImprovedKalmanFilter`: ``y = (ŷ(k|k), K(k), P(k|k))``.

    Scalar indexing only: one run's vectors in the compiled engine, the batch's columns in the
    block's batched methods.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        State ``(ŷ(k−1|k−1), P(k−1|k−1))``.
    u : numpy.ndarray
        Inputs ``(y_m(k), δ(k))``.
    p : numpy.ndarray
        :data:`LAYOUT`: ``Q``, ``R``.
    y : numpy.ndarray
        Outputs, written in place.
    """
    y[0], y[1], y[2] = _ikf_step(x[0], x[1], u[0], u[1], p[AT.Q], p[AT.R])


def ikf_update(t, x, u, p, x_next):
    """Kernel update of :class:`ImprovedKalmanFilter`: ``x(k+1) = (ŷ(k|k), P(k|k))`` (arguments as :func:`ikf_output`).

    Parameters
    ----------
    t, x, u, p
        As :func:`ikf_output`.
    x_next : numpy.ndarray
        Next state, written in place.
    """
    y_post, _K, P_post = _ikf_step(x[0], x[1], u[0], u[1], p[AT.Q], p[AT.R])
    x_next[0] = y_post
    x_next[1] = P_post


class ImprovedKalmanFilter(KernelBlock, DiscreteBlock):
    """Scalar Kalman filter of an output ``y`` whose one-step prediction comes from any data model.

    The model says ``y(k) = y(k−1) + δ(k) + w(k−1)``, ``y_m(k) = y(k) + v(k)``, with ``δ(k)`` a
    predicted increment known at sample ``k`` (for the CFDL data model ``δ(k) = φ̂(k−1) Δu(k−1)``,
    see :class:`ctrl_analysis.controllers.mfac.CFDLPredictor`; ``δ = 0`` gives the scalar
    random-walk Kalman filter). At sample ``k`` the block outputs, from its state
    ``(ŷ(k−1|k−1), P(k−1|k−1))`` and its inputs ``y_m(k)``, ``δ(k)``::

        ŷ(k|k−1) = ŷ(k−1|k−1) + δ(k)                     (11)
        P(k|k−1) = P(k−1|k−1) + Q                         (12)
        K(k)     = P(k|k−1) / (P(k|k−1) + R)              (13)
        ŷ(k|k)   = ŷ(k|k−1) + K(k) (y_m(k) − ŷ(k|k−1))    (14)
        P(k|k)   = (1 − K(k)) P(k|k−1)                    (15)

    and its update stores ``(ŷ(k|k), P(k|k))``. ``K(k)`` converges to the random-walk gain
    ``K∞(Q/R)`` (:attr:`steady_gain`, :func:`ctrl_analysis.estimators.kalman.random_walk_gain`)
    whatever ``δ``: the variance recursion does not depend on the data.

    Block signals: inputs ``y_m``, ``dy_model``; states ``y_hat``, ``P``; outputs ``y_hat``
    (``ŷ(k|k)``), ``K``, ``P`` (``P(k|k)``); direct feedthrough.

    Parameters
    ----------
    Q : float
        Process-noise variance of the data model, ``>= 0``: the variance of the output's change per
        sample that the filter must follow and ``δ`` does not predict. To follow a setpoint profile
        ``r``, ``Q ≈ mean((r(k+1) − r(k))²)`` (a sine of amplitude ``A``, period ``P`` samples:
        ``(2πA/P)²/2``). Not a smoothing knob: too small a ``Q`` makes the filter lag, and a loop
        that acts on its output (IKF-MFAC) falls behind its setpoint. Values per run (a grid on
        the batch axis) are given to ``Loop.simulate(params={name: {"Q": values}})``.
    R : float
        Measurement-noise variance, ``> 0``: the sensor's ``σ²`` (the variance of ``y_m`` at rest),
        per run as ``Q``. Only ``Q/R`` matters once ``P`` has converged: it sets ``K∞``, hence the
        filter's bandwidth, the share ``K∞/(2 − K∞)`` of the noise variance it passes, and its lag,
        ``(1 − K∞)/K∞`` samples per unit slope of a change ``δ`` misses (``docs/guide.rst``,
        "Choosing IKF-MFAC's Q and R", has a sweep).
    y0 : float
        Initial estimate ``ŷ(0|0)`` (the state before the first sample).
    P0 : float
        Initial error variance ``P(0|0)``, ``>= 0``.

    Attributes
    ----------
    steady_gain : float
        ``K∞(Q/R)``, the limit of ``K(k)``.

    Raises
    ------
    ValueError
        ``Q must be >= 0``, ``R must be > 0``, ``P0 must be >= 0``, or a non-finite ``y0``.

    References
    ----------
    Lu X., Hou Z., "Model free adaptive control with disturbance rejection based on modified
    Kalman filter", Control Theory & Applications 39(7), 2022, eq. (9), (11)-(15) (Theorem 2).
    The increment ``δ`` is an input here, so the filter works with any data model.

    Examples
    --------
    >>> import numpy as np
    >>> f = ImprovedKalmanFilter(Q=0.1, R=1.0, y0=0.0, P0=1.0)
    >>> y, x = f.run(np.column_stack([np.ones(200), np.zeros(200)]))
    >>> bool(abs(y[-1, 0, 1] - f.steady_gain) < 1e-12)
    True
    """

    inputs = ("y_m", "dy_model")
    states = ("y_hat", "P")
    outputs = ("y_hat", "K", "P")
    feedthrough = True

    def __init__(self, Q: float, R: float, y0: float = 0.0, P0: float = 1.0):
        self.Q = float(check_nonnegative("Q", Q, scalar=True))
        self.R = float(check_positive("R", R, scalar=True))
        self.y0 = float(check_finite("y0", y0, scalar=True))
        self.P0 = float(check_nonnegative("P0", P0, scalar=True))
        self.steady_gain = random_walk_gain(self.Q, self.R)
        self.kernel_params = LAYOUT.pack(Q=self.Q, R=self.R)

    def initial_state(self) -> np.ndarray:
        return np.array([self.y0, self.P0])

    kernels = Kernels(output=ikf_output, update=ikf_update)

    def __repr__(self) -> str:
        return f"ImprovedKalmanFilter(Q={self.Q}, R={self.R}, y0={self.y0:g}, P0={self.P0:g})"
