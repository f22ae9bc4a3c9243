"""Plain right-hand-side functions ``rhs(t, x, u, params)``: integrated adaptively, or wrapped for python-control.

:func:`simulate_ivp` is the smooth, deterministic path of the engine: a batch of runs integrated
adaptively by solve_ivp. :func:`continuous_nlsys` wraps the same batched ``rhs`` as a
:class:`control.NonlinearIOSystem`. (A loop of blocks runs through :class:`~ctrl_analysis.engine.loop.Loop`.)
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .._validate import (
    check_callable,
    check_finite,
    check_in,
    check_int,
    check_names,
    check_positive,
)
from .blocks import MAX_SIGNALS
from .simresult import SimResult, _check_bound, _prepare

__all__ = ["continuous_nlsys", "simulate_ivp"]

_IVP_METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")


def simulate_ivp(
    rhs: Callable,
    x0,
    t_eval,
    *,
    u: Callable | None = None,
    params=None,
    method: str = "RK45",
    rtol: float = 1e-8,
    atol: float = 1e-10,
    bound: float = 1e8,
) -> SimResult:
    """Smooth, deterministic loop integrated adaptively by :func:`scipy.integrate.solve_ivp`.

    The batch is flattened into one ODE of size ``B*n`` (``rhs`` is vectorised over runs), so one
    adaptive solve serves the whole batch. ``u(t) -> (B, m)`` is an optional smooth input.

    A run leaving ``bound`` is frozen there (zero derivative) and flagged; the others go on. A run
    whose derivative becomes NaN or inf is frozen too, flagged as diverged from the first output
    instant at or after that time, and its states are NaN from there (the solver's step size would
    otherwise become NaN and never end). When the
    batch solve fails (e.g. a run's derivative becomes non-finite), every run is solved on its own
    (``rhs`` still receives the whole batch, the other rows held at ``x0``), so one diverging run
    neither stops nor flags the healthy ones; ``info["per_run"]`` says whether that fallback ran.

    Parameters
    ----------
    rhs : callable
        ``rhs(t, x, u, params)`` with ``x`` of shape ``(B, n)``.
    x0 : array_like, shape (n,) or (B, n)
    t_eval : array_like
        Strictly increasing output instants.
    u : callable, optional
        ``u(t) -> (B, m)``, a smooth input.
    params : optional
    method : str
        A :func:`scipy.integrate.solve_ivp` method.
    rtol, atol : float
        Tolerances (> 0).
    bound : float
        A run leaving ``|x| <= bound`` is flagged as diverged.

    Returns
    -------
    SimResult

    Raises
    ------
    ValueError
        ``t_eval`` not finite and strictly increasing, ``rtol`` / ``atol`` not finite and > 0,
        ``bound`` NaN or not > 0, ``method`` unknown.
    """
    from scipy.integrate import solve_ivp

    check_callable("rhs", rhs, "rhs(t, x, u, params)")
    t_eval = check_finite("t_eval", t_eval)
    t_eval = np.atleast_1d(t_eval)
    if t_eval.ndim != 1 or t_eval.size < 2 or np.any(np.diff(t_eval) <= 0):
        raise ValueError("t_eval must be strictly increasing with at least two instants")
    rtol = check_positive("rtol", rtol, scalar=True)
    atol = check_positive("atol", atol, scalar=True)
    bound = _check_bound(bound)
    check_in("method", method, _IVP_METHODS)
    check_callable("u", u, "u(t) -> (B, m)", optional=True)
    x, _, B = _prepare(x0, None, None)
    n = x.shape[1]

    def solve(rows: np.ndarray):
        """Integrate the runs ``rows``; ``rhs`` always sees the whole batch (other rows held at x0),
        so per-run parameters stay aligned. A run past ``bound`` is frozen (zero derivative) so it
        cannot stop or slow the others."""
        full = x.copy()

        def f(t, z):
            full[rows] = z.reshape(rows.size, n)
            with np.errstate(all="ignore"):
                dx = np.asarray(rhs(t, full, None if u is None else u(t), params), dtype=float).reshape(B, n)[rows]
                dx[np.any(np.abs(full[rows]) > bound, axis=1)] = 0.0
                # a non-finite derivative would make the solver's step size NaN and its loop never
                # end: the run is frozen (zero derivative) and flagged from the first time it happened
                bad = ~np.all(np.isfinite(dx), axis=1)
                if bad.any():
                    nonfinite[rows[bad]] = np.minimum(nonfinite[rows[bad]], t)
                    dx[bad] = 0.0
            return dx.reshape(-1)

        return solve_ivp(f, (t_eval[0], t_eval[-1]), x[rows].reshape(-1), t_eval=t_eval, method=method,
                         rtol=rtol, atol=atol)

    def fill(sol, rows):
        # a solve that failed leaves NaN after its last instant: those runs count as diverged
        m = sol.y.shape[1]
        xs[:m, rows] = sol.y.T.reshape(m, rows.size, n)

    xs = np.full((t_eval.size, B, n), np.nan)
    nonfinite = np.full(B, np.inf)  # per run: the first time rhs returned NaN or inf
    sol = solve(np.arange(B))
    if B > 1 and sol.status != 0:
        statuses = []
        for b in range(B):
            s_b = solve(np.array([b]))
            statuses.append(s_b.status)
            fill(s_b, np.array([b]))
        info = {"status": statuses, "message": "batch solve failed; each run solved on its own",
                "nfev": None, "per_run": True}
    else:
        fill(sol, np.arange(B))
        info = {"status": sol.status, "message": sol.message, "nfev": sol.nfev, "per_run": False}
    for b in np.flatnonzero(np.isfinite(nonfinite)):
        xs[np.searchsorted(t_eval, nonfinite[b]):, b] = np.nan  # NaN from the first instant at or after it
    with np.errstate(invalid="ignore"):
        bad_k = ~np.all(np.isfinite(xs), axis=2) | np.any(np.abs(xs) > bound, axis=2)
    diverged = bad_k.any(axis=0)
    div_step = np.where(diverged, bad_k.argmax(axis=0), -1)
    return SimResult(t=t_eval, x=xs, u=None, y=None, diverged=diverged, diverged_step=div_step,
                     bound=bound, info=info)


def _signal_spec(name: str, value):
    """A signal count (0 to MAX_SIGNALS) or a list of names, as :func:`control.nlsys` takes them."""
    if isinstance(value, (list, tuple, str)):
        return check_names(name, value)
    return check_int(name, value, minimum=0, maximum=MAX_SIGNALS)


def continuous_nlsys(rhs: Callable, *, states, inputs, outputs=None, output: Callable | None = None,
                     params=None, name: str | None = None):
    """Wrap a batched right-hand side as a :class:`control.NonlinearIOSystem` (``control.nlsys``).

    python-control calls the update function with 1-D ``x`` and ``u``; they are lifted to a batch of
    one, so the same ``rhs`` serves the engine and :func:`control.interconnect`.

    Parameters
    ----------
    rhs : callable
        ``rhs(t, x, u, params)`` accepting ``x`` of shape ``(1, n)`` and ``u`` of shape ``(1, m)``.
    states, inputs, outputs : int or list of str
        Signal counts or names, as for :func:`control.nlsys`.
    output : callable, optional
        ``output(t, x, u, params)`` (batched like ``rhs``); default: the full state.

    Returns
    -------
    control.NonlinearIOSystem
    """
    import control as ct

    check_callable("rhs", rhs, "rhs(t, x, u, params)")
    check_callable("output", output, "output(t, x, u, params)", optional=True)
    states, inputs = _signal_spec("states", states), _signal_spec("inputs", inputs)
    outputs = None if outputs is None else _signal_spec("outputs", outputs)

    def updfcn(t, x, u, p):
        return np.asarray(rhs(t, np.atleast_2d(x), np.atleast_2d(u), p if p else params)).reshape(-1)

    outfcn = None
    if output is not None:
        def outfcn(t, x, u, p):
            return np.asarray(output(t, np.atleast_2d(x), np.atleast_2d(u), p if p else params)).reshape(-1)

    if outputs is None:
        outputs = states
    return ct.nlsys(updfcn, outfcn, states=states, inputs=inputs, outputs=outputs, name=name)

