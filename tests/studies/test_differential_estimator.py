"""The differential-estimator study: linear helpers, the loops of Examples 1-2, the linear path, a smoke run."""

from __future__ import annotations

import json
from dataclasses import replace

import control as ct
import numpy as np
import pytest

from analysis.differential_estimator import (
    INFO,
    claims,
    example1,
    example2,
    figures,
    linear_checks,
    loops,
    run,
)
from analysis.differential_estimator.paper import (
    CLAIMS,
    EX1,
    EX2,
    LINEAR,
    READINGS,
    applied_gains,
    han_eso_gains,
    printed_eq9_gain,
)
from ctrl_analysis.engine import Execution
from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.noise import run_seeds
from ctrl_analysis.reporting.report import StudyContext, StudyResult, write_results_json
from ctrl_analysis.reporting.study import missing_plausible
from ctrl_analysis.symbolic.differential import breakaway_gain


def test_linear_helpers():
    # n0 = 3: s^3 + K s^2 + 2aK s + a^2 K is Hurwitz iff K > a/2 (Routh)
    assert linear_checks.min_stable_gain(3, 4.0) == pytest.approx(2.0, rel=1e-9)
    assert linear_checks.min_stable_gain(2, 4.0) == 0.0
    est = DifferentialEstimator(5, 5.0)
    peak_db, _ = linear_checks.peak(est)
    w = np.logspace(0, 3, 20001)
    assert peak_db == pytest.approx(20 * np.log10(np.abs(est.tf(1j * w)).max()), abs=1e-6)
    assert printed_eq9_gain(5, 2.0, 5) == pytest.approx(breakaway_gain(5, 2.0))
    assert applied_gains(LINEAR.ex2_K) == EX2.K
    with pytest.raises(ValueError, match="printed_K must end with the leading coefficient 1"):
        applied_gains((1.0, 2.0))


def test_linear_part_records_eq9_without_a_paper_gain(tmp_path):
    result = StudyResult(INFO)
    linear_checks.eq9_checks(result, LINEAR)
    linear_checks.controller_poles(result, LINEAR)
    # identities are checks, never reproduced cells; the paper prints the formula -n0 a, not the number -10
    bp = result.get("eq9.breakaway_point")
    assert bp.kind == "check" and bp.paper is None and bp.value == -10.0 and "gives -10" in bp.note
    assert result.get("ex2.controller_poles").kind == "check"
    assert result.get("ex2.controller_poles").verdict == "agrees"
    assert result.get("eq9.double_pole_gap").value < 1e-5
    assert [f.get("kind") for f in result.findings] == ["erratum"]
    q = result.get("eq9.gain_K")
    assert q.paper is None and q.value == pytest.approx(5**5 * 2 / 4**4)
    assert "n = 2, 3, 4, 5" in q.note
    np.testing.assert_allclose(result.get("ex2.controller_poles").value, [-12, -13, -14], rtol=1e-9)


def test_example1_loop_is_batch_invariant_and_matches_interconnect():
    p = replace(EX1, T=0.3)
    seeds = run_seeds(4, 3)
    noise = example1.draw(p, seeds)
    sig, div, _ = loops.simulate_example1(p, seeds, noise, chunk=120)
    alone, _, _ = loops.simulate_example1(p, seeds[1:2], noise[:, 1:2], chunk=300)
    assert not div.any()
    for s in ("x[0]", "sig[1]", "eso[0][1]"):
        np.testing.assert_array_equal(sig[s][:, 1], alone[s][:, 0])  # chunked, batched == one run alone
    # Σ alone, noise-free: the engine's RK4 equals python-control's interconnect
    loop = loops.example1_loop(p, [])
    res = loop.simulate(300, inputs={"xi": 0.0, "eta": 0.0},
                        execution=Execution(engine="numpy"))  # no loop structure to compile
    sys = loop.interconnect()
    resp = ct.input_output_response(sys, res.t, np.zeros((2, res.t.size)), X0=np.zeros(sys.nstates),
                                    solve_ivp_kwargs={"rtol": 1e-10, "atol": 1e-12})
    np.testing.assert_allclose(res["sig[1]"][:, 0], resp.outputs[list(loop.outlist).index("sig[1]")], atol=1e-8)


