"""Fixed-step integrators and the divergence test, written once for both engines.

The numpy engine steps a batch ``(B, n)``; the compiled runner (:mod:`ctrl_analysis.engine.codegen`)
steps one run's vector. Both call the same RK4 formulas, :func:`rk4_point` (a stage's state) and
:func:`rk4_sum` (the step, itself :func:`rk4_acc` term by term and :func:`rk4_end`, which the
runner calls stage by stage), numpy on whole arrays and the runner on each state value (inlined,
so the compiled loop is as fast as hand-unrolled arithmetic), and the same test :func:`is_bad`;
so the classical RK4 arithmetic and the divergence rule exist in one place.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["MAX_SUBSTEPS", "STEPPERS", "euler_step", "is_bad", "rk4_acc", "rk4_end", "rk4_point", "rk4_step",
           "rk4_sum"]


def rk4_point(x, k, a):
    """An RK4 stage's state ``x + a k`` (``a`` = h/2, h/2 or h; arrays or one value).

    Parameters
    ----------
    x, k : float or numpy.ndarray
        The state at the start of the step and the previous stage's derivative.
    a : float

    Returns
    -------
    float or numpy.ndarray
    """
    return x + a * k


def rk4_sum(x, k1, k2, k3, k4, h):
    """The RK4 step ``x + h/6 (k1 + 2 k2 + 2 k3 + k4)`` (arrays or one value).

    The sum is taken from the left, term by term (:func:`rk4_acc`, then :func:`rk4_end`): the
    compiled runner adds each stage's term as soon as the stage is done, the same operations in
    the same order, so it keeps one running sum instead of four derivatives.

    Parameters
    ----------
    x : float or numpy.ndarray
        The state at the start of the step.
    k1, k2, k3, k4 : float or numpy.ndarray
        The four stage derivatives.
    h : float

    Returns
    -------
    float or numpy.ndarray
    """
    return rk4_end(x, rk4_acc(rk4_acc(k1, k2, 2.0), k3, 2.0) + k4, h)


def rk4_acc(acc, k, w):
    """A term of RK4's weighted sum of stage derivatives: ``acc + w k`` (``w = 2`` for the two middle stages).

    Parameters
    ----------
    acc, k : float or numpy.ndarray
        The sum so far and the stage's derivative.
    w : float

    Returns
    -------
    float or numpy.ndarray
    """
    return acc + w * k


def rk4_end(x, acc, h):
    """The RK4 step from the weighted sum ``acc = k1 + 2 k2 + 2 k3 + k4``: ``x + h/6 acc``.

    Parameters
    ----------
    x, acc : float or numpy.ndarray
    h : float

    Returns
    -------
    float or numpy.ndarray
    """
    return x + (h / 6.0) * acc


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
    k1 = rhs(t, x, u, params)
    k2 = rhs(t + 0.5 * h, rk4_point(x, k1, 0.5 * h), u, params)
    k3 = rhs(t + 0.5 * h, rk4_point(x, k2, 0.5 * h), u, params)
    k4 = rhs(t + h, rk4_point(x, k3, h), u, params)
    return rk4_sum(x, k1, k2, k3, k4, h)


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


def _flag_divergence(x, bound, diverged, div_step, step_index, div_where=None):
    """Mark runs that just left the bound (in place, with the first bad state's index in ``div_where``) and set every
    diverged run's state to NaN."""
    with np.errstate(invalid="ignore"):
        bad_values = is_bad(x, bound)
    bad = bad_values.any(axis=1) & ~diverged
    if bad.any():
        diverged |= bad
        div_step[bad] = step_index
        if div_where is not None:
            div_where[bad] = np.argmax(bad_values[bad], axis=1)
        x = x.copy()
        x[diverged] = np.nan
    return x
