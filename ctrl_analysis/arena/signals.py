"""Signal classes of the arena, each with a known bound ``L`` on ``|f''|``, and their noise classes.

Every signal is drawn from a seeded :class:`numpy.random.Generator` and returned with its exact first
and second derivatives (closed forms), then scaled so that ``max |f''|`` over the samples is exactly
``L``. Noise classes: bounded uniform (``|η| <= ε``), Gaussian (``σ = ε/3``: ``ε`` is its nominal
3σ bound) and quantisation (step ``q = 2ε`` with a random offset, so ``|η| <= ε``), drawn with the
library's samplers (:func:`ctrl_analysis.noise.uniform_noise`, :func:`~ctrl_analysis.noise.gaussian_noise`).
"""

from __future__ import annotations

import numpy as np

from .._validate import check_finite, check_in, check_int, check_positive
from ..noise import gaussian_noise, uniform_noise

__all__ = ["SIGNAL_CLASSES", "NOISE_CLASSES", "make_signal", "add_noise"]

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
                        rng.uniform(0.4, 1.2, 3)):
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
        A key of :data:`SIGNAL_CLASSES`.
    seed : int
        Seed of the draw (same seed, same signal).
    t : array_like, shape (N,)
        Sample instants (s).
    L : float
        Bound on ``|f''|`` (> 0), attained on ``t``.

    Returns
    -------
    numpy.ndarray, shape (3, N)
        ``f, f', f''``.

    Examples
    --------
    >>> t = np.linspace(0, 10, 1001)
    >>> f = make_signal("chirp", 1, t, 4.0)
    >>> float(np.max(np.abs(f[2])))
    4.0
    """
    check_in("kind", kind, tuple(SIGNAL_CLASSES))
    L = float(check_positive("L", L, scalar=True))
    t = _samples("t", t)
    rng = np.random.default_rng(check_int("seed", seed, minimum=0))
    if kind == "sines":
        parts = _sines(rng, t)
    elif kind == "steps":
        parts = _smooth_steps(rng, t, False)
    elif kind == "ramps":
        parts = _smooth_steps(rng, t, True)
    elif kind == "chirp":
        parts = _chirp(rng, t)
    else:
        parts = [sum(x) for x in zip(*(_scaled(g, 1.0) for g in
                                        (_sines(rng, t), _smooth_steps(rng, t, False), _smooth_steps(rng, t, True))))]
    return np.array(_scaled(parts, L))


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
