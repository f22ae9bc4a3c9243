"""The compiled path of :meth:`Loop.simulate <ctrl_analysis.loop.Loop.simulate>`: choosing it, per-run parameters, running a chunk.

The runner itself is generated and compiled by :mod:`ctrl_analysis._kernels`.
"""

from __future__ import annotations

import numpy as np

from ._kernels import available, compiled_runner, kernel_of


def compiled_for(loop, engine, funcs, params, finite_bound):
    """The compiled runner and the kernels' parameters, or ``None`` for the numpy path."""
    import os

    if engine == "numpy" or (engine == "auto" and os.environ.get("CTRL_ANALYSIS_ENGINE") == "numpy"):
        return None
    
    why = None
    if not available():
        why = "numba is not installed"
    elif funcs or params is not None:
        why = "callable inputs and params need the numpy path"
    kernels = {}
    if why is None:
        for p in loop.placed:
            k = kernel_of(p.block)
            if k is None:
                why = f"block {p.name!r} ({type(p.block).__name__}) has no kernel"
                break
            kernels[p.name] = k
    if why is not None:
        if engine == "compiled":
            raise ValueError(f"engine='compiled' is not possible for this loop: {why}")
        return None
    try:
        run = compiled_runner(loop, kernels, finite_bound)
    except Exception as exc:  # a kernel numba cannot compile: say so, and use the numpy path under "auto"
        if engine == "compiled":
            raise
        import warnings

        warnings.warn(f"compiled engine unavailable for this loop ({type(exc).__name__}: {exc}); "
                      "using the numpy engine", RuntimeWarning, stacklevel=3)
        return None
    P = [_params_2d(p.name, kernels[p.name].params) for p in loop.placed]
    return run, P, {p.name: np.ndim(kernels[p.name].params) == 2 for p in loop.placed}


def _params_2d(name, params):
    """A kernel's parameters as a C-contiguous ``(1, n_p)`` (shared) or ``(B, n_p)`` (per run) array."""
    a = np.asarray(params, dtype=float)
    if a.ndim not in (1, 2):
        raise ValueError(f"block {name!r}: kernel params must be 1-D (shared) or 2-D (one row per run), "
                         f"got shape {a.shape}")
    return np.ascontiguousarray(a[None, :] if a.ndim == 1 else a)


def check_per_run_rows(loop, runner, run_offset: int, B: int, batch_runs: int | None) -> None:
    """Check that the blocks' per-run kernel parameters have one row per run of the batch.

    Parameters
    ----------
    loop : Loop
    runner : tuple
        What :func:`compiled_for` returned.
    run_offset, B : int
        The first run of this call within the batch, and the runs of this call.
    batch_runs : int or None
        Runs of the whole batch (default ``run_offset + B``).

    Raises
    ------
    ValueError
        If two blocks' per-run parameters disagree on the number of runs, or it is not the batch's.
    """
    from ._validate import check_int

    _, P, per_run = runner
    rows = {Pi.shape[0] for Pi, p in zip(P, loop.placed) if per_run[p.name]}
    if len(rows) > 1:
        raise ValueError(f"per-run kernel parameters of the blocks have different numbers of rows: {sorted(rows)}")
    total = run_offset + B if batch_runs is None else check_int("batch_runs", batch_runs, minimum=1)
    if run_offset + B > total:
        raise ValueError(f"batch_runs must cover run_offset + B = {run_offset + B}, got {total}")
    if rows and rows != {total}:
        raise ValueError(f"the loop's per-run block parameters describe {rows.pop()} runs, but the batch has "
                         f"{total} (runs/inputs/x0 set B = {B}): build the blocks for the runs simulated")


def run_compiled(loop, runner, plan, n_steps, t, x, held, bound, keep_cols, store, xs, diverged, div_step,
                 rows=(0, None)):
    """One chunk through the compiled runner, writing into the result slices.

    ``rows = (lo, hi)`` are the chunk's runs within the batch: per-run kernel parameters are sliced
    to them.
    """
    run, P, per_run = runner
    B = x.shape[0]
    lo = rows[0]
    P = [Pi[lo:lo + B] if per_run[p.name] else Pi[0] for Pi, p in zip(P, loop.placed)]
    col = plan["col"]
    S0 = np.zeros(len(plan["names"]))
    for s, a in held.items():
        if a.ndim == 0:
            S0[col[s]] = a
    # inputs that differ per run, (., N+1, B) (each a block copy of its (N, B) record), and inputs
    # shared by every run, (N+1, .): a shared record is not copied B times
    H, HC = _held_matrix([(s, a) for s, a in held.items() if a.ndim == 2], n_steps, B, col)
    HS, HCS = _held_matrix([(s, a) for s, a in held.items() if a.ndim == 1], n_steps, None, col)
    xs_arg = np.empty((0, 0, 0)) if xs is None else xs
    X = np.array(x, dtype=float, order="C")  # a copy, stepped in place by the runner
    run(n_steps, t, loop.dt / loop.substeps, loop.substeps, X, H, HC, HS, HCS, S0,
        keep_cols, store, xs_arg, float(bound), diverged, div_step, *P)
    x[...] = X  # the final state, as the numpy path leaves it (final_states, chunk carry-over)


def _held_matrix(items, n_steps, B, col):
    """Held inputs as one array: ``(k, N+1, B)`` per run (``B`` given) or ``(N+1, k)`` shared; and their columns."""
    k = max(len(items), 1)
    H = np.empty((n_steps + 1, k) if B is None else (k, n_steps + 1, B))
    for j, (_, a) in enumerate(items):
        m = min(a.shape[0], n_steps + 1)
        dst = H[:, j] if B is None else H[j]
        dst[:m] = a[:m]
        dst[m:] = a[m - 1]  # row N repeats row N-1 when absent
    return H, np.array([col[s] for s, _ in items], dtype=np.intp)
