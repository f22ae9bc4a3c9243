"""Compiled per-run kernels of blocks, and the compiled runner of a :class:`~ctrl_analysis.engine.loop.Loop`.

The batched block methods (``rhs``/``update``/``output`` on ``(B, n)`` arrays) pay numpy's call
overhead on every operation, which dominates at small and medium batches. A block can also offer a
**kernel**: plain-arithmetic functions on *one run* that numba compiles (``njit``, one thread,
``cache=True``), with signatures

* ``rhs(t, x, u, p, dx)`` (continuous) or ``update(t, x, u, p, x_next)`` (discrete), and
* ``output(t, x, u, p, y)``,

writing their result into the last argument; ``x``, ``u`` are the run's state and input vectors
and ``p`` a float64 parameter vector fixed when the block was built (``Kernels.params``). Values
that differ per run (a plant gain, an observer bandwidth, a case flag) are given to the simulation,
``Loop.simulate(params=...)`` (:mod:`ctrl_analysis.engine.params`): the engine passes the runner
one parameter row per run and slices the rows with the batch's chunks and processes. A block gives
its kernel with a method ``kernel() -> Kernels`` (or ``None``), which :func:`kernel_of` calls; the engine knows
no concrete block. When every block of a loop has a kernel, :meth:`Loop.simulate
<ctrl_analysis.engine.loop.Loop.simulate>` (``engine="auto"`` or ``"compiled"``) generates one numba
function for the whole loop — steps outermost and the batch's runs inside, the same sample/stage
order and the same RK4 arithmetic as the numpy path — and runs it; otherwise it uses the numpy
path. The generated code (:func:`_gen_source`, whose docstring gives the measured reasons of its
shape) inlines every kernel, keeps its scratch vectors on the stack and hands each kernel views of
them of compile-time length, so LLVM keeps most values in registers between the kernels.

A :class:`~ctrl_analysis.engine.kernels.KernelBlock` has no numpy twin of its kernels: its batched
methods apply the same functions to the batch's columns (or run by run), so both engines run one
source per equation (``tests/lib/test_kernel_blocks.py`` holds them equal bit for bit for every
library block). A block that writes its own ``kernel()`` beside numpy methods keeps a test holding
the pair equal (``tests/lib/test_speed_kernels.py``).

The generated runner is cached in memory per loop structure and process, and on disk (numba's
cache, :func:`~ctrl_analysis.engine.jit.cache_dir`); numba's compile time (a few seconds per structure on a cold cache)
is
reported by :func:`compile_seconds`.
"""

from __future__ import annotations

import contextlib
import inspect
import time
from typing import NamedTuple

from .jit import _JIT, _jit, _runner_module, cacheable, compile_lock
from .kernels import Kernels

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


def kernel_of(block) -> Kernels | None:
    """The block's kernel: its own ``kernel()`` method, or ``None`` (numpy only).

    The engine knows no concrete block: a block that can run compiled says so through ``kernel()``.

    Parameters
    ----------
    block : Block

    Returns
    -------
    Kernels or None
    """
    own = getattr(block, "kernel", None)
    return own() if callable(own) else None


# ------------------------------------------------------------------ the compiled loop runner
_RUNNERS: dict = {}
_COMPILE = {"seconds": 0.0}


def compile_seconds() -> float:
    """Total seconds this process spent compiling loop runners (first call of each structure).

    Returns
    -------
    float
    """
    return _COMPILE["seconds"]


def _scratch_vector():
    """``SCRATCH(n)``: a float64 vector of literal length ``n`` on the runner's stack (a numba intrinsic).

    An ``alloca`` in the function's entry block, wrapped as a C-contiguous array without a
    meminfo: no allocation, no reference counting of the views taken from it, and LLVM knows that
    it aliases nothing else, so the values a kernel writes into it are forwarded to the next
    kernel's reads and most of them stay in registers (scratch vectors from ``np.empty`` may
    alias every array argument, so every store forced the values around it to be reloaded:
    measured 1.4x slower on Example 1).
    """
    if "SCRATCH" not in _JIT:
        from numba import types
        from numba.core import cgutils
        from numba.extending import intrinsic
        from numba.np.arrayobj import make_array, populate_array

        @intrinsic
        def scratch(typingctx, size):
            if not isinstance(size, types.IntegerLiteral):
                return None
            n = size.literal_value
            arrty = types.Array(types.float64, 1, "C")

            def codegen(context, builder, sig, args):
                intp = context.get_value_type(types.intp)
                data = cgutils.alloca_once(builder, context.get_value_type(types.float64),
                                           size=intp(max(n, 1)))
                ary = make_array(arrty)(context, builder)
                populate_array(ary, data=data, shape=cgutils.pack_array(builder, [intp(n)]),
                               strides=cgutils.pack_array(builder, [intp(8)]), itemsize=intp(8), meminfo=None)
                return ary._getvalue()

            return arrty(size), codegen

        _JIT["SCRATCH"] = scratch
    return _JIT["SCRATCH"]


