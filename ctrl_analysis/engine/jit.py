"""numba plumbing shared by the compiled engine and the kernel-first blocks: jitted kernels, generated modules, cache.

* :func:`_jit` compiles a kernel (``inline="always"``, so it disappears into whatever calls it);
* :func:`_runner_module` imports generated source from a file in :func:`cache_dir` named by a hash
  of everything the compiled code depends on (:func:`source_key`), so numba's disk cache can keep
  what it compiles from it across processes and never hands back code compiled from other sources;
* :func:`compiled_rows` runs a kernel over the rows of a batch, compiled: what
  :meth:`KernelBlock.batched <ctrl_analysis.engine.kernels.KernelBlock.batched>` uses for a kernel
  that branches per value (``Kernels(columns=False)``) on a large batch.

Nothing here knows a block, a loop or a kernel's meaning; numba is imported only when used.
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from pathlib import Path

__all__ = ["cache_dir", "compile_lock", "compiled_rows", "source_key"]

_JIT: dict = {}


def _jit(fn):
    """``fn`` compiled by numba as a kernel (``inline="always"``, disk-cached beside its source), once per process."""
    import numba

    if fn not in _JIT:
        try:
            _JIT[fn] = numba.njit(cache=True, error_model="numpy", inline="always")(fn)
        except RuntimeError:  # no file to cache against (a notebook cell, exec'd code): compile, don't cache
            _JIT[fn] = numba.njit(cache=False, error_model="numpy", inline="always")(fn)
    return _JIT[fn]


def cacheable(fns) -> bool:
    """Whether code calling ``fns`` may go to numba's disk cache: each is defined in an importable module file.

    numba's cache re-imports, by name, the module whose globals a compiled function uses; a kernel
    exec'd into a namespace (a notebook cell, a doctest, ``exec``) has none, and a runner cached with it
    inlined fails to load in the next process (``No module named '<dynamic>'``). Such runners are
    compiled once per process instead.

    Parameters
    ----------
    fns : iterable of callable
        Kernels (plain functions or numba dispatchers of them).

    Returns
    -------
    bool
    """
    for fn in fns:
        py = getattr(fn, "py_func", fn)
        module = sys.modules.get(getattr(py, "__module__", None) or "")
        if (module is None or not getattr(module, "__file__", None)
                or getattr(py, "__globals__", None) is not vars(module)):
            return False
    return True


def source_key(fn) -> str:
    """What a compiled kernel depends on, as text: its source, and that of everything it reads by name.

    The runner inlines each kernel and, through it, the helpers the kernel calls and the constants
    it reads (``AT`` offsets of a :class:`~ctrl_analysis.engine.kernels.Layout`, module-level numbers,
    ``@jitable`` functions, numba's own dispatchers): a change in any of them must give another
    runner file, or numba's disk cache would hand back the runner compiled with the old ones. So
    the key is the kernel's module and name and its source, followed by, for every global name its code (and the code of
    functions nested in it) reads, that value's source if it is a function, recursively, or its
    ``repr`` if it is a number, a string or a tuple of them; modules (``np``, ``math``) are keyed by
    name only.

    Parameters
    ----------
    fn : callable
        A kernel (plain Python function, or a numba dispatcher of one).

    Returns
    -------
    str
    """
    import inspect
    import types

    parts, seen = [], set()

    def code_names(code):
        names = list(code.co_names)
        for c in code.co_consts:
            if isinstance(c, types.CodeType):
                names += code_names(c)
        return names

    def visit(f):
        f = getattr(f, "py_func", f)  # a numba dispatcher: the Python function it compiles
        if id(f) in seen:
            return
        seen.add(id(f))
        code, env = getattr(f, "__code__", None), getattr(f, "__globals__", {})
        # where it lives too: numba's cache re-imports a runner's functions by module, so a kernel moved to
        # another module (same source) must not get the runner cached with the old module's name
        parts.append(f"{getattr(f, '__module__', None)}.{getattr(f, '__qualname__', None)}")
        try:
            parts.append(inspect.getsource(f))
        except Exception:  # noqa: BLE001 - no source (exec'd code: a notebook cell, a README example, whose
            # "file" may even exist with other lines in it, giving a TokenError): key on the compiled code itself
            if code is None:
                parts.append(repr(f))
                return
            import marshal

            parts.append(marshal.dumps(code).hex())
        if code is None:
            return
        for name in sorted(set(code_names(code))):
            if name not in env:
                continue  # a builtin or an attribute name
            v = env[name]
            if isinstance(v, types.ModuleType):
                parts.append(f"{name}: module {v.__name__}")
            elif isinstance(v, (int, float, complex, str, bool, tuple)) or v is None:
                parts.append(f"{name} = {v!r}")
            elif callable(v) and (inspect.isfunction(getattr(v, "py_func", v))):
                parts.append(f"{name}:")
                visit(v)
            else:  # anything else (a class, an array): its type, so that a rename still changes the key
                parts.append(f"{name}: {type(v).__module__}.{type(v).__qualname__}")

    visit(fn)
    return "\n".join(parts)


def cache_dir() -> Path:
    """Where generated code (loop runners, row appliers) and numba's cache of it live.

    Returns
    -------
    pathlib.Path
        ``$CTRL_ANALYSIS_CACHE/kernels``, or ``ctrl_analysis/kernels`` under ``$XDG_CACHE_HOME`` (``~/.cache``).
    """
    base = os.environ.get("CTRL_ANALYSIS_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "ctrl_analysis")
    return Path(base) / "kernels"


#: Longest wait, in seconds, for another process compiling the same generated code (:func:`compile_lock`);
#: past it this process compiles the code itself.
COMPILE_WAIT = 900.0


@contextlib.contextmanager
def compile_lock(path):
    """Hold the lock file ``path`` while the block compiles: one process compiles, the others wait and load it.

    Without it, a cold run on many cores compiles each loop structure once in every worker process
    that receives one of its chunks at the same time (221 compilations of 10 structures in a cold
    ``reproduce all --jobs 16``): each worker compiles the same code and writes the same cache.
    With it the first process compiles and saves to numba's disk cache, and the others, once the
    lock is free, load from it (their ``numba.njit(sig, cache=True)`` finds it). ``flock`` on a file
    beside the generated source: the kernel releases it when its holder exits, even by ``kill -9``.
    The lock is polled (no thread or process waits on it uninterruptibly) and given up after
    :data:`COMPILE_WAIT` seconds; where ``flock`` or the file is not available the block runs
    unlocked (compiling twice is wasteful, never wrong: numba's cache writes are atomic).

    Loading a cached runner takes about 0.2 s, so warm workers must not queue on the lock: once a
    block ends without error while holding it, a marker file is written beside it (:func:`_marker`:
    named by numba's cache folder, version and this CPU, what numba's cache is specific to), and a
    later block with the marker present runs at once, unlocked, and loads.

    Parameters
    ----------
    path : str or os.PathLike
        The lock file (created if needed, never removed).

    Yields
    ------
    bool
        Whether the lock is held (``False`` too when the marker says the code is compiled already).
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield False
        return
    marker = _marker(path)
    if os.path.exists(marker):
        yield False
        return
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:
        yield False
        return
    try:
        deadline, delay, held = time.monotonic() + COMPILE_WAIT, 0.005, False
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                held = True
                break
            except BlockingIOError:
                if time.monotonic() > deadline:
                    break
                time.sleep(delay)
                delay = min(2 * delay, 0.1)
        yield held
        if held:  # the block compiled (or loaded) it without error: later blocks need not wait
            with contextlib.suppress(OSError):
                open(marker, "a").close()
    finally:
        os.close(fd)  # releases the lock


def _marker(path) -> str:
    """The file saying that the code locked by ``path`` is in numba's disk cache for this machine's CPU."""
    import hashlib

    import llvmlite.binding as llvm
    import numba
    from numba.core import config

    if "HOST" not in _JIT:
        _JIT["HOST"] = hashlib.sha1(f"{config.CACHE_DIR}|{numba.__version__}|{llvm.get_host_cpu_name()}|"
                                    f"{llvm.get_host_cpu_features().flatten()}".encode()).hexdigest()[:12]
    return f"{path}.{_JIT['HOST']}.done"


def _runner_module(src: str, fns: dict, prefix: str = "loop", extra: str = ""):
    """Import generated source from a file named by its hash, so numba can cache what it compiles from it.

    The hash covers the source, ``extra`` (whatever else the compiled code depends on) and, for
    every global ``fns`` will provide (set on the module by the caller), its :func:`source_key`.
    """
    import hashlib
    import importlib.util

    digest = hashlib.sha1(src.encode())
    digest.update(extra.encode())
    for name in sorted(fns):
        digest.update(name.encode())
        digest.update(source_key(fns[name]).encode())
    d = cache_dir()
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError:  # read-only home: a per-user temporary directory still caches within the machine
        import tempfile

        d = Path(tempfile.gettempdir()) / f"ctrl_analysis-{os.getuid() if hasattr(os, 'getuid') else 0}" / "kernels"
        d.mkdir(parents=True, exist_ok=True)
    path = d / f"{prefix}_{digest.hexdigest()[:20]}.py"
    if not path.exists():
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text("import numpy as np\n\n\n" + src, encoding="utf-8")
        os.replace(tmp, path)
    spec = importlib.util.spec_from_file_location(f"_ctrl_analysis_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # numba's cache re-imports the module by name
    spec.loader.exec_module(module)
    return module


_ROWS_SOURCE = """
def rows(t, X, U, P, stride, Y):
    for b in range(X.shape[0]):
        FN(t, X[b], U[b], P[b * stride], Y[b])
"""


def compiled_rows(fn):
    """``rows(t, X, U, P, stride, Y)``: kernel ``fn`` on each row ``b`` of a batch, compiled; ``None`` without numba.

    ``X``, ``U``, ``Y`` are C-contiguous ``(B, .)`` float arrays, ``P`` the parameter rows, run
    ``b`` reading row ``b * stride`` (``stride`` 0: one row shared by every run). The same
    arithmetic as calling ``fn`` on each row from Python (the compiled engine inlines the same
    compiled kernel), without the interpreter's cost per call. Compiled once per kernel and cached
    on disk (:func:`_runner_module`); a kernel numba cannot compile gives ``None`` too, and the
    caller keeps its Python loop.

    Parameters
    ----------
    fn : callable
        A kernel ``fn(t, x, u, p, out)``.

    Returns
    -------
    callable or None
    """
    key = ("rows", fn)
    if key not in _JIT:
        try:
            import numba
        except ImportError:  # pragma: no cover - numba is a dependency
            _JIT[key] = None
            return None
        module = _runner_module(_ROWS_SOURCE, {"FN": fn}, prefix="rows")
        module.FN = _jit(fn)
        rows = numba.njit(cache=cacheable([fn]), error_model="numpy")(module.rows)
        _JIT[key] = _LockedFirstCall(rows, module.__file__ + ".lock") if cacheable([fn]) else rows
    return _JIT[key]


class _LockedFirstCall:
    """A lazily compiled dispatcher whose compiling calls hold :func:`compile_lock` (one process compiles, the
    others load from numba's cache); once this process has a compiled version, calls go straight to it."""

    def __init__(self, dispatcher, lock):
        self.dispatcher, self.lock = dispatcher, lock

    def __call__(self, *args):
        if not self.dispatcher.signatures:
            with compile_lock(self.lock):
                return self.dispatcher(*args)
        return self.dispatcher(*args)
