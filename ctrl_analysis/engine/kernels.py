"""Kernel-first blocks: a block is its signals, a declared parameter layout and its scalar kernels.

A block's equations are written **once**, as plain module-level Python functions on one run,
which numba can compile:

* ``output(t, x, u, p, y)`` — the outputs, written into ``y``;
* ``update(t, x, u, p, x_next)`` (discrete) or ``rhs(t, x, u, p, dx)`` (continuous).

``x`` and ``u`` are the run's state and input vectors and ``p`` its parameter vector, packed by the
block's :class:`Layout` (names and shapes; the kernels read ``p[AT.name]``, where the module-level
``AT = LAYOUT.at`` holds the offsets, so no position is kept by hand; numba takes the namedtuple
``AT`` as a constant, but not the ``Layout`` object itself). A block lists its kernels in a
:class:`Kernels` (``kernels = Kernels(output=..., update=...)``, the functions themselves, not their
names) and derives from :class:`KernelBlock`; from that the library derives

* the batched methods ``output`` / ``update`` / ``rhs`` on ``(B, n)`` arrays (the kernel applied
  to the batch's columns when it has no per-value branch, ``Kernels(columns=True)``, the default;
  otherwise run by run);
* the compiled engine's per-run kernel (:meth:`KernelBlock.kernel`);
* ``nlsys(dt)`` for python-control (through the batched methods), where python-control's
  ``params`` dict changes the block's parameters by name;
* per-run parameters: :meth:`ctrl_analysis.engine.loop.Loop.simulate` takes
  ``params={"block name": {"parameter": value or per-run values}}``; every numeric argument of the
  block's constructor can be given (:meth:`~ctrl_analysis.engine.blocks.Block.with_params` rebuilds the
  block for each distinct value, so the constructor validates it), and the packed rows are sliced
  with chunks and processes like per-run inputs.

Examples
--------
A first-order low-pass filter ``x(k+1) = x(k) + a (u(k) - x(k))`` as a kernel-first block:

>>> import numpy as np
>>> from ctrl_analysis.engine.blocks import DiscreteBlock
>>> LAG = Layout("a")
>>> AT = LAG.at
>>> def lag_update(t, x, u, p, x_next):
...     x_next[0] = x[0] + p[AT.a] * (u[0] - x[0])
>>> class Lag(KernelBlock, DiscreteBlock):
...     inputs, outputs, states = ("u",), ("y",), ("y",)
...     kernels = Kernels(update=lag_update)
...     def __init__(self, a=0.5):
...         self.kernel_params = LAG.pack(a=a)
>>> Lag(0.5).update(0.0, np.zeros((2, 1)), np.array([[1.0], [2.0]]))
array([[0.5],
       [1. ]])
"""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar, NamedTuple

import numpy as np

from .layout import Layout, offset

__all__ = ["KernelBlock", "Kernels", "Layout", "as_int", "copy_output", "gather", "jitable", "offset",
           "scratch"]


def jitable(fn=None, **options):
    """Decorator: ``fn`` unchanged in Python, and callable from numba-compiled kernels.

    ``numba.extending.register_jitable`` (a no-op without numba). A helper written with scalar
    indexing and ``np`` ufuncs then serves the batch's columns in Python and one run's scalars in a
    compiled kernel: one source for both engines. Use as ``@jitable`` or ``@jitable(inline="always")``.

    Parameters
    ----------
    fn : callable, optional
        The function (when used without options).
    **options
        Passed to ``register_jitable`` (e.g. ``inline="always"``).

    Returns
    -------
    callable
        ``fn`` itself, or a decorator when ``fn`` is omitted.
    """
    def wrap(f):
        try:
            from numba.extending import register_jitable
        except ImportError:  # pragma: no cover - numba is optional: the numpy engine needs none of this
            return f
        return register_jitable(**options)(f) if options else register_jitable(f)

    return wrap if fn is None else wrap(fn)


def copy_output(t, x, u, p, y):
    """Output = the whole state (the default output kernel).

    Parameters
    ----------
    t, x, u, p
        Time, one run's state, its inputs and the parameters (only ``x`` is read).
    y : numpy.ndarray
        The output, overwritten with ``x`` (a compiled kernel returns nothing and allocates nothing).
    """
    for i in range(x.shape[0]):
        y[i] = x[i]


