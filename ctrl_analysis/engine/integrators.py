"""Fixed-step integrators and the divergence test, written once for both engines.

The numpy engine steps a batch ``(B, n)``; the compiled runner (:mod:`ctrl_analysis.engine.codegen`)
steps one run's vector. Both call the same stage helpers, :func:`rk4_stage` and
:func:`rk4_combine` (scalar-indexed over the states: on a batch they are called with the
transposed arrays, so ``x[j]`` is a column of runs), and the same test :func:`is_bad`; so the
classical RK4 arithmetic and the divergence rule exist in one place.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["MAX_SUBSTEPS", "STEPPERS", "euler_step", "is_bad", "rk4_combine", "rk4_stage", "rk4_step"]


def rk4_stage(xc, K, s, h, xt):
    """The state at RK4 stage ``s``: ``xt = xc + a_s K[s-1]`` (``a = 0, h/2, h/2, h``); returns ``a_s``.

    Parameters
    ----------
    xc : numpy.ndarray, shape (n,) or (n, B)
        The state at the start of the step.
    K : numpy.ndarray, shape (4, n) or (4, n, B)
        The stage derivatives so far.
    s : int
        The stage, 0 to 3.
    h : float
        The step.
    xt : numpy.ndarray
        Overwritten with the stage's state.

    Returns
    -------
    float
        The stage's time offset ``a_s`` (the stage time is ``t + a_s``).
    """
    if s == 0:
        for j in range(xc.shape[0]):
            xt[j] = xc[j]
        return 0.0
    a = h if s == 3 else 0.5 * h
    for j in range(xc.shape[0]):
        xt[j] = xc[j] + a * K[s - 1, j]
    return a


def rk4_combine(xc, K, h):
    """The RK4 step in place: ``xc += h/6 (K1 + 2 K2 + 2 K3 + K4)``.

    Parameters
    ----------
    xc : numpy.ndarray, shape (n,) or (n, B)
        The state at the start of the step, overwritten with the state at its end.
    K : numpy.ndarray, shape (4, n) or (4, n, B)
        The four stage derivatives.
    h : float
    """
    for j in range(xc.shape[0]):
        xc[j] = xc[j] + (h / 6.0) * (K[0, j] + 2.0 * K[1, j] + 2.0 * K[2, j] + K[3, j])


def euler_step(rhs: Callable, t: float, x: np.ndarray, u, h: float, params=None) -> np.ndarray:
    """One forward-Euler step of ``x' = rhs(t, x, u, params)`` with ``u`` held.

    Parameters
    ----------
    rhs : callable
        ``rhs(t, x, u, params) -> dx/dt``, batched.
    t, h : float
        Start of the step and its length.
    x : numpy.ndarray, shape (B, n)
    u : object
        Held input passed to ``rhs``.
    params : optional

    Returns
    -------
    numpy.ndarray, shape (B, n)
        The state at ``t + h``.
    """
    return x + h * rhs(t, x, u, params)


def rk4_step(rhs: Callable, t: float, x: np.ndarray, u, h: float, params=None) -> np.ndarray:
    """One classical Runge-Kutta step of ``x' = rhs(t, x, u, params)`` with ``u`` held over the step.

    Parameters
    ----------
    rhs, t, x, u, h, params
        As for :func:`euler_step`.

    Returns
    -------
    numpy.ndarray, shape (B, n)
        The state at ``t + h`` (local error O(h⁵)).
    """
    xc = x.T  # the state's columns: the stage helpers index states, as in the compiled runner
    K = np.empty((4,) + xc.shape)
    xt = np.empty(xc.shape)
    for s in range(4):
        ts = t + rk4_stage(xc, K, s, h, xt)
        K[s] = rhs(ts, xt.T, u, params).T
    out = np.array(x, dtype=float)
    rk4_combine(out.T, K, h)
    return out


#: Fixed-step integrators by name.
STEPPERS = {"euler": euler_step, "rk4": rk4_step}

#: Most integration steps per sample (``substeps``) a runner or a block accepts: beyond it one
#: sample would take minutes; use a smaller sampling period instead.
MAX_SUBSTEPS = 100_000


def is_bad(v, bound):
    """Whether a state value left ``|v| <= bound`` or is not finite (``bound`` may be ``inf``).

    One test for both engines: numpy calls it on whole arrays, the compiled runner on each value.

    Parameters
    ----------
    v : float or numpy.ndarray
    bound : float
        Positive, or ``inf`` (then only non-finite values are bad).

    Returns
    -------
    bool or numpy.ndarray of bool
    """
    a = np.abs(v)
    return np.logical_not(np.logical_and(a < np.inf, a <= bound))  # NaN fails every comparison


def _check_bad(x_new: np.ndarray, bound: float) -> np.ndarray:
    """Runs (rows of ``x_new``) with a bad state value (:func:`is_bad`)."""
    with np.errstate(invalid="ignore"):
        return is_bad(x_new, bound).any(axis=1)


def _flag_divergence(x, bound, diverged, div_step, step_index):
    """Mark runs that just left the bound (in place) and set every diverged run's state to NaN."""
    bad = _check_bad(x, bound) & ~diverged
    if bad.any():
        diverged |= bad
        div_step[bad] = step_index
        x = x.copy()
        x[diverged] = np.nan
    return x