def test_padding_observers_changes_no_other_signal():
    p = replace(EX1, T=0.2)
    seeds = run_seeds(2, 2)
    noise = example1.draw(p, seeds)
    one, _, _ = loops.simulate_example1(p, seeds, noise)  # Han's ESO + a linear rider
    two, _, _ = loops.simulate_example1(p, seeds, noise, [loops.han_eso(p), loops.han_eso(p, 2e-3)])
    assert len(loops.pad_observers([])) == loops.OBSERVERS and "eso[1][0]" not in one
    for s in ("x[0]", "x[1]", "sig[0]", "sig[1]", "eso[0][1]"):
        np.testing.assert_array_equal(one[s], two[s])


def test_linear_path_equals_the_engine():
    p = replace(EX1, T=1.0)
    seeds = run_seeds(0, 2)
    noise = example1.draw(p, seeds)
    sig, _, _ = loops.simulate_example1(p, seeds, noise, [])
    est = DifferentialEstimator(p.n0, p.a)
    z1, z2 = loops.LinearPath(sig["x[0]"][:-1], noise[:, :, 1], p.h).estimates(est.ss)
    scale = np.abs(sig["sig[1]"]).max()
    np.testing.assert_allclose(z2, sig["sig[1]"][:-1], atol=1e-4 * scale)
    np.testing.assert_allclose(z1, sig["sig[0]"][:-1], atol=1e-5 * np.abs(sig["sig[0]"]).max())


def test_linearised_eso_and_equal_bandwidth():
    eso = loops.han_eso(EX1)
    lin = example1.linearised_eso(eso)
    assert eso.delta == EX1.h and np.allclose(eso.L, han_eso_gains(EX1.h))  # None: Han's rule at the simulation step
    np.testing.assert_allclose(lin.L, eso.L * eso.delta ** (np.array(EX1.eso_alpha) - 1))
    bw = float(ct.bandwidth(DifferentialEstimator(EX1.n0, EX1.a).tf))
    tune = example1.equal_bandwidth_tuning(EX1, bw)
    from ctrl_analysis.estimators.eso import ExtendedStateObserver

    assert example1.eso_bandwidth(ExtendedStateObserver.from_bandwidth(2, tune["omega_o"])) == pytest.approx(bw)
    assert example1.eso_bandwidth(lin) > 10 * bw  # the textbook ESO is much wider than Σ


def _assembled(p, a, b1, b2):
    """Linearised Example 2 assembled by hand from the blocks' matrices (independent of control.linearize)."""
    est = DifferentialEstimator(p.n0, a)
    K = np.asarray(p.K)
    M = np.zeros((3 + p.n0, 3 + p.n0))
    M[0, 1] = M[1, 2] = 1.0
    M[2, 0], M[2, 1] = b1, -b2
    M[2, 3:6] -= K  # u = -K z[0..2] at θ = 0 (state reading)
    M[3:, 3:] = est.A
    M[3:, 0] = est.B[:, 0]
    return M


@pytest.mark.parametrize("a, b1, b2", [(5.0, 1.0, 2.0), (34.0, -10.0, 100.0)])
def test_example2_linearisation_matches_the_assembled_matrix(a, b1, b2):
    A = loops.example2_linear(EX2, a, b1, b2)
    M = _assembled(EX2, a, b1, b2)
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(A)), np.sort_complex(np.linalg.eigvals(M)),
                               rtol=1e-6, atol=1e-6)


def test_stable_preset_is_the_smallest_integer_a_with_the_margin():
    assert loops.max_real_eig(loops.example2_linear(EX2)) > 0  # the printed loop is unstable
    a_new, a_star = example2.stable_estimator_a(EX2)
    assert a_star < a_new
    assert loops.max_real_eig(loops.example2_linear(EX2, a_new)) <= -EX2.stable_margin
    assert loops.max_real_eig(loops.example2_linear(EX2, a_new - 1)) > -EX2.stable_margin


