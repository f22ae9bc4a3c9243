"""The compactor sketch behind :class:`ctrl_analysis.streaming.Quantiles`, and the proof of its bound.

The sketch is a compactor hierarchy (Manku, Rajagopalan & Lindsay 1998; the deterministic form of
KLL) over ``E`` trailing elements that see the same runs, so they compact together. ``levels[h]``
is an ``(E, m_h)`` array of values of weight ``2**h``; ``compactions[h]`` counts the compactions
made at level ``h``. When a level holds more than ``k`` values it is sorted, the even part of it
(all but the largest value when the count is odd) is cut in pairs and one value of each pair moves
up with twice the weight: the lower ones on even compactions of that level, the upper ones on odd
ones. Merging two sketches concatenates their levels and compacts. No random numbers are drawn.

**Rank-error bound.** Let ``n`` be the number of values (the total weight, which compactions and
merges keep) and ``R(x)`` the number of values ``<= x`` (or ``< x``; the argument is the same).
The sketch's estimate ``R_est(x)`` is the total weight of the kept values ``<= x``.

1. One compaction at level ``h`` changes ``R_est(x)`` of any ``x`` by at most ``2**h``: of its
   sorted values, those ``<= x`` are a prefix of length ``r``; the kept half holds ``ceil(r/2)``
   or ``floor(r/2)`` of them, of weight ``2**(h+1)``, against ``r`` of weight ``2**h``.
2. Values reach level ``h`` only from compactions below, of total weight at most ``n``, so at most
   ``n / 2**h`` values ever reach it; a compaction takes at least ``k`` of them (more than ``k``,
   less the odd one), so level ``h`` makes at most ``n / (k 2**h)`` compactions: their errors sum
   to at most ``n / k``.
3. Level ``h`` compacts only if more than ``k`` values reached it, i.e. ``n / 2**h > k``: the
   levels ``h < log2(n / k)``, at most ``ceil(log2(n / k))`` of them.

Hence ``|R_est(x) - R(x)| <= E = sum_h compactions[h] 2**h <= n ceil(log2(n / k)) / k`` for
every ``x``, whatever the chunking and the merge tree. ``E`` is tracked, so the bound reported
is the one the data actually met. The ``q``-quantile returned is the smallest kept value ``y``
with ``R_est(y) >= q n``; by the bound, the count of values ``< y`` is at most ``q n + E`` and
the count ``<= y`` at least ``q n - E``. Memory: after a compaction every level holds at most
``k`` values, and at most ``ceil(log2(n / k)) + 1`` levels exist.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["error_bound", "levels_bound", "compact", "merge_levels", "weighted_quantiles"]


def error_bound(n: int, k: int) -> float:
    """The a-priori rank-error bound ``ceil(log2(n / k)) / k`` (0 for ``n <= k``), unchecked.

    Parameters
    ----------
    n : int
        The number of values.
    k : int
        The values a level holds before it compacts.

    Returns
    -------
    float
        The largest ``E / n`` the sketch can reach after ``n`` values.
    """
    return _halvings(n, k) / k


def levels_bound(n: int, k: int) -> int:
    """The most levels the sketch has after ``n`` values, ``ceil(log2(n / k)) + 1`` (1 for ``n <= k``).

    Parameters
    ----------
    n : int
        The number of values.
    k : int
        The values a level holds before it compacts.

    Returns
    -------
    int
    """
    return _halvings(n, k) + 1


def _halvings(n: int, k: int) -> int:
    """How many times ``n`` values must be halved to fit in ``k``: ``ceil(log2(n / k))``, 0 for ``n <= k``."""
    return 0 if n <= k else math.ceil(math.log2(n / k))


def compact(levels: list, compactions: list, k: int) -> None:
    """Compact, bottom up, every level that holds more than ``k`` values (in place).

    Parameters
    ----------
    levels : list of numpy.ndarray
        ``levels[h]``: ``(E, m_h)`` values of weight ``2**h``.
    compactions : list of int
        The compactions made per level.
    k : int
        The values a level holds before it compacts.
    """
    h = 0
    while h < len(levels):
        buf = levels[h]
        if buf.shape[1] > k:
            buf = np.sort(buf, axis=1, kind="quicksort" if h == 0 else "stable")  # above 0: sorted runs
            m = buf.shape[1] - buf.shape[1] % 2
            up = buf[:, compactions[h] % 2:m:2]  # the lower or the upper of each pair, alternately
            levels[h] = buf[:, m:].copy()  # the odd one out (the largest) stays
            compactions[h] += 1
            if h + 1 == len(levels):
                levels.append(np.empty((buf.shape[0], 0)))
                compactions.append(0)
            levels[h + 1] = np.concatenate([levels[h + 1], up], axis=1)
        h += 1


def merge_levels(levels: list, compactions: list, other_levels: list, other_compactions: list, k: int) -> None:
    """Merge another sketch's levels into ``levels`` (concatenated level by level), then compact.

    Parameters
    ----------
    levels, compactions : list
        The sketch merged into, changed in place.
    other_levels, other_compactions : list
        The sketch merged in, unchanged.
    k : int
        The values a level holds before it compacts.
    """
    for h, (buf, c) in enumerate(zip(list(other_levels), list(other_compactions), strict=True)):
        if h == len(levels):
            levels.append(np.empty((buf.shape[0], 0)))
            compactions.append(0)
        levels[h] = np.concatenate([levels[h], buf], axis=1)
        compactions[h] += c
    compact(levels, compactions, k)


def weighted_quantiles(levels: list, qs, n: int) -> np.ndarray:
    """For each ``q``, the smallest kept value ``y`` with ``R_est(y) >= q n``, per trailing element.

    Parameters
    ----------
    levels : list of numpy.ndarray
        The sketch's levels, ``(E, m_h)`` each.
    qs : numpy.ndarray
        Probabilities in [0, 1], 1-D.
    n : int
        The number of values (the total weight).

    Returns
    -------
    numpy.ndarray
        ``(len(qs), E)``.
    """
    items = np.concatenate(levels, axis=1)
    weights = np.concatenate([np.full(b.shape[1], 2 ** h, np.int64) for h, b in enumerate(levels)])
    order = np.argsort(items, axis=1, kind="stable")
    items = np.take_along_axis(items, order, axis=1)
    cum = np.cumsum(weights[order], axis=1)
    rows = np.arange(items.shape[0])
    out = np.empty((len(qs), items.shape[0]))
    for i, q in enumerate(qs):
        out[i] = items[rows, np.minimum((cum < q * n).sum(axis=1), items.shape[1] - 1)]
    return out
