"""Streamed statistics: accumulators fed chunk by chunk, merged across processes, in bounded memory.

A Monte Carlo study reduces its runs to means, standard deviations, percentiles, divergence
counts and histograms. The accumulators here take the runs a chunk at a time, as arrays of shape
``(B_chunk, ...)`` (the runs on axis 0, the trailing axes a per-run trace or a scalar), so memory
is bounded by the trailing shape (and the sketch size), never by the number of runs:

* :class:`Moments`: count, mean, variance / standard deviation (any ``ddof``), min and max per
  trailing element (Chan, Golub & LeVeque's pairwise update; each chunk is centred two-pass);
* :class:`Quantiles`: exact (``np.quantile`` bit for bit) while at most ``k`` runs were added,
  then a deterministic mergeable compactor sketch with a proven, reported rank-error bound;
* :class:`Counts`: how many runs have a flag (e.g. diverged), per trailing element, exact;
* :class:`Histogram`: fixed bins, exact counts (as ``np.histogram``), under- and overflow;
* :class:`Keep`: the traces of chosen runs (the ones a figure draws) with their run index.

Every accumulator has ``add(values, ...)`` (returns the accumulator), ``merge(other)`` (in place,
returns the accumulator), ``copy()``, ``nbytes`` and the class method ``of(values, ...)``.

**Excluded runs.** ``add(values, exclude=mask)`` leaves out the runs where the boolean ``mask``
(one entry per run) is true, e.g. the diverged runs; they are counted in ``excluded``. A NaN or an
infinity in a run that is not excluded is an error, unless the accumulator was built with
``nonfinite="exclude"``: then such a run is left out whole and counted in ``excluded`` too.

**Determinism.** Every accumulator is a pure function of its inputs: no random numbers, no
dependence on the number of processes. ``acc.add(chunk)`` *is* ``acc.merge(type(acc).of(chunk))``
(that is how it is written), so folding per-chunk accumulators in the order of the chunk index
gives the same bits as feeding the chunks to one accumulator, however the chunks were spread over
processes: a worker returns one accumulator per chunk, the parent merges them in chunk order.
Counts, histograms, min, max, kept traces and exact quantiles do not depend on the chunking or
the merge tree at all; means and variances do only through floating-point rounding (a few ulps);
sketched quantiles do within their rank-error bound.
"""

from __future__ import annotations

import copy as _copy
import math

import numpy as np

from ._validate import check_array, check_finite, check_in, check_int

__all__ = ["Moments", "Quantiles", "Counts", "Histogram", "Keep"]

#: What a NaN or inf in a run that is not excluded does: an error, or the run is excluded.
NONFINITE = ("raise", "exclude")
#: The ``method`` values of ``np.quantile``, for the exact regime of :class:`Quantiles`.
METHODS = ("inverted_cdf", "averaged_inverted_cdf", "closest_observation", "interpolated_inverted_cdf",
           "hazen", "weibull", "linear", "median_unbiased", "normal_unbiased", "lower", "higher",
           "midpoint", "nearest")


def _shape(value) -> tuple | None:
    """The trailing shape: ``None`` (taken from the first chunk), an int or a tuple of ints >= 0."""
    if value is None:
        return None
    if isinstance(value, (list, tuple)):
        return tuple(check_int("shape", v, minimum=0) for v in value)
    return (check_int("shape", value, minimum=0),)


def _mask(value, n: int) -> np.ndarray:
    """``exclude`` as a boolean array of ``n`` entries, one per run of the chunk."""
    arr = None if isinstance(value, (str, bytes)) else np.asarray(value)
    if arr is None or arr.dtype != bool:
        raise TypeError(f"exclude must be a boolean array with one entry per run, got {value!r:.80}")
    if arr.shape != (n,):
        raise ValueError(f"exclude must have shape ({n},) (one entry per run of values), got {arr.shape}")
    return arr