class RowsNeeded(ValueError):
    """A kernel called on a batch's columns met a size or switch that differs between runs (:func:`as_int`):
    :meth:`KernelBlock.batched` then runs it run by run."""


def as_int(v) -> int:
    """A size or a switch stored in a parameter vector (an order, a count of substeps, a 0/1 flag), as an int.

    A kernel reads ``n = as_int(p[AT.n])``. Compiled, ``p[AT.n]`` is one run's float. In the batched
    methods on the batch's columns with one parameter row per run, it is the row of the runs'
    values: when they differ (per-run substeps) a size cannot serve every column of one call, and
    :meth:`KernelBlock.batched` runs the kernel run by run instead.

    Parameters
    ----------
    v : float or numpy.ndarray
        The stored value, or the runs' values.

    Returns
    -------
    int

    Raises
    ------
    RowsNeeded
        If the runs' values differ (a ValueError; the batched methods catch it and go run by run).
    """
    a = np.asarray(v)
    if a.ndim:
        if a.size and np.any(a != a.flat[0]):
            raise RowsNeeded(f"a size or switch of a kernel's parameters differs between runs ({np.unique(a)}): "
                             f"it cannot vary between the columns of one call")
        a = a.flat[0]
    return int(a)


def _compiled_as_int():
    """``as_int`` inside numba-compiled kernels: ``int(v)`` of one run's float."""
    try:
        from numba.extending import overload
    except ImportError:  # pragma: no cover - numba is optional: the numpy engine needs none of this
        return

    @overload(as_int, inline="always")
    def _as_int(v):
        return lambda v: int(v)


_compiled_as_int()


def scratch(n: int, like):
    """``n`` zeros for a kernel to work in: numbers for one run, rows of the batch's columns on the columns.

    A kernel that needs space (an aggregated set, per-term activations) writes ``w = scratch(n, x0)``
    with ``x0`` one of its per-run values (``u[0]``, a quantity computed from it): compiled, and for
    one run, ``np.zeros(n)``; on the batch's columns ``x0`` is a row of ``B`` values and ``w[i]`` is a
    row like it. Writing ``w[i] = ...`` and reading ``w[i]`` then serve both.

    Parameters
    ----------
    n : int
        Number of entries.
    like : float or numpy.ndarray
        A per-run value of the kernel (a number, or the runs' values on the batch's columns).

    Returns
    -------
    numpy.ndarray, shape (n,) + shape of ``like``
    """
    return np.zeros((n,) + np.shape(like))


def gather(p, k):
    """``p[k]`` at a computed index ``k`` (a table lookup in a kernel), for one run or on the batch's columns.

    On the columns ``k`` holds one index per run and ``p`` is the shared parameter vector or one
    column per run (``Loop.simulate(params=...)``); run ``b`` gets its own entry ``k[b]``. Compiled, and
    for one run, ``p[k]``.

    Parameters
    ----------
    p : numpy.ndarray, shape (n_p,) or (n_p, B)
        The parameters.
    k : int or numpy.ndarray of int, shape (B,)
        The index, or one per run.

    Returns
    -------
    float or numpy.ndarray, shape (B,)
    """
    if np.ndim(p) == 2 and np.ndim(k):
        return p[k, np.arange(p.shape[1])]
    return p[k]


def _compiled_scratch_gather():
    """:func:`scratch` and :func:`gather` inside numba-compiled kernels: one run's numbers, a plain index."""
    try:
        from numba.extending import overload
    except ImportError:  # pragma: no cover - numba is optional: the numpy engine needs none of this
        return

    @overload(scratch, inline="always")
    def _scratch(n, like):
        return lambda n, like: np.zeros(n)

    @overload(gather, inline="always")
    def _gather(p, k):
        return lambda p, k: p[k]


_compiled_scratch_gather()


