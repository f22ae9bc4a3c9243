"""The arena: the common interface against the library blocks, the algebraic yardstick, signals, noise, tuning."""

import numpy as np
import pytest

from ctrl_analysis.arena import tuning
from ctrl_analysis.arena.algebraic import (
    MAX_WINDOW,
    algebraic_derivative,
    algebraic_weights,
)
from ctrl_analysis.arena.interface import (
    FAMILIES,
    OMEGA_DT_MAX,
    SIGMA_ORDER,
    estimate,
    family,
    scales,
    substeps_for,
)
from ctrl_analysis.arena.recommend import ArenaSettings
from ctrl_analysis.arena.recordcheck import MAX_RECORDS, MAX_ROWS
from ctrl_analysis.arena.signals import (
    NOISE_CLASSES,
    SIGNAL_CLASSES,
    add_noise,
    make_signal,
)
from ctrl_analysis.arena.tuning import (
    MAX_ROUNDS,
    Case,
    Setup,
    param_values,
    pareto_front,
    tune_family,
)
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.estimators.eso import ExtendedStateObserver
from ctrl_analysis.estimators.kalman.alpha_beta import AlphaBetaFilter, kalata_gains
from ctrl_analysis.estimators.lowpass import DiscreteLowPass, LowPassFilter
from ctrl_analysis.estimators.tracking import TrackingDifferentiator

DT = 0.01


def _record(n=300, seed=0, runs=3):
    t = DT * np.arange(n)
    rng = np.random.default_rng(seed)
    return np.sin(1.3 * t)[:, None] + 0.01 * rng.uniform(-1, 1, (n, runs))


def _params(fam, runs=3):
    s = scales(0.01, 2.0, DT)
    row = [max(p.lo, 2.0) if p.ref == "one" else round(s[p.ref]) if p.integer else s[p.ref] for p in fam.params]
    return np.array(row) * np.linspace(1.0, 1.4, runs)[:, None] ** np.array([0 if p.integer else 1 for p in fam.params])


# ------------------------------------------------------------------ algebraic yardstick, by hand
def test_algebraic_weights_match_hand_computation():
    # W = 2, d = 1: the backward difference; W = 3, d = 1: (y_k - y_(k-2)) / 2T; W = 3, d = 2: (3y_k - 4y_(k-1) +
    # y_(k-2)) / 2T
    assert np.allclose(algebraic_weights(2, 1, 0.5)[1], [2.0, -2.0])
    assert np.allclose(algebraic_weights(3, 1, 1.0)[1], [0.5, 0.0, -0.5])
    assert np.allclose(algebraic_weights(3, 2, 1.0)[1], [1.5, -2.0, 0.5])
    assert np.allclose(algebraic_weights(3, 2, 1.0)[2], [1.0, -2.0, 1.0])  # second difference
    assert np.allclose(algebraic_weights(5, 1, 1.0)[1], np.array([2, 1, 0, -1, -2]) / 10.0)  # LS slope


def test_algebraic_exact_on_quadratics_and_causal():
    t = DT * np.arange(60)
    y = (3 - 2 * t + 5 * t**2)[:, None]
    est = algebraic_derivative(np.hstack([y, y]), [7, 12], [2, 2], DT)
    assert np.allclose(est[20:, :, 1], (-2 + 10 * t[20:])[:, None], atol=1e-9)
    assert np.allclose(est[20:, :, 2], 10.0, atol=1e-6)
    y2 = y.copy()
    y2[40:] += 1.0  # a change after sample 39 does not move any estimate before it
    assert np.array_equal(algebraic_derivative(y2, [7], [2], DT)[:40], est[:40, :1])


def test_algebraic_errors_name_the_argument():
    with pytest.raises(ValueError, match="window"):
        algebraic_weights(2, 2, 1.0)
    with pytest.raises(ValueError, match="degree"):
        algebraic_weights(5, 3, 1.0)


