"""Tests of the Mamdani fuzzy controller, its lookup table, and the time-varying Kalman filter block."""

import numpy as np
import pytest
import scipy.integrate

from ctrl_analysis.controllers.fuzzy import (
    FuzzyController,
    FuzzyLookupController,
    piecewise_linear_centroid,
    sum_rule_table,
)
from ctrl_analysis.engine import Execution
from ctrl_analysis.estimators.kalman import (
    AlphaBetaFilter,
    DiscreteKalmanFilter,
    discrete_steady_state,
)


def _fc(**kw):
    args = {"Ke": 2.0, "Kec": 0.5, "Ku": 3.0, "input_range": 6.0, "output_range": 7.0}
    args.update(kw)
    return FuzzyController(sum_rule_table(7), **args)


def test_sum_rule_table():
    r = sum_rule_table(7)
    assert r[3, 3] == 3 and r[0, 0] == 0 and r[6, 6] == 6 and r[6, 0] == 3 and r[4, 4] == 5 and r[5, 6] == 6
    np.testing.assert_array_equal(sum_rule_table(7, -1), 6 - r)
    with pytest.raises(ValueError, match="n_terms must be odd"):
        sum_rule_table(6)


def test_odd_symmetric_for_a_symmetric_rule_table():
    fc = _fc()
    rng = np.random.default_rng(1)
    e, ec = rng.uniform(-4, 4, 500), rng.uniform(-15, 15, 500)
    np.testing.assert_allclose(fc.evaluate(-e, -ec), -fc.evaluate(e, ec), atol=1e-12)
    assert abs(fc.evaluate(np.array([0.0]), np.array([0.0]))[0]) < 1e-12


def test_saturates_at_the_output_range():
    fc = _fc()
    u_big = fc.evaluate(np.array([10.0, 100.0, 1e6]), np.array([20.0, 200.0, 1e6]))
    # beyond the input universes the output is constant: the centroid of the clipped PB triangle, 7 − Δu/3
    # (the triangle's foot 14/3 lies between grid points of the 281-point universe: 1e-4 relative)
    assert np.ptp(u_big) == 0.0
    np.testing.assert_allclose(u_big, 3.0 * (7.0 - (14.0 / 6) / 3.0), rtol=1e-4)
    rng = np.random.default_rng(2)
    u = fc.evaluate(rng.uniform(-50, 50, 2000), rng.uniform(-200, 200, 2000))
    assert np.all(np.abs(u) <= 3.0 * 7.0)


def test_equals_hand_computation():
    fc = FuzzyController(sum_rule_table(7), Ke=1.0, Kec=1.0, Ku=1.0, input_range=6.0, output_range=6.0,
                         n_grid=1201)
    # E = 2 (PS fully), EC = 0 (ZO): one rule, output term PS (centre 2) fires at 1: centroid 2
    assert fc.evaluate(np.array([2.0]), np.array([0.0]))[0] == pytest.approx(2.0, abs=1e-12)
    # E = 1: ZO and PS at 0.5 each; two equal clipped triangles centred at 0 and 2: centroid 1 by symmetry
    assert fc.evaluate(np.array([1.0]), np.array([0.0]))[0] == pytest.approx(1.0, abs=1e-12)
    # E = 0.5: ZO at 0.75, PS at 0.25: centroid of max(min(0.75, ZO), min(0.25, PS)) by quadrature
    def agg(z):
        return max(min(0.75, max(0.0, 1 - abs(z) / 2)), min(0.25, max(0.0, 1 - abs(z - 2) / 2)))

    pts = [-2, -0.5, 0, 1.5, 2, 4]
    num = scipy.integrate.quad(lambda z: z * agg(z), -2, 4, points=pts, epsabs=1e-13)[0]
    den = scipy.integrate.quad(agg, -2, 4, points=pts, epsabs=1e-13)[0]
    assert fc.evaluate(np.array([0.5]), np.array([0.0]))[0] == pytest.approx(num / den, abs=1e-4)


def test_piecewise_linear_centroid_is_exact_for_a_triangle():
    z = np.linspace(0.0, 3.0, 31)
    mu = np.maximum(0.0, 1 - np.abs(z - 1.0))[None] * (z <= 2.0)  # triangle on [0, 2] peaked at 1
    assert piecewise_linear_centroid(z, mu)[0] == pytest.approx(1.0, abs=1e-14)


