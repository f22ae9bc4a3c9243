"""A kernel block's parameter layout: names and shapes of its parameters, packed into one float vector.

A field is a scalar (a name), or an array ``(name, shape)`` packed row-major. A shape may name a
size field of the same layout instead of a number, ``("F", ("n", "n"))``: the layout then serves
every order ``n`` of a block (a Kalman filter of any number of states) with one set of kernels,
which read ``n = as_int(p[AT.n])`` and find an array with :func:`offset` ``(AT.F, n)``.
:meth:`Layout.pack` takes ``n`` from the values; :meth:`Layout.sized` gives the layout of one ``n``.
:mod:`ctrl_analysis.engine.matrix` views the arrays as matrices.

Examples
--------
>>> import numpy as np
>>> KF = Layout("n", "R", ("h", "n"), ("F", ("n", "n")))
>>> AT = KF.at
>>> AT
at(n=0, R=1, h=2, F=(2, 1, 0))
>>> p = KF.pack(n=2, R=0.5, h=[1, 0], F=np.eye(2))
>>> n = int(p[AT.n])
>>> offset(AT.F, n), KF.sized(n=2).at.F
(4, 4)
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from .._validate import check_array

__all__ = ["Layout", "offset"]


def _int(s) -> bool:
    return isinstance(s, (int, np.integer)) and not isinstance(s, bool)


def _parse(fields):
    """``(names, shapes)`` of ``Layout(*fields)``, checked."""
    names, shapes = [], []
    for f in fields:
        try:
            name, shape = (f, ()) if isinstance(f, str) else f
            shape = (shape,) if _int(shape) or isinstance(shape, str) else tuple(shape)
        except (TypeError, ValueError):
            raise TypeError(f"fields: each field must be a name or (name, shape), got {f!r:.80}") from None
        if not isinstance(name, str) or not name.isidentifier():
            raise ValueError(f"fields: a parameter name must be an identifier, got {name!r}")
        if not all(_int(s) or isinstance(s, str) for s in shape):
            raise TypeError(f"fields: the shape of {name!r} must be an int, a size name or a tuple of them, "
                            f"got {shape!r:.80}")
        if any(_int(s) and s < 0 for s in shape):
            raise ValueError(f"fields: the shape of {name!r} must not be negative, got {shape}")
        names.append(name)
        shapes.append(tuple(s if isinstance(s, str) else int(s) for s in shape))
    if len(set(names)) != len(names):
        raise ValueError(f"fields: parameter names must be unique, got {names}")
    return tuple(names), tuple(shapes)


def _size_name(names, shapes):
    """The one size name the shapes use (``None`` if none), checked: an earlier scalar field, at most squared."""
    dims = sorted({s for shape in shapes for s in shape if isinstance(s, str)})
    if not dims:
        return None
    if len(dims) > 1:
        raise ValueError(f"fields: the shapes may name one size field, got {dims}")
    dim = dims[0]
    first = min(i for i, shape in enumerate(shapes) if dim in shape)
    if dim not in names[:first] or shapes[names.index(dim)] != ():
        raise ValueError(f"fields: the size {dim!r} must be a scalar field before the first array sized by it")
    if any(shape.count(dim) > 2 for shape in shapes):
        raise ValueError(f"fields: a shape may use the size {dim!r} at most twice (a matrix)")
    return dim


class Layout:
    """Names and shapes of a block's kernel parameters, packed into one float vector.

    Parameters
    ----------
    *fields : str or (str, int or str or tuple of int or str)
        The parameters in vector order: a name (a scalar) or ``(name, shape)``; a matrix is packed
        row-major. A shape entry may be the name of an earlier scalar field (the size, say ``"n"``),
        at most twice per shape and one size name per layout: the arrays' lengths are then read
        from the vector at run time.

    Attributes
    ----------
    at : namedtuple of int or tuple of int
        The offset of each parameter in the vector; an array's first entry. Kernels read
        ``p[AT.eta]``, ``p[AT.gains + i]`` with ``AT = LAYOUT.at`` at module level: numba takes that
        namedtuple as a compile-time constant (a ``Layout`` object it cannot type). After an array
        sized by ``n`` an offset is the triple ``(c0, c1, c2)`` of ``c0 + c1 n + c2 n²``, which
        :func:`offset` evaluates (kernels write ``offset(AT.F, n)`` for every field alike).
    size : int or None
        Length of the packed vector; ``None`` when it depends on a size field (:meth:`sized`).
    size_name : str or None
        The size field that shapes name, if any.

    Raises
    ------
    ValueError
        If a name repeats, is not an identifier, a shape is negative or names a size wrongly.

    Examples
    --------
    >>> L = Layout("eta", ("gains", 3), ("F", (2, 2)))
    >>> L.at, L.size
    (at(eta=0, gains=1, F=4), 8)
    >>> L.pack(eta=0.5, gains=[1, 2, 3], F=np.eye(2))
    array([0.5, 1. , 2. , 3. , 1. , 0. , 0. , 1. ])
    """

    def __init__(self, *fields):
        self.names, self.shapes = _parse(fields)
        self.size_name = _size_name(self.names, self.shapes)
        offsets, coef = [], [0, 0, 0]  # the running offset c0 + c1 n + c2 n²
        for s in self.shapes:
            offsets.append(coef[0] if coef[1] == coef[2] == 0 else tuple(coef))
            coef[s.count(self.size_name) if self.size_name else 0] += int(np.prod([d for d in s if _int(d)],
                                                                                   dtype=int))
        self.size = coef[0] if coef[1] == coef[2] == 0 else None
        self.at = namedtuple("at", self.names)(*offsets)

    def sized(self, **size) -> Layout:
        """The layout of one value of the size field (every shape a number); the layout itself if it has none.

        Parameters
        ----------
        **size : int
            The size field by name (``n=3``), a whole number >= 0.

        Returns
        -------
        Layout

        Raises
        ------
        ValueError
            If the size is missing, unknown, or not a whole number >= 0.
        """
        want = [] if self.size_name is None else [self.size_name]
        if sorted(size) != want:
            raise ValueError(f"sized needs the layout's size field {want}, got {sorted(size)}")
        if not want:
            return self
        n = size[self.size_name]
        try:
            whole = float(n) == int(n) and int(n) >= 0
        except (TypeError, ValueError, OverflowError):
            whole = False
        if not whole or isinstance(n, (bool, str, bytes)):
            raise ValueError(f"size {self.size_name!r} must be a whole number >= 0, got {n!r:.80}")
        n = int(n)
        return Layout(*[(name, tuple(n if d == self.size_name else d for d in s))
                        for name, s in zip(self.names, self.shapes, strict=True)])

    def pack(self, **values) -> np.ndarray:
        """The parameter vector from one value per name (shapes checked; a size field sets the arrays' shapes).

        Parameters
        ----------
        **values : float or array_like
            Every parameter of the layout, by name.

        Returns
        -------
        numpy.ndarray, shape (size,)

        Raises
        ------
        ValueError
            If a name is missing or unknown, or a value has the wrong shape, is not a number or is NaN.
        """
        if self.size_name is not None and self.size_name in values:
            try:
                return self.sized(**{self.size_name: values[self.size_name]}).pack(**values)
            except ValueError as exc:
                if "must have shape" not in str(exc):
                    raise
                raise ValueError(f"{exc} ({self.size_name} = {values[self.size_name]!r:.40})") from None
        unknown = sorted(set(values) - set(self.names))
        missing = [n for n in self.names if n not in values]
        if unknown or missing:
            raise ValueError(f"pack needs exactly the layout's parameters {list(self.names)}: "
                             f"missing {missing}, unknown {unknown}")
        out = np.empty(self.size)
        for name, shape, lo in zip(self.names, self.shapes, self.at, strict=True):
            try:
                v = check_array(name, values[name])
            except TypeError:
                v = None
            if v is None or values[name] is None or np.isnan(v).any():
                raise ValueError(f"parameter {name!r} must be a number or an array of numbers (no NaN), "
                                 f"got {values[name]!r:.80}")
            if v.shape != shape:
                raise ValueError(f"parameter {name!r} must have shape {shape}, got {v.shape}")
            out[lo:lo + v.size] = v.reshape(-1)
        return out

    def unpack(self, p) -> dict:
        """The parameters of a packed vector, by name (arrays in their declared shapes).

        Parameters
        ----------
        p : array_like, shape (size,)

        Returns
        -------
        dict of str -> float or numpy.ndarray
        """
        p = np.asarray(p, dtype=float)
        if self.size_name is not None and p.ndim == 1 and p.shape[0] > self.at[self.names.index(self.size_name)]:
            return self.sized(**{self.size_name: p[self.at[self.names.index(self.size_name)]]}).unpack(p)
        if p.shape != (self.size,):
            raise ValueError(f"p must have shape ({self.size},), got {p.shape}")
        out = {}
        for name, shape, lo in zip(self.names, self.shapes, self.at, strict=True):
            n = int(np.prod(shape, dtype=int))
            out[name] = float(p[lo]) if shape == () else p[lo:lo + n].reshape(shape).copy()
        return out

    def __repr__(self) -> str:
        return "Layout(" + ", ".join(n if s == () else f"({n!r}, {s})" for n,
                                     s in zip(self.names, self.shapes, strict=True)) + ")"


def offset(o, n):
    """The offset of a layout field for size ``n``: ``o`` itself, or ``c0 + c1 n + c2 n²`` for ``o = (c0, c1, c2)``.

    Callable from numba-compiled kernels (``o`` is then a compile-time constant of ``AT``).

    Parameters
    ----------
    o : int or tuple of 3 int
        ``AT.name`` of a :class:`Layout`.
    n : int
        The size field's value (``as_int(p[AT.n])``).

    Returns
    -------
    int
    """
    _compiled_offset  # noqa: B018 - named so that the runners' cache key (engine.jit.source_key) covers it
    if isinstance(o, tuple):
        return o[0] + o[1] * n + o[2] * n * n
    return o


def _compiled_offset():
    """:func:`offset` inside numba-compiled kernels: typed on ``o``, so a constant offset costs nothing."""
    try:
        from numba import types
        from numba.extending import overload
    except ImportError:  # pragma: no cover - numba is optional: the numpy engine needs none of this
        return

    @overload(offset, inline="always")
    def _offset(o, n):
        if isinstance(o, types.Integer):
            return lambda o, n: o
        return lambda o, n: o[0] + o[1] * n + o[2] * n * n


_compiled_offset()