@pytest.mark.parametrize("compiled", [False, True])
def test_example2_kernels_with_per_run_rows_equal_each_runs_own_block(compiled):
    """Plant (20) and Σ with per-run values: the kernels run by run (plain or jitted), on the rows
    ``simulate(params=...)`` packs, equal the batched methods and each run's own block bit for bit."""
    from ctrl_analysis.engine.codegen import _jit, kernel_of
    from ctrl_analysis.engine.params import resolve
    from ctrl_analysis.engine.stepcheck import unchecked

    rng = np.random.default_rng(7)
    B = 6
    b = (rng.normal(scale=10, size=B), rng.normal(scale=10, size=B), rng.uniform(0.1, 10, size=B))
    a = np.array([5.0, 5.0, 34.0, 34.0, 34.0, 34.0])
    loop = loops.example2_loop(EX2)
    variants = resolve(loop, loops.example2_params(EX2, a, b), B)
    own = {"plant": [loops.Plant20(EX2, (b[0][r], b[1][r], b[2][r])) for r in range(B)],
           "sigma": [DifferentialEstimator(EX2.n0, a[r], reading="state") for r in range(B)]}
    for name, n_u in (("plant", 2), ("sigma", 1)):
        v, first = variants[name], own[name][0]
        k = kernel_of(first)
        rhs = _jit(k.rhs) if compiled else k.rhs
        x, u = rng.normal(size=(B, first.n_states)), rng.normal(size=(B, n_u))
        for t in (0.5, 3.2, 6.4):  # w = sign(cos(0.5 t)) = +1, 0-crossing side, -1
            dx = np.empty_like(x)
            for r in range(B):
                rhs(t, x[r], u[r], v.rows[r], dx[r])
            alone = np.concatenate([unchecked(blk, "rhs")(t, x[r:r + 1], u[r:r + 1], None)
                                    for r, blk in enumerate(own[name])])
            assert np.array_equal(dx, alone)  # bit for bit
            if name == "plant":
                assert np.array_equal(dx, v.block.batched("rhs", t, x, u, v.rows))
    # (20) written out, and Σ's rows use their own a
    x, u = rng.normal(size=(B, 3)), rng.normal(size=(B, 2))
    x3 = b[0] * x[:, 0] - (b[1] - x[:, 0] ** 2) * x[:, 1] - b[2] * x[:, 2] * np.abs(x[:, 2]) + EX2.w_amp + u.sum(1)
    np.testing.assert_allclose(variants["plant"].block.batched("rhs", 0.0, x, u, variants["plant"].rows)[:, 2], x3,
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(variants["sigma"].rows[3], DifferentialEstimator(5, 34.0).a_coeffs)


def test_example2_loop_compiled_equals_numpy_with_a_grid_and_two_presets():
    p = replace(EX2, T=0.4, sweep_b1=(-10.0, 10.0), sweep_b2=(2.0,), sweep_b3=(1.0,))
    seeds = run_seeds(3, 4)
    out = {}
    for engine in ("numpy", "auto"):
        os_env = {"numpy": "numpy", "auto": ""}[engine]
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("CTRL_ANALYSIS_ENGINE", os_env)
            out[engine] = example2.simulate(p, seeds, 34.0, 2)
    a, b = out["numpy"], out["auto"]
    assert a["sig"]["x[0]"].shape == (401, 8) and not a["diverged"].any()
    for s in ("x[0]", "u"):
        np.testing.assert_array_equal(a["sig"][s], b["sig"][s])
    for s in ("x[1]", "xhat[0]", "xhat[1]"):
        np.testing.assert_array_equal(a["traces"][s], b["traces"][s])
    # the re-run traces are the batch's runs
    np.testing.assert_array_equal(b["traces"]["x[0]"], b["sig"]["x[0]"][:, b["pick"]])
    from ctrl_analysis.engine.codegen import kernel_of

    loop = loops.example2_loop(p)
    assert all(kernel_of(pl.block) is not None for pl in loop.placed)  # "auto" ran the compiled engine
    assert np.ptp(b["sig"]["u"][:, 0] - b["sig"]["u"][:, 4]) > 0  # the presets differ (Σ a = 5 vs 34)


def test_plant_is_never_hurwitz():
    result = StudyResult(INFO)
    example2.nonminimum_phase(result, EX2)
    assert all(v >= -1e-12 for v in result.get("ex2.plant.max_real_pole").value)


def _assembled_corrected(p, a, b1, b2):
    """As :func:`_assembled` with eq. (11)'s corrected estimates x̂ = C z + D y fed back."""
    est = DifferentialEstimator(p.n0, a)
    C, D = est.estimate_matrices("corrected")
    M = _assembled(p, a, b1, b2)
    K = np.asarray(p.K)
    M[2, 3:] = -K @ C[:3]  # u = -K x̂[0..2] at θ = 0
    M[2, 0] += -K @ D[:3, 0]  # y = x1 (no noise)
    return M


def test_corrected_reading_is_a_static_gain_after_sigma():
    p = replace(EX2, reading="corrected")
    loop = loops.example2_loop(p)
    assert any(pl.name == "reading" for pl in loop.placed)
    A = loops.example2_linear(p)
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(A)),
                               np.sort_complex(np.linalg.eigvals(_assembled_corrected(p, p.a, p.b1, p.b2))),
                               rtol=1e-6, atol=1e-6)