def test_lookup_within_tolerance_of_direct_inference():
    fc = _fc()
    table = FuzzyLookupController(fc, 121)
    rng = np.random.default_rng(3)
    e, ec = rng.uniform(-3.5, 3.5, 3000), rng.uniform(-14, 14, 3000)
    err = np.abs(table.evaluate(e, ec) - fc.evaluate(e, ec))
    # stated tolerance: 1 % of the output range Ku·Y = 21 on a 0.1-step grid
    assert err.max() < 0.01 * 21.0
    # exact at the grid nodes
    np.testing.assert_allclose(table.evaluate(table.E[::7] / 2.0, table.EC[::7] / 0.5),
                               fc.evaluate(table.E[::7] / 2.0, table.EC[::7] / 0.5), atol=1e-12)


def test_blocks_in_batch_equal_single_runs():
    fc = _fc()
    u = np.random.default_rng(4).normal(size=(50, 2)) * [3.0, 10.0]
    batch = fc.output(0.0, np.zeros((50, 0)), u)
    singles = np.concatenate([fc.output(0.0, np.zeros((1, 0)), u[i:i + 1]) for i in range(50)])
    assert np.array_equal(batch, singles)
    assert fc.feedthrough and fc.n_states == 0 and fc.inputs == ("e", "ec") and fc.outputs == ("u",)


def test_rejects_bad_arguments():
    with pytest.raises(ValueError, match="Ke must be > 0"):
        _fc(Ke=0.0)
    with pytest.raises(ValueError, match="rules must hold output term indices"):
        FuzzyController(sum_rule_table(7), Ke=1, Kec=1, Ku=1, n_output_terms=5)
    with pytest.raises(TypeError, match="controller must be a FuzzyController"):
        FuzzyLookupController(object())


def test_agrees_with_scikit_fuzzy():
    """Same rule base through scikit-fuzzy's Mamdani primitives (trimf, interp_membership, fmin/fmax, defuzz)."""
    fuzz = pytest.importorskip("skfuzzy")
    fc = FuzzyController(sum_rule_table(7), Ke=1.0, Kec=1.0, Ku=1.0, input_range=6.0, output_range=7.0,
                         n_grid=281)
    x_in = np.linspace(-6, 6, 241)
    mf_e = [fuzz.trimf(x_in, [c - fc.w_e, c, c + fc.w_e]) for c in fc.c_e]
    mf_ec = [fuzz.trimf(x_in, [c - fc.w_ec, c, c + fc.w_ec]) for c in fc.c_ec]
    mf_u = [fuzz.trimf(fc.z, [c - fc.w_u, c, c + fc.w_u]) for c in fc.c_u]
    rng = np.random.default_rng(5)
    for E, EC in zip(rng.uniform(-6, 6, 12), rng.uniform(-6, 6, 12), strict=True):
        le = [fuzz.interp_membership(x_in, m, E) for m in mf_e]
        lc = [fuzz.interp_membership(x_in, m, EC) for m in mf_ec]
        agg = np.zeros_like(fc.z)
        for i in range(7):
            for j in range(7):
                w = np.fmin(le[i], lc[j])  # AND = min
                agg = np.fmax(agg, np.fmin(w, mf_u[fc.rules[i, j]]))  # implication min, aggregation max
        ref = fuzz.defuzz(fc.z, agg, "centroid")
        assert fc.evaluate(np.array([E]), np.array([EC]))[0] == pytest.approx(ref, abs=1e-9)


def test_constant_gain_filter_reaches_the_time_varying_kf():
    T = 0.01
    F = np.array([[1.0, T], [0.3 * T, 1.0]])
    Qd, R = np.diag([1e-6, 1e-3]), 1e-2
    ss = discrete_steady_state(F, np.array([[1.0, 0.0]]), np.eye(2), Qd, R)
    const = AlphaBetaFilter(ss.K_filter[0, 0], T * ss.K_filter[1, 0], T, F=F)
    kf = DiscreteKalmanFilter(F, [1.0, 0.0], Qd, R, P0=np.diag([1.0, 1.0]))
    y = np.random.default_rng(6).normal(scale=0.1, size=3000)
    y_ab, _ = const.run(y)
    y_kf, x_kf = kf.run(y)
    # the time-varying gain converges to the steady-state one, and the estimates meet after the transient
    P_end = x_kf[-1, 0, 2:].reshape(2, 2)
    np.testing.assert_allclose(P_end, ss.P_prior, rtol=1e-6)
    np.testing.assert_allclose(y_kf[-500:, 0, :], y_ab[-500:, 0, :], rtol=0, atol=1e-8)
    assert np.max(np.abs(y_kf[:20] - y_ab[:20])) > 1e-3  # they differ during the transient


