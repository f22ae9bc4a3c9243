"""Argument checks shared by every building block: each error names the argument and the rule."""

from __future__ import annotations

import numbers

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
]


def _is_real_scalar(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) or (
        isinstance(value, np.generic) and np.isrealobj(value) and np.ndim(value) == 0
    )


def check_real(name: str, value) -> float:
    """One real number as a float (a type check only: NaN and inf pass; see :func:`check_finite`).

    A list, an array of more than one entry, a string, a bool, a complex number or ``None`` raises
    ``TypeError("X must be a real number, got …")``.
    """
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if not _is_real_scalar(value):
        raise TypeError(f"{name} must be a real number, got {value!r}")
    return float(value)


def check_finite(name: str, value, *, shape=None, scalar: bool = False) -> np.ndarray | float:
    """Return ``value`` as float (scalar) or float array; raise if any entry is NaN/inf.

    With ``scalar=True`` the value must be one real number (see :func:`check_real`).

    Raises
    ------
    TypeError
        If ``value`` is not numeric (or, with ``scalar``, not one real number).
    ValueError
        If ``value`` contains NaN or inf, or does not have ``shape``.
    """
    if scalar:
        value = check_real(name, value)
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(f"{name} must be a real number or array, got {value!r}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real number or array, got {value!r}") from None
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf), got {value!r}")
    if shape is not None and arr.shape != tuple(shape):
        raise ValueError(f"{name} must have shape {tuple(shape)}, got {arr.shape}")
    return float(arr) if arr.ndim == 0 else arr


def check_array(name: str, value) -> np.ndarray:
    """A real float array; NaN and inf allowed (a signal of a diverged run), strings and None not."""
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(f"{name} must be a real array, got {value!r}")
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real array, got {value!r}") from None


def check_positive(name: str, value, *, scalar: bool = False) -> np.ndarray | float:
    """Finite and strictly positive (element-wise); one real number with ``scalar=True``."""
    arr = check_finite(name, value, scalar=scalar)
    if np.any(np.asarray(arr) <= 0):
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return arr


def check_nonnegative(name: str, value, *, scalar: bool = False) -> np.ndarray | float:
    """Finite and >= 0 (element-wise); one real number with ``scalar=True``."""
    arr = check_finite(name, value, scalar=scalar)
    if np.any(np.asarray(arr) < 0):
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return arr


def check_int(name: str, value, *, minimum: int | None = None, maximum: int | None = None) -> int:
    """An integer (not bool) within the given bounds."""
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
    """One of ``allowed``."""
    if value not in allowed:
        raise ValueError(f"{name} must be one of {sorted(allowed)!r}, got {value!r}")
    return value


def check_matrix(name: str, value, *, shape=None, square: bool = False, symmetric: bool = False) -> np.ndarray:
    """A finite 2-D float array, optionally of a given shape, square or symmetric."""
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

    ``name`` is the argument that set the coefficients (e.g. ``"gains"``); ``polynomial`` says which
    polynomial they form, for the message.
    """
    roots = np.roots(np.asarray(poly, dtype=float))
    if roots.size and np.max(roots.real) >= 0:
        worst = roots[np.argmax(roots.real)]
        raise ValueError(f"{name} must make {polynomial} Hurwitz (all roots in the open left half-plane), "
                         f"but it has the root {complex(worst):.4g}")
    return roots


def check_bool(name: str, value) -> bool:
    """``True`` or ``False`` (numpy bools too); anything else is a ``TypeError``."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def check_callable(name: str, value, signature: str = "", *, optional: bool = False):
    """A callable (or ``None`` when ``optional``); ``signature`` documents the expected call."""
    if value is None and optional:
        return None
    if not callable(value):
        raise TypeError(f"{name} must be callable{' ' + signature if signature else ''}, got {value!r}")
    return value
