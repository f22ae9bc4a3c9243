"""Argument checks shared by every building block: each error names the argument and the rule."""

from __future__ import annotations

import numbers
import os
from pathlib import Path

import numpy as np

__all__ = [
    "check_real",
    "check_finite",
    "check_array",
    "check_positive",
    "check_nonnegative",
    "check_int",
    "check_in",
    "check_matrix",
    "check_hurwitz",
    "check_bool",
    "check_callable",
    "check_str",
    "check_names",
    "check_path",
    "check_out_dir",
    "check_vector",
    "check_seeds",
    "finite_result",
]


def _is_real_scalar(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) or (
        isinstance(value, np.generic) and np.isrealobj(value) and np.ndim(value) == 0
    )


def _float_array(name: str, value, what: str) -> np.ndarray:
    """``value`` as a float array; a string, bytes, ``None``, a bool or complex entries are a ``TypeError``."""
    if isinstance(value, (str, bytes, bool, np.bool_)) or value is None:
        raise TypeError(f"{name} must be {what}, got {value!r}")
    try:
        arr = np.asarray(value)
        if arr.dtype.kind in "bcUSV":  # a bool, complex, text or bytes is not a real number
            raise TypeError
        return arr.astype(float, copy=False)
    except (TypeError, ValueError, OverflowError):
        raise TypeError(f"{name} must be {what}, got {value!r:.200}") from None


def check_real(name: str, value) -> float:
    """One real number as a float (a type check only: NaN and inf pass; see :func:`check_finite`).

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : object
        Expected: one real number (NaN and inf pass).

    Returns
    -------
    float

    Raises
    ------
    TypeError
        ``"X must be a real number, got …"`` for a list, an array of more than one entry, a string,
        a bool, a complex number or ``None``.
    """
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if not _is_real_scalar(value):
        raise TypeError(f"{name} must be a real number, got {value!r}")
    return float(value)


def check_finite(name: str, value, *, shape=None, scalar: bool = False) -> np.ndarray | float:
    """Return ``value`` as float (scalar) or float array; raise if any entry is NaN/inf.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : array_like
        Expected: a finite number or array.
    shape : tuple of int, optional
        The shape ``value`` must have.
    scalar : bool
        With ``True`` the value must be one real number (see :func:`check_real`).

    Returns
    -------
    float or numpy.ndarray
        A float for a 0-d value, else a float array.

    Raises
    ------
    TypeError
        If ``value`` is not numeric (or, with ``scalar``, not one real number).
    ValueError
        If ``value`` contains NaN or inf, or does not have ``shape``.
    """
    if scalar:
        value = check_real(name, value)
    arr = _float_array(name, value, "a real number or array")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf), got {value!r}")
    if shape is not None and arr.shape != tuple(shape):
        raise ValueError(f"{name} must have shape {tuple(shape)}, got {arr.shape}")
    return float(arr) if arr.ndim == 0 else arr


def check_array(name: str, value) -> np.ndarray:
    """A real float array; NaN and inf allowed (a signal of a diverged run), strings and None not.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : array_like
        Expected: a real array (NaN and inf pass).

    Returns
    -------
    numpy.ndarray
        ``value`` as a float array.

    Raises
    ------
    TypeError
        If ``value`` is a string, ``None``, a bool, complex or not convertible to a float array.
    """
    return _float_array(name, value, "a real array")


def check_positive(name: str, value, *, scalar: bool = False) -> np.ndarray | float:
    """Finite and strictly positive (element-wise); one real number with ``scalar=True``.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : array_like
        Expected: finite entries > 0.
    scalar : bool
        With ``True`` the value must be one real number.

    Returns
    -------
    float or numpy.ndarray

    Raises
    ------
    TypeError, ValueError
        As :func:`check_finite`; ``ValueError`` also for an entry ``<= 0``.
    """
    arr = check_finite(name, value, scalar=scalar)
    if np.any(np.asarray(arr) <= 0):
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return arr


def check_nonnegative(name: str, value, *, scalar: bool = False) -> np.ndarray | float:
    """Finite and >= 0 (element-wise); one real number with ``scalar=True``.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : array_like
        Expected: finite entries >= 0.
    scalar : bool
        As in :func:`check_positive`.

    Returns
    -------
    float or numpy.ndarray
        ``value`` as a float (with ``scalar``) or a float array.

    Raises
    ------
    TypeError, ValueError
        As :func:`check_finite`; ``ValueError`` also for an entry ``< 0``.
    """
    arr = check_finite(name, value, scalar=scalar)
    if np.any(np.asarray(arr) < 0):
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return arr