def test_every_reconstruction_has_a_plausible_range():
    for params in (LINEAR, EX1, EX2, READINGS):
        assert missing_plausible(params) == []


def test_stability_map_legend_shows_every_outcome():
    outcome = np.array([0, 1, 2, 1]).reshape(2, 2, 1)
    fig = figures.plot_stability_map(np.array([0.0, 1.0]), np.array([2.0, 3.0]), (1.0,),
                                     [("a", outcome, np.zeros((2, 2))), ("b", np.zeros_like(outcome), np.ones((2, 2)))],
                                     "t")
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    assert [t.split(":")[0].split(" (")[0] for t in texts[:3]] == ["settles", "oscillates", "diverges"]
    assert [int(t.rsplit(": ", 1)[1]) for t in texts[:3]] == [5, 2, 1]  # counts over both panels


def test_evaluate_flips_the_fair_claim_with_the_fal_exponents():
    """The sensitivity evaluation: at equal bandwidth the fal ESO ties Σ (fair claim fails); the linear form loses."""
    base = {"linear": LINEAR, "ex1": EX1, "ex2": replace(EX2, T=1.0)}
    kw = dict(runs=10, seed=0, grid={"sweep_b1": (1.0,), "sweep_b2": (2.0,), "sweep_b3": (1.0,)})
    at = {a: claims.evaluate(dict(base, ex1=replace(EX1, eso_alpha=a)), **kw) for a in ((1.0, 0.5, 0.25),
                                                                                       (1.0, 1.0, 1.0))}
    fair = [r.get_claim("sigma-beats-eso-fair") for r in at.values()]
    assert [c.holds for c in fair] == [False, True]
    assert "fal ESO error ÷ Σ's error 0.98" in fair[0].note  # a tie on x1, not an advantage
    for r in at.values():  # robust: the paper's comparison and the divergence of a badly tuned ESO
        assert r.get_claim("sigma-beats-eso").holds and r.get_claim("eso-diverges").holds
    # the margin is a reading the sweep varies: with a margin below the fal ESO's 0.98 the fair claim holds
    lax = claims.evaluate(dict(base, claims=replace(READINGS, fair_margin=0.9)), **kw)
    assert lax.get_claim("sigma-beats-eso-fair").holds and "at least 0.9 " in lax.get_claim("sigma-beats-eso-fair").note


def test_the_closed_form_softener_equals_the_libraries_zero_order_hold():
    from analysis.differential_estimator.paper import setpoint
    from ctrl_analysis.estimators.lowpass import LowPassFilter
    from ctrl_analysis.estimators.tracking import softened_setpoint

    for omega, h, T in ((2.0, 1e-3, 30.0), (0.5, 2e-3, 50.0), (5.0, 5e-4, 25.0)):
        p = replace(EX2, omega=omega, h=h, T=T)
        r = setpoint(p, round(T / h))
        ref = softened_setpoint(LowPassFilter(omega, 3), r, h)
        got = example2.softened_square_wave(omega, r, h)
        assert np.all(np.abs(got - ref).max(axis=0) <= 1e-12 * np.abs(ref).max(axis=0))
    assert example2.softened_square_wave(2.0, np.ones(5), 1e-3)[0].tolist() == [0.0, 0.0, 0.0]