class Kernels(NamedTuple):
    """A block's kernel functions (module-level, plain Python that numba can compile), and its parameters.

    One type describes kernels everywhere: a :class:`KernelBlock` lists its functions in the class
    attribute ``kernels = Kernels(output=..., update=...)``, and :meth:`KernelBlock.kernel` (or a
    block's own ``kernel()``) gives the engine the same record with ``params``, the block's parameter
    vector, filled in.

    Attributes
    ----------
    output : callable
        ``output(t, x, u, p, y)``; default :func:`copy_output` (the whole state).
    update : callable, optional
        ``update(t, x, u, p, x_next)`` of a discrete block.
    rhs : callable, optional
        ``rhs(t, x, u, p, dx)`` of a continuous block.
    columns : bool
        Whether the kernels can be called on the batch's columns (``x.T``, ``u.T``, ``p``): scalar
        indexing and no branch on a value (``if x[0] > 0``). Otherwise the batched methods call
        them run by run.
    params : numpy.ndarray or None
        The block's 1-D parameter vector (``None`` in a class's description, set by ``kernel()``);
        values that differ per run are given to ``Loop.simulate(params=...)``, which gives the engine
        one row per run, ``(B, n_p)``.
    """

    output: Callable = copy_output
    update: Callable | None = None
    rhs: Callable | None = None
    columns: bool = True
    params: np.ndarray | None = None


#: From this many runs on, a kernel that branches per value (``Kernels(columns=False)``) runs compiled
#: over the batch's rows (:func:`ctrl_analysis.engine.jit.compiled_rows`), not row by row in Python: the
#: numpy engine then steps a fal ESO, an MFAC estimator or an RLS block at numba's speed. Below it,
#: compiling the kernel (once per machine, then from the disk cache) is not worth it.
ROWS_COMPILED_MIN = 64


def rows_compiled(fn, t, x, u, P, out) -> bool:
    """Kernel ``fn`` on every row of the batch, compiled, into ``out``; ``False`` (nothing written) if it cannot be.

    The same arithmetic as the Python loop over the rows (the compiled engine inlines the same
    compiled kernel; ``tests/lib/test_kernel_blocks_controllers.py`` holds the two equal bit for bit).
    """
    from .jit import compiled_rows

    rows = compiled_rows(fn)
    if rows is None:
        return False
    P2 = np.ascontiguousarray(P[None, :] if P.ndim == 1 else P, dtype=float)
    try:
        rows(float(t), np.ascontiguousarray(x), np.ascontiguousarray(u), P2, 0 if P.ndim == 1 else 1, out)
    except Exception as exc:  # noqa: BLE001 - numba cannot compile this kernel: the Python loop runs it
        from .jit import _JIT

        _JIT[("rows", fn)] = None
        import warnings

        warnings.warn(f"kernel {getattr(fn, '__name__', fn)!r} runs row by row in Python on the numpy engine: numba "
                      f"could not compile it ({type(exc).__name__})", RuntimeWarning, stacklevel=4)
        return False
    return True


#: (kernel, kind, sizes) already checked by :func:`_check_row_kernel`
_ROWS_CHECKED: set = set()


def _outside(block, kind, fn, x, u, P, width, exc) -> ValueError:
    return ValueError(
        f"block ({type(block).__name__}): its kernel {kind} {getattr(fn, '__name__', fn)!r} reads or writes outside "
        f"its vectors (state {x.shape[-1]}, inputs {u.shape[-1]}, parameters {P.shape[-1]} as laid out by its "
        f"Layout, result {width}): {exc}")


def _check_row_kernel(block, kind, fn, t, x, u, P, width) -> None:
    """Run ``fn`` in Python on the batch's first and last rows (and at inputs 0, ±1): an index outside a vector is a
    clear error naming the block, never a crash or garbage from the compiled rows. Once per kernel and sizes."""
    key = (fn, kind, x.shape[-1], u.shape[-1], P.shape[-1], P.ndim, width)
    if key in _ROWS_CHECKED:
        return
    import warnings

    rows = [0, x.shape[0] - 1]
    for b in rows:
        p = P if P.ndim == 1 else P[b]
        for level in (None, 0.0, 1.0, -1.0):
            uu = u[b].copy() if level is None else np.full(u.shape[-1], level)
            try:
                with np.errstate(all="ignore"), warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    fn(t, x[b].copy(), uu, p.copy(), np.zeros(width))
            except IndexError as exc:
                raise _outside(block, kind, fn, x, u, P, width, exc) from None
            except Exception:  # noqa: BLE001, S112 - only indices outside the vectors are this check's concern
                continue
    _ROWS_CHECKED.add(key)


