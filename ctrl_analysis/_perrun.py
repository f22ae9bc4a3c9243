"""Per-run block parameters on both engines: how many runs a block describes, and a chunk's window on them.

A block may hold parameters that differ per run (a kernel's ``(B, n_p)`` parameter rows, the row
groups of :class:`~ctrl_analysis.blocks.RowGroups`). Both engines require the batch to have exactly
that many runs (:func:`check_rows`), so the same call gives the same answer or the same error on
either engine. The compiled engine slices the parameter rows with each chunk; the numpy engine
calls such a block's batched methods on arrays of all its rows, the chunk's runs at their places
(:func:`chunk_functions`), so a chunk ``lo:hi`` of runs reads rows ``lo:hi`` of the parameters.
"""

from __future__ import annotations

import numpy as np

from ._stepcheck import unchecked

__all__ = ["check_rows", "chunk_functions", "per_run_rows"]


def per_run_rows(block) -> int | None:
    """The number of runs ``block``'s parameters describe, or ``None`` when they are shared by every run.

    Parameters
    ----------
    block : Block

    Returns
    -------
    int or None
        ``block.run_rows`` when the block declares it, else the rows of its kernel's 2-D parameters.
    """
    rows = getattr(block, "run_rows", None)
    if rows is not None:
        return int(rows)
    from ._kernels import kernel_of

    try:
        kernel = kernel_of(block)
    except Exception:  # noqa: BLE001 - a block the compiled engine cannot take still runs on numpy
        return None
    return None if kernel is None or np.ndim(kernel.params) != 2 else int(np.shape(kernel.params)[0])


def check_rows(rows: dict, run_offset: int, B: int, batch_runs: int | None) -> None:
    """Check that the blocks' per-run parameters describe the batch's runs.

    Parameters
    ----------
    rows : dict of block name -> int
        :func:`per_run_rows` of each block that has per-run parameters.
    run_offset, B : int
        The first run of this call within the batch, and the runs of this call.
    batch_runs : int or None
        Runs of the whole batch (default ``run_offset + B``).

    Raises
    ------
    ValueError
        If two blocks disagree on the number of runs, or it is not the batch's.
    """
    from ._validate import check_int

    total = run_offset + B if batch_runs is None else check_int("batch_runs", batch_runs, minimum=1)
    if run_offset + B > total:
        raise ValueError(f"batch_runs must cover run_offset + B = {run_offset + B}, got {total}")
    counts = set(rows.values())
    if len(counts) > 1:
        raise ValueError(f"per-run parameters of the blocks describe different numbers of runs: {rows}")
    if counts and counts != {total}:
        raise ValueError(f"the loop's per-run block parameters describe {counts.pop()} runs, but the batch has "
                         f"{total} (runs/inputs/x0 set B = {B}): build the blocks {sorted(rows)} for the runs "
                         f"simulated")


def _window(fn, start: int, total: int):
    """``fn`` on ``(total, .)`` arrays holding the chunk's runs at rows ``start:start+B`` (others: its first run)."""
    def call(t, x, u, params=None):
        B = x.shape[0]
        xx = np.empty((total, x.shape[1]))
        uu = np.empty((total, u.shape[1]))
        xx[:], uu[:] = x[:1], u[:1]
        xx[start:start + B], uu[start:start + B] = x, u
        return np.asarray(fn(t, xx, uu, params))[start:start + B]

    return call


def _variant_function(variant, kind: str, lo: int, B: int):
    """The per-step function of a block under run-time parameters, for runs ``lo:lo+B`` of the call."""
    if variant.rows is not None and hasattr(variant.block, "batched"):
        P = variant.rows[lo:lo + B]
        block = variant.block

        def call(t, x, u, params=None):
            return block.batched(kind, t, x, u, P)

        return call
    if variant.groups is not None:
        parts = []
        for block, idx in variant.groups:
            mine = idx[(idx >= lo) & (idx < lo + B)] - lo
            if mine.size:
                parts.append((unchecked(block, kind), mine))

        def call(t, x, u, params=None):
            out = None
            for f, idx in parts:
                y = np.asarray(f(t, x[idx], u[idx], None))
                if out is None:
                    out = np.empty((x.shape[0],) + y.shape[1:])
                out[idx] = y
            return out

        return call
    return unchecked(variant.block, kind)


def chunk_functions(plan: dict, rows: dict, start: int, B: int, variants=None, lo: int = 0) -> dict:
    """The per-step functions the numpy engine calls for a chunk of ``B`` runs from run ``start``.

    Parameters
    ----------
    plan : dict
        The loop's plan (``order``, ``stage``, ``discrete``, ``continuous``: ``(block, ic, oc, sl)``).
    rows : dict of int -> int
        ``id(block)`` -> runs of its per-run parameters.
    start, B : int
        The chunk's first run within the batch and its runs.
    variants : dict of int -> Variant, optional
        ``id(block)`` -> the block's run-time parameters (:mod:`ctrl_analysis.engine.params`).
    lo : int
        The chunk's first run within this call (where the run-time parameter rows are read).

    Returns
    -------
    dict
        Per key of ``plan``, ``(output or rhs or update function, ic, oc, sl)`` with the unchecked
        methods, windowed for blocks with per-run parameters unless the chunk is the whole batch.
    """
    variants = variants or {}

    def fn(block, kind):
        if id(block) in variants:
            return _variant_function(variants[id(block)], kind, lo, B)
        f = unchecked(block, kind)
        total = rows.get(id(block))
        return f if total is None or (start == 0 and B == total) else _window(f, start, total)

    kinds = {"order": "output", "stage": "output", "discrete": "update", "continuous": "rhs"}
    return {key: [(fn(b, kind), ic, oc, sl) for b, ic, oc, sl in plan[key]] for key, kind in kinds.items()}
