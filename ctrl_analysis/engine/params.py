"""Run-time block parameters: ``Loop.simulate(params={"block": {"name": value or per-run values}})``.

A block is independent of the batch size. The parameters a simulation changes are given to
:meth:`~ctrl_analysis.engine.loop.Loop.simulate` by block name and constructor argument; a value with one
more axis than the block's own value (its first axis the batch's runs) differs per run, any
other value is shared by every run. :func:`resolve` rebuilds the block once per distinct value with
:meth:`~ctrl_analysis.engine.blocks.Block.with_params`, so the block's constructor validates every value,
and gives the engines what they run:

* the rebuilt block when every run shares the values;
* per-run values: one parameter row per run, ``(B, n_p)``, and a :class:`PerRunBlocks` that steps
  them: a kernel block's rows are its kernel parameter vectors (the compiled engine and the derived
  batched methods read row ``b`` for run ``b``); a block without a kernel becomes a Python row kernel
  whose row is the index of the run's rebuilt block (the numpy engine groups runs by it).

:func:`chunk_functions` gives the numpy engine the per-step functions of a chunk of runs (its rows
of the per-run values); :func:`take` cuts the per-run values to a chunk of runs, as per-run inputs
are cut, so a chunk in another process gets exactly its runs' parameters.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .stepcheck import unchecked

__all__ = ["PerRunBlocks", "Variant", "chunk_functions", "resolve", "runs_of", "split", "take"]


@dataclass(frozen=True)
class Variant:
    """What the engines run for one placed block under run-time parameters.

    Attributes
    ----------
    block : Block or PerRunBlocks
        The block with the shared changes applied (the placed block itself when none); with per-run
        values, a :class:`PerRunBlocks` whose rows are ``rows``.
    rows : numpy.ndarray or None
        Per-run values: one parameter row per run, ``(B, n_p)``. For a block with a kernel these are its
        kernel parameter vectors (the compiled engine and the batched methods read row ``b`` for run
        ``b``); for a block without one, the index of the run's rebuilt block (a Python row kernel,
        which only the numpy engine runs).
    x0 : numpy.ndarray or None
        With per-run values, each run's initial state ``(B, n)``: its rebuilt block's ``initial_state()``
        (so ``params={"block": {"x0": per-run values}}`` gives each run its own).
    """

    block: object
    rows: np.ndarray | None = None
    x0: np.ndarray | None = None


class PerRunBlocks:
    """A block rebuilt per distinct run-time value, stepped as one block whose parameter row selects the run's.

    The numpy engine calls :meth:`batched` with the chunk's rows, like a kernel block's: a kernel
    block's own batched methods take its kernel rows directly; any other block's runs are grouped by
    their row and each group is stepped by its rebuilt block.

    Parameters
    ----------
    blocks : tuple of Block
        One rebuilt block per distinct value; a run's row is its block's kernel parameters, or its index ``[i]``.
    kernel_rows : bool
        Whether the runs' rows are the blocks' kernel parameter vectors (then the first block's kernel,
        with the per-run rows, runs every run).
    """

    def __init__(self, blocks, kernel_rows: bool):
        self.blocks, self.kernel_rows = tuple(blocks), kernel_rows
        self._parts = (None, None)

    def kernel(self):
        """The first block's kernel when the rows are kernel rows, else ``None`` (no compiled engine).

        Returns
        -------
        Kernels or None
        """
        own = getattr(self.blocks[0], "kernel", None)
        return own() if self.kernel_rows and callable(own) else None

    def batched(self, kind: str, t, x, u, P) -> np.ndarray:
        """Method ``kind`` (output, update or rhs) of every run, each by its row's block.

        Parameters
        ----------
        kind : {"output", "update", "rhs"}
        t : float
        x, u : numpy.ndarray
            ``(B, n)`` and ``(B, m)``.
        P : numpy.ndarray, shape (B, n_p)
            The runs' rows (the same array at every step of a chunk: its grouping is kept).

        Returns
        -------
        numpy.ndarray
        """
        first = self.blocks[0]
        if self.kernel_rows:
            if hasattr(first, "batched"):
                return first.batched(kind, t, x, u, P)
            fn = getattr(first.kernel(), kind)  # a block with its own kernel(): the kernel run by run
            out = np.empty((x.shape[0], len(first.outputs) if kind == "output" else x.shape[1]))
            for b in range(x.shape[0]):
                fn(t, x[b], u[b], P[b], out[b])
            return out
        if self._parts[0] is not P:
            which = P[:, 0].astype(np.intp)
            self._parts = (P, [(unchecked(b, kind), np.flatnonzero(which == i)) for i, b in enumerate(self.blocks)
                               if (which == i).any()])
        out = None
        for f, idx in self._parts[1]:
            y = np.asarray(f(t, x[idx], u[idx], None))
            if out is None:
                out = np.empty((x.shape[0],) + y.shape[1:])
            out[idx] = y
        return out


def split(block, values: dict, B: int, where: str) -> tuple[dict, dict]:
    """Shared and per-run values of one block's parameters.

    Parameters
    ----------
    block : Block
    values : dict of str -> value
        Constructor arguments by name.
    B : int
        Runs of the batch.
    where : str
        How the caller names the block in messages (``params['plant']``).

    Returns
    -------
    shared, per_run : dict
        ``per_run`` values have a leading axis of length ``B``.

    Raises
    ------
    TypeError
        If ``values`` is not a dict.
    ValueError
        If a name is not a constructor argument, or a per-run value does not have ``B`` rows.
    """
    if not isinstance(values, dict):
        raise TypeError(f"{where} must be a dict of parameter name -> value, got {values!r:.80}")
    current = block.init_args()
    unknown = sorted(set(values) - set(current))
    if unknown:
        raise ValueError(f"{where} names {unknown}, not parameters of {type(block).__name__}; its parameters are "
                         f"{sorted(current)}")
    shared, per_run = {}, {}
    for name, v in values.items():
        own = current[name]
        a = np.asarray(v) if not isinstance(v, (str, bytes)) else None
        if a is not None and own is not None and a.dtype != object and a.ndim == np.ndim(own) + 1:
            if a.shape[0] != B:
                raise ValueError(f"{where}[{name!r}] differs per run (one axis more than the block's value), so "
                                 f"its first axis must have the batch's {B} runs, got shape {a.shape}")
            per_run[name] = a
        elif a is not None and own is None and _per_run_of_none(block, name, a, B):
            per_run[name] = a
        else:
            shared[name] = v
    return shared, per_run


def _accepts(block, name: str, value) -> bool:
    try:
        block.with_params(**{name: value})
    except (TypeError, ValueError):
        return False
    return True


def _per_run_of_none(block, name: str, a: np.ndarray, B: int) -> bool:
    """Whether ``a`` holds one value per run of an argument whose current value is ``None`` (say ``x0=None``).

    Such an argument has no shape to count axes against; ``a`` is per run when its first axis has the ``B`` runs
    and the block's constructor takes one run's value ``a[0]`` but not ``a`` itself.
    """
    if a.dtype == object or a.ndim < 1 or a.shape[0] != B or B < 2:
        return False
    return _accepts(block, name, a[0]) and not _accepts(block, name, a)


def runs_of(loop, params) -> int | None:
    """The number of runs ``params``' per-run values give (their first axis), or ``None`` if none differs per run.

    Lets :meth:`~ctrl_analysis.engine.loop.Loop.simulate` take the batch size from the parameters, as it
    does from per-run inputs. Malformed ``params`` give ``None`` here and their error in :func:`resolve`.

    Parameters
    ----------
    loop : Loop or Plan
        Its placed blocks (``placed``).
    params : dict or None

    Returns
    -------
    int or None
    """
    if not isinstance(params, dict):
        return None
    placed = {p.name: p.block for p in loop.placed}
    for name, values in params.items():
        if name not in placed or not isinstance(values, dict):
            continue
        try:
            current = placed[name].init_args()
        except TypeError:
            continue
        for key, v in values.items():
            own = current.get(key)
            if isinstance(v, (str, bytes)) or key not in current:
                continue
            a = np.asarray(v)
            if own is None:  # no shape to count against: one run's value taken, the whole value refused
                if a.dtype != object and a.ndim >= 1 and a.shape[0] > 1 \
                        and _per_run_of_none(placed[name], key, a, a.shape[0]):
                    return int(a.shape[0])
                continue
            if a.dtype != object and a.ndim == np.ndim(own) + 1 and a.shape[0] > 0:
                return int(a.shape[0])
    return None


def _rebuild(block, changes: dict, where: str):
    try:
        return block.with_params(**changes)
    except (TypeError, ValueError) as exc:
        raise type(exc)(f"{where}: {exc}") from None


def resolve(loop, params, B: int) -> dict:
    """The :class:`Variant` of every block ``params`` changes.

    Parameters
    ----------
    loop : Loop or Plan
        Its placed blocks (``placed``).
    params : dict of block name -> dict of parameter name -> value, or None
    B : int
        Runs of the batch.

    Returns
    -------
    dict of block name -> Variant

    Raises
    ------
    TypeError, ValueError
        Naming ``params[block]`` (and the parameter) for an unknown block or parameter, a per-run
        value of the wrong length, a value the block's constructor refuses, or per-run values that
        change a kernel block's parameter layout.
    """
    if params is None:
        return {}
    if not isinstance(params, dict):
        raise TypeError(f"params must be a dict of block name -> {{parameter: value}}, got {params!r:.80}")
    placed = {p.name: p for p in loop.placed}
    unknown = sorted(set(params) - set(placed))
    if unknown:
        raise ValueError(f"params names blocks {unknown} that are not in the loop; its blocks are {list(placed)}")
    out = {}
    for name, values in params.items():
        where = f"params[{name!r}]"
        block = placed[name].block
        shared, per_run = split(block, values, B, where)
        base = _rebuild(block, shared, where) if shared else block
        if not per_run:
            out[name] = Variant(base)
            continue
        flat = np.concatenate([np.asarray(v, dtype=float).reshape(B, -1) for v in per_run.values()], axis=1)
        _, first, inverse = np.unique(flat, axis=0, return_index=True, return_inverse=True)
        inverse = np.asarray(inverse).reshape(-1)
        blocks = [_rebuild(block, {**shared, **{k: v[b] for k, v in per_run.items()}}, where) for b in first.tolist()]
        distinct = _kernel_rows(blocks, per_run, where)
        kernel_rows = distinct is not None
        if not kernel_rows:  # a Python row kernel: the row is the index of the run's rebuilt block
            distinct = np.arange(len(blocks), dtype=float).reshape(-1, 1)
        # a static block under the StaticBlock protocol has no initial_state (and no state to start)
        x0 = np.stack([_initial_state(b, where) for b in blocks])[inverse] \
            if hasattr(block, "initial_state") else None
        out[name] = Variant(PerRunBlocks(blocks, kernel_rows), rows=np.ascontiguousarray(distinct[inverse]),
                            x0=x0)
    return out


def _initial_state(block, where):
    v = np.asarray(block.initial_state(), dtype=float).reshape(-1)
    if not np.isfinite(v).all():
        raise ValueError(f"{where}: the block's initial_state() must be finite, got {v}")
    return v


def _kernel_rows(blocks, per_run, where):
    """Each block's kernel parameter vector as a row, or ``None`` when the blocks have no kernel with one."""
    from .codegen import kernel_of

    try:
        kernels = [kernel_of(b) for b in blocks]
    except Exception:  # noqa: BLE001 - a block the compiled engine cannot take runs on numpy
        return None
    if any(k is None or k.params is None or np.ndim(k.params) != 1 for k in kernels):
        return None
    if len({(k.output, k.update, k.rhs) for k in kernels}) > 1:
        return None  # different kernel functions per value: only the numpy engine can run them side by side
    sizes = {np.size(k.params) for k in kernels}
    if len(sizes) > 1:
        raise ValueError(f"{where}: per-run values of {sorted(per_run)} change the size of the block's "
                         f"parameter vector ({sorted(sizes)}); values that change a block's structure "
                         f"(an order, a number of states) cannot vary per run")
    return np.stack([np.asarray(k.params, dtype=float) for k in kernels])


