"""Compiled per-run kernels of blocks, and the compiled runner of a :class:`~ctrl_analysis.engine.loop.Loop`.

The batched block methods (``rhs``/``update``/``output`` on ``(B, n)`` arrays) pay numpy's call
overhead on every operation, which dominates at small and medium batches. A block can also offer a
**kernel**: plain-arithmetic functions on *one run* that numba compiles (``njit``, one thread,
``cache=True``), with signatures

* ``rhs(t, x, u, p, dx)`` (continuous) or ``update(t, x, u, p, x_next)`` (discrete), and
* ``output(t, x, u, p, y)``,

writing their result into the last argument; ``x``, ``u`` are the run's state and input vectors
and ``p`` a float64 parameter vector fixed when the block was built (``BlockKernel.params``). Values
that differ per run (a plant gain, an observer bandwidth, a case flag) are given to the simulation,
``Loop.simulate(params=...)`` (:mod:`ctrl_analysis.engine.params`): the engine passes the runner
one parameter row per run and slices the rows with the batch's chunks and processes. A block gives
its kernel with a method ``kernel() -> BlockKernel`` (or ``None``), which :func:`kernel_of` calls; the engine knows
no concrete block. When every block of a loop has a kernel, :meth:`Loop.simulate
<ctrl_analysis.engine.loop.Loop.simulate>` (``engine="auto"`` or ``"compiled"``) generates one numba
function for the whole loop — runs outermost, the same sample/stage order and the same RK4
arithmetic as the numpy path — and runs it; otherwise it uses the numpy path.

A :class:`~ctrl_analysis.engine.kernels.KernelBlock` has no numpy twin of its kernels: its batched
methods apply the same functions to the batch's columns (or run by run), so both engines run one
source per equation (``tests/lib/test_kernel_blocks.py`` holds them equal bit for bit for every
library block). A block that writes its own ``kernel()`` beside numpy methods keeps a test holding
the pair equal (``tests/lib/test_speed_kernels.py``).

The generated runner is cached in memory per loop structure and process, and on disk (numba's
cache, :func:`cache_dir`); numba's compile time (a few seconds per structure on a cold cache) is
reported by :func:`compile_seconds`.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

# Σ's and the ESO's kernels live with their blocks; analysis/ and arena/ still import them from here
from .kernels import BlockKernel

__all__ = ["available", "compile_seconds", "compiled_runner", "kernel_of"]


def available() -> bool:
    """Whether numba can be imported (the compiled engine is optional).

    Returns
    -------
    bool
    """
    try:
        import numba  # noqa: F401
    except ImportError:  # pragma: no cover - numba is installed in the project's environment
        return False
    return True


def kernel_of(block) -> BlockKernel | None:
    """The block's kernel: its own ``kernel()`` method, or ``None`` (numpy only).

    The engine knows no concrete block: a block that can run compiled says so through ``kernel()``.

    Parameters
    ----------
    block : Block

    Returns
    -------
    BlockKernel or None
    """
    own = getattr(block, "kernel", None)
    return own() if callable(own) else None


# ------------------------------------------------------------------ the compiled loop runner
_JIT: dict = {}
_RUNNERS: dict = {}
_COMPILE = {"seconds": 0.0}


def compile_seconds() -> float:
    """Total seconds this process spent compiling loop runners (first call of each structure).

    Returns
    -------
    float
    """
    return _COMPILE["seconds"]


def _jit(fn):
    import numba

    if fn not in _JIT:
        try:
            _JIT[fn] = numba.njit(cache=True, error_model="numpy", inline="always")(fn)
        except RuntimeError:  # no file to cache against (a notebook cell, exec'd code): compile, don't cache
            _JIT[fn] = numba.njit(cache=False, error_model="numpy", inline="always")(fn)
    return _JIT[fn]


def _gen_source(blocks, order, stage, discrete, continuous, nc, method):
    """Python source of the runner (see :func:`compiled_runner`).

    Runs are stepped side by side (steps outermost, so the result rows are written in memory
    order; runs outermost was measured 1.5x slower at B = 1000, its strided stores miss the TLB).
    The kernels are compiled with ``inline="always"`` so the whole loop is one function (measured
    2.2x faster than calls at B = 1000, about a second more compile time per structure); states and
    derivatives are passed as views, inputs and outputs through small scratch vectors allocated once.
    """
    L = []
    add = L.append
    pargs = ", ".join(f"P{i}" for i in range(len(blocks)))

    def call(i, kind, t, xx, out, ind):
        """Lines evaluating block ``i`` (``kind``: out / rhs / upd) on state vector ``xx``."""
        b = blocks[i]
        lo, hi = b["sl"]
        # the state and the derivative / next state are passed as views (inlined kernels: pointer
        # arithmetic); the inputs are gathered from the signal row with literal indices
        xv = f"X[b, {lo}:{hi}]" if xx == "X" else f"{xx}[{lo}:{hi}]"
        lines = [f"UB{i}[{j}] = S[{c}]" for j, c in enumerate(b["ic"])]
        pr = f"P{i}[b * PS[{i}]]"  # PS[i] = 1: one row per run, 0: one row shared
        if kind == "out":
            lines.append(f"K{i}_out({t}, {xv}, UB{i}, {pr}, YB{i})")
            lines += [f"S[{c}] = YB{i}[{j}]" for j, c in enumerate(b["oc"])]
        else:
            fn = "rhs" if kind == "rhs" else "upd"
            lines.append(f"K{i}_{fn}({t}, {xv}, UB{i}, {pr}, {out}[{lo}:{hi}])")
        return [ind + s for s in lines]

    def stage_lines(tau, xx, dx, ind):
        out = []
        for i in stage:
            out += call(i, "out", tau, xx, None, ind)
        for i in continuous:
            out += call(i, "rhs", tau, xx, dx, ind)
        return out

    add(f"def run(n_steps, t, h, substeps, X0, H, HC, HS, HCS, S0, KEEP, EVERY, store, xs, bound, diverged, div_step, PS, "
        f"{pargs}):")
    add("    B = X0.shape[0]")
    add("    n = X0.shape[1]")
    for i, b in enumerate(blocks):
        lo, hi = b["sl"]
        add(f"    XB{i} = np.empty({hi - lo}); UB{i} = np.empty({len(b['ic'])}); YB{i} = np.empty({b['np']}); "
            f"DB{i} = np.empty({hi - lo})")
    add(f"    k1 = np.empty({nc}); KS = np.empty((4, {nc}))")
    add(f"    xt = np.empty({nc}); xc = np.empty({nc})")
    add("    xn = np.empty(n)")
    add("    X = X0  # stepped in place: the caller reads the final state from it")
    # one signal vector serves every run: each sample writes the held inputs and every block's
    # output before anything reads them, and the constant inputs (S0) are never written
    add("    S = S0.copy()")
    add("    for k in range(n_steps + 1):")
    add("        tk = t[k]")
    add("        for b in range(B):")
    add("            for j in range(HC.shape[0]):")
    add("                S[HC[j]] = H[j, k, b]")
    add("            for j in range(HCS.shape[0]):")
    add("                S[HCS[j]] = HS[k, j]")
    ind = " " * 12
    for i in order:
        L.extend(call(i, "out", "tk", "X", None, ind))
    add("            if k % EVERY == 0:  # every EVERY-th sample is kept")
    add("                for j in range(KEEP.shape[0]):")
    add("                    store[k // EVERY, b, j] = S[KEEP[j]]")
    add("                if xs.shape[0] > 0:")
    add("                    for j in range(n):")
    add("                        xs[k // EVERY, b, j] = X[b, j]")
    add("            if k == n_steps:")
    add("                continue")
    add("            for j in range(n):")
    add("                xn[j] = X[b, j]")
    for i in discrete:
        L.extend(call(i, "upd", "tk", "X", "xn", ind))
    if nc:
        add(f"            for j in range({nc}):")
        add("                xc[j] = X[b, j]")
        add("            tau = tk")
        add("            for _ in range(substeps):")
        ind2 = " " * 16
        if method == "rk4":
            # ctrl_analysis.engine.integrators' rk4_point / rk4_sum (the numpy engine's RK4 too) on each
            # state value; the four stages are one loop, so the kernels are inlined once, not four times
            add("                for s in range(4):")
            add("                    if s == 0:")
            L.extend(f"                        xt[{j}] = xc[{j}]" for j in range(nc))
            add("                        ts = tau")
            add("                    else:")
            add("                        a = h if s == 3 else 0.5 * h")
            L.extend(f"                        xt[{j}] = RK4_POINT(xc[{j}], KS[s - 1, {j}], a)" for j in range(nc))
            add("                        ts = tau + a")
            L.extend(stage_lines("ts", "xt", "KS[s]", " " * 20))
            L.extend(f"                xc[{j}] = RK4_SUM(xc[{j}], KS[0, {j}], KS[1, {j}], KS[2, {j}], KS[3, {j}], h)"
                     for j in range(nc))
        else:
            # ctrl_analysis.simulate.euler_step
            L.extend(stage_lines("tau", "xc", "k1", ind2))
            L.extend(f"                xc[{j}] = xc[{j}] + h * k1[{j}]" for j in range(nc))
        add("                tau += h")
        add(f"            for j in range({nc}):")
        add("                xn[j] = xc[j]")
    # divergence: ctrl_analysis.engine.integrators.is_bad, the numpy engine's test too
    add("            bad = False")
    add("            for j in range(n):")
    add("                v = xn[j]")
    add("                if IS_BAD(v, bound):")
    add("                    bad = True")
    add("                X[b, j] = v")
    add("            if bad and not diverged[b]:")
    add("                diverged[b] = True")
    add("                div_step[b] = k + 1")
    add("                for j in range(n):")
    add("                    X[b, j] = np.nan")
    return "\n".join(L) + "\n"


def compiled_runner(loop, kernels: dict):
    """The numba runner of ``loop`` (generated once per structure and process) and its constant arguments.

    Parameters
    ----------
    loop : Loop
    kernels : dict of block name -> BlockKernel
        Every block's kernel.

    Returns
    -------
    run : callable
        ``run(n_steps, t, h, substeps, X0, H, HC, HS, HCS, S0, KEEP, EVERY, store, xs, bound, diverged, div_step, PS, *P)``:
        ``H`` holds the per-run inputs ``(., N+1, B)`` at signal columns ``HC``, ``HS`` the inputs
        shared by every run ``(N+1, .)`` at columns ``HCS``.
    consts : dict
        ``IC<i>``/``OC<i>`` index arrays are baked into the runner; ``P`` lists the parameter vectors.
    """
    import numba

    plan = loop._plan()
    col = plan.col
    names = [p.name for p in loop.placed]
    blocks = []
    for p in loop.placed:
        sl = loop.slices.get(p.name, slice(0, 0))
        blocks.append({"ic": [col[s] for s in p.inputs], "oc": [col[s] for s in p.outputs],
                       "np": len(p.outputs), "sl": (sl.start, sl.stop)})
    idx = {n: i for i, n in enumerate(names)}
    stage_set = {e[0] for e in plan.stage}
    stage = [idx[p.name] for p in loop.stage_order if p.block in stage_set]
    order = [idx[p.name] for p in loop.order]
    discrete = [idx[p.name] for p in loop.discrete]
    continuous = [idx[p.name] for p in loop.continuous]
    key = (tuple((tuple(b["ic"]), tuple(b["oc"]), b["sl"]) for b in blocks), tuple(order), tuple(stage),
           tuple(discrete), tuple(continuous), loop.n_continuous, loop.method,
           tuple((kernels[n].output, kernels[n].rhs, kernels[n].update) for n in names))
    if key not in _RUNNERS:
        t0 = time.perf_counter()
        src = _gen_source(blocks, order, stage, discrete, continuous, loop.n_continuous, loop.method)
        from .integrators import is_bad, rk4_point, rk4_sum

        fns = {"RK4_POINT": rk4_point, "RK4_SUM": rk4_sum, "IS_BAD": is_bad}
        for i, n in enumerate(names):
            k = kernels[n]
            fns[f"K{i}_out"] = k.output
            if k.rhs is not None:
                fns[f"K{i}_rhs"] = k.rhs
            if k.update is not None:
                fns[f"K{i}_upd"] = k.update
        module = _runner_module(src, fns)
        for name, fn in fns.items():
            setattr(module, name, _jit(fn))
        f64, i64 = numba.float64, numba.int64
        sig = numba.void(i64, f64[::1], f64, i64, f64[:, ::1], f64[:, :, ::1], numba.intp[::1], f64[:, ::1],
                         numba.intp[::1], f64[::1],
                         numba.intp[::1], i64, f64[:, :, :], f64[:, :, :], f64, numba.boolean[:], i64[:], numba.intp[::1],
                         *[f64[:, ::1] for b in blocks])
        run = numba.njit(sig, cache=True, error_model="numpy")(module.run)
        _RUNNERS[key] = (run, time.perf_counter() - t0)
        _COMPILE["seconds"] += _RUNNERS[key][1]
    return _RUNNERS[key][0]


def cache_dir() -> Path:
    """Where generated loop runners (and numba's cache of them) live: ``$CTRL_ANALYSIS_CACHE`` or ``~/.cache``."""
    base = os.environ.get("CTRL_ANALYSIS_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "ctrl_analysis")
    return Path(base) / "kernels"


def _runner_module(src: str, fns: dict):
    """Import the generated source from a file named by its hash (and the kernels' sources), so numba can cache it."""
    import hashlib
    import importlib.util
    import inspect

    digest = hashlib.sha1(src.encode())
    for name in sorted(fns):
        try:
            digest.update(inspect.getsource(fns[name]).encode())
        except (OSError, TypeError):  # pragma: no cover - source unavailable: key on the identity
            digest.update(repr(fns[name]).encode())
    d = cache_dir()
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError:  # read-only home: a per-user temporary directory still caches within the machine
        import tempfile

        d = Path(tempfile.gettempdir()) / f"ctrl_analysis-{os.getuid() if hasattr(os, 'getuid') else 0}" / "kernels"
        d.mkdir(parents=True, exist_ok=True)
    path = d / f"loop_{digest.hexdigest()[:20]}.py"
    if not path.exists():
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text("import numpy as np\n\n\n" + src, encoding="utf-8")
        os.replace(tmp, path)
    spec = importlib.util.spec_from_file_location(f"_ctrl_analysis_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # numba's cache re-imports the module by name
    spec.loader.exec_module(module)
    return module