def test_a_sweep_discretised_together_and_cut_kernels_equal_each_system_alone():
    from scipy import fft

    p = replace(EX1, T=6.0)
    seeds = run_seeds(1, 3)
    noise = example1.draw(p, seeds)
    sig, _, _ = loops.simulate_example1(p, seeds, noise, [])
    path = loops.LinearPath(sig["x[0]"][:-1], noise[:, :, 1], p.h)
    systems = [DifferentialEstimator(n0, 7.0).ss for n0 in (2, 5, 8)]
    n = path.n
    nfft = fft.next_fast_len(2 * n - 1, real=True)
    for sys, got in zip(systems, path.estimates_many(systems), strict=True):
        for o in (0, 1):  # the full-length convolution of each output alone, its own discretisations
            spec = 0
            for method, u in (("foh", sig["x[0]"][:-1]), ("zoh", noise[:, :, 1])):
                g = loops.impulse_response(ct.c2d(sys[o, 0], p.h, method=method), n)
                spec = spec + fft.rfft(u, nfft, axis=0) * fft.rfft(g, nfft)[:, None]
            ref = fft.irfft(spec, nfft, axis=0)[:n]
            np.testing.assert_allclose(got[o], ref, rtol=0, atol=1e-5 * np.abs(ref).max())
    assert max(path._spectra) < nfft  # the kernels were cut: a shorter transform than 2N - 1


def test_the_corrected_reading_of_x2_reads_z1_z2_and_y():
    est = DifferentialEstimator(EX1.n0, EX1.a)
    rng = np.random.default_rng(3)
    z, y = rng.normal(size=(4, EX1.n0)), rng.normal(size=4)
    C, D = est.estimate_matrices("corrected")
    np.testing.assert_allclose(est.estimates(z, y, reading="corrected")[:, 1],
                               z[:, 1] + est.a_coeffs[0] * (y - z[:, 0]), rtol=1e-12)
    assert not C[1, 2:].any() and D[1, 0] == pytest.approx(est.a_coeffs[0])


def test_the_plausible_box_of_the_study():
    from ctrl_analysis.reporting.box import Box

    box = Box({"linear": LINEAR, "ex1": EX1, "ex2": EX2, "claims": READINGS})
    names = [d.name for d in box.dims]
    # the estimate reading is remark (1)'s whenever there is noise: fixed, neither a range nor an algorithm axis
    assert "ex1.reading" not in names and "ex2.reading" not in names and box.algorithm is None
    assert {"ex1.h", "ex1.T", "ex1.method", "ex1.eso_tuning_ratio", "ex1.eso_delta", "ex2.h"} <= set(names)
    # the ESO's design step follows the simulation step: Han's rule for h' = ratio · h, δ = h' unless given
    eso = loops.han_eso(replace(EX1, h=2e-3, eso_tuning_ratio=1.5))
    assert np.allclose(eso.L, han_eso_gains(3e-3)) and eso.delta == pytest.approx(3e-3)
    assert loops.han_eso(replace(EX1, eso_delta=1e-2)).delta == 1e-2
    assert box.chosen[names.index("ex1.eso_tuning_ratio")] == 0.0  # h' = h: the range's lower end
    assert box.changed(box.chosen) == {}  # every chosen value (δ = h' is None) is a point of the box
    claims_by_id = {c.id: c for c in CLAIMS}
    assert claims_by_id["sigma-beats-eso-fair"].beyond and not any(
        c.beyond for c in CLAIMS if c.id != "sigma-beats-eso-fair")


def _claim_result(**values):
    result = StudyResult(INFO)
    for id_, v in values.items():
        result.quantity(id_.replace("__", "."), id_, v, unit="", runs=10)
    return result


