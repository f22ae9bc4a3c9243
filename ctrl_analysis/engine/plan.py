"""The execution plan of a :class:`~ctrl_analysis.engine.loop.Loop`: which block runs when, on which signal columns.

Both engines step the loop from one frozen :class:`Plan`: every signal is a column of one
``(B, n_signals)`` array (external inputs first, then every block's outputs); each block is an
entry ``(block or its per-step function, input columns, output columns, state slice)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

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

    placed : tuple of Placed
        The loop's blocks as placed (name, block, signals), in the loop's order.
    index : dict of str -> tuple of int
        For ``order``, ``stage``, ``discrete`` and ``continuous``: the positions in ``placed`` of
        their blocks (the compiled engine's view of the same plan).
    dt, method, substeps : float, str, int
        The loop's sampling period and integrator.
    n_states, n_continuous : int
        Width of the state vector, and of its continuous part (first).
    slices : dict of str -> slice
        Each block's part of the state vector.
    external, outlist : tuple of str
        The loop's external inputs and reported outputs.
    state_names, where_names : tuple of str
        ``block.state`` of every state; and how a divergence names each state and then each signal.
    cache : dict
        Per-loop memo of the engines (a compiled runner and its checks), never part of equality.

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
    placed: tuple = ()
    index: dict = field(default_factory=dict)
    dt: float = 1.0
    method: str = "rk4"
    substeps: int = 1
    n_states: int = 0
    n_continuous: int = 0
    slices: dict = field(default_factory=dict)
    external: tuple = ()
    outlist: tuple = ()
    state_names: tuple = ()
    where_names: tuple = ()
    cache: dict = field(default_factory=dict, compare=False, repr=False)


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
    stage = [p for p in loop.stage_order if p.name in needed]
    groups = {"order": loop.order, "stage": stage, "discrete": loop.discrete, "continuous": loop.continuous}
    position = {p.name: i for i, p in enumerate(loop.placed)}
    state_names = tuple(f"{p.name}.{s}" for p in loop.continuous + loop.discrete for s in p.block.states)
    owner = {s: p.name for p in loop.placed for s in p.outputs}
    where = tuple(f"{owner[s]}.{s} (output of block {owner[s]!r})" if s in owner else f"{s} (an input of the loop)"
                  for s in names)
    return Plan(names=tuple(names), col=col, **{k: tuple(entries[p.name] for p in g) for k, g in groups.items()},
                placed=tuple(loop.placed), index={k: tuple(position[p.name] for p in g) for k, g in groups.items()},
                dt=loop.dt, method=loop.method, substeps=loop.substeps, n_states=loop.n_states,
                n_continuous=loop.n_continuous, slices=dict(loop.slices), external=tuple(loop.external),
                outlist=tuple(loop.outlist), state_names=state_names, where_names=state_names + where)