def check_int(name: str, value, *, minimum: int | None = None, maximum: int | None = None) -> int:
    """An integer (not bool) within the given bounds; an integral float such as ``3.0`` is accepted.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : object
        Expected: an integer (not a bool).
    minimum, maximum : int, optional
        Inclusive bounds.

    Returns
    -------
    int

    Raises
    ------
    TypeError
        If ``value`` is not an integer.
    ValueError
        If it lies outside ``[minimum, maximum]``.
    """
    if isinstance(value, bool) or not isinstance(value, (numbers.Integral, np.integer)):
        if isinstance(value, (float, np.floating)) and float(value).is_integer():
            value = int(value)
        else:
            raise TypeError(f"{name} must be an integer, got {value!r}")
    value = int(value)
    if minimum is not None and value < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {value}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{name} must be <= {maximum}, got {value}")
    return value


def check_in(name: str, value, allowed) -> object:
    """One of ``allowed``.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : object
        Expected: one of ``allowed``.
    allowed : collection
        The admissible values.

    Returns
    -------
    object
        ``value`` itself.

    Raises
    ------
    ValueError
        If ``value`` is not in ``allowed``.
    """
    try:
        ok = value in allowed
    except TypeError:  # unhashable value against a set or dict
        ok = False
    if not ok:
        raise ValueError(f"{name} must be one of {sorted(allowed)!r}, got {value!r}")
    return value


def check_matrix(name: str, value, *, shape=None, square: bool = False, symmetric: bool = False) -> np.ndarray:
    """A finite 2-D float array, optionally of a given shape, square or symmetric.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : array_like
        Expected: a finite matrix (a scalar or a vector is promoted to a 1-row matrix).
    shape : tuple of int, optional
        The shape the matrix must have.
    square, symmetric : bool
        Require a square (symmetric) matrix.

    Returns
    -------
    numpy.ndarray, 2-D

    Raises
    ------
    TypeError, ValueError
        As :func:`check_finite`, or when a shape rule fails.
    """
    arr = np.atleast_2d(check_finite(name, value))
    if arr.ndim != 2:
        raise ValueError(f"{name} must be a 2-D matrix, got ndim={arr.ndim}")
    if shape is not None and arr.shape != tuple(shape):
        raise ValueError(f"{name} must have shape {tuple(shape)}, got {arr.shape}")
    if square and arr.shape[0] != arr.shape[1]:
        raise ValueError(f"{name} must be square, got shape {arr.shape}")
    if symmetric and not np.allclose(arr, arr.T, rtol=1e-10, atol=1e-12):
        raise ValueError(f"{name} must be symmetric")
    return arr


def check_hurwitz(name: str, poly, *, polynomial: str = "the characteristic polynomial") -> np.ndarray:
    """Roots of ``poly`` (descending coefficients); raise unless all lie in the open left half-plane.

    Parameters
    ----------
    name : str
        The argument that set the coefficients (e.g. ``"gains"``), for the message.
    poly : array_like
        Polynomial coefficients, highest power first.
    polynomial : str
        Which polynomial they form, for the message.

    Returns
    -------
    numpy.ndarray
        The roots.

    Raises
    ------
    ValueError
        If a root has a non-negative real part.
    """
    roots = np.roots(np.asarray(poly, dtype=float))
    if roots.size and np.max(roots.real) >= 0:
        worst = roots[np.argmax(roots.real)]
        raise ValueError(f"{name} must make {polynomial} Hurwitz (all roots in the open left half-plane), "
                         f"but it has the root {complex(worst):.4g}")
    return roots


def check_bool(name: str, value) -> bool:
    """``True`` or ``False`` (numpy bools too); anything else is a ``TypeError``.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : object
        Expected: True or False.

    Returns
    -------
    bool
    """
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def check_callable(name: str, value, signature: str = "", *, optional: bool = False):
    """A callable (or ``None`` when ``optional``); ``signature`` documents the expected call.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : object
        Expected: a callable.
    signature : str
        The expected call, e.g. ``"f(t, x)"``, for the message.
    optional : bool
        Whether ``None`` is accepted.

    Returns
    -------
    callable or None
        ``value`` itself.

    Raises
    ------
    TypeError
        If ``value`` is not callable.
    """
    if value is None and optional:
        return None
    if not callable(value):
        raise TypeError(f"{name} must be callable{' ' + signature if signature else ''}, got {value!r}")
    return value


def check_str(name: str, value, *, empty: bool = False) -> str:
    """A string, non-empty unless ``empty``.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : object
        Expected: a string.
    empty : bool
        Whether ``""`` (or only blanks) is accepted.

    Returns
    -------
    str

    Raises
    ------
    TypeError
        If ``value`` is not a string.
    ValueError
        If it is blank and ``empty`` is False.
    """
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string, got {value!r}")
    if not empty and not value.strip():
        raise ValueError(f"{name} must be a non-empty string, got {value!r}")
    return value


