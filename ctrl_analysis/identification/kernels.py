"""Per-run kernels of the identification blocks (:mod:`ctrl_analysis.identification`).

* :func:`arx_update` / :func:`arx_output`: the tapped delay lines of
  :class:`~ctrl_analysis.identification.ArxRegressor` (a kernel-first block, parameters :data:`ARX`),
  written with scalar indexing only, so they also run on a batch's columns.
* :func:`rls_update` / :func:`rls_output` (:func:`rls_hold_output` without feedthrough): the equations of
  :class:`~ctrl_analysis.identification.RecursiveLeastSquaresBlock` (a kernel-first block: the compiled
  engine and its batched methods run these kernels; the projection and the trace cap branch per value, so
  the batched methods call them run by run).

Parameters ``p`` of the RLS kernels: :func:`rls_layout` (``n``, ``forgetting`` λ, ``max_trace`` (0: none),
``projected`` (0/1, informative: the kernels clip to the bounds always, and infinite bounds make the
projection the identity), ``lower`` (n), ``upper`` (n)); state ``[θ (n), R row by row (n·n)]``; input
``[z, h (n)]``.
"""

from __future__ import annotations

from ..engine.kernels import Layout, jitable, offset
from ..engine.matrix import matrix, symmetrize, trace, vector

__all__: list = []  # kernels: reached through the blocks' kernel() methods

# : Parameters of :class:`~ctrl_analysis.identification.ArxRegressor` (orders and lag, structural: one value for every
# run).
ARX = Layout("na", "nb", "lag")
ARX_AT = ARX.at  # offsets, a numba constant


def arx_update(t, x, u, p, x_next):
    """Shift both delay lines: ``s(k−1) <- s(k)``, ``s(k−i) <- s(k−i+1)``, the same for ``u``.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        ``[s(k−1) .. s(k−na−d), u(k−1) .. u(k−nb−d)]``.
    u : numpy.ndarray
        ``[s(k), u(k)]``.
    p : numpy.ndarray
        Packed by :data:`ARX`.
    x_next : numpy.ndarray
        Written in place.
    """
    ns, nu = int(p[ARX_AT.na]) + int(p[ARX_AT.lag]), int(p[ARX_AT.nb]) + int(p[ARX_AT.lag])
    for i in range(ns):
        x_next[i] = u[0] if i == 0 else x[i - 1]
    for i in range(nu):
        x_next[ns + i] = u[1] if i == 0 else x[ns + i - 1]


def arx_output(t, x, u, p, y):
    """``z = s(k−d)``; ``h = [s(k−d−1) .. s(k−d−na), u(k−d−1) .. u(k−d−nb)]``.

    Parameters
    ----------
    t, x, u, p
        As :func:`arx_update`.
    y : numpy.ndarray
        ``[z, h]``, written in place.
    """
    na, nb, d = int(p[ARX_AT.na]), int(p[ARX_AT.nb]), int(p[ARX_AT.lag])
    ns = na + d
    y[0] = u[0]
    for _ in range(min(d, 1)):  # z = s(k−d): the stored s(k−d) when d >= 1 (a loop, not a branch: leaner in numba)
        y[0] = x[d - 1]
    for i in range(na):
        y[1 + i] = x[d + i]
    for j in range(nb):
        y[1 + na + j] = x[ns + d + j]


#: The parameters of the RLS kernels for ``n`` parameters: the head, then the bounds ``lower``, ``upper``.
RLS_LAYOUT = Layout("n", "forgetting", "max_trace", "projected", ("lower", "n"), ("upper", "n"))
RLS_AT = RLS_LAYOUT.at  # offsets, a numba constant


def rls_layout(n: int) -> Layout:
    """The parameters of the RLS kernels for ``n`` parameters: :data:`RLS_LAYOUT` for this ``n``.

    Parameters
    ----------
    n : int

    Returns
    -------
    Layout
    """
    return RLS_LAYOUT.sized(n=n)


