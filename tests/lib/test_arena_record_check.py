"""The arena's checks of a user's record (ctrl_analysis.arena.recordcheck): the record's own noise and curvature,
the stated bounds held against them, the scale, the cost model and its limits, and the caps that bound the work."""

import math

import numpy as np
import pytest

from ctrl_analysis.arena import recordcheck, tuning
from ctrl_analysis.arena.interface import FAMILIES, OFFLINE, family
from ctrl_analysis.arena.recordcheck import (
    check_record,
    record_estimates,
    work_estimate,
)
from ctrl_analysis.arena.signals import add_noise, make_signal


def _sine(n=600, dt=0.01, eps=0.01, seed=0):
    t = dt * np.arange(n)
    return t, np.sin(t) + eps * np.random.default_rng(seed).uniform(-1, 1, n)


@pytest.mark.parametrize("noise", ["uniform", "gaussian", "quantisation"])
@pytest.mark.parametrize("eps", [0.002, 0.05])
def test_the_estimates_find_the_noise_bound_and_stay_below_the_curvature(noise, eps):
    """On the arena's own signal classes (L = 4 exactly): ε̂ within a factor 2 of ε (Gaussian: ε is its 3σ, so
    ε̂ = √3 σ ≈ 0.58 ε), and L̂, a lower estimate, never above L and within an order of magnitude of it."""
    dt, n = 0.002, 4000
    t = dt * np.arange(n)
    for sig in ("sines", "steps", "ramps", "chirp", "mixed"):
        f = make_signal(sig, 1, t, 4.0)[0]
        e = record_estimates(add_noise(noise, f, eps, 2), dt)
        assert 0.5 < e["noise_bound"] / eps < 2.0, (sig, e)
        assert e["accel"] <= 4.0 * 1.02, (sig, e)
        if noise != "quantisation" or eps < 0.01:  # 5 quantisation levels over a step hide its curvature
            assert e["accel"] > 0.4, (sig, e)


def test_a_clean_record_shows_its_curvature_and_almost_no_noise():
    t = 0.01 * np.arange(600)
    e = record_estimates(np.sin(t), 0.01)
    assert e["noise_bound"] < 1e-5 and e["accel"] == pytest.approx(1.0, rel=0.02)
    e = record_estimates(np.sin(t), 0.01, d1=np.cos(t))  # max |Δf'|/dt, a lower bound on max |f''|
    assert 0.98 < e["accel"] <= 1.0


def test_noise_alone_shows_no_curvature_and_a_quantiser_its_step():
    rng = np.random.default_rng(3)
    e = record_estimates(0.1 * rng.uniform(-1, 1, 5000), 0.001)
    assert e["accel"] == 0.0 and e["accel_time"] is None and 0.05 < e["noise_bound"] < 0.2
    t = 0.001 * np.arange(5000)
    e = record_estimates(0.1 * np.round(np.sin(t) / 0.1), 0.001)  # a slow sine through a quantiser of step 0.1
    assert e["quantum"] == pytest.approx(0.1) and e["noise_bound"] == pytest.approx(0.05)


@pytest.mark.parametrize("eps, L, message", [
    (1e-8, 1.0, "eps 1e-08 is far below the record's own noise: the spread of its third differences gives ε ≈ 0.011"),
    (0.01, 1e-6, "L 1e-06 is far below what the record's y shows: beyond its noise, its smoothed second differences "
                 "reach |f''| ≈ 0.8"),
    (1e4, 1.0, "the bounds' time scale √(ε/L) = 100 s is longer than the record (5.99 s)"),
], ids=["noise-too-small", "accel-too-small", "noise-too-large"])
def test_a_bound_tighter_than_the_record_or_beyond_it_is_an_error_with_the_records_estimate(eps, L, message):
    t, y = _sine()
    with pytest.raises(ValueError, match="the record: ") as info:
        check_record(t, y, None, eps, L)
    assert message in str(info.value)


@pytest.mark.parametrize("eps, L, which", [(1.0, 1.0, "eps 1 is 87.6× above"), (0.01, 1e6, "L 1e+06 is 1.07e+06×")])
def test_a_looser_bound_is_a_warning(eps, L, which):
    t, y = _sine()
    out = check_record(t, y, None, eps, L)
    assert len(out["warnings"]) == 1 and out["warnings"][0].startswith(which)
    assert out["stated"] == {"noise_bound": eps, "accel_bound": L}
    assert out["estimates"]["noise_bound"] == pytest.approx(0.0114, rel=0.01)


