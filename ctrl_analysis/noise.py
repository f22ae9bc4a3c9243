"""Seeds and noise of Monte Carlo runs: per-run seeds from one base seed, white-noise samplers, noise drawn up front.

Noise is drawn before a loop runs, one :class:`numpy.random.Generator` per run seeded with that
run's recorded seed, so a batch equals the stacked single runs and the same seed always gives the
same numbers on every machine.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ._validate import check_finite, check_int, check_seeds
from .engine.memory import RESULT_BYTES, check_result_memory

__all__ = ["MAX_RUNS", "draw_noise", "gaussian_noise", "run_seeds", "uniform_noise"]

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
    return _spawned_states(base_seed, runs).tolist()


# numpy's SeedSequence constants (numpy/random/bit_generator.pyx)
_INIT_A, _MULT_A, _INIT_B, _MULT_B = 0x43B0D7E5, 0x931E8875, 0x8B51F9DD, 0x58F38DED
_MIX_L, _MIX_R, _POOL = 0xCA01F9DD, 0x4973F715, 4
_M32 = 0xFFFFFFFF


def _spawned_states(base_seed: int, runs: int) -> np.ndarray:
    """``[SeedSequence(base_seed).spawn(runs)[i].generate_state(1)[0] for i]`` as uint32, vectorised over ``i``.

    Child ``i`` is ``SeedSequence(base_seed, spawn_key=(i,))``; its pool mixes the base seed's words
    (the same for every child, done once in Python integers) and then the word ``i``, and its first
    state word hashes pool word 0. The hash constant evolves independently of the data, so the per-child
    work is a handful of uint32 operations on an array of ``i``: 10^7 seeds in a second instead of
    minutes and gigabytes of SeedSequence objects (``tests/lib/test_noise.py`` checks equality with
    numpy's own SeedSequence).
    """
    words = []
    n = base_seed
    while True:  # numpy's _coerce_to_uint32_array: little-endian 32-bit words, 0 -> [0]
        words.append(n & _M32)
        n >>= 32
        if n == 0:
            break
    words += [0] * max(0, _POOL - len(words))  # padded to the pool size since a spawn key follows
    hash_const = _INIT_A

    def hashmix(value):
        nonlocal hash_const
        value = (value ^ hash_const) & _M32
        hash_const = (hash_const * _MULT_A) & _M32
        value = (value * hash_const) & _M32
        return value ^ (value >> 16)

    def mix(x, y):
        r = (_MIX_L * x - _MIX_R * y) & _M32
        return r ^ (r >> 16)

    pool = [hashmix(words[i]) for i in range(_POOL)]
    for i_src in range(_POOL):
        for i_dst in range(_POOL):
            if i_src != i_dst:
                pool[i_dst] = mix(pool[i_dst], hashmix(pool[i_src]))
    for w in words[_POOL:]:
        for i_dst in range(_POOL):
            pool[i_dst] = mix(pool[i_dst], hashmix(w))
    # the spawn key (i,) is one 32-bit word per child: runs <= MAX_RUNS < 2**32
    u64, m32 = np.uint64, np.uint64(_M32)
    value = (np.arange(runs, dtype=u64) ^ u64(hash_const)) & m32  # hashmix(i): only pool word 0 is needed,
    value = (value * u64((hash_const * _MULT_A) & _M32)) & m32  # and it is mixed first
    value ^= value >> u64(16)
    r = (u64(_MIX_L * pool[0] & _M32) - u64(_MIX_R) * value) & m32
    r ^= r >> u64(16)
    state = (r ^ u64(_INIT_B)) & m32  # generate_state(1): hash pool word 0 with INIT_B
    state = (state * u64((_INIT_B * _MULT_B) & _M32)) & m32
    state ^= state >> u64(16)
    return state


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
    mean = np.atleast_1d(check_finite("mean", mean))
    if mean.shape not in ((1,), std.shape):
        raise ValueError(f"mean must be one number or have std's shape {std.shape}, got shape {mean.shape}")
    mean = np.broadcast_to(mean, std.shape)

    def sample(rng: np.random.Generator, n_steps: int) -> np.ndarray:
        return mean + std * rng.standard_normal((n_steps, std.size))

    return sample


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
    seeds = check_seeds(seeds)
    if not seeds:
        raise ValueError("seeds must contain at least one seed")
    n_steps = check_int("n_steps", n_steps, minimum=1)
    check_result_memory(8.0 * n_steps * len(seeds), RESULT_BYTES, f"draw_noise(n_steps={n_steps}, {len(seeds)} seeds)")
    if not samplers:
        raise ValueError("draw_noise needs at least one sampler")
    per_run = []
    for s in seeds:
        rng = np.random.default_rng(s)
        per_run.append(np.concatenate([np.asarray(f(rng, n_steps)).reshape(n_steps, -1) for f in samplers], axis=1))
    return np.stack(per_run, axis=1)
