"""What each simulated chunk of the `meso` study adds to Tables 2-3: the |e| sums and sup |Δx3/h|.

:func:`x3_true` is the true extended state, :func:`_chunk_errors` every table metric's |e| at a chunk's
samples (the reference), :func:`_accumulate` the same sums in one compiled pass (:func:`_accumulator`);
:func:`full_solved` counts the batches that solved the full regression.
"""


import numpy as np

__all__ = ["METRIC_ORDER", "full_solved", "x3_true"]


def full_solved(rows, regression: str, log10_cond, rank) -> np.ndarray:
    """Batches in which each run solved the full regression (16)/(10) (0 everywhere for the reduced (22)).

    The literal and direct rules solve it every batch; the well-posed rule only where it passes the gate
    (numerically full rank and column-scaled condition number <= the run's threshold, Theorem 1).
    """
    out = np.zeros(len(rows), dtype=int)
    if regression != "full":
        return out
    for b, r in enumerate(rows):
        lc, rk = log10_cond[:, b], rank[:, b]
        ok = np.isfinite(lc)
        if r.variant == "wellposed":
            out[b] = int(np.sum(ok & (rk == 4) & (10.0 ** np.where(ok, lc, 0.0) <= r.threshold)))
        elif r.variant in ("literal", "direct"):
            out[b] = int(np.sum(ok))
    return out


def x3_true(sig, rows, paper, b0):
    """True extended state at the samples: x3 = x2' − b0 u − XᵀΘ_used (ESO: Θ_used = 0).

    Parameters
    ----------
    sig : dict of str -> ndarray, shape (n, B)
        Signals ``x[0], x[1], u, level, xhat[0], xhat[1], theta[0..3]``.
    rows : sequence of Row
        The runs (their plant gain ``b``).
    paper : Paper
    b0 : float

    Returns
    -------
    ndarray, shape (n, B)
    """
    b = np.array([r.b_plant for r in rows])
    x1, x2, u = sig["x[0]"], sig["x[1]"], sig["u"]
    x2dot = paper.theta1 * x1 + paper.theta2 * x2 + sig["level"] + b * u
    f = sig["theta[0]"] * sig["xhat[0]"] + sig["theta[1]"] * sig["xhat[1]"] + sig["theta[2]"] * u + sig["theta[3]"]
    return x2dot - b0 * u - f


def _chunk_errors(sig, t, rows, paper, b0):
    """|e| of every table metric at the chunk's samples, each (n, B) (the reference of :func:`_accumulate`)."""
    x3 = x3_true(sig, rows, paper, b0)
    return {
        "est_x1": np.abs(sig["x[0]"] - sig["xhat[0]"]),
        "est_x2": np.abs(sig["x[1]"] - sig["xhat[1]"]),
        "est_x3": np.abs(x3 - sig["xhat[2]"]),
        "est_x3_no_bu": np.abs(x3 - (paper.b - b0) * sig["u"] - sig["xhat[2]"]),
        "track_x1": np.abs(np.sin(t)[:, None] - sig["x[0]"]),
        "track_x2": np.abs(np.cos(t)[:, None] - sig["x[1]"]),
    }, x3


#: the metrics of :func:`_chunk_errors`, in the order of :func:`_accumulate`'s rows
METRIC_ORDER = ("est_x1", "est_x2", "est_x3", "est_x3_no_bu", "track_x1", "track_x2")


def _accumulate(x1, x2, xh1, xh2, xh3, u, level, th0, th1, th2, th3, t, w, b, b0, theta1, theta2, bb, t_step, h,
                t_from, prev, has_prev, sums, wsums, sup):
    """One pass over a chunk (``n`` samples, ``A`` runs): the |e| sums of :func:`_chunk_errors` (whole run and
    window ``w``) and sup |Δx3/h| from ``t_from`` on (M, N of (5)/(8)), the θ4 step excluded, added in place; ``prev``
    holds each run's last x3.

    Signals are ``(n, A)`` (any strides); ``b`` (A,) the plant gains; ``bb = paper.b − b0``. Compiled with numba
    (:func:`_accumulator`); the same function runs in Python.
    """
    n, A = x1.shape
    for k in range(n):
        r1, r2, tk = np.sin(t[k]), np.cos(t[k]), t[k]
        skip = abs(tk - t_step) < 0.5 * h or tk < t_from
        for j in range(A):
            x2dot = theta1 * x1[k, j] + theta2 * x2[k, j] + level[k, j] + b[j] * u[k, j]
            f = th0[k, j] * xh1[k, j] + th1[k, j] * xh2[k, j] + th2[k, j] * u[k, j] + th3[k, j]
            x3 = x2dot - b0 * u[k, j] - f
            e0 = abs(x1[k, j] - xh1[k, j])
            e1 = abs(x2[k, j] - xh2[k, j])
            e2 = abs(x3 - xh3[k, j])
            e3 = abs(x3 - bb * u[k, j] - xh3[k, j])
            e4 = abs(r1 - x1[k, j])
            e5 = abs(r2 - x2[k, j])
            sums[0, j] += e0
            sums[1, j] += e1
            sums[2, j] += e2
            sums[3, j] += e3
            sums[4, j] += e4
            sums[5, j] += e5
            if w[k]:
                wsums[0, j] += e0
                wsums[1, j] += e1
                wsums[2, j] += e2
                wsums[3, j] += e3
                wsums[4, j] += e4
                wsums[5, j] += e5
            if (k > 0 or has_prev) and not skip:
                d = abs(x3 - prev[j]) / h
                if np.isfinite(d) and d > sup[j]:
                    sup[j] = d
            prev[j] = x3


_ACC: list = []


def _accumulator():
    """:func:`_accumulate` compiled by numba (once per process; numba's disk cache keeps it across processes)."""
    if not _ACC:
        import numba

        try:
            _ACC.append(numba.njit(cache=True, error_model="numpy")(_accumulate))
        except RuntimeError:  # no writable cache next to the source: compile, don't cache
            _ACC.append(numba.njit(cache=False, error_model="numpy")(_accumulate))
    return _ACC[0]