class KernelBlock:
    """Mixin (first among the bases): the block's batched methods and compiled kernel from its :class:`Kernels`.

    A subclass sets the class attribute ``kernels`` and, in its constructor, ``self.kernel_params``
    (the packed 1-D vector, e.g. ``LAYOUT.pack(...)``). Nothing else: ``output``, ``update`` /
    ``rhs``, :meth:`kernel` and python-control's ``nlsys`` follow.
    """

    kernels: ClassVar[Kernels] = Kernels()
    #: The packed parameter vector (set by the constructor).
    kernel_params: np.ndarray

    # --------------------------------------------------------------- the batched methods, derived
    def batched(self, kind: str, t, x, u, P) -> np.ndarray:
        """Kernel ``kind`` on a batch: ``x`` ``(B, n)``, ``u`` ``(B, m)``, ``P`` ``(n_p,)`` shared or ``(B, n_p)``.

        The engine's numpy path calls this with the chunk's parameter rows.

        Parameters
        ----------
        kind : {"output", "update", "rhs"}
        t : float
        x, u : numpy.ndarray
            ``(B, n)`` and ``(B, m)``; also one run (1-D) or extra leading batch axes (with ``P``
            shared); ``x`` may be ``None`` for a block without state.
        P : numpy.ndarray
            The parameter vector (every run) or one row per run.

        Returns
        -------
        numpy.ndarray, shape (B, width)
        """
        fn = getattr(self.kernels, kind)
        u = np.asarray(u, dtype=float)
        x = np.empty(u.shape[:-1] + (0,)) if x is None else np.asarray(x, dtype=float)
        if u.ndim != 2:  # one run (1-D) or extra leading batch axes: the runs flattened, shared parameters
            runs = int(np.prod(u.shape[:-1], dtype=int))
            out = self.batched(kind, t, x.reshape(runs, x.shape[-1]), u.reshape(runs, u.shape[-1]), P)
            return out.reshape(u.shape[:-1] + out.shape[-1:])
        B = u.shape[0]
        out = np.empty((B, len(self.outputs) if kind == "output" else x.shape[1]))
        if self.kernels.columns:
            try:
                fn(t, x.T, u.T, P if P.ndim == 1 else P.T, out.T)
                return out
            except RowsNeeded:  # a size or switch differs between runs (per-run substeps): run by run below
                pass
        if B >= ROWS_COMPILED_MIN:
            # compiled code does not check bounds: a kernel that reads or writes outside its vectors would
            # corrupt memory or return garbage, so it is first run in Python on the real first and last rows
            _check_row_kernel(self, kind, fn, t, x, u, P, out.shape[1])
            if rows_compiled(fn, t, x, u, P, out):
                return out
        try:
            for b in range(B):
                fn(t, x[b], u[b], P if P.ndim == 1 else P[b], out[b])
        except IndexError as exc:
            raise _outside(self, kind, fn, x, u, P, out.shape[1], exc) from None
        return out

    def _vector(self, params):
        """The parameter vector of a direct call: this block's, or python-control's ``params`` applied."""
        if not params:
            return self.kernel_params
        return self.with_params(**params).kernel_params

    def output(self, t, x, u, params=None) -> np.ndarray:
        """The outputs of every run (the ``output`` kernel on the batch).

        Parameters
        ----------
        t : float
        x : numpy.ndarray, shape (B, n)
        u : numpy.ndarray, shape (B, m)
        params : dict, optional
            python-control's ``params``: constructor arguments changed by name for this call.

        Returns
        -------
        numpy.ndarray, shape (B, len(outputs))
        """
        return self.batched("output", t, x, u, self._vector(params))

    def update(self, t, x, u, params=None) -> np.ndarray:
        """The next state of every run (the ``update`` kernel; discrete blocks).

        Parameters
        ----------
        t, x, u, params
            As in :meth:`output`.

        Returns
        -------
        numpy.ndarray, shape (B, n)
        """
        return self.batched("update", t, x, u, self._vector(params))

    def rhs(self, t, x, u, params=None) -> np.ndarray:
        """The state derivative of every run (the ``rhs`` kernel; continuous blocks).

        Parameters
        ----------
        t, x, u, params
            As in :meth:`output`.

        Returns
        -------
        numpy.ndarray, shape (B, n)
        """
        return self.batched("rhs", t, x, u, self._vector(params))

    def kernel(self):
        """The compiled engine's kernel: the block's :class:`Kernels` and its parameter vector.

        Returns
        -------
        Kernels
            The class's :attr:`kernels` with ``params`` this block's parameter vector.
        """
        return self.kernels._replace(params=self.kernel_params)
