"""The lower bound 2√(εL) and its adversarial pair; every tuned family stays above it."""

import numpy as np
import pytest

from ctrl_analysis.arena.bound import adversarial_error, adversarial_pair, lower_bound
from ctrl_analysis.arena.interface import FAMILIES, estimate
from ctrl_analysis.arena.tuning import Case, Setup, tune_family

EPS, L, DT = 0.01, 2.0, 0.01


def test_bound_constant():
    # 2 √(ε L): ε = 0.01, L = 1 gives 0.2; the constant is 2 (and the bound scales as √ε and √L)
    assert lower_bound(0.01, 1.0) == pytest.approx(0.2, rel=1e-15)
    assert lower_bound(0.04, 1.0) == pytest.approx(2 * lower_bound(0.01, 1.0))
    assert lower_bound(0.01, 4.0) == pytest.approx(2 * lower_bound(0.01, 1.0))
    with pytest.raises(ValueError, match="eps"):
        lower_bound(-1.0, 1.0)


def test_adversarial_pair_is_admissible_and_attains_the_constant():
    p = adversarial_pair(EPS, L, 0.001, 3000, 2000)
    k = p["k_star"]
    # both signals: |f''| <= L, noise |η| <= ε, and measurements equal up to t*
    assert np.max(np.abs(p["f2"])) <= L * (1 + 1e-12)
    assert np.max(np.abs(p["noise"])) <= EPS * (1 + 1e-12)
    assert np.array_equal(p["y"][0, :k + 1], p["y"][1, :k + 1])
    # f1, f2 are the derivatives of f, f1 (trapezoid integration)
    h = 0.001
    for a, b in (("f", "f1"), ("f1", "f2")):
        for s in range(2):
            integral = p[a][s, 0] + np.concatenate([[0], np.cumsum(0.5 * h * (p[b][s, 1:] + p[b][s, :-1]))])
            assert np.allclose(integral, p[a][s], atol=1e-6 if a == "f" else 3 * h * L)  # f'' jumps 3 times
    # the derivatives differ by 4√(εL) = 2 × bound at t*: the constant 2 of the statement
    assert p["f1"][0, k] - p["f1"][1, k] == pytest.approx(2 * lower_bound(EPS, L), rel=1e-12)


def test_the_pair_has_a_stated_maximum_of_samples():
    from ctrl_analysis.arena.recordcheck import MAX_ROWS

    with pytest.raises(ValueError, match=f"n_samples must be <= {MAX_ROWS}, got 1000000000000"):
        adversarial_pair(0.01, 1.0, 0.01, 10**12, 50)
    assert adversarial_pair(0.01, 1.0, 0.01, MAX_ROWS, 50)["t"].shape == (MAX_ROWS,)


def test_a_noncausal_differentiator_can_beat_the_bound():
    # the error measure is not >= bound by construction: a central difference that looks past t* beats it there
    p = adversarial_pair(EPS, L, 0.001, 3000, 2000)
    k, m = p["k_star"], 100
    est = (p["y"][:, k + m] - p["y"][:, k - m]) / (2 * m * 0.001)
    assert np.max(np.abs(est - p["f1"][:, k])) < 0.8 * lower_bound(EPS, L)


@pytest.mark.parametrize("fam", FAMILIES, ids=lambda f: f.name)
def test_every_tuned_family_is_not_below_the_bound(fam):
    setup = Setup(dt=DT, n=500, transient=2.0)
    case = Case("sines", "uniform", EPS, L, (11,))
    tuned = tune_family(fam.name, [case], setup, rounds=1, engine="numpy")
    row = tuned["best"][0]["worst"][0]
    pair = adversarial_pair(EPS, L, DT, 500, 400, slope=1.0)
    est = estimate(fam, np.tile(row, (2, 1)), pair["y"].T, DT, engine="numpy")[:, :, 1]
    err = adversarial_error(est, pair, k_from=setup.k_from)
    assert err >= lower_bound(EPS, L) * (1 - 1e-9)
    # and at t* itself both estimates coincide, so one of the two errs by at least the bound
    assert est[400, 0] == pytest.approx(est[400, 1], abs=1e-12)


def test_bound_constant_against_the_papers_example():
    # Aldana-López, Seeber, Haimovich, Gómez-Gutiérrez, IEEE TAC 2025 (arXiv:2404.05863), example as the authors'
    # testbench (github.com/RodrigoAldana/OREdiff, matlab/diff_testbench.m) runs it: f = L sin t, L = 1, noise
    # uniform within N = 0.08, sampling Δ = 0.01 s. Its dashed line, the accuracy its differentiator guarantees
    # without knowing N, is A = 2√(2 N L) + L Δ/2 = 0.805: √2 × our bound plus the sampling term.
    L, N, D = 1.0, 0.08, 0.01
    assert np.sqrt(2.0) * lower_bound(N, L) + L * D / 2 == pytest.approx(0.805, abs=5e-4)
    # with N known, the difference quotient over ⌈2√(N/L)/Δ⌉ = 57 samples errs by at most 2√(NL) + LΔ/2 = 0.5707
    # on every admissible signal (window error: 2N/(lΔ) + L lΔ/2) and by at least 2√(NL) = 0.5657 on the pair:
    # the bound's constant 2 is pinned to within LΔ/2 (a constant of 1 or 2√2 fails one of the two asserts)
    l = int(np.ceil(2 * np.sqrt(N / L) / D))
    assert l == 57
    lo, hi = lower_bound(N, L), lower_bound(N, L) + L * D / 2
    assert (round(lo, 4), round(hi, 4)) == (0.5657, 0.5707)
    rng = np.random.default_rng(7)
    t = D * np.arange(2001)
    y = L * np.sin(t) + N * rng.uniform(-1, 1, t.size)
    err_sin = np.max(np.abs((y[l:] - y[:-l]) / (l * D) - L * np.cos(t[l:])))
    assert err_sin <= hi  # the example's signal and noise
    pair = adversarial_pair(N, L, D, 2001, 1200)
    est = (pair["y"][:, l:] - pair["y"][:, :-l]) / (l * D)
    err_pair = np.max(np.abs(est - pair["f1"][:, l:]))
    assert lo * (1 - 1e-9) <= err_pair <= hi


def test_the_difference_quotient_keeps_its_guarantee_on_every_admissible_record():
    """Its worst-case error is at most 2ε/(m dt) + L m dt/2 <= 2√(εL) + L dt/2 on any signal with |f''| <= L and noise
    |η| <= ε: checked on sines with |f''| = L exactly and the most adverse bounded noise of a seeded draw."""
    from ctrl_analysis.arena.bound import difference_quotient

    rng = np.random.default_rng(7)
    dt, n = 0.001, 3000
    t = dt * np.arange(n)
    for _ in range(20):
        eps, L, w = 10 ** rng.uniform(-3, -1), 10 ** rng.uniform(-1, 1), rng.uniform(0.5, 5.0)
        f, d1 = (L / w**2) * np.sin(w * t + 1.0), (L / w) * np.cos(w * t + 1.0)
        noise = eps * np.sign(rng.uniform(-1, 1, n))  # ±ε: the largest noise allowed
        d, m, g = difference_quotient(f + noise, dt, eps, L)
        assert np.nanmax(np.abs(d - d1)) <= g * (1 + 1e-9)
        assert g <= lower_bound(eps, L) + L * dt / 2 + 1e-12 and np.all(np.isnan(d[:m]))
    with pytest.raises(ValueError, match="shorter than y"):
        difference_quotient(np.zeros(10), 0.01, 1.0, 1e-6)
