"""Signal classes of the arena, each with a known bound ``L`` on ``|f''|``, and their noise classes.

Every signal is drawn from a seeded :class:`numpy.random.Generator` and returned with its exact first
and second derivatives (closed forms), then scaled so that ``max |f''|`` over the samples is exactly
``L``. Noise classes: bounded uniform (``|η| <= ε``), Gaussian (``σ = ε/3``: ``ε`` is its nominal
3σ bound) and quantisation (step ``q = 2ε`` with a random offset, so ``|η| <= ε``), drawn with the
library's samplers (:func:`ctrl_analysis.noise.uniform_noise`, :func:`~ctrl_analysis.noise.gaussian_noise`).

**Registered classes.** Signals the library cannot build by itself (a paper's plant output: the
plant, its parameters and its loop belong to the study, and the library never imports the studies)
are added with :func:`register_signal_class`: a generator ``generate(seed, dt, n) -> (f, f', f'', L)``
on the samples ``t_k = k dt`` at the signal's own scale, with its bound ``L >= |f''|`` over the whole
record (e.g. over every integration step, not only the samples), and a sentence saying how ``L`` is
computed. :func:`make_signal` scales them by the case's ``L`` over that bound (a change of units: the
shape and time scale stay the plant's, and ``|f''| <= L`` holds between the samples too);
:func:`native_bound` gives the bound in the plant's own units. The CLI registers the studies' classes
(``analysis/arena_hooks.py``) before it runs the arena.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .._validate import (
    check_finite,
    check_in,
    check_int,
    check_positive,
    check_str,
    finite_result,
)
from ..noise import gaussian_noise, uniform_noise

__all__ = ["NOISE_CLASSES", "SIGNAL_CLASSES", "SignalClass", "add_noise", "make_signal", "native_bound",
           "simulate_registered",
           "register_signal_class", "registered_signal_classes", "signal_classes"]

#: Signal classes: name -> what it is.
SIGNAL_CLASSES = {
    "sines": "sum of 3 sinusoids, 0.3-2 rad/s, random phases",
    "steps": "3 smoothed steps (cosine ramps of 0.4-1.2 s)",
    "ramps": "ramps whose slope changes in 3 smoothed steps",
    "chirp": "chirp sin(φ(t)), frequency sweeping 0.2-0.5 → 1.5-2.5 rad/s",
    "mixed": "sines + steps + ramps, each at a third of the acceleration budget",
}
#: Noise classes: name -> what it is.
NOISE_CLASSES = {
    "uniform": "white, uniform on [-ε, ε]",
    "gaussian": "white Gaussian, σ = ε/3 (ε is its nominal 3σ bound)",
    "quantisation": "quantiser of step 2ε with a random offset (|η| <= ε)",
}




@dataclass(frozen=True)
class SignalClass:
    """A signal class registered from outside the library (see :func:`register_signal_class`).

    Attributes
    ----------
    name, description : str
    generate : callable
        ``generate(seed, dt, n) -> (f, f', f'', L)``: three arrays of shape ``(n,)`` at ``t_k = k dt``
        in the signal's own units and the bound ``L >= max |f''|`` over the record; a module-level
        function (picklable by reference).
    bound_how : str
        How the bound ``L`` is computed (shown in results.json).
    """

    name: str
    description: str
    generate: Callable
    bound_how: str


#: Registered classes, name -> SignalClass (:func:`register_signal_class`).
_REGISTERED: dict = {}


def register_signal_class(name: str, description: str, generate: Callable, bound_how: str) -> SignalClass:
    """Add a signal class (registering the same name again replaces it).

    Parameters
    ----------
    name : str
        Class name (not one of :data:`SIGNAL_CLASSES`).
    description : str
        What the signal is.
    generate : callable
        ``generate(seed, dt, n) -> (f, f', f'', L)`` on ``t_k = k dt``, ``k < n``, at the signal's own
        scale, ``L >= |f''|`` over the whole record.
    bound_how : str
        How its bound ``L`` on ``|f''|`` is computed.

    Returns
    -------
    SignalClass

    Raises
    ------
    TypeError, ValueError
        A name, description or ``bound_how`` that is not a non-empty string, a built-in class name, or
        ``generate`` not callable.
    """
    for arg, value in (("name", name), ("description", description), ("bound_how", bound_how)):
        check_str(arg, value)
    if name in SIGNAL_CLASSES:
        raise ValueError(f"name must not be a built-in signal class ({', '.join(SIGNAL_CLASSES)}), got {name!r}")
    if not callable(generate):
        raise TypeError(f"generate must be callable generate(seed, dt, n), got {generate!r:.80}")
    cls = SignalClass(name, description, generate, bound_how)
    _REGISTERED[name] = cls
    _native.cache_clear()
    _SIMULATED.clear()
    return cls


def registered_signal_classes() -> dict:
    """The registered classes, name -> :class:`SignalClass` (a copy).

    Returns
    -------
    dict
    """
    return dict(_REGISTERED)


def signal_classes() -> dict:
    """Every signal class, built-in (:data:`SIGNAL_CLASSES`) then registered: name -> description.

    Returns
    -------
    dict
    """
    return {**SIGNAL_CLASSES, **{k: c.description for k, c in _REGISTERED.items()}}


#: (kind, seed, dt, n) -> _native's value, simulated in other processes by simulate_registered
_SIMULATED: dict = {}


def simulate_registered(kinds, seeds, t, *, jobs: int = 1) -> None:
    """Simulate every registered class's record for ``seeds`` on ``t`` once, side by side over ``jobs`` processes.

    A registered class is usually a plant simulated in closed loop; :func:`make_signal` of one of its
    records then reads what this computed (the same values: the same generator in another process)
    instead of simulating it in this process, and processes forked afterwards inherit it.

    Parameters
    ----------
    kinds : iterable of str
        Signal classes; built-in ones are skipped (they cost nothing to draw).
    seeds : iterable of int
    t : array_like, shape (N,)
        Uniform samples ``k dt`` from 0.
    jobs : int
        Local processes (:func:`ctrl_analysis.runs.parallel.map_chunks`, never a cluster).
    """
    from ..runs.parallel import map_chunks

    for arg, value in (("kinds", kinds), ("seeds", seeds)):
        if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
            raise TypeError(f"{arg} must be a sequence, got {value!r:.80}")
    kinds = [check_in("kinds", k, tuple(SIGNAL_CLASSES) + tuple(_REGISTERED)) for k in kinds]
    seeds = [check_int("seeds", s, minimum=0) for s in seeds]
    t = _samples("t", t)
    dt, n = _uniform_grid(t), t.size
    todo = [(k, s, dt, n) for k in dict.fromkeys(kinds) if k in _REGISTERED for s in dict.fromkeys(seeds)
            if (k, s, dt, n) not in _SIMULATED]
    for key, value in zip(todo, map_chunks(_native_task, todo, jobs=jobs, scheduler=False), strict=True):
        for a in value[:3]:
            a.setflags(write=False)
        _SIMULATED[key] = value


def _native_task(key: tuple) -> tuple:
    """:func:`_native` of ``(kind, seed, dt, n)`` (a call of simulate_registered's map)."""
    return _native(*key)


@functools.lru_cache(maxsize=256)
def _native(kind: str, seed: int, dt: float, n: int) -> tuple:
    """A registered class's ``(f, f', f'', L)`` at its own scale, checked, cached (a plant is simulated once)."""
    if (kind, seed, dt, n) in _SIMULATED:
        return _SIMULATED[(kind, seed, dt, n)]
    cls = _REGISTERED[kind]
    out = tuple(cls.generate(seed, dt, n))
    arrays = tuple(np.asarray(a, dtype=float) for a in out[:3])
    if len(out) != 4 or any(a.shape != (n,) for a in arrays) or not all(np.all(np.isfinite(a)) for a in arrays):
        raise ValueError(f"signal class {kind!r}: generate(seed, dt, n) must return three finite arrays of shape "
                         f"({n},) and a bound, got {len(out)} items")
    bound = float(out[3])
    if not np.isfinite(bound) or bound <= 0 or bound < np.max(np.abs(arrays[2])) * (1 - 1e-12):
        raise ValueError(f"signal class {kind!r}: the bound must be finite, > 0 and >= max |f''| on the samples "
                         f"({np.max(np.abs(arrays[2])):.6g}), got {bound!r}")
    for a in arrays:
        a.setflags(write=False)
    return (*arrays, bound)


def _uniform_grid(t) -> float:
    """The step of a uniform grid starting at 0 (a registered class is generated on ``t_k = k dt``)."""
    dt = float(t[1] - t[0]) if t.size > 1 else 1.0
    if t[0] != 0.0 or dt <= 0 or not np.allclose(np.diff(t), dt, rtol=1e-9, atol=0.0):
        lo, hi = (np.min(np.diff(t)), np.max(np.diff(t))) if t.size > 1 else (0, 0)
        raise ValueError(f"t must be uniform samples k dt from 0 for a registered signal class, got t[0] = {t[0]:g} "
                         f"and steps {lo:g}..{hi:g}")
    return dt


def native_bound(kind: str, seed: int, t) -> float:
    """The bound ``L`` on ``|f''|`` of one record of a registered class, in its own units (from its generator).

    Parameters
    ----------
    kind : str
        A registered class.
    seed : int
    t : array_like, shape (N,)
        Uniform samples ``k dt`` from 0.

    Returns
    -------
    float
    """
    check_in("kind", kind, tuple(_REGISTERED))
    t = _samples("t", t)
    return _native(kind, check_int("seed", seed, minimum=0), _uniform_grid(t), t.size)[3]


def _sines(rng, t):
    a, w, p = rng.uniform(0.3, 1.0, 3), rng.uniform(0.3, 2.0, 3), rng.uniform(0, 2 * np.pi, 3)
    arg = w[:, None] * t + p[:, None]
    return ((a[:, None] * np.sin(arg)).sum(0), (a[:, None] * w[:, None] * np.cos(arg)).sum(0),
            -(a[:, None] * w[:, None] ** 2 * np.sin(arg)).sum(0))


def _smooth_steps(rng, t, integrate: bool):
    """Σ h_i S((t - t_i)/w_i), S(u) = (1 - cos πu)/2 on [0, 1]; or its integral (ramps)."""
    f, f1, f2 = np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)
    T = t[-1] if t.size else 1.0
    for ti, h, w in zip(np.sort(rng.uniform(0.1 * T, 0.8 * T, 3)), rng.choice([-1, 1], 3) * rng.uniform(0.5, 1, 3),
                        rng.uniform(0.4, 1.2, 3), strict=True):
        u = np.clip((t - ti) / w, 0.0, 1.0)
        inside = (t > ti) & (t < ti + w)
        S = 0.5 * (1 - np.cos(np.pi * u))
        dS = np.where(inside, 0.5 * np.pi / w * np.sin(np.pi * u), 0.0)
        ddS = np.where(inside, 0.5 * (np.pi / w) ** 2 * np.cos(np.pi * u), 0.0)
        if integrate:  # ∫S dt = w (u/2 - sin(πu)/(2π)) inside, w(u - 1/2) after
            after = (t - ti) / w
            iS = np.where(t >= ti + w, w * (after - 0.5), w * (u / 2 - np.sin(np.pi * u) / (2 * np.pi)))
            f, f1, f2 = f + h * iS, f1 + h * S, f2 + h * dS
        else:
            f, f1, f2 = f + h * S, f1 + h * dS, f2 + h * ddS
    return f, f1, f2


def _chirp(rng, t):
    T = max(t[-1], 1e-9)
    w0, w1, p = rng.uniform(0.2, 0.5), rng.uniform(1.5, 2.5), rng.uniform(0, 2 * np.pi)
    k = (w1 - w0) / T
    phi, dphi = p + w0 * t + 0.5 * k * t**2, w0 + k * t
    return np.sin(phi), np.cos(phi) * dphi, -np.sin(phi) * dphi**2 + np.cos(phi) * k


def _samples(name: str, value) -> np.ndarray:
    """A finite, non-empty 1-D float array (errors name ``name``)."""
    arr = np.asarray(check_finite(name, value))
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array of samples, got shape {arr.shape}")
    return arr


def _scaled(parts, L):
    f, f1, f2 = parts
    s = L / max(np.max(np.abs(f2)), 1e-300)
    return f * s, f1 * s, f2 * s


def make_signal(kind: str, seed: int, t, L: float) -> np.ndarray:
    """One signal of class ``kind`` with its exact derivatives, scaled to ``max |f''| = L`` on ``t``.

    Parameters
    ----------
    kind : str
        A key of :data:`SIGNAL_CLASSES` or a registered class (:func:`register_signal_class`).
    seed : int
        Seed of the draw (same seed, same signal).
    t : array_like, shape (N,)
        Sample instants (s).
    L : float
        Bound on ``|f''|`` (> 0), attained on ``t`` (a registered class: attained on its record, between
        the samples if there).

    Returns
    -------
    numpy.ndarray, shape (3, N)
        ``f, f', f''``.

    Raises
    ------
    TypeError, ValueError
        An unknown class, a seed that is not a non-negative integer, ``t`` not a finite non-empty 1-D array (for a
        registered class, not uniform samples from 0), ``L`` not > 0, or magnitudes of ``t`` and ``L`` for which
        the signal overflows double precision.

    Examples
    --------
    >>> t = np.linspace(0, 10, 1001)
    >>> f = make_signal("chirp", 1, t, 4.0)
    >>> float(np.max(np.abs(f[2])))
    4.0
    """
    check_in("kind", kind, tuple(signal_classes()))
    L = float(check_positive("L", L, scalar=True))
    t = _samples("t", t)
    seed = check_int("seed", seed, minimum=0)
    if kind in _REGISTERED:
        *parts, bound = _native(kind, seed, _uniform_grid(t), t.size)
        return np.array(parts) * (L / bound)
    return finite_result("t and L", lambda: np.array(_scaled(_built_in(kind, np.random.default_rng(seed), t), L)))


def _built_in(kind: str, rng, t) -> tuple:
    """``(f, f', f'')`` of a built-in class on ``t``, before scaling."""
    if kind == "sines":
        return _sines(rng, t)
    if kind == "steps":
        return _smooth_steps(rng, t, False)
    if kind == "ramps":
        return _smooth_steps(rng, t, True)
    if kind == "chirp":
        return _chirp(rng, t)
    return [sum(x) for x in zip(*(_scaled(g, 1.0) for g in
                                   (_sines(rng, t), _smooth_steps(rng, t, False), _smooth_steps(rng, t, True))),
                                   strict=True)]


def add_noise(kind: str, f, eps: float, seed: int) -> np.ndarray:
    """The measurement ``f + η`` of one signal with noise class ``kind`` of bound ``eps``.

    Parameters
    ----------
    kind : str
        A key of :data:`NOISE_CLASSES`.
    f : array_like, shape (N,)
        The noise-free samples.
    eps : float
        Noise bound ``ε`` (> 0; for Gaussian noise the nominal 3σ).
    seed : int
        Seed of the draw.

    Returns
    -------
    numpy.ndarray, shape (N,)

    Examples
    --------
    >>> y = add_noise("quantisation", np.linspace(0, 1, 50), 0.05, 3)
    >>> bool(np.max(np.abs(y - np.linspace(0, 1, 50))) <= 0.05)
    True
    """
    check_in("kind", kind, tuple(NOISE_CLASSES))
    eps = float(check_positive("eps", eps, scalar=True))
    f = _samples("f", f)
    rng = np.random.default_rng(check_int("seed", seed, minimum=0))
    if kind == "uniform":
        return f + uniform_noise(-eps, eps)(rng, f.size)[:, 0]
    if kind == "gaussian":
        return f + gaussian_noise(eps / 3.0)(rng, f.size)[:, 0]
    q, off = 2.0 * eps, rng.uniform()
    return q * (np.round(f / q + off) - off)
