"""Streamed statistics (ctrl_analysis.streaming): against numpy on the whole array, merges, bounds, errors."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from ctrl_analysis.streaming import Counts, Histogram, Keep, Moments, Quantiles


def _chunks(x, rng, max_size):
    """``x`` cut at random points along axis 0 into chunks of 1 to ``max_size`` runs."""
    cuts, at = [], 0
    while at < len(x):
        step = int(rng.integers(1, max_size + 1))
        cuts.append(x[at:at + step])
        at += step
    return cuts


def _fold(cls, chunks, **options):
    acc = cls(**options)
    for c in chunks:
        acc.add(c)
    return acc


# -- Moments -------------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_moments_match_numpy_on_1e5_values_in_random_chunkings(seed):
    rng = np.random.default_rng(seed)
    x = rng.normal(3.0, 2.0, size=(100_000, 3)) * np.array([1.0, 1e-3, 1e4])
    m = _fold(Moments, _chunks(x, rng, 5000))
    assert m.count == 100_000 and m.excluded == 0
    np.testing.assert_allclose(m.mean, x.mean(axis=0), rtol=1e-12)
    for ddof in (0, 1):
        np.testing.assert_allclose(m.var(ddof), x.var(axis=0, ddof=ddof), rtol=1e-12)
        np.testing.assert_allclose(m.std(ddof), x.std(axis=0, ddof=ddof), rtol=1e-12)
    assert np.array_equal(m.min, x.min(axis=0)) and np.array_equal(m.max, x.max(axis=0))


def test_moments_hold_where_the_naive_sum_of_squares_cancels():
    rng = np.random.default_rng(5)
    noise = np.round(rng.normal(0.0, 1.0, 200_000) * 2 ** 20) / 2 ** 20  # exact in 1e9 + noise
    x = 1e9 + noise
    assert np.array_equal(x - 1e9, noise)  # the data are exactly 1e9 + noise: their variance is noise's
    truth = np.var(noise)
    m = _fold(Moments, _chunks(x, rng, 3000))
    naive = (np.sum(x * x) - np.sum(x) ** 2 / x.size) / x.size
    assert abs(naive - truth) / truth > 1.0  # the textbook formula is wrong in every digit here
    assert abs(m.var() - truth) / truth < 1e-13
    assert abs(m.mean - (1e9 + noise.mean())) <= np.spacing(1e9)  # the mean to its last bit


def test_moments_merge_is_associative_and_add_is_a_fold_of_per_chunk_merges():
    rng = np.random.default_rng(7)
    chunks = _chunks(rng.normal(size=(30_000, 4)) + 50.0, rng, 2000)
    parts = [Moments.of(c) for c in chunks]
    serial = _fold(Moments, chunks)
    folded = Moments()
    for p in parts:
        folded.merge(p)
    for name in ("mean", "min", "max"):  # same chunks, same order: the same bits, however many processes
        assert np.array_equal(getattr(serial, name), getattr(folded, name))
    assert np.array_equal(serial.var(), folded.var())
    a, b, c = (Moments().merge(p) for p in (parts[0], parts[1], parts[2]))
    left = a.copy().merge(b).merge(c)
    right = a.copy().merge(b.copy().merge(c))
    np.testing.assert_allclose(left.mean, right.mean, rtol=1e-14)
    np.testing.assert_allclose(left.var(), right.var(), rtol=1e-13)
    half = len(parts) // 2  # two "processes", merged as a tree
    tree = Moments()
    for p in parts[:half]:
        tree.merge(p)
    other = Moments()
    for p in parts[half:]:
        other.merge(p)
    tree.merge(other)
    np.testing.assert_allclose(tree.var(), serial.var(), rtol=1e-13)
    assert np.array_equal(tree.min, serial.min) and tree.count == serial.count


def test_moments_exclude_diverged_runs_and_count_them():
    x = np.arange(20.0).reshape(10, 2)
    x[[2, 7]] = np.nan
    diverged = np.isnan(x).any(axis=1)
    m = Moments().add(x[:5], exclude=diverged[:5]).add(x[5:], exclude=diverged[5:])
    assert (m.count, m.excluded, m.n_runs) == (8, 2, 10)
    np.testing.assert_allclose(m.mean, x[~diverged].mean(axis=0), rtol=1e-15)
    auto = Moments(nonfinite="exclude").add(x)
    assert auto.excluded == 2 and np.array_equal(auto.var(1), m.var(1))
    with pytest.raises(ValueError, match="values must be finite"):
        Moments().add(x)
    empty = Moments(shape=2)
    assert np.isnan(empty.mean).all() and np.isnan(Moments().add(x[:1]).var(ddof=1)).all()


# -- Quantiles -----------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["linear", "inverted_cdf", "median_unbiased", "nearest"])
def test_exact_quantiles_equal_numpy_bit_for_bit_under_the_threshold(method):
    rng = np.random.default_rng(11)
    x = rng.standard_t(3, size=(4096, 5))
    q = [0.0, 0.001, 0.05, 0.25, 0.5, 0.9, 0.99, 1.0]
    acc = Quantiles(k=4096, method=method)
    for c in _chunks(x, rng, 700):
        acc.add(c)
    assert acc.exact and acc.rank_error == 0.0
    assert np.array_equal(acc.quantile(q), np.quantile(x, q, axis=0, method=method))
    assert np.array_equal(acc.percentile(99.5), np.percentile(x, 99.5, axis=0, method=method))
    merged = Quantiles(k=4096, method=method).merge(Quantiles.of(x[2000:], method=method)).merge(
        Quantiles.of(x[:2000], method=method))  # another order, another tree: the same bits
    assert np.array_equal(merged.quantile(q), acc.quantile(q))


DISTRIBUTIONS = {
    "normal": lambda rng, n: rng.normal(size=n),
    "lognormal": lambda rng, n: rng.lognormal(0.0, 2.0, size=n),
    "discrete": lambda rng, n: rng.integers(0, 50, size=n).astype(float),  # ties
}


@pytest.mark.parametrize("name", sorted(DISTRIBUTIONS))
def test_sketch_rank_error_within_the_stated_bound_on_1e6_values(name):
    rng = np.random.default_rng(sorted(DISTRIBUTIONS).index(name))
    n, k = 1_000_000, 1024
    x = DISTRIBUTIONS[name](rng, n)
    acc = Quantiles(k=k)
    for c in np.array_split(x, 1000):
        acc.add(c)
    assert not acc.exact
    bound = acc.rank_error
    assert 0 < bound <= Quantiles.error_bound(n, k)
    assert Quantiles.error_bound(n, k) == math.ceil(math.log2(n / k)) / k
    s = np.sort(x)
    q = np.linspace(0.0, 1.0, 201)
    got = acc.quantile(q)
    below, upto = np.searchsorted(s, got, side="left"), np.searchsorted(s, got, side="right")
    e = bound * n
    assert np.all(below <= q * n + e) and np.all(upto >= q * n - e), name
    worst = np.max(np.maximum(below - q * n, q * n - upto)) / n
    assert worst <= bound
    assert got[0] == s[0] and got[-1] == s[-1]


def test_sketch_merged_from_processes_stays_within_its_bound():
    rng = np.random.default_rng(3)
    x = rng.exponential(size=(200_000, 2))
    parts = [Quantiles.of(c, k=512) for c in np.array_split(x, 40)]
    acc = Quantiles(k=512)
    for group in (parts[:13], parts[13:27], parts[27:]):  # three processes, then the parent
        sub = Quantiles(k=512)
        for p in group:
            sub.merge(p)
        acc.merge(sub)
    assert acc.count == 200_000 and acc.rank_error <= Quantiles.error_bound(200_000, 512)
    q = np.array([0.01, 0.5, 0.99])
    got = acc.quantile(q)
    for j in range(2):
        s = np.sort(x[:, j])
        r = np.searchsorted(s, got[:, j])
        assert np.all(np.abs(r - q * len(s)) <= acc.rank_error * len(s) + 1)
    serial = _fold(Quantiles, np.array_split(x, 40), k=512)
    again = _fold(Quantiles, np.array_split(x, 40), k=512)
    assert np.array_equal(serial.quantile(q), again.quantile(q))  # deterministic: no random numbers


def test_memory_is_bounded_by_the_sketch_not_the_run_count():
    rng = np.random.default_rng(4)
    sizes = {}
    for n in (10_000, 1_000_000):
        acc = Quantiles(k=1024)
        m = Moments()
        for c in np.array_split(rng.normal(size=(n, 4)), n // 1000):
            acc.add(c)
            m.add(c)
        sizes[n] = acc.nbytes
        assert acc.nbytes <= acc.bytes_bound(n), n
        assert m.nbytes == 5 * 4 * 8  # shift, mean - shift, M2, min, max of 4 elements, whatever n
    assert sizes[1_000_000] <= sizes[10_000] * (math.ceil(math.log2(1e6 / 1024)) + 1)
    assert sizes[1_000_000] < 0.01 * 1_000_000 * 4 * 8  # under 1 % of holding the values


def test_accumulators_pickle_for_other_processes():
    m = Moments().add(np.ones((3, 2)))
    q = Quantiles(k=16).add(np.arange(40.0))
    assert np.array_equal(pickle.loads(pickle.dumps(m)).mean, m.mean)
    assert np.array_equal(pickle.loads(pickle.dumps(q)).quantile(0.5), q.quantile(0.5))


# -- Counts, Histogram, Keep -----------------------------------------------------------------------
def test_histogram_and_counts_merge_exactly():
    rng = np.random.default_rng(9)
    x = rng.normal(size=(50_000, 3))
    edges = np.linspace(-2.0, 2.0, 17)
    parts = [Histogram.of(c, edges=edges) for c in _chunks(x, rng, 4000)]
    forward, backward = Histogram(edges), Histogram(edges)
    for p in parts:
        forward.merge(p)
    for p in parts[::-1]:
        backward.merge(p)
    assert np.array_equal(forward.counts, backward.counts)
    for j in range(3):
        assert np.array_equal(forward.counts[j], np.histogram(x[:, j], bins=edges)[0])
        assert forward.below[j] == np.sum(x[:, j] < -2.0) and forward.above[j] == np.sum(x[:, j] > 2.0)
    flags = x > 1.5
    c = Counts()
    for part in np.array_split(flags, 7)[::-1]:
        c.merge(Counts.of(part))
    assert np.array_equal(c.hits, flags.sum(axis=0)) and c.n_runs == 50_000
    np.testing.assert_allclose(c.fraction, flags.mean(axis=0), rtol=0)


def test_keep_holds_the_first_runs_with_their_index():
    x = np.arange(60.0).reshape(20, 3)
    x[4] = np.nan  # a diverged run is drawn as it is
    kept = Keep(5)
    for c in np.array_split(x, 6):
        kept.add(c)
    assert kept.runs.tolist() == [0, 1, 2, 3, 4]
    assert np.array_equal(kept.traces, x[:5], equal_nan=True)
    spread = Keep([2, 17]).merge(Keep.of(x[10:], start=10, runs=[2, 17])).merge(Keep.of(x[:10], runs=[2, 17]))
    assert spread.runs.tolist() == [2, 17] and np.array_equal(spread.traces, x[[2, 17]])
    assert spread.nbytes <= 2 * 3 * 8 + 2 * 8 + 2 * 8
    with pytest.raises(ValueError, match="other holds run 2"):
        spread.merge(Keep.of(x[:3], runs=[2, 17]))


def test_empty_chunks_change_nothing():
    x = np.arange(40.0) / 7
    results = {Moments: lambda a: (a.mean, a.var(1), a.min), Quantiles: lambda a: a.quantile([0.1, 0.5]),
               Histogram: lambda a: (a.counts, a.above)}
    for cls, read in results.items():
        options = dict(edges=[0.0, 1.0, 2.0]) if cls is Histogram else dict(k=16) if cls is Quantiles else {}
        plain = cls(**options).add(x[:25]).add(x[25:])
        padded = cls(**options).add(np.zeros(0)).add(x[:25]).add(np.zeros(0)).add(x[25:])
        assert plain.count == padded.count == 40, cls
        for a, b in zip(read(plain), read(padded), strict=True):
            assert np.array_equal(a, b), cls


# -- bad input ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("call, arg", [
    (lambda: Moments().add("abc"), "values"),
    (lambda: Moments().add(3.0), "values"),
    (lambda: Moments(shape=3).add(np.ones((2, 4))), "values"),
    (lambda: Moments().add(np.ones(3), exclude=[1, 0, 1]), "exclude"),
    (lambda: Moments().add(np.ones(3), exclude=np.ones(2, bool)), "exclude"),
    (lambda: Moments(nonfinite="skip"), "nonfinite"),
    (lambda: Moments(shape="x"), "shape"),
    (lambda: Moments().add(np.ones(3)).var(ddof=-1), "ddof"),
    (lambda: Moments().merge(Quantiles()), "other"),
    (lambda: Moments().add(np.ones((2, 2))).merge(Moments.of(np.ones((2, 3)))), "other"),
    (lambda: Quantiles(k=4), "k"),
    (lambda: Quantiles(method="banana"), "method"),
    (lambda: Quantiles().add(np.ones(3)).quantile(1.5), "q"),
    (lambda: Quantiles().add(np.ones(3)).quantile([np.nan]), "q"),
    (lambda: Quantiles().add(np.ones(3)).percentile(-1.0), "p"),
    (lambda: Quantiles(k=16).merge(Quantiles(k=32)), "other"),
    (lambda: Counts().add(np.ones(3)), "values"),
    (lambda: Histogram([1.0, 0.0]), "edges"),
    (lambda: Histogram([0.0, np.nan]), "edges"),
    (lambda: Histogram([0.0, 1.0]).merge(Histogram([0.0, 2.0])), "other"),
    (lambda: Keep(-1), "runs"),
    (lambda: Keep("ab"), "runs"),
    (lambda: Keep(3).add(np.ones(3), start=-2), "start"),
])
def test_bad_input_errors_name_the_argument(call, arg):
    with pytest.raises((TypeError, ValueError), match=rf"\b{arg}\b"):
        call()


def test_moments_refuse_values_whose_spread_overflows_and_stay_as_they_were():
    with pytest.raises(ValueError, match="spread overflows double precision"):
        Moments().add(np.array([[1e300, 1.0], [1.0, 1.0]]))
    m = Moments().add(np.array([[1e150, 1.0]]))
    with pytest.raises(ValueError, match="spread overflows"):
        m.add(np.array([[-1e160, 1.0]]))  # merging: d² = 1e320
    assert m.count == 1 and m.mean.tolist() == [1e150, 1.0] and m.var().tolist() == [0.0, 0.0]
    # large but representable spreads are kept
    assert Moments().add(np.array([[1e150], [-1e150]])).var() == pytest.approx(1e300)