def take(params, B: int, loop, lo: int, hi: int):
    """``params`` for runs ``lo:hi`` of a batch of ``B``: per-run values cut, shared values kept.

    Parameters
    ----------
    params : dict or None
        As :meth:`~ctrl_analysis.engine.loop.Loop.simulate` takes it (already checked by :func:`resolve`).
    B : int
    loop : Loop or Plan
        Its placed blocks (``placed``).
    lo, hi : int

    Returns
    -------
    dict or None
    """
    if not params:
        return params
    placed = {p.name: p for p in loop.placed}
    out = {}
    for name, values in params.items():
        shared, per_run = split(placed[name].block, values, B, f"params[{name!r}]")
        out[name] = {**shared, **{k: v[lo:hi] for k, v in per_run.items()}}
    return out


def _variant_function(variant, kind: str, lo: int, B: int):
    """The per-step function of a block under run-time parameters, for runs ``lo:lo+B`` of the call."""
    if variant.rows is None:
        return unchecked(variant.block, kind)
    P = variant.rows[lo:lo + B]
    block = variant.block

    def call(t, x, u, params=None):
        return block.batched(kind, t, x, u, P)

    return call


def chunk_functions(plan, variants: dict, lo: int, B: int) -> dict:
    """The per-step functions the numpy engine calls for the ``B`` runs from run ``lo`` of the call.

    Parameters
    ----------
    plan : Plan
        The loop's plan (``order``, ``stage``, ``discrete``, ``continuous``: ``(block, ic, oc, sl)``).
    variants : dict of int -> Variant
        ``id(block)`` -> the block's run-time parameters (:func:`resolve`).
    lo, B : int
        The chunk's first run within the call, and its runs.

    Returns
    -------
    dict
        Per key of ``plan``, ``(output or rhs or update function, ic, oc, sl)``: the blocks' unchecked
        methods, or for a block under run-time parameters a function on the chunk's values.
    """
    def fn(block, kind):
        if id(block) in variants:
            return _variant_function(variants[id(block)], kind, lo, B)
        return unchecked(block, kind)

    kinds = {"order": "output", "stage": "output", "discrete": "update", "continuous": "rhs"}
    return {key: [(fn(b, kind), ic, oc, sl) for b, ic, oc, sl in getattr(plan, key)] for key, kind in kinds.items()}
