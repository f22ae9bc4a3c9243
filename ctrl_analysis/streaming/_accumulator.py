"""The base of the streamed-statistics accumulators (:mod:`ctrl_analysis.streaming`) and their input checks.

:class:`Accumulator` holds what every accumulator shares: the trailing shape (given or taken from
the first chunk), the runs offered and excluded, the exclusion mask and the non-finite policy,
``add`` (written as a merge of a one-chunk accumulator, which makes a fold of per-chunk merges in
chunk order bit-identical to feeding the chunks), ``merge``, ``copy`` and ``nbytes``. A subclass
fills ``_allocate`` (its empty arrays), ``_fill`` (one chunk) and ``_merge`` (another one).
"""

from __future__ import annotations

import copy as _copy
import math

import numpy as np

from .._validate import check_array, check_in, check_int

__all__ = ["Accumulator", "NONFINITE"]

#: What a NaN or inf in a run that is not excluded does: an error, or the run is excluded.
NONFINITE = ("raise", "exclude")


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


class Accumulator:
    """The base of the streaming accumulators: the trailing shape, excluded runs, add, merge, copy.

    Parameters
    ----------
    shape : int or tuple of int, optional
        The trailing shape of the values (``()``: one number per run); by default that of the first chunk.
    nonfinite : {"raise", "exclude"}
        What a NaN or inf does in a run that is not excluded: an error, or the run is excluded.
    """

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
        """A new accumulator (built with ``options``) holding one chunk; arguments as :meth:`add`.

        Parameters
        ----------
        values, exclude
            As :meth:`add`.
        **options
            The constructor's keyword arguments.

        Returns
        -------
        accumulator
        """
        acc = cls(**options)
        acc._fill(values, exclude)
        return acc

    def add(self, values, exclude=None):
        """Accumulate one chunk: ``self.merge(type(self).of(values, exclude, <the same options>))``.

        Parameters
        ----------
        values : array_like
            The chunk, shape ``(B, ...)``: runs on axis 0, the trailing shape as before.
        exclude : array_like of bool, optional
            One entry per run; true leaves the run out (e.g. diverged), counted in ``excluded``.

        Returns
        -------
        accumulator
            ``self``.
        """
        fresh = self._empty()
        fresh._fill(values, exclude)
        return self.merge(fresh)

    def merge(self, other):
        """Merge ``other`` (same class, trailing shape and options; unchanged) into this accumulator.

        Parameters
        ----------
        other : accumulator
            E.g. from another process.

        Returns
        -------
        accumulator
            ``self``.
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
        """An independent (deep) copy.

        Returns
        -------
        accumulator
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
        arr = self._rows(values)
        b = arr.shape[0]
        keep = np.ones(b, bool) if exclude is None else ~_mask(exclude, b)
        flat = arr.reshape(b, math.prod(arr.shape[1:]))
        bad = keep & ~np.isfinite(flat).all(axis=1)
        if bad.any():
            if self.nonfinite == "raise":
                raise ValueError(f"values must be finite in every run not excluded (run {int(np.argmax(bad))} of "
                                 "the chunk is not): pass exclude=<mask of diverged runs> or nonfinite='exclude'")
            keep &= ~bad
        if self.shape is None:
            self.shape = arr.shape[1:]
            self._allocate()
        self.n_runs, self.excluded = b, int(b - keep.sum())
        return flat[keep]

    def _reset(self):
        if self.shape is not None:
            self._allocate()

    def _rows(self, values) -> np.ndarray:
        return _rows(values, self.shape)

    def _check_options(self, other):
        pass
