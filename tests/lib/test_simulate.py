"""Engine tests: seeds, batch axis, divergence, integrator order, python-control interop."""

import control as ct
import numpy as np
import pytest

from ctrl_analysis.simulate import (
    continuous_nlsys,
    draw_noise,
    gaussian_noise,
    run_seeds,
    simulate_discrete,
    simulate_ivp,
    simulate_sampled,
    uniform_noise,
)

# A damped oscillator x'' + 2 ζ ω x' + ω² x = u with known solution.
OMEGA, ZETA = 2.0, 0.1
A = np.array([[0.0, 1.0], [-OMEGA**2, -2 * ZETA * OMEGA]])
Bm = np.array([0.0, 1.0])


def linear_rhs(t, x, u, params=None):
    dx = x @ A.T
    if u is not None:
        dx = dx + np.asarray(u)[:, :1] * Bm
    return dx


def exact_free(t, x0):
    from scipy.linalg import expm

    return np.array([expm(A * tk) @ x0 for tk in t])


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
    with pytest.raises(ValueError, match="h must be > 0"):
        simulate_sampled(linear_rhs, [1, 0], -0.1, 10)
    with pytest.raises(ValueError, match="method"):
        simulate_sampled(linear_rhs, [1, 0], 0.1, 10, method="midpoint")
    with pytest.raises(ValueError, match="x0 must be finite"):
        simulate_sampled(linear_rhs, [np.nan, 0], 0.1, 10)