def test_the_true_bounds_of_the_arenas_classes_are_accepted():
    dt, n = 0.002, 4000
    t = dt * np.arange(n)
    for sig in ("sines", "steps", "ramps", "chirp", "mixed"):
        for noise in ("uniform", "gaussian"):
            for eps in (0.002, 0.01, 0.05):
                y = add_noise(noise, make_signal(sig, 1, t, 4.0)[0], eps, 2)
                assert check_record(t, y, None, eps, 4.0)["warnings"] == [], (sig, noise, eps)


def test_a_spike_beyond_the_noise_bound_is_located():
    t, y = _sine()
    y[300] += 1.0  # one sample 100 x the noise bound
    with pytest.raises(ValueError, match=r"at t ≈ 3 s .*a spike or a jump"):
        check_record(t, y, None, 0.01, 1.0)


@pytest.mark.parametrize("scale_y, eps, L, message", [
    (1e200, 0.01, 1.0, "the record: the largest |measurement| (y) is 1.01e+200, outside the magnitudes 1e-50 to 1e+50"),
    (1.0, 1e-300, 1e-300, "eps is 1e-300, outside the magnitudes 1e-50 to 1e+50 in which the arena's arithmetic "
                          "stays finite (the record's own estimates: ε ≈ 0.0114"),
], ids=["values-1e200", "bounds-1e-300"])
def test_values_or_bounds_whose_arithmetic_overflows_are_refused(scale_y, eps, L, message):
    t, y = _sine()
    with pytest.raises(ValueError) as info:
        check_record(t, scale_y * y, None, eps, L)
    assert message in str(info.value) and "rescale" in str(info.value)


def test_a_scaled_record_is_judged_like_the_original():
    t, y = _sine()
    a = check_record(t, y, None, 0.01, 1.0)["estimates"]
    b = check_record(t, 1e20 * y, None, 1e18, 1e20)["estimates"]
    assert b["noise_bound"] == pytest.approx(1e20 * a["noise_bound"]) and b["accel"] == pytest.approx(1e20 * a["accel"])


def test_arrays_and_bounds_are_checked_by_name():
    t, y = _sine()
    for kwargs, name in ((dict(t=t[::-1]), "t"), (dict(y=y[:-1]), "y"), (dict(d1=np.full(600, np.nan)), "d1"),
                         (dict(eps=-1.0), "eps"), (dict(L=np.inf), "L"), (dict(t="abc"), "t")):
        args = dict(t=t, y=y, d1=None, eps=0.01, L=1.0) | kwargs
        with pytest.raises((TypeError, ValueError), match=rf"^{name} "):
            check_record(**args)
    for name in ("t", "y", "d1"):  # a complex array is not read as its real part
        args = {"t": t, "y": y, "d1": None, "eps": 0.01, "L": 1.0} | {name: (t if name == "t" else y) + 1j}
        with pytest.raises(TypeError, match=f"^{name} must be a 1-D array of real numbers"):
            check_record(**args)


# ------------------------------------------------------------------------------------------------ the cost
def test_the_cost_tables_agree_with_the_tuning():
    for fam in FAMILIES + OFFLINE:
        grid, steps = tuning._grid(fam)
        starts = len({tuple(z[steps == 0]) for z in grid})  # one pattern search per value without a step
        assert recordcheck.FAMILY_GRIDS[fam.name] == (int(np.sum(steps > 0)), len(grid), starts), fam.name
    grid, _ = tuning._grid(family("algebraic"))
    assert np.allclose(np.unique(np.exp(grid[:, 0])), recordcheck.WINDOW_MULTIPLES)


def test_windows_are_capped_at_the_record_so_a_tiny_dt_costs_no_more():
    """500 rows at dt = 1e-9 s asked for algebraic windows of 2√(ε/L)/dt x 10 = 2e9 samples (20 GB): now capped."""
    n, dt, eps, L = 500, 1e-9, 0.01, 1.0
    case = tuning.Case("user", "user", eps, L, (0,))
    setup = tuning.Setup(dt=dt, n=n, transient=0.25 * n * dt)
    fam = family("algebraic")
    grid, _ = tuning._grid(fam)
    assert tuning.param_values(fam, grid + 5.0, case, setup)[:, 0].max() == n  # beyond the grid, too
    kal = tuning.param_values(family("kalman"), [[7.0]], tuning.Case("user", "user", 1e-8, 1.0, (0,)),
                              tuning.Setup(dt=0.01, n=600, transient=0.5))
    assert kal[0, 0] == tuning.LAMBDA_MAX  # ω dt = 100 asked Λ = 1e7: gains α = 1, β = 2, the stability edge
    w = work_estimate(n, dt, eps, L)
    assert w["window"] == n and w["memory_bytes"] < 1e9 and w["core_s"] < 10
    assert work_estimate(n, dt, eps, L) == work_estimate(n, 1e-6, eps, L)  # both capped at the record