def _rows(values, shape) -> np.ndarray:
    """``values`` as a float array ``(B, *shape)`` with the runs on axis 0."""
    arr = check_array("values", values)
    if arr.ndim < 1:
        raise ValueError("values must have the runs on axis 0 (ndim >= 1), got a single number")
    if shape is not None and arr.shape[1:] != shape:
        raise ValueError(f"values must have the trailing shape {shape} of the accumulator (runs on axis 0), "
                         f"got shape {arr.shape}")
    return arr


class _Accumulator:
    """Plumbing shared by the accumulators: the trailing shape, excluded runs, add, merge, copy."""

    def __init__(self, shape=None, *, nonfinite: str = "raise"):
        self.shape = _shape(shape)
        self.nonfinite = check_in("nonfinite", nonfinite, NONFINITE)
        self.n_runs = 0  # runs offered to add, the excluded ones included
        self.excluded = 0
        self._reset()

    @property
    def count(self) -> int:
        """The number of runs accumulated (offered minus excluded)."""
        return self.n_runs - self.excluded

    @property
    def size(self) -> int:
        """The number of trailing elements (1 for scalar values)."""
        return math.prod(self.shape or ())

    @classmethod
    def of(cls, values, exclude=None, **options):
        """A new accumulator holding one chunk.

        Parameters
        ----------
        values : array_like
            The chunk, shape ``(B, ...)``: runs on axis 0.
        exclude : array_like of bool, optional
            One entry per run; true leaves the run out (counted in ``excluded``).
        **options
            The constructor's keyword arguments.

        Returns
        -------
        accumulator
            A new accumulator of this class that has seen only ``values``.
        """
        acc = cls(**options)
        acc._fill(values, exclude)
        return acc

    def add(self, values, exclude=None):
        """Accumulate one chunk of runs: ``self.merge(type(self).of(values, exclude, <same options>))``.

        Parameters
        ----------
        values : array_like
            The chunk, shape ``(B, ...)``: runs on axis 0, the trailing shape as before.
        exclude : array_like of bool, optional
            One entry per run; true leaves the run out (e.g. diverged), counted in ``excluded``.

        Returns
        -------
        accumulator
            ``self``, updated.
        """
        fresh = self._empty()
        fresh._fill(values, exclude)
        return self.merge(fresh)

    def merge(self, other):
        """Merge another accumulator of the same kind into this one (in place; ``other`` is unchanged).

        Parameters
        ----------
        other : accumulator
            Of the same class, the same trailing shape and options (e.g. from another process).

        Returns
        -------
        accumulator
            ``self``, updated.
        """
        if not isinstance(other, type(self)):
            raise TypeError(f"other must be a {type(self).__name__}, got {type(other).__name__}")
        if self.shape is not None and other.shape is not None and self.shape != other.shape:
            raise ValueError(f"other must have the trailing shape {self.shape}, got {other.shape}")
        self._check_options(other)
        if self.shape is None:
            self.shape = other.shape
            if other.shape is not None:
                self._allocate()
        if other.shape is not None:
            self._merge(other)
        self.n_runs += other.n_runs
        self.excluded += other.excluded
        return self

    def copy(self):
        """An independent copy.

        Returns
        -------
        accumulator
            A deep copy of ``self``.
        """
        return _copy.deepcopy(self)

    @property
    def nbytes(self) -> int:
        """Bytes held by the accumulator's arrays (what grows with the data, if anything)."""
        return sum(v.nbytes for v in vars(self).values() if isinstance(v, np.ndarray)) + sum(
            a.nbytes for v in vars(self).values() if isinstance(v, list) for a in v if isinstance(a, np.ndarray))

    # -- hooks -----------------------------------------------------------------------------
    def _empty(self):
        acc = _copy.copy(self)  # same options
        acc.shape, acc.n_runs, acc.excluded = self.shape, 0, 0
        acc._reset()
        return acc

    def _kept(self, values, exclude) -> np.ndarray:
        """The chunk's kept runs as ``(n, size)`` rows; sets the shape and the run counts."""
        arr = _rows(values, self.shape)
        b = arr.shape[0]
        keep = np.ones(b, bool) if exclude is None else ~_mask(exclude, b)
        flat = arr.reshape(b, -1)
        bad = keep & ~np.isfinite(flat).all(axis=1)
        if bad.any():
            if self.nonfinite == "raise":
                raise ValueError(f"values must be finite in every run not excluded (run {int(np.argmax(bad))} of the "
                                 "chunk is not): pass exclude=<mask of diverged runs> or build with nonfinite='exclude'")
            keep &= ~bad
        if self.shape is None:
            self.shape = arr.shape[1:]
            self._allocate()
        self.n_runs, self.excluded = b, int(b - keep.sum())
        return flat[keep]

    def _reset(self):
        if self.shape is not None:
            self._allocate()

    def _check_options(self, other):
        pass