def check_names(name: str, value, *, length: int | None = None) -> tuple:
    """A sequence of non-empty strings (signal names) as a tuple, optionally of a given length.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : sequence of str
        The names; a single string is rejected (it would be split into characters).
    length : int, optional
        How many names there must be.

    Returns
    -------
    tuple of str

    Raises
    ------
    TypeError
        If ``value`` is not a sequence of strings.
    ValueError
        If a name is empty or the length differs.
    """
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
        raise TypeError(f"{name} must be a list or tuple of signal names, got {value!r}")
    for item in value:
        check_str(name, item)
    if length is not None and len(value) != length:
        raise ValueError(f"{name} must name {length} signals, got {len(value)}: {tuple(value)!r}")
    return tuple(value)


def check_path(name: str, value) -> Path:
    """A non-empty file-system path (``str`` or ``os.PathLike``) as a :class:`~pathlib.Path`.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : str or os.PathLike
        The path.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    TypeError
        If ``value`` is not a path.
    ValueError
        If it is empty (which would silently mean the current directory).
    """
    if not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{name} must be a path (str or os.PathLike), got {value!r}")
    if not os.fspath(value).strip():
        raise ValueError(f"{name} must be a non-empty path, got {value!r}")
    return Path(value)


def check_out_dir(name: str, value) -> Path:
    """An output directory, created if needed and proved writable (a temporary file is made and removed).

    Parameters
    ----------
    name : str
        The argument's name, for the message (e.g. ``"--out"``).
    value : str or os.PathLike
        The directory.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    TypeError
        If ``value`` is not a path.
    ValueError
        If it is empty, names a file, or cannot be created or written.
    """
    import tempfile

    if isinstance(value, str) and not value.strip():
        raise ValueError(f"{name} must name a directory, got an empty string")
    out = check_path(name, value)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{name} must be a directory, got the file {os.fspath(value)!r}")
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as exc:
        raise ValueError(f"{name} {os.fspath(value)!r} is not a writable directory ({exc.strerror or exc})") from None
    return out


def check_vector(name: str, value, n: int, *, allow_inf: bool = False, broadcast: bool = True) -> np.ndarray:
    """A float vector of length ``n`` (a scalar is repeated ``n`` times when ``broadcast``).

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : float or array_like, shape (n,)
        The value to check.
    n : int
        The length required.
    allow_inf : bool
        Whether ``±inf`` entries are accepted (bounds); NaN never is.
    broadcast : bool
        Whether a scalar stands for ``n`` equal entries.

    Returns
    -------
    numpy.ndarray, shape (n,)
        A fresh float array.

    Raises
    ------
    TypeError
        If ``value`` is not numeric.
    ValueError
        If it has NaN (or inf without ``allow_inf``) or another length.
    """
    arr = check_array(name, value) if allow_inf else np.asarray(check_finite(name, value), dtype=float)
    if np.any(np.isnan(arr)):
        raise ValueError(f"{name} must not contain NaN, got {value!r}")
    if arr.ndim == 0 and broadcast:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        rule = f"one number or shape ({n},)" if broadcast else f"shape ({n},)"
        raise ValueError(f"{name} must be {rule}, got shape {arr.shape}")
    return arr.copy()


def finite_result(names: str, compute):
    """``compute()``, whose arguments were checked finite; a ``ValueError`` naming ``names`` if it overflows.

    Parameters
    ----------
    names : str
        The arguments the result comes from, for the message (e.g. ``"omega and order"``).
    compute : callable
        ``compute()`` returns a number, an array (real or complex) or a tuple of them.

    Returns
    -------
    The value ``compute()`` returned.

    Raises
    ------
    ValueError
        If ``compute()`` raises ``OverflowError`` or returns NaN or inf: finite arguments of too large or
        too small a magnitude for double precision.
    """
    try:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            value = compute()
        parts = value if isinstance(value, tuple) else (value,)  # a tuple: arrays of different shapes
        finite = all(bool(np.all(np.isfinite(np.asarray(v, dtype=complex)))) for v in parts)
    except OverflowError:
        finite = False
    if not finite:
        raise ValueError(f"{names} overflow double precision (the result is not finite): use values of a "
                         f"smaller magnitude")
    return value


def check_seeds(seeds) -> list:
    """``seeds`` as a list of non-negative integers (one seed per run).

    Parameters
    ----------
    seeds : sequence of int

    Returns
    -------
    list of int

    Raises
    ------
    TypeError
        If ``seeds`` is a string or not a sequence.
    ValueError
        If a seed is not a non-negative integer.
    """
    if isinstance(seeds, (str, bytes)) or not hasattr(seeds, "__len__"):
        raise TypeError(f"seeds must be a sequence of non-negative integers, got {seeds!r}")
    return [check_int("seeds", s, minimum=0) for s in seeds]