def test_sigma_beats_eso_is_judged_run_by_run():
    base = {"ex1__sigma__mean_abs_err_x1": 1e-4, "ex1__sigma__mean_abs_err_x2": 5e-3,
            "ex1__eso__mean_abs_err_x1": 4e-4, "ex1__eso__mean_abs_err_x2": 0.2, "ex1__eso_over_sigma_x1": 4.0,
            "ex1__eso_over_sigma_x2": 40.0, "ex1__fair__textbook_eso_bandwidth": 400.0,
            "ex1__fair__sigma_bandwidth": 13.0, "ex1__sigma__corrected__mean_abs_err_x2": 0.05}
    # mean ratios above 1 do not decide it: Σ must be the more accurate in the typical run
    for share, holds in ((0.4, False), (0.5, False), (0.6, True)):
        r = _claim_result(**base, ex1__sigma_beats_eso__share_of_runs=share)
        r.quantity("ex1.eso_over_sigma.median_run", "m", [1.1, 9.0], unit="", runs=10)
        claims._sigma_beats_eso(r, EX1)
        c = r.get_claim("sigma-beats-eso")
        assert c.holds is holds and f"{share:.0%} of 10 runs" in c.note and "still below" in c.note


def test_ex2_tracks_is_judged_run_by_run_on_a_stable_loop():
    for max_re, share, holds in ((-0.5, 0.8, True), (-0.5, 0.5, False), (0.3, 1.0, False)):
        r = _claim_result(ex2__literal__max_real_eig=max_re, ex2__literal__share_settled=share,
                          ex2__literal__tail_amplitude=0.02, ex2__literal__mean_abs_tracking_error=0.1)
        claims._ex2_tracks(r, EX2)  # the stable preset is not simulated in a box evaluation: the note omits it
        c = r.get_claim("ex2-tracks")
        assert c.holds is holds and "stable preset" not in c.note
        assert c.evidence == ("ex2.literal.max_real_eig", "ex2.literal.share_settled", "ex2.literal.tail_amplitude",
                              "ex2.literal.mean_abs_tracking_error")


def test_a_box_evaluation_skips_what_no_claim_or_cell_reads():
    base = {"linear": LINEAR, "ex1": replace(EX1, T=2.0), "ex2": replace(EX2, T=2.0)}
    r = claims.evaluate(base, runs=4, seed=0)
    ids = {q.id for q in r.quantities}
    assert "ex2.literal.share_settled" in ids and "ex1.sigma_beats_eso.share_of_runs" in ids
    assert not any(i.startswith("ex2.fast_estimator") for i in ids) and "ex2.sweep.fraction_stable" not in ids
    assert "ex1.fair.linear_path_check_x1" not in ids and not any(i.startswith("ex1.tradeoff") for i in ids)
    assert [c.claim.id for c in r.claims] == [c.id for c in CLAIMS]


def test_another_plausible_integrator_lands_on_sigmas_printed_x2_error():
    """Issue 26: Σ's |ε̄2| = 5.4e-3 is outside the band of RK4 at the chosen values, inside it with forward Euler."""
    from ctrl_analysis.reporting.box_cells import cell_state

    base = {"linear": LINEAR, "ex1": EX1, "ex2": replace(EX2, T=1.0)}
    grid = {"sweep_b1": (1.0,), "sweep_b2": (2.0,), "sweep_b3": (1.0,)}
    states = {m: cell_state(claims.evaluate(dict(base, ex1=replace(EX1, method=m)), runs=8, seed=0,
                                            grid=grid).get("ex1.sigma.mean_abs_err_x2")) for m in ("rk4", "euler")}
    assert not states["rk4"]["in_band"] and states["rk4"]["gap"] < 0
    assert states["euler"]["in_band"]