def test_the_row_limit_fits_the_memory_limit_and_the_cost_grows_with_windows():
    assert work_estimate(recordcheck.MAX_ROWS, 0.01, 0.01, 1.0)["memory_bytes"] < recordcheck.MAX_MEMORY_BYTES
    a, b = work_estimate(10**5, 1e-3, 0.01, 1.0), work_estimate(10**5, 1e-4, 0.01, 1.0)
    assert b["window"] == 10 * a["window"] and b["core_s"] > 5 * a["core_s"]
    assert work_estimate(10**5, 1e-3, 0.01, 1.0, derivative=True)["fit_taps"] == 0
    # measured on the 2-core development machine (jobs=1): 10^6 rows, windows up to 200 samples, 97 s, 3.1 GB
    big = work_estimate(10**6, 0.01, 0.01, 1.0)
    assert 97 < big["core_s"] < 4 * 97 and 3.07e9 < big["memory_bytes"] < 2 * 3.07e9


def test_a_run_over_the_work_or_memory_limit_is_refused_with_the_limit_and_the_way_under_it(monkeypatch):
    t, y = _sine(n=2000, dt=0.001, eps=0.001)
    monkeypatch.setattr(recordcheck, "MAX_WORK_S", 5.2)
    with pytest.raises(ValueError) as info:
        check_record(t, y, None, 0.001, 1.0)
    msg = str(info.value)
    assert "2000 rows at dt = 0.001 s with ε = 0.001, L = 1 need about" in msg and "core-seconds" in msg
    assert "over the limit of 5.2: decimate the record (keep every k-th row" in msg
    monkeypatch.setattr(recordcheck, "MAX_WORK_S", 1e9)
    monkeypatch.setattr(recordcheck, "MAX_MEMORY_BYTES", 2**28)
    with pytest.raises(ValueError, match=r"need about 0\.\d+ GiB of memory.*over the limit of 0.25 GiB: decimate"):
        check_record(t, y, None, 0.001, 1.0)
    monkeypatch.setattr(recordcheck, "MAX_ROWS", 1000)
    with pytest.raises(ValueError, match="has 2000 rows, over the limit of 1000: decimate"):
        check_record(t, y, None, 0.001, 1.0)


@pytest.mark.parametrize("kwargs, name", [(dict(n=1), "n"), (dict(n=2.5), "n"), (dict(dt=0.0), "dt"),
                                          (dict(eps=math.nan), "eps"), (dict(L=-1.0), "L"),
                                          (dict(derivative="yes"), "derivative")])
def test_work_estimate_names_a_bad_argument(kwargs, name):
    with pytest.raises((TypeError, ValueError), match=name):
        work_estimate(**(dict(n=100, dt=0.01, eps=0.01, L=1.0) | kwargs))


def test_the_estimates_refuse_magnitudes_beyond_the_scale_range_and_a_scalar_derivative():
    _, y = _sine()
    for kwargs, name in (({"dt": 1e300}, "dt is 1e"), ({"dt": 1e-300}, "dt is 1e-300"),
                         ({"eps": 1e300}, "eps is 1e"), ({"d1": np.full(600, 1e60)}, "d1's largest magnitude")):
        with pytest.raises(ValueError, match=f"{name}.*outside the magnitudes 1e-50 to 1e[+]50"):
            record_estimates(y, **({"dt": 0.01} | kwargs))
    with pytest.raises(ValueError, match=r"y's largest magnitude is 1e\+300"):
        record_estimates(np.full(600, 1e300), 0.01)
    with pytest.raises(ValueError, match=r"d1 must have the shape of y \(600,\), got \(\)"):
        record_estimates(y, 0.01, d1=3)
    assert record_estimates(-y, 0.01)["noise_bound"] == record_estimates(y, 0.01)["noise_bound"]  # any sign
    with pytest.raises(ValueError, match=f"n must be <= {recordcheck.MAX_ROWS}"):
        work_estimate(10**100, 0.01, 0.01, 1.0)


def test_an_extreme_ratio_of_the_bounds_does_not_overflow_the_estimate():
    w = work_estimate(1000, 1e-300, 1e300, 1e-300)
    assert w["window"] == 1000 and w["fit_taps"] == 1000 and math.isfinite(w["core_s"])