@pytest.mark.parametrize("method", ["euler", "rk4"])
def test_batch_equals_stacked_single_runs(method):
    seeds = run_seeds(3, 5)
    noise = draw_noise(seeds, 400, gaussian_noise(1.0))

    def controller(k, t, x, w):
        return -0.5 * x[:, :1] + w  # discrete part using state and held noise

    batch = simulate_sampled(linear_rhs, [1.0, 0.0], 0.01, 400, noise=noise, controller=controller,
                             method=method, seeds=seeds)
    for b, s in enumerate(seeds):
        single = simulate_sampled(linear_rhs, [1.0, 0.0], 0.01, 400, noise=noise[:, b:b + 1],
                                  controller=controller, method=method, seeds=[s])
        np.testing.assert_allclose(batch.x[:, b], single.x[:, 0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(batch.u[:, b], single.u[:, 0], rtol=0, atol=1e-12)
    assert batch.seeds == seeds and not batch.diverged.any()


@pytest.mark.parametrize("method,order", [("euler", 1), ("rk4", 4)])
def test_order_of_convergence(method, order):
    x0 = np.array([1.0, 0.0])
    T = 2.0
    errs = []
    hs = [0.02, 0.01, 0.005]
    for h in hs:
        n = round(T / h)
        res = simulate_sampled(linear_rhs, x0, h, n, method=method)
        errs.append(np.max(np.abs(res.x[-1, 0] - exact_free([T], x0)[0])))
    slopes = np.diff(np.log(errs)) / np.diff(np.log(hs))
    np.testing.assert_allclose(slopes, order, atol=0.15)


def test_substeps_refine_inside_a_held_sample():
    x0 = np.array([1.0, 0.0])
    coarse = simulate_sampled(linear_rhs, x0, 0.1, 20, method="euler")
    fine = simulate_sampled(linear_rhs, x0, 0.1, 20, method="euler", substeps=50)
    exact = exact_free(coarse.t, x0)
    assert np.max(np.abs(fine.x[:, 0] - exact)) < 0.1 * np.max(np.abs(coarse.x[:, 0] - exact))


def test_divergence_is_flagged_with_run_and_step():
    # x' = λ x with λ = 0 for run 0 and λ = 5 for run 1: run 1 crosses 1e3 at t = ln(1e3)/5 ≈ 1.38 s
    lam = np.array([[0.0], [5.0]])

    def rhs(t, x, u, p):
        return lam * x

    res = simulate_sampled(rhs, np.ones((2, 1)), 0.01, 300, bound=1e3)
    assert res.diverged.tolist() == [False, True]
    k = res.diverged_step[1]
    assert abs(res.t[k] - np.log(1e3) / 5) < 0.02
    assert np.all(np.isnan(res.x[k:, 1])) and np.all(np.isfinite(res.x[:, 0]))
    rec = res.divergences()
    assert rec == [{"run": 1, "step": int(k), "t": float(res.t[k]), "seed": None}]
    assert res.ok.tolist() == [True, False]


def test_discrete_loop_matches_closed_form_and_flags_nan():
    # x(k+1) = a x(k): geometric sequence; run with a = 2 overflows the bound
    a = np.array([[0.5], [2.0]])
    res = simulate_discrete(lambda k, x, w, p: a * x, np.ones((2, 1)), 40, bound=1e6)
    np.testing.assert_allclose(res.x[:, 0, 0], 0.5 ** np.arange(41), rtol=1e-14)
    assert res.diverged.tolist() == [False, True] and res.diverged_step[1] == 20  # 2^20 > 1e6


def test_ivp_path_matches_closed_form_for_a_batch():
    x0 = np.array([[1.0, 0.0], [0.0, 1.0]])
    t = np.linspace(0, 3, 31)
    res = simulate_ivp(linear_rhs, x0, t)
    for b in range(2):
        np.testing.assert_allclose(res.x[:, b], exact_free(t, x0[b]), atol=1e-7)
    assert not res.diverged.any()


def test_continuous_block_as_nlsys_in_an_interconnection():
    """The engine's rhs wrapped as control.nlsys, closed with a static gain via ct.feedback,
    matches the same loop simulated by the engine."""
    plant = continuous_nlsys(linear_rhs, states=2, inputs=1, outputs=1,
                             output=lambda t, x, u, p: x[:, :1], name="osc")
    assert isinstance(plant, ct.NonlinearIOSystem)
    closed = ct.feedback(plant, 3.0)  # u = r - 3 x1
    t = np.linspace(0, 5, 501)
    resp = ct.input_output_response(closed, t, U=np.ones_like(t), X0=[0, 0],
                                    solve_ivp_kwargs={"rtol": 1e-10, "atol": 1e-12})

    def rhs_cl(tt, x, u, p):
        return linear_rhs(tt, x, 1.0 - 3.0 * x[:, :1])

    res = simulate_sampled(rhs_cl, [0.0, 0.0], 0.01, 500)
    np.testing.assert_allclose(resp.outputs, res.x[:, 0, 0], atol=1e-5)
    # and against the linear closed loop as a python-control StateSpace
    lin = ct.ss(A - np.outer(Bm, [3.0, 0.0]), Bm.reshape(2, 1), [[1.0, 0.0]], 0)
    np.testing.assert_allclose(ct.step_response(lin, t).outputs, res.x[:, 0, 0], atol=1e-8)


def test_ivp_one_diverging_run_does_not_poison_the_batch():
    rate = np.array([[-1.0], [3.0], [-2.0]])
    t = np.linspace(0.0, 10.0, 101)
    # run 1 grows past the bound: it is frozen and flagged, the others finish unflagged
    res = simulate_ivp(lambda t, x, u, p: rate * x, np.ones((3, 1)), t, bound=1e3)
    assert res.diverged.tolist() == [False, True, False]
    assert res.diverged_step[1] in (23, 24)  # e^(3t) passes 1e3 at t = 2.30 s
    np.testing.assert_allclose(res.x[-1, [0, 2], 0], np.exp([-10.0, -20.0]), rtol=1e-5, atol=1e-9)

    # run 1 blows up in finite time (x' = x^2 from 1 at t = 1) with no bound: the batch solve fails,
    # each run is then solved on its own and only run 1 is flagged
    def blowup(t, x, u, p):
        out = rate * x
        out[1] = x[1] ** 2
        return out

    res = simulate_ivp(blowup, np.ones((3, 1)), t, bound=np.inf)
    assert res.info["per_run"] and res.diverged.tolist() == [False, True, False]
    np.testing.assert_allclose(res.x[-1, [0, 2], 0], np.exp([-10.0, -20.0]), rtol=1e-5, atol=1e-9)
    healthy = simulate_ivp(lambda t, x, u, p: -x, np.ones((2, 1)), t)
    assert not healthy.info["per_run"] and not healthy.diverged.any()


@pytest.mark.parametrize("kw,fragment", [
    ({"rtol": float("nan")}, "rtol must be finite"),
    ({"atol": -1.0}, "atol must be > 0"),
    ({"rtol": [1e-6]}, "rtol must be a real number"),
    ({"bound": float("nan")}, "bound must be > 0"),
    ({"bound": -np.inf}, "bound must be > 0"),
    ({"method": "Euler"}, "method must be one of"),
])
def test_ivp_rejects_bad_tolerances_and_bounds(kw, fragment):
    with pytest.raises((ValueError, TypeError), match=fragment):
        simulate_ivp(lambda t, x, u, p: -x, [1.0], [0.0, 1.0], **kw)


@pytest.mark.parametrize("bound", [float("nan"), -np.inf, 0.0, "big"])
def test_fixed_step_runners_reject_bad_bound(bound):
    with pytest.raises((ValueError, TypeError), match="bound must be"):
        simulate_sampled(linear_rhs, [1, 0], 0.1, 10, bound=bound)
    with pytest.raises((ValueError, TypeError), match="bound must be"):
        simulate_discrete(lambda k, x, w, p: x, [1.0], 10, bound=bound)


@pytest.mark.parametrize("base_seed", [0, 1, 7, 2**32 - 1, 2**32, 2**64 + 5, 2**127 + 3, 2**130 + 11])
def test_run_seeds_equal_numpy_seedsequence_children(base_seed):
    # run_seeds computes SeedSequence's hash vectorised over the children; it must give numpy's own numbers
    expected = [int(c.generate_state(1)[0]) for c in np.random.SeedSequence(base_seed).spawn(2000)]
    assert run_seeds(base_seed, 2000) == expected
    assert all(type(s) is int for s in run_seeds(base_seed, 3))


def test_sampled_runner_calls_controller_and_observe_once_per_sample_in_order():
    # the wrapper over Loop keeps the runner's callback order: controller(k) then observe(k), k = 0..N-1,
    # then observe(N) with u None; the controller sees the whole plant state and may keep state
    calls, h, t0, n = [], 0.1, 0.5, 6
    noise = draw_noise(run_seeds(2, 3), n, gaussian_noise(1.0))

    class Integrating:
        z = 0.0

        def __call__(self, k, t, x, w):
            calls.append(("controller", k, t))
            self.z = self.z + x[:, :1]
            return np.hstack([-self.z, w])

    ctrl = Integrating()

    def observe(k, t, x, u):
        calls.append(("observe", k, t, u is None))
        return np.hstack([x, ctrl.z + 0 * x[:, :1]])

    res = simulate_sampled(linear_rhs, [1.0, 0.0], h, n, controller=ctrl, noise=noise, observe=observe, t0=t0)
    expected = []
    for k in range(n):
        expected += [("controller", k, t0 + k * h), ("observe", k, t0 + k * h, False)]
    expected.append(("observe", n, t0 + n * h, True))
    assert [c[:2] for c in calls] == [c[:2] for c in expected]
    np.testing.assert_allclose([c[2] for c in calls], [c[2] for c in expected], rtol=0, atol=1e-15)
    assert [c[3] for c in calls if c[0] == "observe"] == [c[3] for c in expected if c[0] == "observe"]
    assert res.u.shape == (n, 3, 2) and res.y.shape == (n + 1, 3, 3)
    np.testing.assert_array_equal(res.u[:, :, 1], noise[:, :, 0])
    np.testing.assert_array_equal(res.y[:, :, :2], res.x)
    np.testing.assert_array_equal(res.y[:n, :, 2], np.cumsum(res.x[:n, :, 0], axis=0))  # the controller's z


def test_sampled_runner_observe_in_chunks_equals_whole_batch():
    noise = draw_noise(run_seeds(4, 5), 30, uniform_noise(-1.0, 1.0))

    def observe(k, t, x, u):
        return x[:, :1] * (1.0 if u is None else u)

    whole = simulate_sampled(linear_rhs, [1.0, 0.0], 0.05, 30, noise=noise, observe=observe)
    chunked = simulate_sampled(linear_rhs, [1.0, 0.0], 0.05, 30, noise=noise, observe=observe, chunk_runs=2)
    for name in ("x", "u", "y"):
        np.testing.assert_array_equal(getattr(chunked, name), getattr(whole, name))


def test_discrete_runner_observes_k_0_to_n_minus_1_with_noise_and_params():
    noise = draw_noise(run_seeds(1, 2), 8, gaussian_noise(1.0))
    ks = []

    def observe(k, x, w):
        ks.append(k)
        return x + w

    res = simulate_discrete(lambda k, x, w, p: p * x + w + k, [1.0], 8, noise=noise, params=0.5, observe=observe)
    assert ks == list(range(8)) and res.y.shape == (8, 2, 1) and res.u is None
    np.testing.assert_array_equal(res.y, res.x[:-1] + noise)
    np.testing.assert_array_equal(res.x[1:], 0.5 * res.x[:-1] + noise + np.arange(8.0)[:, None, None])
    np.testing.assert_array_equal(res.t, np.arange(9.0))


def test_runners_refuse_non_finite_noise():
    noise = np.zeros((5, 1, 1))
    noise[2] = np.nan
    with pytest.raises(ValueError, match="noise must be finite"):
        simulate_sampled(linear_rhs, [1.0, 0.0], 0.1, 5, noise=noise)
    with pytest.raises(ValueError, match="noise must be finite"):
        simulate_discrete(lambda k, x, w, p: x, [1.0], 5, noise=noise)
