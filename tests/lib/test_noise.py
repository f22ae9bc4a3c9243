"""Tests of ctrl_analysis.noise: per-run seeds, the noise samplers, noise drawn up front per run."""

import numpy as np
import pytest

from ctrl_analysis.noise import draw_noise, gaussian_noise, run_seeds, uniform_noise


def test_same_seed_same_noise_and_batch_independent():
    n1 = draw_noise([7, 8], 50, uniform_noise(-1, 1), gaussian_noise([0.5, 2.0]))
    n2 = draw_noise([7, 8], 50, uniform_noise(-1, 1), gaussian_noise([0.5, 2.0]))
    assert n1.shape == (50, 2, 3)
    np.testing.assert_array_equal(n1, n2)
    single = draw_noise([8], 50, uniform_noise(-1, 1), gaussian_noise([0.5, 2.0]))
    np.testing.assert_array_equal(single[:, 0], n1[:, 1])
    assert not np.allclose(n1[:, 0], n1[:, 1])
    assert np.all(np.abs(n1[:, :, 0]) <= 1)


def test_run_seeds_and_bad_input():
    seeds = run_seeds(10, 3)
    assert seeds == [int(c.generate_state(1)[0]) for c in np.random.SeedSequence(10).spawn(3)]
    assert run_seeds(10, 5)[:3] == seeds  # run i does not depend on the number of runs
    assert not set(run_seeds(11, 3)) & set(seeds)  # neighbouring base seeds share no run
    with pytest.raises(ValueError, match="runs"):
        run_seeds(0, 0)
    with pytest.raises(ValueError, match="high"):
        uniform_noise(1, -1)


@pytest.mark.parametrize("base_seed", [0, 1, 7, 2**32 - 1, 2**32, 2**64 + 5, 2**127 + 3, 2**130 + 11])
def test_run_seeds_equal_numpy_seedsequence_children(base_seed):
    # run_seeds computes SeedSequence's hash vectorised over the children; it must give numpy's own numbers
    expected = [int(c.generate_state(1)[0]) for c in np.random.SeedSequence(base_seed).spawn(2000)]
    assert run_seeds(base_seed, 2000) == expected
    assert all(type(s) is int for s in run_seeds(base_seed, 3))