def test_quick_run_smoke(tmp_path):
    ctx = StudyContext(out_dir=tmp_path, quick=True, runs=2, seed=5)
    ex2 = replace(EX2, T=1.0, sweep_b1=(-10.0, 0.0, 10.0), sweep_b2=(2.0,), sweep_b3=(1.0,))
    result = run(ctx, params={"ex1": replace(EX1, T=0.4, t_sens=0.2), "ex2": ex2})
    ids = {q.id for q in result.quantities}
    assert {"eq9.gain_K", "ex1.sigma.mean_abs_err_x1", "ex1.eso_over_sigma_x2",
            "ex1.fair.equal_bw.leso.mean_abs_err_x2",
            "ex1.tradeoff.sigma.err_x2", "ex1.n0_sweep.fixed_a.err_x1", "ex2.literal.max_real_eig",
            "ex2.sweep.fraction_stable", "ex2.sweep.literal.fraction_stable", "ex2.plant.rhp_zeros"} <= ids
    # every quantity with a paper value names its cell, except the checks; the ESO/Σ ratios are not printed
    assert all(q.cell for q in result.quantities if q.paper is not None and q.kind == "reproduction")
    primaries = {q.cell for q in result.quantities if q.primary}
    assert len(primaries) == 4 and result.get("ex1.eso_over_sigma_x1").cell is None
    for q in result.quantities:
        # Example 1's cells come from one noisy run of the paper: percentile policy
        if q.cell is not None and q.kind == "reproduction":
            assert q.policy == "percentile" and q.percentile is not None
    assert result.get("ex1.eso_over_sigma_x1").paper is None
    assert "0.0005769 / 0.00013179 = 4.38" in result.get("ex1.eso_over_sigma_x1").note
    assert result.seeds["ex1"] == run_seeds(5, 2)
    for name in result.figures:
        assert (tmp_path / name).stat().st_size > 10_000
    assert {"fig5_tracking_a5_and_a34.png", "ex1_tradeoff.png", "fig_ex2_stability_map.png",
            "sensitivity.png"} <= set(result.figures)
    names = {r["name"] for r in result.reconstructions}
    assert {"ex1.h", "ex1.eso_alpha", "ex1.eso_tuning_ratio", "ex2.K", "ex2.omega", "ex2.ripple_tol",
            "claims.fair_margin"} <= names
    # the claims, judged with their evidence; deterministic ones do not depend on the Monte Carlo runs
    assert [c.claim.id for c in result.claims] == [c.id for c in CLAIMS]
    verdicts = {c.claim.id: c.base_verdict for c in result.claims}
    assert verdicts == {"breakaway-design": "holds", "lowpass": "holds", "larger-n0": "fails",
                        "sigma-beats-eso": "holds", "sigma-beats-eso-fair": "fails", "eso-diverges": "holds",
                        "ex2-tracks": "fails", "ex2-robust": "fails", "nonminimum-phase": "fails"}
    assert result.get_claim("ex2-tracks").evidence[:2] == ("ex2.literal.max_real_eig", "ex2.literal.share_settled")
    assert result.get_claim("sigma-beats-eso").evidence[-2:] == ("ex1.eso_over_sigma_x1", "ex1.eso_over_sigma_x2")
    assert result.sensitivity["evaluations"] > 1
    data = json.loads(write_results_json(result, tmp_path).read_text())
    # "Not reproduced" (the report's list) names every printed cell that does not agree, then the study's 2 other items
    from ctrl_analysis.reporting.markdown import not_reproduced

    bad = [q for q in data["quantities"] if q.get("primary") and q["verdict"] in ("differs", "diverged")]
    items = not_reproduced(data)
    assert all(m.startswith(q["cell"] + " (") for m,
               q in zip(items, bad, strict=False))  # items: the differing cells first, then the missing ones
    assert len(items) == len(bad) + 2 and len(data["missing"]) == 2