#: Largest scratch (float64 values) a runner keeps on its stack; a loop needing more uses heap vectors.
STACK_VALUES = 4096


class Wiring(NamedTuple):
    """Where one placed block reads and writes in the generated runner.

    Attributes
    ----------
    inputs, outputs : tuple of int
        The signal columns (of ``S``) the block reads and writes.
    states : tuple of (int, int)
        Its slice ``(start, stop)`` of the loop's state vector (empty for a block without state).
    """

    inputs: tuple
    outputs: tuple
    states: tuple


def _gen_source(blocks, order, stage, discrete, continuous, nc, method, n_signals):
    """Python source of the runner (see :func:`compiled_runner`), for the blocks' :class:`Wiring` in ``blocks``.

    Runs are stepped side by side (steps outermost, so the result rows are written in memory
    order; runs outermost was measured 1.5x slower at B = 1000, its strided stores miss the TLB).
    The kernels are compiled with ``inline="always"`` so the whole loop is one function (measured
    2.2x faster than calls at B = 1000). The code around the kernels is shaped so that LLVM keeps
    the run's values in registers from one kernel to the next; each choice was measured on
    Example 1 at B = 1000 when it was made, interleaved with the code before it (times relative
    to the hand-written compiled loop of ``benchmarks/bench_example1.py``, keep=[]: 2.17x before,
    1.32x after all of them; the arithmetic is unchanged, the results equal bit for bit):

    * every scratch vector (the signals ``S``, the run's state ``x``, a stage's state ``xt`` and
      derivative ``dx``, the RK4 sum ``acc``) lives on the stack (:func:`_scratch_vector`), so
      LLVM knows that it aliases no argument: 2.4x -> 1.7x against the same code on ``np.empty``
      vectors, whose every store forced the values around it to be reloaded;
    * every vector has a length known to the compiler, and so has every view a kernel receives:
      a kernel's loops over its state are unrolled and its indices unchecked. The state is read
      from ``X[b]`` into ``x`` once per step, not viewed in ``X``, whose width is a run-time value;
    * a block's inputs are a view of ``S`` when they are consecutive signals (gathered into a
      small vector otherwise), its outputs always a view of ``S`` (they are consecutive): no
      copies in and out;
    * RK4 steps ``x`` in place and adds each stage's term of ``rk4_sum`` as soon as the stage
      ends (``rk4_acc``: the same operations in the same order), so one derivative vector is
      reused and every scratch index is a constant once LLVM unrolls the per-element loops: the
      stage vectors become registers (1.50x -> 1.45x against four derivative vectors picked by
      the stage index, which must stay in memory). Copies between vectors in memory are avoided
      too: LLVM vectorised one (``xt = xc``) into wide loads of values just stored one by one,
      which stalls store forwarding (6 % of the run time in an earlier version); between stack
      vectors at constant indices a copy is register moves;
    * the four stages are one loop, so each kernel is inlined once by numba (unrolling them in the
      source gained 2 % for twice the compile time); LLVM unrolls that loop instead, allowed a
      larger budget while the runner compiles (:data:`UNROLL_BUDGET`: 1.44x -> 1.32x, no
      measurable compile time). The per-element loops (RK4 formulas, the divergence test) are
      loops in the source too: generated line by line they inlined ``rk4_point`` and friends once
      per state value, a third of the compile time;
    * per run, each block's parameter row index is computed once per step, and per step the
      decimation test once for all runs.
    """
    L = []
    add = L.append
    n = max([b.states[1] for b in blocks] + [0])  # states: the continuous ones first, x[:nc]
    rk4 = method == "rk4"
    gathered = [i for i, b in enumerate(blocks) if not _consecutive(b.inputs)]
    values = n_signals + n + (n if discrete else 0) + 3 * nc + sum(
        len(blocks[i].inputs) for i in gathered)
    new = "SCRATCH" if values <= STACK_VALUES else "np.empty"

    def call(i, kind, t, xv, out, ind):
        """Lines evaluating block ``i`` (``kind``: out / rhs / upd) on state vector ``xv``, into ``out``."""
        b = blocks[i]
        lo, hi = b.states
        if i in gathered:
            lines = [f"UB{i}[{j}] = S[{c}]" for j, c in enumerate(b.inputs)]
            u = f"UB{i}"
        else:
            lines, u = [], _view("S", b.inputs)
        if kind == "out":
            out = _view("S", b.outputs)
        else:
            out = f"{out}[{lo}:{hi}]"
        lines.append(f"K{i}_{kind}({t}, {xv}[{lo}:{hi}], {u}, P{i}[r{i}], {out})")
        return [ind + s for s in lines]

    pargs = ", ".join(f"P{i}" for i in range(len(blocks)))
    add(f"def run(n_steps, t, h, substeps, X0, H, HC, HS, HCS, S0, KEEP, EVERY, store, xs, bound, diverged, div_step, "
        "div_where, PS, "
        f"{pargs}):")
    add("    B = X0.shape[0]")
    # one signal vector serves every run: each sample writes the held inputs and every block's
    # output before anything reads them, and the constant inputs (S0) are never written
    add(f"    S = {new}({n_signals})  # every signal at t_k (and at a stage's time)")
    add(f"    for j in range({n_signals}):")
    add("        S[j] = S0[j]")
    for i in gathered:
        add(f"    UB{i} = {new}({len(blocks[i].inputs)})  # block {i}'s inputs, not consecutive signals")
    add(f"    x = {new}({n})  # the run's state at t_k; RK4 steps its continuous part in place")
    if discrete:
        add(f"    xn = {new}({n})  # the discrete states at t_k+1, xn[{nc}:]")
    if nc:
        add(f"    dx = {new}({nc})  # a stage's derivative")
        if rk4:
            add(f"    xt = {new}({nc})  # a stage's state")
            add(f"    acc = {new}({nc})  # the weighted sum of the stage derivatives")
    add("    X = X0  # stepped in place: the caller reads the final state from it")
    add("    for k in range(n_steps + 1):")
    add("        tk = t[k]")
    add("        kept = k % EVERY == 0  # every EVERY-th sample is kept")
    add("        kk = k // EVERY")
    add("        for b in range(B):")
    for i in range(len(blocks)):  # PS[i] = 1: one parameter row per run, 0: one row shared
        add(f"            r{i} = b * PS[{i}]")
    add("            for j in range(HC.shape[0]):")
    add("                S[HC[j]] = H[j, k, b]")
    add("            for j in range(HCS.shape[0]):")
    add("                S[HCS[j]] = HS[k, j]")
    add(f"            for j in range({n}):")
    add("                x[j] = X[b, j]")
    ind = " " * 12
    for i in order:
        L.extend(call(i, "out", "tk", "x", None, ind))
    add("            if kept:")
    add("                for j in range(KEEP.shape[0]):")
    add("                    store[kk, b, j] = S[KEEP[j]]")
    add("                if xs.shape[0] > 0:")
    add(f"                    for j in range({n}):")
    add("                        xs[kk, b, j] = x[j]")
    # a signal that is not finite (a block's output, also while its states stay finite) ends the run here, as a
    # state that leaves the bound does: the numpy engine's test too (numpy_engine.run_numpy)
    # (a branch-free sum first: S[j] * 0.0 is 0 for a finite value and NaN for NaN or ±inf; the signal that went
    # bad is looked for only then)
    # four independent sums, not one: one sum is a chain of dependent additions (4 cycles each, about 100 for
    # Example 1's signals), which LLVM may not reorder; the outcome (0, or NaN) is the same in any order
    quads = n_signals - n_signals % 4
    add("            if not diverged[b]:")
    add("                f0 = 0.0")
    add("                f1 = 0.0")
    add("                f2 = 0.0")
    add("                f3 = 0.0")
    add(f"                for j in range(0, {quads}, 4):")
    add("                    f0 += S[j] * 0.0")
    add("                    f1 += S[j + 1] * 0.0")
    add("                    f2 += S[j + 2] * 0.0")
    add("                    f3 += S[j + 3] * 0.0")
    add(f"                for j in range({quads}, {n_signals}):")
    add("                    f0 += S[j] * 0.0")
    add("                if (f0 + f1) + (f2 + f3) != 0.0:")
    add("                    diverged[b] = True")
    add("                    div_step[b] = k")
    add(f"                    for j in range({n_signals}):")
    add("                        if not abs(S[j]) < np.inf:")
    add(f"                            div_where[b] = {n} + j")
    add("                            break")
    add(f"                    for jj in range({n}):")
    add("                        x[jj] = np.nan")
    add("            if k == n_steps:")
    add("                continue")
    for i in discrete:
        L.extend(call(i, "upd", "tk", "x", "xn", ind))
    if nc:
        add("            tau = tk")
        add("            for _ in range(substeps):")
        if rk4:
            # ctrl_analysis.engine.integrators' rk4_point and rk4_sum (the numpy engine's RK4 too) on each
            # state value, rk4_sum's terms added as the stages end; the four stages are one loop, so
            # the kernels are inlined once, not four times
            add(f"                for j in range({nc}):")
            add("                    xt[j] = x[j]")
            add("                ts = tau")
            add("                for s in range(4):")
            for i in stage:
                L.extend(call(i, "out", "ts", "xt", None, " " * 20))
            for i in continuous:
                L.extend(call(i, "rhs", "ts", "xt", "dx", " " * 20))
            add("                    if s == 0:")
            add(f"                        for j in range({nc}):")
            add("                            acc[j] = dx[j]")
            add("                    elif s < 3:")
            add(f"                        for j in range({nc}):")
            add("                            acc[j] = RK4_ACC(acc[j], dx[j], 2.0)")
            add("                    else:")
            add(f"                        for j in range({nc}):")
            add("                            acc[j] = acc[j] + dx[j]  # rk4_sum's last term")
            add("                    if s < 3:  # the next stage's time and state")
            add("                        a = h if s == 2 else 0.5 * h")
            add(f"                        for j in range({nc}):")
            add("                            xt[j] = RK4_POINT(x[j], dx[j], a)")
            add("                        ts = tau + a")
            add(f"                for j in range({nc}):")
            add("                    x[j] = RK4_END(x[j], acc[j], h)")
        else:
            # ctrl_analysis.engine.integrators.euler_step
            for i in stage:
                L.extend(call(i, "out", "tau", "x", None, " " * 16))
            for i in continuous:
                L.extend(call(i, "rhs", "tau", "x", "dx", " " * 16))
            add(f"                for j in range({nc}):")
            add("                    x[j] = x[j] + h * dx[j]")
        add("                tau += h")
    # divergence: ctrl_analysis.engine.integrators.is_bad, the numpy engine's test too
    add("            bad = -1")
    for lo, hi, vec in ((0, nc, "x"), (nc, n, "xn")):
        if hi > lo:
            add(f"            for j in range({lo}, {hi}):")
            add(f"                v = {vec}[j]")
            add("                if bad < 0 and IS_BAD(v, bound):")
            add("                    bad = j")
            add("                X[b, j] = v")
    add("            if bad >= 0 and not diverged[b]:")
    add("                diverged[b] = True")
    add("                div_step[b] = k + 1")
    add("                div_where[b] = bad")
    add(f"                for j in range({n}):")
    add("                    X[b, j] = np.nan")
    return "\n".join(L) + "\n"