def test_kalman_filter_batch_equals_single_runs():
    F = np.array([[1.0, 0.01], [0.0, 1.0]])
    kf = DiscreteKalmanFilter(F, [1.0, 0.0], np.diag([0.0, 1e-4]), 0.01, b=[0.0, 0.01])
    u = np.random.default_rng(7).normal(size=(40, 5, 2))
    yb, _ = kf.run(u)
    ys = np.concatenate([kf.run(u[:, i:i + 1, :])[0] for i in range(5)], axis=1)
    assert np.array_equal(yb, ys)
    with pytest.raises(ValueError, match="R must be > 0"):
        DiscreteKalmanFilter(F, [1.0, 0.0], np.eye(2), 0.0)


def test_controller_runs_in_python_control():
    import control as ct

    fc = _fc()
    e, ec = np.array([0.1, 0.5, 1.0, 2.0, 3.0]), np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    resp = ct.input_output_response(fc.nlsys(0.01, "fuzzy"), 0.01 * np.arange(5), np.stack([e, ec]))
    np.testing.assert_allclose(np.ravel(resp.outputs), fc.evaluate(e, ec), rtol=0, atol=1e-12)


# ---------------------------------------------- the kernels, called per point (the numpy methods derive from them)
def _per_point(fn, p, e, ec, n_out=1):
    out = np.empty((e.size, n_out))
    for k in range(e.size):
        fn(0.0, np.empty(0), np.array([e[k], ec[k]]), p, out[k])
    return out


def _fuzzy_inputs(n=400, seed=5):
    rng = np.random.default_rng(seed)
    e, ec = rng.uniform(-5, 5, n), rng.uniform(-20, 20, n)  # inside and beyond the universes (saturation)
    e[:4], ec[:4] = [np.nan, 0.0, 1e9, 3.0], [0.0, np.nan, -1e9, 12.0]  # NaN in, NaN out
    e[4:6], ec[4:6] = [0.5, -1.0], [2.0, -4.0]  # exactly on grid points / term peaks
    return e, ec


@pytest.mark.parametrize("compiled", [False, True])
def test_lookup_kernel_equals_the_block_output_bit_for_bit(compiled):
    from ctrl_analysis.controllers.fuzzy import lookup_output
    from ctrl_analysis.engine.codegen import _jit

    table = FuzzyLookupController(_fc(), 41)
    e, ec = _fuzzy_inputs()
    k = table.kernel()
    assert k.output is lookup_output and k.update is not None
    fn = _jit(lookup_output) if compiled else lookup_output
    y = _per_point(fn, k.params, e, ec)
    with np.errstate(invalid="ignore"):
        ref = table.output(0.0, np.zeros((e.size, 0)), np.stack([e, ec], 1))
    assert np.array_equal(y, ref, equal_nan=True) and np.isnan(y[:2]).all() and np.isfinite(y[2:]).all()


@pytest.mark.parametrize("compiled", [False, True])
def test_mamdani_kernel_equals_the_block_output_bit_for_bit(compiled):
    from ctrl_analysis.controllers.fuzzy import mamdani_output
    from ctrl_analysis.engine.codegen import _jit

    fc = _fc(n_grid=121)
    e, ec = _fuzzy_inputs()
    k = fc.kernel()
    assert k.output is mamdani_output and k.update is not None and k.params is fc.kernel_params
    fn = _jit(mamdani_output) if compiled else mamdani_output
    ref = fc.output(0.0, np.zeros((e.size, 0)), np.stack([e, ec], 1))  # the kernel on the batch's columns
    y = _per_point(fn, k.params, e, ec)  # one run at a time
    # one centroid (summed in numpy's pairwise order), one inference: bit for bit, NaN in, NaN out
    assert np.array_equal(y, ref, equal_nan=True) and np.isnan(y[:2]).all() and np.isfinite(y[2:]).all()