def test_example1_runs_reduced_part_by_part_record_the_same_quantities(monkeypatch):
    """Above RUNS_PER_PART, Example 1's runs are simulated in parts, each reduced to its per-run errors (the Euler and
    half-step re-simulations and every linear-path sweep too) and joined: memory bounded by the part. Every
    quantity equals the one batch's to rounding (numpy's reductions over the runs' samples and the linear path's
    FFTs round differently for batches of other widths: relative differences of about 1e-16), every finding's
    text is the same, and Fig. 3-4 draw the same run."""
    p = replace(EX1, T=0.6, t_sens=0.2)
    seeds = run_seeds(3, 7)

    def record(d):
        res = StudyResult(INFO)
        example1.main_quantities(res, p, d)
        example1.sensitivities(res, p, d)
        example1.fair_comparison(res, p, d)
        example1.n0_sweep(res, p, d)
        return res.to_dict()

    whole = example1.simulate(p, seeds)
    monkeypatch.setattr(example1, "RUNS_PER_PART", 3)
    parts = example1.simulate(p, seeds)
    assert "per_run" in parts and "sig" not in parts and "noise" not in parts
    a, b = record(whole), record(parts)
    qa, qb = ({q["id"]: q for q in r["quantities"]} for r in (a, b))
    assert qa.keys() == qb.keys() and len(qa) > 30
    for k, q in qa.items():
        for f in ("value", "std", "runs", "runs_diverged"):
            if q.get(f) is None or isinstance(q[f], (int, str)):
                assert qb[k].get(f) == q.get(f), (k, f)
            else:
                np.testing.assert_allclose(qb[k][f], q[f], rtol=1e-12, atol=0, err_msg=f"{k} {f}")
    assert len(a["findings"]) == len(b["findings"]) > 3

    def numbers(v):  # the numeric leaves of a finding's evidence, in order
        if isinstance(v, dict):
            return [x for k in sorted(v) for x in numbers(v[k])]
        if isinstance(v, (list, tuple)):
            return [x for e in v for x in numbers(e)]
        return [float(v)] if isinstance(v, (int, float)) else []

    for fa, fb in zip(a["findings"], b["findings"], strict=True):
        assert {k: v for k, v in fa.items() if k != "evidence"} == {k: v for k, v in fb.items() if k != "evidence"}
        np.testing.assert_allclose(numbers(fb.get("evidence")), numbers(fa.get("evidence")), rtol=1e-12)
    (bw, tw), (bp, tp) = example1.shown_run(whole), example1.shown_run(parts)
    assert bw == bp and all(np.array_equal(tw[k], tp[k]) for k in example1.SHOWN)


def test_example2_runs_reduced_part_by_part_record_the_same_quantities(monkeypatch):
    """Above RUNS_PER_PART, each preset's rows (Monte Carlo runs and grid points) are simulated in parts reduced to
    their per-run values as they end: the same quantities to rounding, the same findings, the same Fig. 5 runs."""
    p = replace(EX2, T=1.2)
    runs = 7
    seeds = run_seeds(5, runs + len(p.sweep_b1) * len(p.sweep_b2) * len(p.sweep_b3))
    lin = example2.linear_analysis(StudyResult(INFO), p)

    def record(d):
        res = StudyResult(INFO)
        example2.quantities(res, p, d, lin)
        return res.to_dict()

    whole = example2.simulate(p, seeds, lin["a_new"], runs)
    monkeypatch.setattr(example2, "RUNS_PER_PART", 3)
    parts = example2.simulate(p, seeds, lin["a_new"], runs)
    assert whole["sig"] is not None and parts["sig"] is None
    for k in ("ok", "diverged", "step"):
        np.testing.assert_array_equal(whole[k], parts[k])
    assert whole["pick"] == parts["pick"]
    assert all(np.array_equal(whole["traces"][s], parts["traces"][s]) for s in whole["traces"])
    a, b = record(whole), record(parts)
    qa, qb = ({q["id"]: q for q in r["quantities"]} for r in (a, b))
    assert qa.keys() == qb.keys() and len(qa) >= 10
    for k, q in qa.items():
        if q.get("value") is not None:
            np.testing.assert_allclose(qb[k]["value"], q["value"], rtol=1e-12, err_msg=k)
    assert [f["id"] for f in a["findings"]] == [f["id"] for f in b["findings"]] and a["findings"]


def test_fig3_zoom_falls_inside_a_short_run():
    """--quick runs 2 s: the 10-10.5 s zoom of Fig. 3-4 would be an empty panel; it moves to the run's last 0.5 s."""
    t = np.linspace(0.0, 2.0, 2001)
    fig = figures.plot_x2(t, np.sin(t), np.sin(t) + 0.01, "short run", "estimate")
    zoom_ax = fig.axes[2]
    assert zoom_ax.get_xlim() == pytest.approx((1.5, 2.0))
    assert len(zoom_ax.lines[0].get_xdata()) == 501  # the estimate is drawn there
    fig = figures.plot_x2(np.linspace(0.0, 20.0, 20001), np.zeros(20001), np.zeros(20001), "full run", "estimate")
    assert fig.axes[2].get_xlim() == pytest.approx((10.0, 10.5))  # a full run keeps the paper-length zoom