def _consecutive(cols) -> bool:
    """Whether signal columns ``cols`` are consecutive (then a block reads them as a view of ``S``)."""
    return list(cols) == list(range(cols[0], cols[0] + len(cols))) if len(cols) else True


def _view(vec, cols) -> str:
    """Source of the view of ``vec`` at consecutive columns ``cols``."""
    return f"{vec}[{cols[0]}:{cols[0] + len(cols)}]" if len(cols) else f"{vec}[0:0]"


def compiled_runner(plan, kernels: dict):
    """The numba runner of a loop's ``plan`` (generated once per structure and process).

    Parameters
    ----------
    plan : Plan
        The loop's plan (:attr:`Loop.plan <ctrl_analysis.engine.loop.Loop.plan>`): its placed blocks, signal
        columns, evaluation groups and integrator.
    kernels : dict of block name -> Kernels
        Every block's kernel.

    Returns
    -------
    run : callable
        ``run(n_steps, t, h, substeps, X0, H, HC, HS, HCS, S0, KEEP, EVERY, store, xs, bound, diverged, div_step,
        div_where, PS, *P)``:
        ``H`` holds the per-run inputs ``(., N+1, B)`` at signal columns ``HC``, ``HS`` the inputs
        shared by every run ``(N+1, .)`` at columns ``HCS``; ``P`` lists the parameter rows.
    """
    import numba

    col = plan.col
    names = [p.name for p in plan.placed]
    blocks = []
    for p in plan.placed:
        sl = plan.slices.get(p.name, slice(0, 0))
        blocks.append(Wiring(tuple(col[s] for s in p.inputs), tuple(col[s] for s in p.outputs), (sl.start, sl.stop)))
    order, stage, discrete, continuous = (list(plan.index[k]) for k in ("order", "stage", "discrete", "continuous"))
    key = (tuple(blocks), tuple(order), tuple(stage),
           tuple(discrete), tuple(continuous), plan.n_continuous, plan.method,
           tuple((kernels[n].output, kernels[n].rhs, kernels[n].update) for n in names))
    if key not in _RUNNERS:
        t0 = time.perf_counter()
        src = _gen_source(blocks, order, stage, discrete, continuous, plan.n_continuous, plan.method, len(plan.names))
        from .integrators import is_bad, rk4_acc, rk4_end, rk4_point

        fns = {"RK4_POINT": rk4_point, "RK4_ACC": rk4_acc, "RK4_END": rk4_end, "IS_BAD": is_bad}
        for i, n in enumerate(names):
            k = kernels[n]
            fns[f"K{i}_out"] = k.output
            if k.rhs is not None:
                fns[f"K{i}_rhs"] = k.rhs
            if k.update is not None:
                fns[f"K{i}_upd"] = k.update
        # the generated code's SCRATCH and the unrolling budget it is compiled with are in the key too
        # (numba's cache knows neither)
        module = _runner_module(src, fns, extra=inspect.getsource(_scratch_vector) + f"unroll budget {UNROLL_BUDGET}")
        for name, fn in fns.items():
            setattr(module, name, _jit(fn))
        module.SCRATCH = _scratch_vector()
        f64, i64 = numba.float64, numba.int64
        sig = numba.void(i64, f64[::1], f64, i64, f64[:, ::1], f64[:, :, ::1], numba.intp[::1], f64[:, ::1],
                         numba.intp[::1], f64[::1],
                         numba.intp[::1], i64, f64[:, :, :], f64[:, :, :], f64, numba.boolean[:], i64[:], i64[:],
                         numba.intp[::1],
                         *[f64[:, ::1] for b in blocks])
        cache = cacheable(fn for k, fn in fns.items() if k.startswith("K"))
        # one process compiles a structure, the others load it from numba's cache once it is saved
        with compile_lock(module.__file__ + ".lock") if cache else contextlib.nullcontext():
            run = _compile(module.run, sig, cache=cache)
        _RUNNERS[key] = (run, time.perf_counter() - t0)
        _COMPILE["seconds"] += _RUNNERS[key][1]
    return _RUNNERS[key][0]


