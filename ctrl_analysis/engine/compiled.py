"""The compiled path of :meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>`: choosing it, per-run parameters, running a chunk.

The runner itself is generated and compiled by :mod:`ctrl_analysis.engine.codegen`. Per-run parameters
are run-time values (``Loop.simulate(params=...)``, :mod:`ctrl_analysis.engine.params`): one kernel
parameter row per run of the call, read at the run's index within the call.
"""

from __future__ import annotations

import numpy as np


def compiled_for(loop, engine, funcs, variants):
    """The compiled runner and the kernels' parameters, or ``None`` for the numpy path.

    ``variants`` (block name -> :class:`~ctrl_analysis.engine.params.Variant`) are the run-time
    parameters: a changed block's kernel, or per-run parameter rows.

    Returns
    -------
    tuple or None
        ``(run, P, per_run)``: the runner, each block's parameters as ``(1, n_p)`` (shared) or
        ``(B, n_p)`` rows, and whether each block's are per run.
    """
    import os

    if engine == "numpy" or (engine == "auto" and os.environ.get("CTRL_ANALYSIS_ENGINE") == "numpy"):
        return None
    # imported here: _kernels re-exports kernels of the estimators, which `import ctrl_analysis` must not load
    from .codegen import available, compiled_runner, kernel_of
    
    why = None
    if not available():
        why = "numba is not installed"
    elif funcs:
        why = "callable inputs need the numpy path"
    kernels = {}
    variants = variants or {}
    if why is None:
        for p in loop.placed:
            v = variants.get(p.name)
            if v is not None and v.groups is not None and v.rows is None:
                why = f"block {p.name!r} ({type(p.block).__name__}) has per-run parameters but no kernel"
                break
            k = kernel_of(p.block if v is None else v.block)
            if k is None:
                why = f"block {p.name!r} ({type(p.block).__name__}) has no kernel"
                break
            if v is not None and v.rows is not None:
                k = k._replace(params=v.rows)
            elif np.ndim(k.params) != 1:
                raise ValueError(f"block {p.name!r} ({type(p.block).__name__}): its kernel parameters must be one "
                                 f"vector shared by every run, got shape {np.shape(k.params)}; give per-run values "
                                 f"to Loop.simulate(params={{block: {{parameter: values}}}})")
            kernels[p.name] = k
    if why is not None:
        if engine == "compiled":
            raise ValueError(f"engine='compiled' is not possible for this loop: {why}")
        _tell_slow_path(loop, why)
        return None
    if variants or getattr(loop, "_kernels_checked", None) is not loop.placed:
        check_kernel_reads(loop, kernels)
        if not variants:
            loop._kernels_checked = loop.placed  # once per loop: its blocks (and their parameters) are fixed
    try:
        run = compiled_runner(loop, kernels)
    except Exception as exc:  # a kernel numba cannot compile: say so, and use the numpy path under "auto"
        if engine == "compiled":
            raise
        import warnings

        warnings.warn(f"compiled engine unavailable for this loop ({type(exc).__name__}: {exc}); "
                      "using the numpy engine", RuntimeWarning, stacklevel=3)
        return None
    P = [_params_2d(p.name, kernels[p.name].params) for p in loop.placed]
    return run, P, [np.ndim(kernels[p.name].params) == 2 for p in loop.placed]


class SlowPathWarning(RuntimeWarning):
    """A loop runs on the numpy engine under ``engine="auto"`` (told once per loop, with what would make it compile)."""


#: What makes each reason for the numpy path go away.
_REMEDY = {
    "no kernel": ("write it as a kernel block (a Layout and scalar kernels, CONTRIBUTING.md 'Add a block'), or a "
                  "sum/difference/selection as StaticGain"),
    "per-run parameters but no kernel": "write it as a kernel block, whose per-run parameters the compiled engine reads",
    "callable inputs": "give the input as an array of its samples, shape (N,) or (N, B)",
    "numba is not installed": "install numba",
}