def test_algebraic_windows_have_a_maximum_and_a_dt_whose_weights_overflow_is_refused():
    with pytest.raises(ValueError, match=f"window must be <= {MAX_WINDOW}"):
        algebraic_weights(MAX_WINDOW + 1, 2, 1.0)
    with pytest.raises(ValueError, match=r"windows must be in \[1, 1000000\]"):
        algebraic_derivative(np.zeros((20, 1)), [10**12], [2], 0.1)
    with pytest.raises(ValueError, match="dt = 1e-300 s is too small for double precision"):
        algebraic_weights(5, 2, 1e-300)  # 2 c2 / dt² overflows
    with pytest.raises(ValueError, match="dt = 1e-300 s is too small"):
        algebraic_derivative(np.zeros((20, 1)), [5], [2], 1e-300)
    w = algebraic_weights(5, 2, 1e300)  # f'' weights below double precision: 0, and finite
    assert np.all(np.isfinite(w)) and np.all(w[2] == 0.0) and np.all(w[1] != 0.0)
    assert np.array_equal(algebraic_weights(5, 2, 0.1)[2], algebraic_weights(5, 2, 1.0)[2] / 0.1**2)
    with pytest.raises(ValueError, match="y and dt overflow double precision"):
        algebraic_derivative(np.full((20, 1), 1e300), [5], [2], 1e-100)


# ------------------------------------------------------------------ the interface runs the library's blocks
def _library_block(name, row):
    """The library block of one configuration, its input names and the (f, f') outputs."""
    if name == "sigma":
        return DifferentialEstimator(3, row[0]), ("y",), ("xhat[0]", "xhat[1]")
    if name in ("leso2", "leso3"):
        obs = ExtendedStateObserver.from_bandwidth(1 if name == "leso2" else 2, row[0])
        return obs, ("y", "u"), ("xhat[0]", "xhat[1]")
    if name == "neso":
        alpha = np.array([1.0, 0.5, 0.25])
        gains = np.array([3 * row[0], 3 * row[0] ** 2, row[0] ** 3]) * row[1] ** (1 - alpha)
        return ExtendedStateObserver(gains, alpha=alpha, delta=row[1]), ("y", "u"), ("xhat[0]", "xhat[1]")
    if name == "td":
        return TrackingDifferentiator(row[0], DT, h0=row[1]), ("v",), ("x[0]", "x[1]")
    if name == "kalman":
        return AlphaBetaFilter(*kalata_gains(row[0]), DT), ("y",), ("xhat[0]", "xhat[1]")
    return DiscreteLowPass(LowPassFilter(row[0], 2), DT, channels=2), ("u[0]", "u[1]"), ("w[0]", "w[1]")


@pytest.mark.parametrize("init", ["first", "zero"])
@pytest.mark.parametrize("name", ["sigma", "leso2", "leso3", "neso", "td", "kalman", "difflp"])
def test_interface_equals_the_library_block_run_alone(name, init):
    # started at rest on the first sample: the library block with its first state y_0, the others 0
    fam = family(name)
    y = _record()
    P = _params(fam)
    est = estimate(fam, P, y, DT, engine="numpy", init=init)
    b = 2
    block, ins, outs = _library_block(name, P[b])
    x0 = np.zeros(len(block.states))
    if init == "first":
        x0[0] = y[0, b]
    continuous = name in ("sigma", "leso2", "leso3", "neso")
    loop = Loop([place(block, "x", outputs=list(block.outputs))], DT, substeps=2 if continuous else 1)
    inputs = {ins[0]: y[:, b]}
    if ins[-1] == "u":
        inputs["u"] = 0.0
    if name == "difflp":
        inputs["u[1]"] = np.concatenate([[0.0], np.diff(y[:, b]) / DT])
    res = loop.simulate(y.shape[0], inputs=inputs, x0={"x": x0}, execution=Execution(engine="numpy", progress=False))
    for j, s in enumerate(outs):
        assert np.allclose(est[:, b, j], res.signals[s][:-1, 0], rtol=1e-12, atol=1e-12), s


