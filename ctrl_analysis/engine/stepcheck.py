"""Checks of the block protocol made outside the hot loop: argument widths of direct per-step calls.

A block's per-step methods (``output``, ``update``, ``rhs``) check nothing inside the engine, which
calls them millions of times with arrays it has shaped itself. Called directly by a user, a state
or input of the wrong width would be read past its columns or broadcast into a wrong answer, so
:class:`~ctrl_analysis.engine.blocks.Block` wraps every subclass's per-step methods with
:func:`checked`: the public method checks the widths, and the engine calls the unwrapped function
(:func:`unchecked`).
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["check_step_args", "checked", "unchecked"]

_STEP_METHODS = ("output", "update", "rhs")


def check_step_args(block, x, u) -> None:
    """Raise unless the last axis of ``x`` has ``n_states`` entries and that of ``u`` at most ``len(inputs)``.

    ``x`` is ``(B, n)`` and ``u`` ``(B, m)`` in the engine; one run as 1-D vectors, extra leading
    batch axes (equal for both) and ``x=None`` for a block without state are accepted too.

    Parameters
    ----------
    block : Block
        The block whose per-step method is called.
    x, u : array_like
        The state and the input of the call.

    Raises
    ------
    ValueError
        If a width or the batch shape differs, naming the block, the argument, the shape expected
        and the one given.
    """
    n, m = block.n_states, len(block.inputs)
    us = np.shape(u)
    xs = us[:-1] + (0,) if x is None and n == 0 else np.shape(x)
    name = type(block).__name__
    if len(xs) < 1 or xs[-1] != n:
        raise ValueError(f"x must have shape (B, {n}) for {name} (one column per state {tuple(block.states)}), "
                         f"got shape {xs}")
    # fewer input columns pass: a block whose output reads only its first inputs may be handed only
    # those (a filter's correction step given y alone); reading a missing one raises IndexError
    if len(us) < 1 or us[-1] > m:
        raise ValueError(f"u must have shape (B, {m}) for {name} (one column per input {tuple(block.inputs)}), "
                         f"got shape {us}")
    if xs[:-1] != us[:-1]:
        raise ValueError(f"x and u must have the same runs (leading shape), got shapes {xs} and {us}")


def checked(fn):
    """``fn(self, t, x, u, params)`` behind a check of the widths of ``x`` and ``u`` (see module docstring).

    Parameters
    ----------
    fn : callable
        A per-step method.

    Returns
    -------
    callable
        The checking method; ``.unchecked`` is ``fn``.
    """
    @functools.wraps(fn)
    def method(self, t, x, u, params=None):
        check_step_args(self, x, u)
        return fn(self, t, x, u, params)

    method.unchecked = fn
    return method


def wrap_step_methods(cls) -> None:
    """Replace the per-step methods ``cls`` defines or inherits unwrapped (from a mixin) by :func:`checked` ones."""
    for kind in _STEP_METHODS:
        fn = getattr(cls, kind, None)
        if callable(fn) and not hasattr(fn, "unchecked"):
            setattr(cls, kind, checked(fn))


def unchecked(block, kind: str):
    """The bound per-step method ``kind`` of ``block`` without the width check (what the engine calls).

    Parameters
    ----------
    block : Block
    kind : {"output", "update", "rhs"}

    Returns
    -------
    callable
        ``f(t, x, u, params)``.
    """
    method = getattr(block, kind)
    raw = getattr(method, "unchecked", None)
    return method if raw is None else raw.__get__(block)
