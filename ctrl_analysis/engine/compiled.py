"""The compiled path of :meth:`~ctrl_analysis.engine.loop.Loop.simulate`: choosing it, per-run parameters, a chunk.

The runner itself is generated and compiled by :mod:`ctrl_analysis.engine.codegen`. Per-run parameters
are run-time values (``Loop.simulate(params=...)``, :mod:`ctrl_analysis.engine.params`): one kernel
parameter row per run of the call, read at the run's index within the call.
"""

from __future__ import annotations

import numpy as np

from .kernels import KernelBlock

_DERIVED = KernelBlock.kernel

def compiled_for(plan, engine, funcs, variants):
    """The compiled runner and the kernels' parameters, or ``None`` for the numpy path.

    Parameters
    ----------
    plan : Plan
        The loop's plan (:attr:`Loop.plan <ctrl_analysis.engine.loop.Loop.plan>`).
    engine : {"auto", "numpy", "compiled"}
    funcs : dict
        The callable inputs (they need the numpy path).
    variants : dict of str -> Variant or None
        The run-time parameters (:mod:`ctrl_analysis.engine.params`): a changed block's kernel, or
        per-run parameter rows.

    Returns
    -------
    tuple or None
        ``(run, P, per_run)``: the runner, each block's parameters as ``(1, n_p)`` (shared) or
        ``(B, n_p)`` rows, and whether each block's are per run. Without run-time parameters it is
        found once per plan (its blocks are fixed) and kept in ``plan.cache``.
    """
    import os

    if engine == "numpy" or (engine == "auto" and os.environ.get("CTRL_ANALYSIS_ENGINE") == "numpy"):
        return None
    if not funcs and not variants:
        memo = plan.cache.get("runner")
        if memo is not None:
            fresh = _fresh_params(plan, memo)
            if fresh is not None:
                return fresh
    found = _compiled_for(plan, engine, funcs, variants or {})
    if found is not None and not funcs and not variants:
        plan.cache["runner"] = found + (_kernel_functions(plan),)
        return found
    return found


def _kernel_functions(plan):
    """Each block's kernel functions, or ``None`` if a block has no kernel now."""
    from .codegen import kernel_of

    ks = [kernel_of(p.block) for p in plan.placed]
    return None if any(k is None for k in ks) else tuple((k.output, k.update, k.rhs) for k in ks)


def _fresh_params(plan, memo):
    """The cached runner with the blocks' current parameter vectors (a block's attributes may have been changed
    since), or ``None`` when a block's kernel functions or parameter sizes changed (then the runner is found anew)."""
    run, P, per_run, functions = memo
    fresh = []
    for p, Pi, fn in zip(plan.placed, P, functions, strict=True):
        b = p.block
        if type(b).kernel is _DERIVED:  # KernelBlock.kernel() without building its record: the same two reads
            k, a = b.kernels, b.kernel_params
        else:
            own = getattr(b, "kernel", None)  # codegen.kernel_of, without importing it at every call
            k = own() if callable(own) else None
            if k is None:
                return None
            a = k.params
        if (k.output, k.update, k.rhs) != fn:
            return None
        if type(a) is not np.ndarray or a.dtype != np.float64 or a.ndim != 1 or a.shape[0] != Pi.shape[1]:
            return None
        fresh.append(a.reshape(1, -1) if a.flags.c_contiguous else np.ascontiguousarray(a).reshape(1, -1))
    return run, fresh, per_run


def _compiled_for(plan, engine, funcs, variants):
    # imported here: _kernels re-exports kernels of the estimators, which `import ctrl_analysis` must not load
    from .codegen import available, compiled_runner, kernel_of

    why = None
    if not available():
        why = "numba is not installed"
    elif funcs:
        why = "callable inputs need the numpy path"
    kernels = {}
    if why is None:
        for p in plan.placed:
            v = variants.get(p.name)
            if v is not None and v.rows is not None and not v.block.kernel_rows:
                why = f"block {p.name!r} ({type(p.block).__name__}) has per-run parameters but no kernel"
                break
            k = kernel_of(p.block if v is None else v.block)
            if k is None:
                why = f"block {p.name!r} ({type(p.block).__name__}) has no kernel"
                break
            if k.params is None:
                raise ValueError(f"block {p.name!r} ({type(p.block).__name__}): its kernel() gave Kernels without "
                                 f"params; give the block's parameter vector, Kernels(..., params=vector)")
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
        _tell_slow_path(plan, why)
        return None
    if variants or not plan.cache.get("kernels_checked"):
        check_kernel_reads(plan, kernels)
        if not variants:
            plan.cache["kernels_checked"] = True  # once per loop: its blocks (and their parameters) are fixed
    try:
        run = compiled_runner(plan, kernels)
    except Exception as exc:  # a kernel numba cannot compile: say so, and use the numpy path under "auto"
        if engine == "compiled":
            raise
        import warnings

        warnings.warn(f"compiled engine unavailable for this loop ({type(exc).__name__}: {exc}); "
                      "using the numpy engine", RuntimeWarning, stacklevel=6)
        return None
    P = [_params_2d(p.name, kernels[p.name].params) for p in plan.placed]
    return run, P, [np.ndim(kernels[p.name].params) == 2 for p in plan.placed]


class SlowPathWarning(RuntimeWarning):
    """A loop runs on the numpy engine under ``engine="auto"`` (told once per loop, with what would make it compile)."""


