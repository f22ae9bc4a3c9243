"""Streamed statistics: accumulators fed chunk by chunk, merged across processes, in bounded memory.

The accumulators take a Monte Carlo run's results a chunk at a time, as arrays of shape
``(B_chunk, ...)`` (runs on axis 0; the trailing axes a per-run trace, or none for a scalar), so
memory is bounded by the trailing shape (and a sketch), never by the number of runs:
:class:`Moments` (count, mean, variance, min, max), :class:`Quantiles` (exact up to ``k`` runs,
then a sketch with a proven rank-error bound), :class:`Counts` (e.g. diverged runs),
:class:`Histogram` (fixed bins) and :class:`Keep` (the traces of the runs a figure draws). Each
has ``add(values, ...)``, ``merge(other)`` (both in place, returning the accumulator), ``copy()``,
``nbytes`` and the class method ``of(values, ...)``; all pickle, for other processes.

**Excluded runs.** ``add(values, exclude=mask)`` leaves out the runs where the boolean ``mask``
(one entry per run) is true, e.g. the diverged ones, and counts them in ``excluded``. A NaN or inf
in a run that is not excluded is an error, unless the accumulator was built with
``nonfinite="exclude"``: then that run is left out whole and counted in ``excluded`` too.

**Determinism.** No random numbers; nothing depends on the number of processes. ``acc.add(chunk)``
*is* ``acc.merge(type(acc).of(chunk))``, so folding per-chunk accumulators in chunk-index order
gives the same bits as feeding the chunks to one accumulator, however the chunks were spread over
processes (a worker returns one accumulator per chunk; the parent merges them in chunk order).
Counts, histograms, min, max, kept traces and exact quantiles do not depend on the chunking or the
merge tree at all; means and variances only through rounding (a few ulps); sketched quantiles
within their rank-error bound.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import check_finite, check_in, check_int
from . import _sketch
from ._accumulator import Accumulator

__all__ = ["Moments", "Quantiles", "Counts", "Histogram", "Keep"]

#: The ``method`` values of ``np.quantile``, for the exact regime of :class:`Quantiles`.
METHODS = ("inverted_cdf", "averaged_inverted_cdf", "closest_observation", "interpolated_inverted_cdf",
           "hazen", "weibull", "linear", "median_unbiased", "normal_unbiased", "lower", "higher",
           "midpoint", "nearest")



def _check_spread(m2) -> None:
    """Refuse finite values whose spread overflows double precision (a sum of squared deviations beyond 1.8e308)."""
    if not np.all(np.isfinite(m2)):
        raise ValueError("values: their spread overflows double precision (squared deviations from the mean beyond "
                         "1.8e308, e.g. values near 1e300 beside values near 1): scale them before adding")


class Moments(Accumulator):
    """Count, mean, variance, min and max per trailing element, combined chunk by chunk by the pairwise update.

    Each chunk is reduced two-pass around its first run ``x0`` (the shift): ``r = mean(x - x0)``,
    ``M2 = sum((x - x0 - r)**2)``; the mean is kept as ``x0 + r``. Chunks and accumulators are
    combined with the pairwise update of Chan, Golub & LeVeque: with ``d = mean_b - mean_a``
    (formed from the shifts and the small ``r``'s), ``n = n_a + n_b``, ``r += d * n_b / n`` and
    ``M2 = M2_a + M2_b + d**2 * n_a * n_b / n``. No sum of squares of the raw values is formed,
    and no difference of two large means: values far from zero (``1e9 + noise``) keep the
    variance of the noise to a few ulps.

    Parameters
    ----------
    shape : int or tuple of int, optional
        The trailing shape of the values (``()`` for one number per run); by default that of the
        first chunk.
    nonfinite : {"raise", "exclude"}
        What a NaN or inf does in a run that is not excluded: an error, or the run is excluded.

    Examples
    --------
    >>> import numpy as np
    >>> from ctrl_analysis.streaming import Moments
    >>> x = np.arange(12.0).reshape(6, 2)
    >>> m = Moments().add(x[:4]).add(x[4:])
    >>> m.count, m.mean.tolist(), m.std(ddof=1).tolist() == np.std(x, axis=0, ddof=1).tolist()
    (6, [5.0, 6.0], True)
    >>> m.add([[np.nan, np.nan], [1.0, 1.0]], exclude=np.array([True, False])).excluded
    1
    """

    def _allocate(self):
        self._n = 0  # the mean is _shift + _rel: _shift is the first run seen, _rel holds the digits that vary
        self._shift, self._rel, self._m2 = np.zeros(self.size), np.zeros(self.size), np.zeros(self.size)
        self._min, self._max = np.full(self.size, np.inf), np.full(self.size, -np.inf)

    def _reset(self):
        self._n = 0
        super()._reset()

    def _fill(self, values, exclude):
        rows = self._kept(values, exclude)
        n = rows.shape[0]
        if n:
            with np.errstate(over="ignore", invalid="ignore"):
                d = rows - rows[0]
                rel = d.mean(axis=0)
                m2 = ((d - rel) ** 2).sum(axis=0)
            _check_spread(m2)
            self._n, self._shift, self._rel, self._m2 = n, rows[0].copy(), rel, m2
            self._min, self._max = rows.min(axis=0), rows.max(axis=0)

    def _merge(self, other):
        na, nb = self._n, other._n
        if nb == 0:
            return
        if na == 0:
            self._shift, self._rel, self._m2 = other._shift.copy(), other._rel.copy(), other._m2.copy()
        else:
            n = na + nb
            with np.errstate(over="ignore", invalid="ignore"):
                d = ((other._shift - self._shift) + other._rel) - self._rel  # small numbers: no cancellation
                m2 = self._m2 + other._m2 + d * d * (na * nb / n)
            _check_spread(m2)
            self._rel = self._rel + d * (nb / n)
            self._m2 = m2
        self._min, self._max = np.minimum(self._min, other._min), np.maximum(self._max, other._max)
        self._n = na + nb

    def _result(self, arr, valid: bool):
        return (arr() if valid else np.full(self.size, np.nan)).reshape(self.shape or ())[()]

    mean = property(lambda self: self._result(lambda: self._shift + self._rel, self.count > 0),
                    doc="The mean per trailing element (NaN before any run).")
    min = property(lambda self: self._result(lambda: self._min, self.count > 0),
                   doc="The smallest value per trailing element (NaN before any run).")
    max = property(lambda self: self._result(lambda: self._max, self.count > 0),
                   doc="The largest value per trailing element (NaN before any run).")

    def var(self, ddof: int = 0):
        """The variance per trailing element, ``M2 / (count - ddof)``, as ``np.var(x, axis=0, ddof=ddof)``.

        Parameters
        ----------
        ddof : int
            Delta degrees of freedom, >= 0 (1: the unbiased sample variance).

        Returns
        -------
        numpy.ndarray or numpy.float64
            Of the trailing shape; NaN where ``count <= ddof``.
        """
        ddof = check_int("ddof", ddof, minimum=0)
        return self._result(lambda: self._m2 / (self.count - ddof), self.count > ddof)

    def std(self, ddof: int = 0):
        """The standard deviation per trailing element, ``sqrt(var(ddof))``.

        Parameters
        ----------
        ddof : int
            As :meth:`var`.

        Returns
        -------
        numpy.ndarray or numpy.float64
        """
        return np.sqrt(self.var(ddof))


class Quantiles(Accumulator):
    """Quantiles per trailing element: exact up to ``k`` runs, then a mergeable sketch with a rank-error bound.

    While at most ``k`` runs were accumulated every value is kept and :meth:`quantile` /
    :meth:`percentile` return ``np.quantile`` / ``np.percentile`` with ``method``, bit for bit,
    whatever the chunking and merge order. Past ``k`` the values go into a deterministic compactor
    sketch (levels of values of weight ``2**h``, at most ``k`` per level; :mod:`ctrl_analysis.streaming._sketch`
    has the design and the proof). All trailing elements see the same runs and compact together.

    **Bound.** With ``n`` values and ``R(x)`` the number of them ``<= x``, the sketch's estimate
    of ``R(x)`` is within ``E`` of it for every ``x``, where ``E <= n * ceil(log2(n / k)) / k``
    (:meth:`error_bound`); ``E / n`` as actually reached is :attr:`rank_error`. A sketched
    ``q``-quantile ``y`` is the smallest kept value whose estimated rank reaches ``q n`` (inverted
    CDF, whatever ``method``): the count of values ``< y`` is at most ``q n + E``, the count
    ``<= y`` at least ``q n - E``. ``q = 0`` and ``q = 1`` give the exact min and max.
    **Memory**: at most ``k`` values on each of ``ceil(log2(n / k)) + 1`` levels
    (:meth:`bytes_bound`), plus the chunk being added. With ``k = 4096`` and ``10**6`` runs:
    ``E / n <= 0.2 %`` and at most 288 KiB per trailing element.

    Parameters
    ----------
    shape : int or tuple of int, optional
        The trailing shape of the values; by default that of the first chunk.
    k : int
        Values kept per level, 16 to 2**24: exact up to ``k`` runs.
    method : str
        ``np.quantile``'s method, used while exact (default ``"linear"``).
    nonfinite : {"raise", "exclude"}
        What a NaN or inf does in a run that is not excluded: an error, or the run is excluded.

    Examples
    --------
    >>> import numpy as np
    >>> from ctrl_analysis.streaming import Quantiles
    >>> x = np.random.default_rng(0).normal(size=(3000, 2))
    >>> qs = Quantiles(k=4096).add(x[:1000]).add(x[1000:])
    >>> qs.exact, bool(np.array_equal(qs.quantile([0.05, 0.5]), np.quantile(x, [0.05, 0.5], axis=0)))
    (True, True)
    >>> big = Quantiles(k=256).add(np.random.default_rng(1).normal(size=100_000))
    >>> big.exact, big.rank_error <= Quantiles.error_bound(100_000, 256)
    (False, True)
    """

    def __init__(self, shape=None, *, k: int = 4096, method: str = "linear", nonfinite: str = "raise"):
        self.k = check_int("k", k, minimum=16, maximum=2 ** 24)
        self.method = check_in("method", method, METHODS)
        super().__init__(shape, nonfinite=nonfinite)

    def _allocate(self):
        self._levels, self._compactions = [np.empty((self.size, 0))], [0]  # level h: (size, m_h), weight 2**h
        self._min, self._max = np.full(self.size, np.inf), np.full(self.size, -np.inf)

    def _reset(self):
        self._levels, self._compactions = [], []
        if self.shape is not None:
            self._allocate()

    def _check_options(self, other):
        if other.k != self.k:
            raise ValueError(f"other must have the same k as this accumulator ({self.k}), got {other.k}")

    def _fill(self, values, exclude):
        rows = self._kept(values, exclude)
        self._levels = [np.ascontiguousarray(rows.T)]
        if rows.shape[0]:
            self._min, self._max = rows.min(axis=0), rows.max(axis=0)
        _sketch.compact(self._levels, self._compactions, self.k)

    def _merge(self, other):
        _sketch.merge_levels(self._levels, self._compactions, other._levels, other._compactions, self.k)
        self._min, self._max = np.minimum(self._min, other._min), np.maximum(self._max, other._max)

    @property
    def exact(self) -> bool:
        """True while every value is kept (at most ``k`` runs): results equal ``np.quantile``'s."""
        return not any(self._compactions)

    @property
    def rank_error(self) -> float:
        """The proven bound on the rank error reached, ``E / n`` (0.0 while exact)."""
        e = sum(c * 2 ** h for h, c in enumerate(self._compactions))
        return e / self.count if self.count else 0.0

    @staticmethod
    def error_bound(n: int, k: int) -> float:
        """The a-priori bound on :attr:`rank_error` after ``n`` values: ``ceil(log2(n / k)) / k`` (0 if ``n <= k``).

        Parameters
        ----------
        n : int
            The number of values, >= 0.
        k : int
            The sketch's values per level, >= 1.

        Returns
        -------
        float
            Holds whatever the chunking and the merges.
        """
        return _sketch.error_bound(check_int("n", n, minimum=0), check_int("k", k, minimum=1))

    def bytes_bound(self, n: int) -> int:
        """The most bytes :attr:`nbytes` reaches between chunks after ``n`` runs.

        Parameters
        ----------
        n : int
            The number of runs, >= 0.

        Returns
        -------
        int
            ``8 * size * (min(n, k) * (ceil(log2(n / k)) + 1) + 2)``: the levels, the min and the max.
        """
        n = check_int("n", n, minimum=0)
        return 8 * self.size * (min(n, self.k) * _sketch.levels_bound(n, self.k) + 2)

    def _answer(self, q, name: str, scale: float):
        qs = check_finite(name, q)
        if np.any((qs < 0) | (qs > scale)):
            raise ValueError(f"{name} must be in [0, {scale:g}], got {q!r:.80}")
        qs = np.asarray(qs, float)
        if self.count == 0:
            return np.full(qs.shape + (self.shape or ()), np.nan)[()]
        if self.exact:
            out = (np.percentile if scale == 100 else np.quantile)(self._levels[0], qs, axis=1, method=self.method)
        else:
            flat = qs.ravel() / scale
            out = _sketch.weighted_quantiles(self._levels, flat, self.count)
            out[flat == 0.0], out[flat == 1.0] = self._min, self._max
        return out.reshape(qs.shape + self.shape)[()]

    def quantile(self, q):
        """The ``q``-quantiles per trailing element: ``np.quantile(x, q, axis=0)`` while :attr:`exact`.

        Parameters
        ----------
        q : float or array_like
            Probabilities in [0, 1].

        Returns
        -------
        numpy.ndarray or numpy.float64
            Shape ``q.shape + shape``; NaN before any run. Sketched: within :attr:`rank_error` in rank.
        """
        return self._answer(q, "q", 1.0)

    def percentile(self, p):
        """The ``p``-th percentiles per trailing element: ``np.percentile(x, p, axis=0)`` while :attr:`exact`.

        Parameters
        ----------
        p : float or array_like
            Percentages in [0, 100].

        Returns
        -------
        numpy.ndarray or numpy.float64
            Shape ``p.shape + shape``; sketched, as :meth:`quantile` of ``p / 100``.
        """
        return self._answer(p, "p", 100.0)


class Counts(Accumulator):
    """How many runs have a flag set (e.g. diverged), per trailing element; merged exactly.

    Parameters
    ----------
    shape : int or tuple of int, optional
        The trailing shape of the flags (``()``: one flag per run); by default that of the first chunk.

    Examples
    --------
    >>> import numpy as np
    >>> from ctrl_analysis.streaming import Counts
    >>> c = Counts().add(np.array([True, False, False])).add(np.array([True]))
    >>> int(c.hits), c.n_runs, float(c.fraction)
    (2, 4, 0.5)
    """

    def __init__(self, shape=None):
        super().__init__(shape)

    def _allocate(self):
        self._hits = np.zeros(self.size, np.int64)

    def _fill(self, values, exclude):
        if exclude is not None:
            raise TypeError("exclude is not taken by Counts: every run is counted")
        arr = None if isinstance(values, (str, bytes)) else np.asarray(values)
        if arr is None or arr.dtype != bool or arr.ndim < 1:
            raise TypeError(f"values must be a boolean array with the runs on axis 0, got {values!r:.80}")
        if self.shape is not None and arr.shape[1:] != self.shape:
            raise ValueError(f"values must have the trailing shape {self.shape} (runs on axis 0), got {arr.shape}")
        if self.shape is None:
            self.shape = arr.shape[1:]
        self._hits = arr.reshape(arr.shape[0], math.prod(arr.shape[1:])).sum(axis=0, dtype=np.int64)
        self.n_runs = arr.shape[0]

    def _merge(self, other):
        self._hits = self._hits + other._hits

    @property
    def hits(self):
        """The number of runs whose flag is set, per trailing element."""
        return np.int64(0) if self.shape is None else self._hits.reshape(self.shape)[()]

    @property
    def fraction(self):
        """``hits / n_runs`` per trailing element (NaN before any run)."""
        return self.hits / self.n_runs if self.n_runs else np.full(self.shape or (), np.nan)[()]


class Histogram(Accumulator):
    """Counts in fixed bins per trailing element, as ``np.histogram(x, bins=edges)``; merged exactly.

    Bin ``i`` holds ``edges[i] <= x < edges[i + 1]``, the last bin also ``x == edges[-1]``; values
    below or above the edges are counted in :attr:`below` and :attr:`above`.

    Parameters
    ----------
    edges : array_like
        The bin edges: finite, strictly increasing, at least two.
    shape : int or tuple of int, optional
        The trailing shape of the values; by default that of the first chunk.
    nonfinite : {"raise", "exclude"}
        What a NaN or inf does in a run that is not excluded: an error, or the run is excluded.

    Examples
    --------
    >>> import numpy as np
    >>> from ctrl_analysis.streaming import Histogram
    >>> h = Histogram([0.0, 1.0, 2.0]).add(np.array([0.5, 1.0, 2.0, 3.0]))
    >>> h.counts.tolist(), int(h.above)
    ([1, 2], 1)
    """

    def __init__(self, edges, shape=None, *, nonfinite: str = "raise"):
        e = check_finite("edges", edges)
        if np.ndim(e) != 1 or np.size(e) < 2 or np.any(np.diff(e) <= 0):
            raise ValueError(f"edges must be a strictly increasing 1-D array of at least 2 entries, got {edges!r:.80}")
        self.edges = np.asarray(e, float)
        super().__init__(shape, nonfinite=nonfinite)

    def _allocate(self):
        nb = len(self.edges) - 1
        self._counts = np.zeros((self.size, nb), np.int64)
        self._below, self._above = np.zeros(self.size, np.int64), np.zeros(self.size, np.int64)

    def _check_options(self, other):
        if not np.array_equal(other.edges, self.edges):
            raise ValueError("other must have the same edges as this histogram")

    def _fill(self, values, exclude):
        rows = self._kept(values, exclude)
        nb = len(self.edges) - 1
        idx = np.searchsorted(self.edges, rows, side="right") - 1
        idx[rows == self.edges[-1]] = nb - 1
        col = np.broadcast_to(np.arange(self.size), rows.shape)
        inside = (idx >= 0) & (idx < nb)
        self._counts = np.bincount(col[inside] * nb + idx[inside], minlength=self.size * nb).reshape(self.size, nb)
        self._below, self._above = (idx < 0).sum(axis=0), (idx >= nb).sum(axis=0)

    def _merge(self, other):
        self._counts = self._counts + other._counts
        self._below, self._above = self._below + other._below, self._above + other._above

    def _shaped(self, arr, tail=()):
        return arr.reshape((self.shape or ()) + tail)[()] if self.shape is not None else None

    @property
    def counts(self):
        """The counts per bin: shape ``shape + (len(edges) - 1,)``."""
        return self._shaped(getattr(self, "_counts", None), (len(self.edges) - 1,))

    @property
    def below(self):
        """The number of values below ``edges[0]``, per trailing element."""
        return self._shaped(getattr(self, "_below", None))

    @property
    def above(self):
        """The number of values above ``edges[-1]``, per trailing element."""
        return self._shaped(getattr(self, "_above", None))


class Keep(Accumulator):
    """The traces of chosen runs (those a figure draws), with their run index, NaN included.

    Parameters
    ----------
    runs : int or array_like of int
        An int ``k``: the runs ``0 .. k-1``; or the run indices to keep (>= 0).
    shape : int or tuple of int, optional
        The trailing shape of the values; by default that of the first chunk.

    Examples
    --------
    >>> import numpy as np
    >>> from ctrl_analysis.streaming import Keep
    >>> x = np.arange(10.0).reshape(5, 2)
    >>> kept = Keep([1, 3]).merge(Keep.of(x[2:], start=2, runs=[1, 3])).add(x[:2], start=0)
    >>> kept.runs.tolist(), kept.traces.tolist()
    ([1, 3], [[2.0, 3.0], [6.0, 7.0]])
    """

    def __init__(self, runs, shape=None):
        if isinstance(runs, (int, np.integer)) and not isinstance(runs, bool):
            wanted = np.arange(check_int("runs", runs, minimum=0, maximum=10 ** 7))
        else:
            if isinstance(runs, (str, bytes)) or runs is None or np.ndim(runs) != 1:
                raise TypeError(f"runs must be an int or a 1-D sequence of run indices, got {runs!r:.80}")
            wanted = np.array([check_int("runs", r, minimum=0) for r in runs], np.int64)
        self.wanted = np.unique(wanted)
        super().__init__(shape)

    def _reset(self):
        self.seen = 0  # one past the largest run index offered
        super()._reset()

    def _allocate(self):
        self._runs, self._traces = np.zeros(0, np.int64), np.empty((0, self.size))

    def _check_options(self, other):
        if not np.array_equal(other.wanted, self.wanted):
            raise ValueError("other must keep the same runs as this accumulator")

    @classmethod
    def of(cls, values, start=0, **options):
        """A new :class:`Keep` (built with ``options``) holding one chunk; arguments as :meth:`add`.

        Parameters
        ----------
        values, start
            As :meth:`add` (``start`` 0 by default).
        **options
            The constructor's arguments.

        Returns
        -------
        Keep
        """
        return super().of(values, start, **options)

    def add(self, values, start=None):
        """Keep the wanted runs of one chunk.

        Parameters
        ----------
        values : array_like
            The chunk, shape ``(B, ...)``: runs on axis 0; NaN and inf are kept as they are.
        start : int, optional
            The run index of ``values[0]``; by default one past the largest index seen so far.

        Returns
        -------
        Keep
            ``self``.
        """
        fresh = self._empty()
        fresh._fill(values, self.seen if start is None else start)
        return self.merge(fresh)

    def _fill(self, values, start):
        start = check_int("start", start, minimum=0)
        arr = self._rows(values)
        if self.shape is None:
            self.shape = arr.shape[1:]
        index = start + np.arange(arr.shape[0])
        take = np.isin(index, self.wanted)
        self._runs, self._traces = index[take], arr.reshape(arr.shape[0], math.prod(arr.shape[1:]))[take]
        self.n_runs, self.seen = arr.shape[0], start + arr.shape[0]

    def _merge(self, other):
        both = np.intersect1d(self._runs, other._runs)
        if both.size:
            raise ValueError(f"other holds run {int(both[0])}, already kept here (a chunk added twice?)")
        runs = np.concatenate([self._runs, other._runs])
        order = np.argsort(runs, kind="stable")
        self._runs, self._traces = runs[order], np.concatenate([self._traces, other._traces])[order]
        self.seen = max(self.seen, other.seen)

    @property
    def runs(self):
        """The indices of the runs kept so far, increasing."""
        return getattr(self, "_runs", np.zeros(0, np.int64))

    @property
    def traces(self):
        """The kept runs' values, shape ``(len(runs),) + shape``, in the order of :attr:`runs`."""
        return None if self.shape is None else self._traces.reshape((-1,) + self.shape)