@pytest.mark.parametrize("name", ["leso3", "kalman"])
def test_interface_compiled_equals_numpy(name):
    y = _record(n=200)
    P = _params(family(name))
    a = estimate(name, P, y, DT, engine="numpy")
    c = estimate(name, P, y, DT, engine="compiled")
    assert np.allclose(a, c, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("fam", FAMILIES, ids=lambda f: f.name)
def test_batch_equals_single_runs(fam):
    y = _record(n=150)
    P = _params(fam)
    whole = estimate(fam, P, y, DT, engine="numpy")
    alone = estimate(fam, P[1:2], y[:, 1:2], DT, engine="numpy")
    assert np.array_equal(whole[:, 1], alone[:, 0])


def test_estimate_rejects_bad_shapes():
    with pytest.raises(ValueError, match="P must have shape"):
        estimate("leso2", [[1.0, 2.0]], np.zeros((10, 1)), DT)
    with pytest.raises(ValueError, match="family"):
        estimate("nope", [[1.0]], np.zeros((10, 1)), DT)


def test_references_and_parameters_beyond_double_precision_are_refused_naming_them():
    for eps, L, dt in ((1e-300, 4.0, 0.002), (0.01, 1e300, 0.002), (0.01, 4.0, 1e300), (1e300, 1e-300, 0.002)):
        with pytest.raises(ValueError, match="eps, L and dt .* give reference values beyond double precision"):
            scales(eps, L, dt)
    assert scales(1e-12, 1e4, 0.1)["window"] == 0.0  # a window under a sample is capped at 2 later, not refused
    with pytest.raises(ValueError, match=r"P \(leso2 parameters omega_o\) gives no valid estimator: m and omega"):
        estimate("leso2", [[1e299]], np.zeros((50, 1)), 1e-299)  # ω dt = 1, but ω² overflows
    with pytest.raises(ValueError, match=r"P column 0 \(leso2 parameter omega_o\) must put the fastest pole within "
                                         r"OMEGA_DT_MAX / dt \(ω dt <= 8"):
        estimate("leso2", [[1e300]], np.zeros((50, 1)), DT)
    with pytest.raises(ValueError, match=r"P column 0 \(algebraic parameter window\) must be <= MAX_WINDOW"):
        estimate("algebraic", [[1e300, 2.0]], np.zeros((50, 1)), DT)


# ------------------------------------------------------------------ signals and noise
def test_a_signal_that_overflows_is_refused_naming_t_and_L():
    t = np.linspace(0.0, 1.0, 20)
    t[0] = 1e300
    with pytest.raises(ValueError, match="t and L overflow double precision"):
        make_signal("chirp", 1, t, 2.0)


@pytest.mark.parametrize("kind", sorted(SIGNAL_CLASSES))
def test_signals_have_their_derivatives_and_bound(kind):
    t = np.linspace(0, 8, 8001)
    f = make_signal(kind, 5, t, 3.0)
    assert np.isclose(np.max(np.abs(f[2])), 3.0)
    h = t[1] - t[0]
    # f' and f'' integrate (trapezoid) to f and f' (f'' may jump where a smoothed step starts)
    for lo, hi in ((0, 1), (1, 2)):
        integral = f[lo][0] + np.concatenate([[0.0], np.cumsum(0.5 * h * (f[hi][1:] + f[hi][:-1]))])
        assert np.allclose(integral, f[lo], atol=1e-4 if lo == 0 else 1e-2)  # jumps of f'' cost O(h)
    assert np.array_equal(make_signal(kind, 5, t, 3.0), f)  # reproducible from its seed
    assert not np.array_equal(make_signal(kind, 6, t, 3.0), f)


def test_noise_classes_respect_their_bound():
    f = np.linspace(-1, 1, 20000)
    for kind in NOISE_CLASSES:
        eta = add_noise(kind, f, 0.02, 1) - f
        if kind == "gaussian":
            assert abs(np.std(eta) - 0.02 / 3) < 3e-4
        else:
            assert np.max(np.abs(eta)) <= 0.02 + 1e-15 and np.max(np.abs(eta)) > 0.019
    assert np.array_equal(add_noise("uniform", f, 0.1, 4), add_noise("uniform", f, 0.1, 4))


# ------------------------------------------------------------------ tuning
def test_tuning_finds_the_known_optimum_of_a_one_parameter_family():
    # the refined optimum is at least as good as every grid point, and the costs are monotone where they must be
    setup = Setup(dt=DT, n=600, transient=2.0)
    case = Case("sines", "uniform", 0.01, 2.0, (3,))
    r = tune_family("leso2", [case], setup, rounds=2, engine="numpy")
    worst = [m[0] for _, m in r["evaluated"][0]]
    assert r["best"][0]["worst"][1][0] == min(worst)
    assert r["tunings"] == 9 + 2 * 2 * 2
    lag = np.array([[v[0], m[2]] for v, m in r["evaluated"][0]])
    lag = lag[np.argsort(lag[:, 0])]
    assert np.all(np.diff(lag[:5, 1]) < 0)  # more bandwidth, less lag at the slow end


def test_families_tuned_side_by_side_equal_each_tuned_alone():
    """Issue 30: the families' rounds go into one map per round (one wait per round, not per family and round);
    each family's result is its own tuning's, value for value."""
    setup = Setup(dt=DT, n=400, transient=1.0)
    cases = [Case("sines", "uniform", 0.01, 2.0, (3,)), Case("steps", "gaussian", 0.02, 2.0, (4,))]
    names = ["leso2", "difflp", "algebraic"]
    together = tuning.tune_families(names, cases, setup, rounds=1, engine="numpy", jobs=2)
    assert list(together) == names
    for name in names:
        alone = tune_family(name, cases, setup, rounds=1, engine="numpy")
        assert together[name]["tunings"] == alone["tunings"]
        for a, b in zip(together[name]["evaluated"], alone["evaluated"], strict=True):
            assert all(np.array_equal(va, vb) and np.array_equal(ma, mb, equal_nan=True)
                       for (va, ma), (vb, mb) in zip(a, b, strict=True))
    with pytest.raises(ValueError, match="distinct family names"):
        tuning.tune_families(["leso2", "leso2"], cases, setup)


def test_pareto_front_is_non_dominated():
    rng = np.random.default_rng(1)
    p = rng.uniform(size=(200, 2))
    idx = pareto_front(p)
    for i in idx:
        assert not np.any((p[:, 0] <= p[i, 0]) & (p[:, 1] <= p[i, 1]) & ((p[:, 0] < p[i, 0]) | (p[:, 1] < p[i, 1])))
    assert len(idx) >= 1


def test_sizes_of_the_tuning_have_a_maximum_and_are_checked_before_any_work(monkeypatch):
    def no_work(*args, **kwargs):
        raise AssertionError("the tuning started")

    monkeypatch.setattr(tuning, "drive", no_work)
    setup = Setup(dt=DT, n=600, transient=2.0)
    case = Case("sines", "uniform", 0.01, 2.0, (3,))
    with pytest.raises(ValueError, match=f"rounds must be <= {MAX_ROUNDS}, got 1000000000000"):
        tune_family("leso2", [case], setup, rounds=10**12)
    with pytest.raises(ValueError, match=f"n must be <= {MAX_ROWS}"):
        Setup(dt=DT, n=10**100, transient=2.0)
    with pytest.raises(ValueError, match=f"records must be <= {MAX_RECORDS}"):
        ArenaSettings(records=MAX_RECORDS + 1)
    with pytest.raises(ValueError, match=f"rounds must be <= {MAX_ROUNDS}"):
        ArenaSettings(rounds=10**100)
    with pytest.raises(ValueError, match="z must give td parameter values .* finite and > 0"):
        param_values(family("td"), [[1e300, 0.5]], case, setup)
    with pytest.raises(ValueError, match="z must give td parameter values"):
        param_values(family("td"), [[-1e300, 0.5]], case, setup)
    assert np.all(param_values(family("td"), [[0.0, 0.5]], case, setup) > 0)


@pytest.mark.parametrize("name", sorted(SIGMA_ORDER))
def test_sigma_families_fastest_pole_is_n0_a_and_is_capped_by_the_sample_period(name):
    from ctrl_analysis.arena.tuning import Case, Setup, param_values
    from ctrl_analysis.estimators.differential import DifferentialEstimator

    n0, a = SIGMA_ORDER[name], 2.0
    poles = np.roots(np.r_[1.0, DifferentialEstimator(n0, a).a_coeffs])
    assert np.max(np.abs(poles)) == pytest.approx(n0 * a, rel=1e-6)  # the breakaway double pole -n0 a
    setup = Setup(dt=0.01, n=300, transient=1.0)
    v = param_values(family(name), [[50.0]], Case("sines", "uniform", 1e-6, 1e6, (1,)), setup)
    assert v[0, 0] * n0 * setup.dt == pytest.approx(OMEGA_DT_MAX)
    # a capped value runs, though n0 a dt may come back a few ulps above the cap (8.000000000000002 at dt = 3 ms)
    for dt in (0.003, 0.0123, 0.01):
        s = Setup(dt=dt, n=300, transient=0.1)
        v = param_values(family(name), [[50.0]], Case("sines", "uniform", 1e-6, 1e6, (1,)), s)
        assert np.all(np.isfinite(estimate(name, v, np.zeros((20, 1)), dt)))


def test_every_value_of_a_degree_or_order_gets_its_own_pattern_search():
    # algebraic: 5 windows x 2 degrees on the grid, then per cost and round ±1 window step from each degree's best
    case, setup = Case("sines", "uniform", 0.01, 2.0, (1,)), Setup(dt=DT, n=300, transient=1.0)
    r = tune_family("algebraic", [case], setup, rounds=1, engine="numpy")
    assert r["tunings"] == 10 + 2 * 2 * 2
    refined = r["evaluated"][0][10:]
    assert {int(v[1]) for v, _ in refined} == {1, 2}
    for cost, j in (("worst", 0), ("rms", 1)):  # no worse than either degree's best grid point
        for d in (1, 2):
            assert r["best"][0][cost][1][j] <= min(m[j] for v, m in r["evaluated"][0][:10] if v[1] == d)


def test_sigma_with_n0_tuned_is_sigma_of_that_order_at_the_same_fastest_pole():
    # one batch holding several orders and substep counts: each run is the fixed-order family's, bit for bit
    y = _record(n=200, runs=4)
    P = np.array([[30.0, 3], [30.0, 5], [30.0, 4], [600.0, 3]])
    est = estimate("sigman", P, y, DT, engine="numpy")
    assert np.array_equal(est[:, :1], estimate("sigma", [[10.0]], y[:, :1], DT, engine="numpy"))
    assert np.array_equal(est[:, 1:2], estimate("sigma5", [[6.0]], y[:, 1:2], DT, engine="numpy"))
    assert np.array_equal(est[:, 3:], estimate("sigma", [[200.0]], y[:, 3:], DT, engine="numpy"))
    assert not np.array_equal(est[:, 2], est[:, 0])  # n0 = 4 is another estimator
    with pytest.raises(ValueError, match=r"P column 1 \(sigman parameter n0\) must be in \[3, 6\]"):
        estimate("sigman", [[30.0, 2]], y[:, :1], DT)
    case, setup = Case("sines", "uniform", 1e-6, 1e6, (1,)), Setup(dt=DT, n=300, transient=1.0)
    v = param_values(family("sigman"), [[50.0, 4]], case, setup)
    assert v[0, 0] * DT == pytest.approx(OMEGA_DT_MAX) and v[0, 1] == 4  # the pole itself is capped


@pytest.mark.parametrize("name", ["leso2", "sigma"])
def test_a_pole_beyond_the_sample_rate_is_integrated_with_more_substeps_whatever_its_batch(name):
    # ω dt = 4: 8 RK4 substeps (ω h = 0.5), against the same observer integrated with 64; alone and beside a slow run
    y = _record(n=200, runs=2)
    P = np.array([[4.0 / DT / SIGMA_ORDER.get(name, 1)], [0.3 / DT / SIGMA_ORDER.get(name, 1)]])
    both = estimate(name, P, y, DT, engine="numpy")
    alone = estimate(name, P[:1], y[:, :1], DT, engine="numpy")
    assert np.array_equal(both[:, :1], alone)
    block, ins, outs = _library_block(name, P[0])
    x0 = np.zeros(len(block.states))
    x0[0] = y[0, 0]
    inputs = {ins[0]: y[:, 0]} | ({"u": 0.0} if ins[-1] == "u" else {})
    run = {}
    for n_sub in (64, 2):
        loop = Loop([place(block, "x", outputs=list(block.outputs))], DT, substeps=n_sub)
        res = loop.simulate(200, inputs=inputs, x0={"x": x0}, execution=Execution(engine="numpy", progress=False))
        run[n_sub] = res.signals[outs[1]][:-1, 0]
    err = np.max(np.abs(alone[:, 0, 1] - run[64]))
    assert err < 5e-3 * np.max(np.abs(run[64]))  # RK4 at ω h = 0.5, the accuracy of ω dt = 1 with 2 substeps
    assert np.max(np.abs(run[2] - run[64])) > 10 * err  # two substeps at ω dt = 4 (ω h = 2) would not be
    assert substeps_for([4.0, 0.3]).tolist() == [8, 2]
    with pytest.raises(ValueError, match="omega_dt must be <= OMEGA_DT_MAX"):
        substeps_for(9.0)


def test_the_given_gains_filter_runs_as_given_and_is_never_tuned():
    from ctrl_analysis.arena.tuning import Case, Setup, tune_family
    from ctrl_analysis.estimators.kalman import AlphaBetaFilter

    y = _record(n=120)
    est = estimate("ab", [[0.95, 0.863]] * y.shape[1], y, DT, engine="numpy", init="zero")
    ref, _ = AlphaBetaFilter(0.95, 0.863, DT).run(y[:, :, None])  # (N, B, [x̂, v̂]), from the zero state
    np.testing.assert_allclose(est[:, :, :2], ref, rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match=r"alpha\) must be in \(0, 2\]"):
        estimate("ab", [[2.5, 0.5]], y[:, :1], DT)
    with pytest.raises(ValueError, match="family name"):
        tune_family("ab", [Case("sines", "uniform", 0.01, 2.0, (1,))], Setup(dt=DT, n=120, transient=0.1))


def test_the_signal_error_column_and_a_third_cost_leave_the_derivatives_tuning_unchanged():
    from ctrl_analysis.arena.tuning import METRICS, Case, Setup, case_records, evaluate, tune_families

    setup = Setup(dt=DT, n=300, transient=0.5)
    case = Case("sines", "uniform", 0.01, 2.0, (3, 4))
    # the raw backward difference's f̂ is the measurement: its error is the noise itself
    m = evaluate(("algebraic", setup, (case,), [(0, np.array([2.0, 1.0]))], "numpy"))
    _, y, f = case_records(case, setup)
    k = setup.k_from
    assert m[0, METRICS.index("rms_f")] == pytest.approx(np.sqrt(np.mean((y[k:] - f[k:]) ** 2)), rel=1e-9)
    two = tune_families(["leso3"], [case], setup, rounds=1, engine="numpy")["leso3"]
    three = tune_families(["leso3"], [case], setup, rounds=1, engine="numpy", costs=("worst", "rms", "rms_f"))["leso3"]
    for cost in ("worst", "rms"):
        np.testing.assert_array_equal(two["best"][0][cost][1], three["best"][0][cost][1])
    grid = [mm for _, mm in three["evaluated"][0][:9]]  # leso3's grid: 9 bandwidths
    assert three["best"][0]["rms_f"][1][4] <= min(g[4] for g in grid)
    with pytest.raises(ValueError, match="costs"):
        tune_families(["leso3"], [case], setup, costs=("lag",))