#: What makes each reason for the numpy path go away.
_REMEDY = {
    "no kernel": ("write it as a kernel block (a Layout and scalar kernels, CONTRIBUTING.md 'Add a block'), or a "
                  "sum/difference/selection as StaticGain"),
    "per-run parameters but no kernel": ("write it as a kernel block, whose per-run parameters the compiled engine "
                                         "reads"),
    "callable inputs": "give the input as an array of its samples, shape (N,) or (N, B)",
    "numba is not installed": "install numba",
}


def _tell_slow_path(plan, why: str) -> None:
    """Warn once per loop (its plan) that it runs on the numpy engine: which block (or input) would compile how."""
    if plan.cache.get("slow_path_told"):
        return
    plan.cache["slow_path_told"] = True
    import warnings

    remedy = next((r for key, r in _REMEDY.items() if key in why), "")
    warnings.warn(f"this loop runs on the numpy engine, often 10-100x slower than compiled: {why}"
                  + (f"; to compile it, {remedy}" if remedy else "")
                  + " (execution=Execution(engine='numpy') chooses the numpy engine without this warning)",
                  SlowPathWarning, stacklevel=7)


def check_kernel_reads(plan, kernels: dict) -> None:
    """Call every kernel once in Python on vectors of the engine's sizes: an out-of-range index or input write fails.

    Compiled code does not check bounds, so a kernel reading a parameter slot its block did not
    fill (or a state, input or output beyond the block's) would return garbage; the same function
    run by Python raises ``IndexError``. The compiled runner hands a block its inputs as a view of
    the loop's signals (no copy), so a kernel that wrote into ``u`` would change other blocks'
    inputs: that is an error too. Each kernel is tried at the block's initial state with
    inputs 0, 1 and -1, with the first and last row of per-run parameters (other exceptions, e.g. a
    division by zero at those values, are not this check's concern).

    Parameters
    ----------
    plan : Plan
        The loop's plan (its placed blocks).
    kernels : dict of block name -> Kernels

    Raises
    ------
    ValueError
        Naming the block, the kernel function, the sizes it was given and the index it read (or
        saying that it wrote into its inputs).
    """
    import warnings

    for p in plan.placed:
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


def run_compiled(plan, runner, t, held, bound, rec, lo=0):
    """One chunk through the compiled runner, writing into the chunk's record (every ``rec.every``-th sample).

    Parameters
    ----------
    plan : Plan
    runner : tuple
        ``(run, P, per_run)`` from :func:`compiled_for`.
    t : numpy.ndarray, shape (N+1,)
    held : dict of str -> numpy.ndarray
        The chunk's held inputs.
    bound : float
    rec : Record
        The chunk's part of the record (:class:`~ctrl_analysis.engine.engines.Record`); ``rec.x``
        holds the initial states and receives the final ones.
    lo : int
        The chunk's first run within the call: per-run parameter rows ``lo:lo+B`` are its runs'.
    """
    run, P, per_run = runner
    x = rec.x
    B = x.shape[0]
    n_steps = t.shape[0] - 1
    if any(per_run):
        P = [Pi[lo:lo + B] if pr else Pi[:1] for Pi, pr in zip(P, per_run, strict=True)]
    PS = plan.cache.get(("PS", tuple(per_run)))
    if PS is None:
        PS = plan.cache[("PS", tuple(per_run))] = np.array(per_run, dtype=np.intp)
    col = plan.col
    S0 = np.zeros(len(plan.names))
    shared, runs_ = [], []
    for s, a in held.items():
        if a.ndim == 0:
            S0[col[s]] = a
        elif a.ndim == 2:
            runs_.append((s, a))
        else:
            shared.append((s, a))
    # inputs that differ per run, (., N+1, B) (each a block copy of its (N, B) record), and inputs
    # shared by every run, (N+1, .): a shared record is not copied B times
    H, HC = _held_matrix(runs_, n_steps, B, col)
    HS, HCS = _held_matrix(shared, n_steps, None, col)
    xs_arg = _NO_XS if rec.xs is None else rec.xs
    # the record's own states (a C-contiguous block of rows) are stepped in place: they end as the final states,
    # as the numpy path leaves them (final_states, chunk carry-over)
    X = x if x.flags.c_contiguous and x.dtype == np.float64 else np.array(x, dtype=float, order="C")
    run(n_steps, t, plan.dt / plan.substeps, plan.substeps, X, H, HC, HS, HCS, S0,
        rec.keep, rec.every, rec.store, xs_arg, float(bound), rec.diverged, rec.div_step, rec.div_where, PS, *P)
    if X is not x:
        x[...] = X


_NO_XS = np.empty((0, 0, 0))
_NO_COLS = np.empty(0, dtype=np.intp)
_NO_SHARED = np.empty((1, 1))
_NO_RUNS = np.empty((1, 1, 1))


def _held_matrix(items, n_steps, B, col):
    """Held inputs as one array: ``(k, N+1, B)`` per run (``B`` given) or ``(N+1, k)`` shared; and their columns."""
    k = max(len(items), 1)
    if not items:  # the runner reads no row of it (it loops over the empty columns)
        return (_NO_SHARED if B is None else _NO_RUNS), _NO_COLS
    H = np.empty((n_steps + 1, k) if B is None else (k, n_steps + 1, B))
    for j, (_, a) in enumerate(items):
        m = min(a.shape[0], n_steps + 1)
        dst = H[:, j] if B is None else H[j]
        dst[:m] = a[:m]
        dst[m:] = a[m - 1]  # row N repeats row N-1 when absent
    return H, np.array([col[s] for s, _ in items], dtype=np.intp)