@jitable
def rls_gain(x, u, p, out):
    """``R(k−1) h(k)`` into ``out[:n]``; returns ``λ + hᵀ R h`` and the innovation ``z − hᵀ θ(k−1)``."""
    n = int(p[RLS_AT.n])
    theta, R, h = vector(x, 0, n), matrix(x, n, n, n), vector(u, 1, n)
    # R h, hᵀ R h and hᵀ θ written out in two passes (this kernel runs for every run and sample: calling
    # mat_vec and dot here measured 1.3x slower compiled)
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc = acc + R[i, j] * h[j]  # (R h)[i]
        out[i] = acc
    hRh, hth = 0.0, 0.0
    for i in range(n):
        hRh = hRh + h[i] * out[i]
        hth = hth + h[i] * theta[i]
    return p[RLS_AT.forgetting] + hRh, u[0] - hth


@jitable
def _rls_theta(x, p, out, den, innov):
    """``θ(k) = Π[θ(k−1) + D(k) (z − hᵀ θ(k−1))]``, ``D = R h / den``, from ``R h`` in ``out[:n]`` (overwritten)."""
    n = int(p[RLS_AT.n])
    lower, upper = vector(p, offset(RLS_AT.lower, n), n), vector(p, offset(RLS_AT.upper, n), n)
    for i in range(n):
        v = x[i] + out[i] / den * innov
        # projection onto the box lower <= θ <= upper (NaN stays NaN, as np.clip; infinite bounds: identity)
        v = lower[i] if v < lower[i] else v
        out[i] = upper[i] if v > upper[i] else v


def rls_update(t, x, u, p, x_next):
    """One RLS step, eq. (9): ``[θ(k), R(k)]``, the update kernel of ``RecursiveLeastSquaresBlock``.

    Parameters
    ----------
    t : float
        Time (unused).
    x : numpy.ndarray
        ``[θ(k−1), R(k−1)]`` of one run.
    u : numpy.ndarray
        ``[z(k), h(k)]``.
    p : numpy.ndarray
        Packed parameters (module docstring).
    x_next : numpy.ndarray
        Written in place.
    """
    n = int(p[RLS_AT.n])
    lam = p[RLS_AT.forgetting]
    R, R_new = matrix(x, n, n, n), matrix(x_next, n, n, n)
    den, innov = rls_gain(x, u, p, x_next)  # R h in x_next[:n] until θ(k) overwrites it
    Rh = vector(x_next, 0, n)
    for i in range(n):
        d = Rh[i] / den  # D = R h / den
        for j in range(n):
            R_new[i, j] = (R[i, j] - d * Rh[j]) / lam  # R(k) = (R − D (R h)ᵀ) / λ
    symmetrize(R_new)  # R(k) = 0.5 (R(k) + R(k)ᵀ)
    # anti-windup: trace R(k) <= max_trace, R(k) scaled by min(1, max_trace / trace) (NaN propagates, as
    # np.minimum); a scale of 1 (no cap) is exact. Conditional expressions, not if statements, keep numba lean.
    tr = trace(R_new)
    s = p[RLS_AT.max_trace] / tr if p[RLS_AT.max_trace] > 0.0 else 1.0
    s = 1.0 if s >= 1.0 else s
    for i in range(n):
        for j in range(n):
            R_new[i, j] = R_new[i, j] * s
    _rls_theta(x, p, x_next, den, innov)


def rls_output(t, x, u, p, y):
    """``θ(k)``, the estimate after the update with this sample (feedthrough); arguments as :func:`rls_update`.

    Parameters
    ----------
    t, x, u, p
        As :func:`rls_update`.
    y : numpy.ndarray
        ``θ(k)``, written in place.
    """
    den, innov = rls_gain(x, u, p, y)
    _rls_theta(x, p, y, den, innov)


def rls_hold_output(t, x, u, p, y):
    """The stored ``θ(k−1)`` (``feedthrough=False``); arguments as :func:`rls_update`.

    Parameters
    ----------
    t, x, u, p
        As :func:`rls_update`.
    y : numpy.ndarray
        ``θ(k−1)``, written in place.
    """
    for i in range(y.shape[0]):
        y[i] = x[i]