class Moments(_Accumulator):
    """Count, mean, variance, min and max per trailing element, merged exactly as pairs of chunks.

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
        if self.shape is not None:
            self._allocate()

    def _fill(self, values, exclude):
        rows = self._kept(values, exclude)
        n = rows.shape[0]
        if n:
            d = rows - rows[0]
            self._n, self._shift, self._rel = n, rows[0].copy(), d.mean(axis=0)
            self._m2 = ((d - self._rel) ** 2).sum(axis=0)
            self._min, self._max = rows.min(axis=0), rows.max(axis=0)

    def _merge(self, other):
        na, nb = self._n, other._n
        if nb == 0:
            return
        if na == 0:
            self._shift, self._rel, self._m2 = other._shift.copy(), other._rel.copy(), other._m2.copy()
        else:
            n = na + nb
            d = ((other._shift - self._shift) + other._rel) - self._rel  # small numbers: no cancellation
            self._rel = self._rel + d * (nb / n)
            self._m2 = self._m2 + other._m2 + d * d * (na * nb / n)
        self._min, self._max = np.minimum(self._min, other._min), np.maximum(self._max, other._max)
        self._n = na + nb

    def _result(self, arr, valid: bool):
        out = arr if valid else np.full(self.size, np.nan)
        return out.reshape(self.shape or ())[()]

    @property
    def mean(self):
        """The mean per trailing element (NaN before any run is accumulated)."""
        return self._result(self._shift + self._rel if self.count else None, self.count > 0)

    @property
    def min(self):
        """The smallest value per trailing element (NaN before any run is accumulated)."""
        return self._result(getattr(self, "_min", None), self.count > 0)

    @property
    def max(self):
        """The largest value per trailing element (NaN before any run is accumulated)."""
        return self._result(getattr(self, "_max", None), self.count > 0)

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
        valid = self.count > ddof
        return self._result(self._m2 / (self.count - ddof) if valid else None, valid)

    def std(self, ddof: int = 0):
        """The standard deviation per trailing element, ``sqrt(var(ddof))``.

        Parameters
        ----------
        ddof : int
            Delta degrees of freedom, >= 0.

        Returns
        -------
        numpy.ndarray or numpy.float64
            Of the trailing shape; NaN where ``count <= ddof``.
        """
        return np.sqrt(self.var(ddof))


class Quantiles(_Accumulator):
    """Quantiles per trailing element: exact up to ``k`` runs, then a mergeable sketch with a rank-error bound.

    While at most ``k`` runs were accumulated every value is kept and :meth:`quantile` /
    :meth:`percentile` return ``np.quantile`` / ``np.percentile`` with ``method``, bit for bit
    (whatever the chunking and merge order). Past ``k`` the values form a compactor hierarchy
    (Manku, Rajagopalan & Lindsay; the deterministic form of KLL): level ``h`` holds values of
    weight ``2**h``; when a level holds more than ``k`` values they are sorted and every other one
    moves up with twice the weight (the lower or upper of each pair, alternately), an odd one out
    staying. All trailing elements see the same runs, so they compact together.

    **Rank-error bound.** Let ``n`` be the count and ``R(x)`` the number of values ``<= x``. One
    compaction at level ``h`` changes the estimated ``R(x)`` of any ``x`` by at most ``2**h``;
    level ``h`` receives at most ``n / 2**h`` values and each compaction takes at least ``k`` of
    them, so its compactions cost at most ``n / k``, and only levels ``h < log2(n / k)`` compact.
    Hence for every ``x``: ``|R_est(x) - R(x)| <= E <= n * ceil(log2(n / k)) / k``, where ``E``
    (the sum of ``2**h`` over the compactions made) is tracked: :attr:`rank_error` is ``E / n``.
    In the sketch regime the ``q``-quantile returned is the smallest kept value ``y`` with
    ``R_est(y) >= q n`` (inverted CDF, whatever ``method``); its true rank (the count below it to
    the count up to it) meets ``[q n - E, q n + E]``. ``q = 0`` and ``q = 1`` give the exact min
    and max. Memory: at most ``k`` values per level and ``ceil(log2(n / k)) + 1`` levels, i.e.
    ``8 * k * (ceil(log2(n / k)) + 1)`` bytes per trailing element (:meth:`bytes_bound`), plus
    one chunk while it is added. With ``k = 4096`` and ``10**6`` runs: ``E / n <= 0.2 %``,
    288 KiB per trailing element.

    Parameters
    ----------
    shape : int or tuple of int, optional
        The trailing shape of the values; by default that of the first chunk.
    k : int
        Values kept per level, 16 to 2**24: exact up to ``k`` runs, rank error ``<= ceil(log2(n/k))/k``.
    method : str
        ``np.quantile``'s method for the exact regime (default ``"linear"``).
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
        self._levels = [np.empty((self.size, 0))]  # level h: (size, m_h) values of weight 2**h
        self._compactions = [0]
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
        self._compactions = [0]
        if rows.shape[0]:
            self._min, self._max = rows.min(axis=0), rows.max(axis=0)
        self._compact()

    def _merge(self, other):
        for h, (buf, c) in enumerate(zip(other._levels, other._compactions)):
            if h == len(self._levels):
                self._levels.append(np.empty((self.size, 0)))
                self._compactions.append(0)
            self._levels[h] = np.concatenate([self._levels[h], buf], axis=1)
            self._compactions[h] += c
        self._min, self._max = np.minimum(self._min, other._min), np.maximum(self._max, other._max)
        self._compact()

    def _compact(self):
        h = 0
        while h < len(self._levels):
            buf = self._levels[h]
            if buf.shape[1] > self.k:
                buf = np.sort(buf, axis=1, kind="quicksort" if h == 0 else "stable")  # upper levels: sorted runs
                m = buf.shape[1] - buf.shape[1] % 2
                up = buf[:, self._compactions[h] % 2:m:2]  # the lower or upper of each pair, alternately
                self._levels[h] = buf[:, m:].copy()  # the odd one out (the largest) stays
                self._compactions[h] += 1
                if h + 1 == len(self._levels):
                    self._levels.append(np.empty((self.size, 0)))
                    self._compactions.append(0)
                self._levels[h + 1] = np.concatenate([self._levels[h + 1], up], axis=1)
            h += 1

    @property
    def exact(self) -> bool:
        """True while every value is kept (at most ``k`` runs): results equal ``np.quantile``'s."""
        return not any(self._compactions)

    @property
    def rank_error(self) -> float:
        """The proven bound on the rank error now, as a fraction of the count (0.0 while exact)."""
        e = sum(c * 2 ** h for h, c in enumerate(self._compactions))
        return e / self.count if self.count else 0.0

    @staticmethod
    def error_bound(n: int, k: int) -> float:
        """The a-priori rank-error bound ``ceil(log2(n / k)) / k`` for ``n`` values (0 for ``n <= k``).

        Parameters
        ----------
        n : int
            The number of values, >= 0.
        k : int
            The sketch's values per level, >= 1.

        Returns
        -------
        float
            The largest possible :attr:`rank_error` after ``n`` values, whatever the chunking and merges.
        """
        n, k = check_int("n", n, minimum=0), check_int("k", k, minimum=1)
        return 0.0 if n <= k else math.ceil(math.log2(n / k)) / k

    def bytes_bound(self, n: int) -> int:
        """The most bytes the kept values take after ``n`` runs (between chunks), by the bound above.

        Parameters
        ----------
        n : int
            The number of runs, >= 0.

        Returns
        -------
        int
            ``8 * size * k * (levels)`` plus the min and max, where ``levels = ceil(log2(n / k)) + 1``.
        """
        n = check_int("n", n, minimum=0)
        levels = 1 if n <= self.k else math.ceil(math.log2(n / self.k)) + 1
        return 8 * self.size * (min(n, self.k) * levels + 2)

    def _answer(self, q, name: str, scale: float):
        qs = check_finite(name, q)
        if np.any((qs < 0) | (qs > scale)):
            raise ValueError(f"{name} must be in [0, {scale:g}], got {q!r:.80}")
        qs = np.asarray(qs, float)
        if self.count == 0:
            return np.full(qs.shape + (self.shape or ()), np.nan)[()]
        if self.exact:
            fn = np.percentile if scale == 100 else np.quantile
            out = fn(self._levels[0], qs, axis=1, method=self.method)
            return out.reshape(qs.shape + self.shape)[()]
        out = self._sketch(qs.ravel() / scale)
        return out.reshape(qs.shape + self.shape)[()]

    def _sketch(self, qs):
        items = np.concatenate(self._levels, axis=1)
        weights = np.concatenate([np.full(b.shape[1], 2 ** h, np.int64) for h, b in enumerate(self._levels)])
        order = np.argsort(items, axis=1, kind="stable")
        items = np.take_along_axis(items, order, axis=1)
        cum = np.cumsum(weights[order], axis=1)
        out = np.empty((len(qs), self.size))
        for i, q in enumerate(qs):
            idx = np.minimum((cum < q * self.count).sum(axis=1), items.shape[1] - 1)
            out[i] = items[np.arange(self.size), idx]
            if q == 0.0 or q == 1.0:
                out[i] = self._min if q == 0.0 else self._max
        return out

    def quantile(self, q):
        """The ``q``-quantiles per trailing element (``np.quantile(x, q, axis=0)`` while :attr:`exact`).

        Parameters
        ----------
        q : float or array_like
            Probabilities in [0, 1].

        Returns
        -------
        numpy.ndarray or numpy.float64
            Shape ``q.shape + shape``; NaN before any run is accumulated. In the sketch regime the
            rank of each answer is within :attr:`rank_error` of ``q`` (see the class).
        """
        return self._answer(q, "q", 1.0)

    def percentile(self, p):
        """The ``p``-th percentiles per trailing element (``np.percentile(x, p, axis=0)`` while :attr:`exact`).

        Parameters
        ----------
        p : float or array_like
            Percentages in [0, 100].

        Returns
        -------
        numpy.ndarray or numpy.float64
            Shape ``p.shape + shape``, as :meth:`quantile` of ``p / 100``.
        """
        return self._answer(p, "p", 100.0)


class Counts(_Accumulator):
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
        self._hits = arr.reshape(arr.shape[0], -1).sum(axis=0, dtype=np.int64)
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


class Histogram(_Accumulator):
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


class Keep(_Accumulator):
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
        """A new :class:`Keep` holding the wanted runs of one chunk whose first run is ``start``.

        Parameters
        ----------
        values : array_like
            The chunk, shape ``(B, ...)``: runs on axis 0.
        start : int
            The run index of ``values[0]``.
        **options
            The constructor's arguments (``runs``, ``shape``).

        Returns
        -------
        Keep
        """
        acc = cls(**options)
        acc._fill(values, start)
        return acc

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
            ``self``, updated.
        """
        fresh = self._empty()
        fresh._fill(values, self.seen if start is None else start)
        return self.merge(fresh)

    def _fill(self, values, start):
        start = check_int("start", start, minimum=0)
        arr = _rows(values, self.shape)
        if self.shape is None:
            self.shape = arr.shape[1:]
        index = start + np.arange(arr.shape[0])
        take = np.isin(index, self.wanted)
        self._runs, self._traces = index[take], arr.reshape(arr.shape[0], -1)[take]
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