def test_centroid_sums_in_numpys_order():
    """The kernel's centroid takes its sums as ``np.sum`` along a row does (pairwise: blocks of 128, 8 accumulators)."""
    rng = np.random.default_rng(8)
    for n in (3, 8, 9, 17, 129, 130, 281, 300, 1201, 5000):
        z = np.linspace(-7.0, 7.0, n)
        mu = rng.random((4, n)) ** 3
        a, b = mu[:, :-1], mu[:, 1:]
        area = 0.5 * (a + b)
        moment = z[None, :-1] * area + (z[1] - z[0]) * (a + 2.0 * b) / 6.0
        assert np.array_equal(piecewise_linear_centroid(z, mu), np.sum(moment, axis=1) / np.sum(area, axis=1)), n


def test_compiled_surface_and_evaluate_equal_the_numpy_path_bit_for_bit():
    fc = _fc(n_grid=121)
    E, EC, U = fc.control_surface(51, 49)  # 2499 points: the compiled kernel
    EE, CC = np.meshgrid(E, EC, indexing="ij")
    u = np.stack([EE.ravel(), CC.ravel()], 1)
    assert np.array_equal(U.ravel(), fc.batched("output", 0.0, None, u, fc._unit_params)[:, 0])
    table = FuzzyLookupController(fc, 21)
    e, ec = _fuzzy_inputs(2500, seed=7)
    e, ec = e[2:], ec[2:]
    for blk in (fc, table):
        ref = blk.output(0.0, np.zeros((e.size, 0)), np.stack([e, ec], 1))[:, 0]  # numpy, on the batch's columns
        assert np.array_equal(blk.evaluate(e, ec), ref)  # compiled, point by point
    assert np.array_equal(table.lookup(*fc.quantise(e, ec)) * fc.Ku, table.evaluate(e, ec))


def test_per_run_parameters_equal_single_blocks():
    """Parameter rows per run on the batch's columns (the numpy engine's per-run path) equal each block alone."""
    u = np.random.default_rng(9).normal(size=(6, 2)) * [3.0, 10.0]
    Ke = np.array([0.5, 1.0, 2.0, 0.5, 4.0, 2.0])
    blocks = [_fc(Ke=k, n_grid=41) for k in Ke]
    tables = [FuzzyLookupController(b, 11) for b in blocks]  # a table per run: the cells differ per run
    for group in (blocks, tables):
        P = np.stack([b.kernel_params for b in group])
        rows = group[0].batched("output", 0.0, None, u, P)
        single = np.concatenate([b.output(0.0, np.zeros((1, 0)), u[i:i + 1]) for i, b in enumerate(group)])
        assert np.array_equal(rows, single)


def test_fuzzy_and_filter_blocks_in_a_loop_compiled_equal_numpy():
    """One loop (one compiled structure): Kalman and α-β filters, an error gain, lookup and Mamdani controllers."""
    from ctrl_analysis.engine.blocks import StaticGain
    from ctrl_analysis.engine.loop import Loop, place

    rng = np.random.default_rng(3)
    N, B = 60, 4
    y = np.cumsum(rng.standard_normal((N, B)), axis=0) * 0.1
    kf = DiscreteKalmanFilter([[1.0, 0.1], [0.0, 1.0]], [1.0, 0.0], np.diag([1e-4, 1e-2]), 0.05, b=[0.0, 0.1])
    ab = AlphaBetaFilter(0.5, 0.2, 0.1, b=[0.0, 0.1])
    err = StaticGain([[-1.0, 0.0], [0.0, -1.0]], ("xhat[0]", "xhat[1]"), ("e", "ec"))
    # the filters' u is an input (their output has feedthrough from u: fed back it would be an algebraic loop)
    loop = Loop([place(kf, "kf"), place(ab, "ab", outputs=("ab0", "ab1")), place(err, "err"),
                 place(FuzzyLookupController(_fc(), 31), "table", outputs=("u_table",)),
                 place(_fc(n_grid=41), "mamdani", outputs=("u_mamdani",))], 0.1)
    res = {eng: loop.simulate(N, inputs={"y": y, "u": np.sin(y)}, runs=B,
                              execution=Execution(engine=eng)) for eng in ("numpy", "compiled")}
    a, b = res["numpy"], res["compiled"]
    for s in ("xhat[0]", "xhat[1]", "ab0", "ab1", "u_table", "u_mamdani"):
        assert np.array_equal(a[s], b[s]), s
    assert np.ptp(a["u_table"]) > 0.1 and np.ptp(a["ab1"]) > 0.1 and np.ptp(a["u_mamdani"]) > 0.1