def _tell_slow_path(loop, why: str) -> None:
    """Warn once per loop that it runs on the numpy engine: which block (or input) and what would make it compile."""
    if getattr(loop, "_slow_path_told", False):
        return
    loop._slow_path_told = True
    import warnings

    remedy = next((r for key, r in _REMEDY.items() if key in why), "")
    warnings.warn(f"this loop runs on the numpy engine, often 10-100x slower than compiled: {why}"
                  + (f"; to compile it, {remedy}" if remedy else "")
                  + " (engine='numpy' chooses the numpy engine without this warning)", SlowPathWarning, stacklevel=4)


def check_kernel_reads(loop, kernels: dict) -> None:
    """Call every kernel once in Python on vectors of the engine's sizes: an out-of-range index, or a write into the inputs, is an error.

    Compiled code does not check bounds, so a kernel reading a parameter slot its block did not
    fill (or a state, input or output beyond the block's) would return garbage; the same function
    run by Python raises ``IndexError``. The compiled runner hands a block its inputs as a view of
    the loop's signals (no copy), so a kernel that wrote into ``u`` would change other blocks'
    inputs: that is an error too. Each kernel is tried at the block's initial state with
    inputs 0, 1 and -1, with the first and last row of per-run parameters (other exceptions, e.g. a
    division by zero at those values, are not this check's concern).

    Parameters
    ----------
    loop : Loop
    kernels : dict of block name -> BlockKernel

    Raises
    ------
    ValueError
        Naming the block, the kernel function, the sizes it was given and the index it read (or
        saying that it wrote into its inputs).
    """
    import warnings

    for p in loop.placed:
        k = kernels[p.name]
        params = np.asarray(k.params, dtype=float)
        rows = [params] if params.ndim != 2 else [params[0], params[-1]]
        x0 = np.asarray(p.block.initial_state(), dtype=float).reshape(-1)
        sizes = {"output": len(p.outputs), "update": x0.size, "rhs": x0.size}
        for kind in ("output", "update", "rhs"):
            fn = getattr(k, kind)
            if fn is None:
                continue
            for row in rows:
                for level in (0.0, 1.0, -1.0):
                    args = (0.0, x0 + level, np.full(len(p.inputs), level), row.copy(), np.zeros(sizes[kind]))
                    try:
                        with np.errstate(all="ignore"), warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            fn(*args)
                    except IndexError as exc:
                        raise ValueError(
                            f"block {p.name!r} ({type(p.block).__name__}): its kernel {kind} "
                            f"{getattr(fn, '__name__', fn)!r} reads or writes outside its vectors (state {x0.size}, "
                            f"inputs {len(p.inputs)}, parameters {row.size}, result {sizes[kind]}): {exc}; the "
                            f"compiled engine would return garbage") from None
                    except Exception:  # noqa: BLE001, S112 - only out-of-range indices are checked here
                        continue
                    if np.any(args[2] != level):
                        raise ValueError(
                            f"block {p.name!r} ({type(p.block).__name__}): its kernel {kind} "
                            f"{getattr(fn, '__name__', fn)!r} writes into its inputs u; the compiled engine "
                            f"passes them as a view of the loop's signals (write into the last argument only)")


def _params_2d(name, params):
    """A kernel's parameters as a C-contiguous ``(1, n_p)`` (shared) or ``(B, n_p)`` (per run) array."""
    a = np.asarray(params, dtype=float)
    if a.ndim not in (1, 2):
        raise ValueError(f"block {name!r}: kernel params must be 1-D (shared) or 2-D (one row per run), "
                         f"got shape {a.shape}")
    return np.ascontiguousarray(a[None, :] if a.ndim == 1 else a)


def run_compiled(loop, runner, plan, n_steps, t, x, held, bound, keep_cols, store, xs, diverged, div_step, div_where,
                 lo=0, every=1):
    """One chunk through the compiled runner, writing into the result slices (every ``every``-th sample).

    ``lo`` is the chunk's first run within the call: per-run parameter rows ``lo:lo+B`` are its runs'.
    """
    run, P, per_run = runner
    B = x.shape[0]
    P = [Pi[lo:lo + B] if pr else Pi[:1] for Pi, pr in zip(P, per_run)]
    PS = np.array(per_run, dtype=np.intp)
    col = plan.col
    S0 = np.zeros(len(plan.names))
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
        keep_cols, every, store, xs_arg, float(bound), diverged, div_step, div_where, PS, *P)
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
