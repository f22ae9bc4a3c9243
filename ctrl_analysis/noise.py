"""Seeds and noise of Monte Carlo runs: per-run seeds from one base seed, white-noise samplers, noise drawn up front.

Noise is drawn before a loop runs, one :class:`numpy.random.Generator` per run seeded with that
run's recorded seed, so a batch equals the stacked single runs and the same seed always gives the
same numbers on every machine.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ._validate import check_finite, check_int

__all__ = ["MAX_RUNS", "run_seeds", "draw_noise", "uniform_noise", "gaussian_noise"]

#: Most runs :func:`run_seeds` makes at once (a list of Python integers; beyond it the list alone
#: takes gigabytes): split larger studies into batches of seeds from different base seeds.
MAX_RUNS = 10**7


# ----------------------------------------------------------------------------------------------
# Seeds and noise
# ----------------------------------------------------------------------------------------------

def run_seeds(base_seed: int, runs: int) -> list[int]:
    """Per-run seeds derived from ``base_seed``; record them in results.

    The runs are the children ``numpy.random.SeedSequence(base_seed).spawn(runs)``, each recorded
    as the integer ``child.generate_state(1)[0]`` (then expanded again by
    :func:`numpy.random.default_rng`). Neighbouring base seeds therefore give independent sets of
    runs (``base_seed + i`` schemes share all runs but one), and run ``i`` does not depend on
    ``runs``.

    Parameters
    ----------
    base_seed : int
        The study's base seed (``--seed``), >= 0.
    runs : int
        Number of Monte Carlo runs, from 1 to :data:`MAX_RUNS`.

    Returns
    -------
    list of int
        One seed per run.

    Raises
    ------
    ValueError
        If ``base_seed`` < 0, or ``runs`` is < 1 or > :data:`MAX_RUNS`.

    Examples
    --------
    >>> a, b = run_seeds(7, 3), run_seeds(8, 3)
    >>> len(set(a) & set(b)), run_seeds(7, 2) == a[:2]
    (0, True)
    """
    base_seed = check_int("base_seed", base_seed, minimum=0)
    runs = check_int("runs", runs, minimum=1)
    if runs > MAX_RUNS:
        raise ValueError(f"runs must be <= {MAX_RUNS} (MAX_RUNS: the seeds alone would take "
                         f"{runs * 36 / 2**30:.3g} GiB), got {runs}")
    return [int(child.generate_state(1)[0]) for child in np.random.SeedSequence(base_seed).spawn(runs)]


def uniform_noise(low, high) -> Callable:
    """Sampler of white noise uniform on ``[low, high]`` per channel.

    Parameters
    ----------
    low, high : float or array_like
        Bounds per channel (scalars, or vectors of equal length with ``high >= low``).

    Returns
    -------
    callable
        ``sample(rng, n_steps) -> (n_steps, channels)``, for :func:`draw_noise`.
    """
    low = np.atleast_1d(check_finite("low", low))
    high = np.atleast_1d(check_finite("high", high))
    if low.shape != high.shape or np.any(high < low):
        raise ValueError(f"high must be >= low element-wise with the same length, got low={low}, high={high}")

    def sample(rng: np.random.Generator, n_steps: int) -> np.ndarray:
        return rng.uniform(low, high, size=(n_steps, low.size))

    return sample


def gaussian_noise(std, mean=0.0) -> Callable:
    """Sampler of white Gaussian noise with standard deviation ``std`` per channel.

    Parameters
    ----------
    std : float or array_like
        Standard deviation per channel (>= 0).
    mean : float or array_like
        Mean per channel (broadcast to ``std``).

    Returns
    -------
    callable
        ``sample(rng, n_steps) -> (n_steps, channels)``, for :func:`draw_noise`.
    """
    std = np.atleast_1d(check_finite("std", std))
    if np.any(std < 0):
        raise ValueError(f"std must be >= 0, got {std}")
    mean = np.broadcast_to(np.atleast_1d(check_finite("mean", mean)), std.shape)

    def sample(rng: np.random.Generator, n_steps: int) -> np.ndarray:
        return mean + std * rng.standard_normal((n_steps, std.size))

    return sample


def _check_seeds(seeds) -> list:
    """A sequence of non-negative integer seeds."""
    if isinstance(seeds, (str, bytes)) or not hasattr(seeds, "__len__"):
        raise TypeError(f"seeds must be a sequence of non-negative integers, got {seeds!r}")
    return [check_int("seeds", s, minimum=0) for s in seeds]


def draw_noise(seeds, n_steps: int, *samplers: Callable) -> np.ndarray:
    """Draw the noise of every run up front: an array of shape ``(n_steps, B, m)``.

    Run ``b`` uses ``numpy.random.default_rng(seeds[b])``; the samplers are called in order on that
    generator and their channels concatenated, so run ``b``'s noise does not depend on ``B``.

    Parameters
    ----------
    seeds : sequence of int
        One seed per run (e.g. from :func:`run_seeds`).
    n_steps : int
        Number of samples (>= 1).
    *samplers : callable
        Samplers such as :func:`uniform_noise`, :func:`gaussian_noise`.

    Returns
    -------
    numpy.ndarray, shape (n_steps, B, m)
        ``m`` the total number of channels of the samplers.
    """
    seeds = _check_seeds(seeds)
    if not seeds:
        raise ValueError("seeds must contain at least one seed")
    n_steps = check_int("n_steps", n_steps, minimum=1)
    if not samplers:
        raise ValueError("draw_noise needs at least one sampler")
    per_run = []
    for s in seeds:
        rng = np.random.default_rng(s)
        per_run.append(np.concatenate([np.asarray(f(rng, n_steps)).reshape(n_steps, -1) for f in samplers], axis=1))
    return np.stack(per_run, axis=1)