#: LLVM's loop-unrolling budget while a runner compiles (``-unroll-threshold-aggressive``; LLVM's own
#: value at -O3, 300, is restored right after). With it LLVM unrolls the four RK4 stages of a typical
#: loop (Example 1 needs about 800), removing the stage loop's branches and keeping the stages'
#: values in registers across them: Example 1 at B = 1000, keep=[], 1.44x -> 1.32x of the compiled
#: reference, with no measurable change of compile time (the stages are unrolled in LLVM's IR,
#: not in numba's, whose passes are most of the compile time). 0: leave LLVM's setting alone.
UNROLL_BUDGET = 2000
_LLVM_UNROLL_DEFAULT = 300


def _compile(fn, sig, cache=True):
    """``numba.njit(sig)`` of the generated runner, with LLVM's unrolling budget raised to :data:`UNROLL_BUDGET`.

    LLVM's options are global to the process: they are changed and restored under numba's compiler
    lock, so no other numba compilation runs with the raised budget (a runner loaded from numba's
    disk cache is not compiled at all).
    """
    import numba

    if not UNROLL_BUDGET:
        return numba.njit(sig, cache=cache, error_model="numpy")(fn)
    import llvmlite.binding as llvm
    from numba.core.compiler_lock import global_compiler_lock

    with global_compiler_lock:
        llvm.set_option("", f"-unroll-threshold-aggressive={UNROLL_BUDGET}")
        try:
            return numba.njit(sig, cache=cache, error_model="numpy")(fn)
        finally:
            llvm.set_option("", f"-unroll-threshold-aggressive={_LLVM_UNROLL_DEFAULT}")


