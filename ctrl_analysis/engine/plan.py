"""The execution plan of a :class:`~ctrl_analysis.engine.loop.Loop`: which block runs when, on which signal columns.

Both engines step the loop from one frozen :class:`Plan`: every signal is a column of one
``(B, n_signals)`` array (external inputs first, then every block's outputs); each block is an
entry ``(block or its per-step function, input columns, output columns, state slice)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .blocks import DiscreteBlock

__all__ = ["Plan", "make_plan"]

_NO_STATE = slice(0, 0)


@dataclass(frozen=True)
class Plan:
    """A loop's evaluation order and signal columns, built once per loop by :func:`make_plan`.

    Attributes
    ----------
    names : tuple of str
        Every signal, in column order.
    col : dict of str -> int
        Column of each signal.
    order : tuple of entries
        Every block in dependency order (outputs at a sample instant).
    stage : tuple of entries
        The static and continuous blocks re-evaluated at an integration stage (those feeding a
        continuous block).
    discrete, continuous : tuple of entries
        The blocks updated once per sample, and those integrated.

    An entry is ``(block, ic, oc, sl)``: the block (or, in a chunk's plan, its per-step
    function), its input and output columns (a slice when contiguous, else an index array) and
    its slice of the state vector.
    """

    names: tuple
    col: dict
    order: tuple
    stage: tuple
    discrete: tuple
    continuous: tuple


def make_plan(loop) -> Plan:
    """The :class:`Plan` of ``loop``.

    Parameters
    ----------
    loop : Loop

    Returns
    -------
    Plan
    """
    names = list(loop.external) + [s for p in loop.placed for s in p.outputs]
    col = {s: j for j, s in enumerate(names)}

    def cols(sigs):
        idx = [col[s] for s in sigs]
        if idx and idx == list(range(idx[0], idx[0] + len(idx))):
            return slice(idx[0], idx[0] + len(idx))  # contiguous: a view, no gather
        return np.array(idx, dtype=np.intp)

    entries = {p.name: (p.block, cols(p.inputs), cols(p.outputs), loop.slices.get(p.name, _NO_STATE))
               for p in loop.placed}
    # at integration stages only the blocks feeding a continuous block (through static blocks) matter
    producer = {s: p for p in loop.placed for s in p.outputs}
    needed, todo = set(), [s for p in loop.continuous for s in p.inputs]
    while todo:
        s = todo.pop()
        p = producer.get(s)
        if p is None or p.name in needed or isinstance(p.block, DiscreteBlock):
            continue
        needed.add(p.name)
        if p.block.feedthrough:
            todo.extend(p.inputs)
    stage = [entries[p.name] for p in loop.stage_order if p.name in needed]
    return Plan(names=tuple(names), col=col, order=tuple(entries[p.name] for p in loop.order), stage=tuple(stage),
                discrete=tuple(entries[p.name] for p in loop.discrete),
                continuous=tuple(entries[p.name] for p in loop.continuous))

