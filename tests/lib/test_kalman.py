"""Tests of ctrl_analysis.estimators.kalman: Riccati solutions, gain forms, α-β filters, errors."""

import control as ct
import numpy as np
import pytest
import scipy.linalg

from ctrl_analysis.estimators.kalman import (
    AlphaBetaFilter,
    alpha_beta_from_gain,
    alpha_beta_stable,
    care_residual,
    check_controllable,
    check_observable,
    continuous_steady_state,
    continuous_steady_state_gain,
    controllability_rank,
    dare_residual,
    discrete_steady_state,
    discrete_steady_state_batch,
    discretize_noise,
    gain_from_alpha_beta,
    kalata_gains,
    observability_matrix,
    observability_rank,
    random_walk_gain,
    riccati_trajectory,
    tracking_index,
    tracking_index_from_gains,
)

C2 = np.array([[1.0, 0.0]])
G2 = np.array([[0.0], [1.0]])


def osc(a21):
    return np.array([[0.0, 1.0], [a21, 0.0]])


def dwna(T):
    """Discrete white-noise-acceleration model (Kalata's α-β tracker)."""
    return np.array([[1.0, T], [0.0, 1.0]]), np.array([[T * T / 2.0], [T]])


# --------------------------------------------------------------------------- continuous


@pytest.mark.parametrize("a21, Q, R", [(26.149, 100.0, 50.0), (2.6149, 100.0, 50.0), (0.0, 1.0, 1.0),
                                       (-4.0, 3.0, 0.2), (1.0, 1e4, 1e-2)])
def test_continuous_are_residual_and_references(a21, Q, R):
    A = osc(a21)
    ss = continuous_steady_state(A, C2, G2, Q, R)
    # ARE residual relative to the size of P: tolerance 1e-9
    res = care_residual(A, C2, G2, Q, R, ss.P)
    np.testing.assert_allclose(res, 0.0, atol=1e-9 * np.abs(ss.P).max())
    # scipy's CARE on the dual problem and python-control's lqe
    P_sp = scipy.linalg.solve_continuous_are(A.T, C2.T, G2 @ G2.T * Q, np.array([[R]]))
    np.testing.assert_allclose(ss.P, P_sp, rtol=1e-8, atol=1e-10 * np.abs(P_sp).max())
    L, P_ct, _ = ct.lqe(A, G2, C2, Q, R)
    np.testing.assert_allclose(ss.K, L, rtol=1e-8)
    np.testing.assert_allclose(ss.K, ss.P @ C2.T / R, rtol=1e-12)
    assert np.all(ss.poles.real < 0)
    assert np.all(np.linalg.eigvalsh(ss.P) > 0)
    np.testing.assert_allclose(continuous_steady_state_gain(A, C2, G2, Q, R), ss.K)


def test_continuous_double_integrator_known_gain():
    # A = [[0,1],[0,0]], q = Q/R: k1 = √2 q^¼, k2 = √q
    q = 16.0
    K = continuous_steady_state_gain(osc(0.0), C2, G2, q, 1.0).ravel()
    np.testing.assert_allclose(K, [np.sqrt(2) * q**0.25, np.sqrt(q)], rtol=1e-10)


# --------------------------------------------------------------------------- Riccati ODE


@pytest.mark.parametrize("P0", [np.zeros((2, 2)), np.diag([1e3, 1e3]), np.diag([1e2, 1e5])])
def test_riccati_trajectory_converges_to_are_solution(P0):
    A = osc(26.149)
    t = np.linspace(0.0, 3.0, 61)
    P = riccati_trajectory(A, C2, G2, 100.0, 50.0, P0, t)
    assert P.shape == (61, 2, 2)
    np.testing.assert_allclose(P[0], P0)
    np.testing.assert_allclose(P, np.swapaxes(P, 1, 2))
    P_bar = continuous_steady_state(A, C2, G2, 100.0, 50.0).P
    np.testing.assert_allclose(P[-1], P_bar, rtol=1e-5)
    assert np.linalg.norm(P_bar) > 1e3  # it converges to P̄, not to zero


def test_riccati_trajectory_scalar_closed_form():
    # ṗ = q − p²/r  ⇒  p(t) = √(qr) tanh(t √(q/r) + atanh(p0/√(qr)))
    q, r, p0 = 4.0, 0.25, 0.3
    t = np.linspace(0.0, 2.0, 21)
    P = riccati_trajectory([[0.0]], [[1.0]], [[1.0]], q, r, [[p0]], t, rtol=1e-10)
    s = np.sqrt(q * r)
    np.testing.assert_allclose(P[:, 0, 0], s * np.tanh(t * np.sqrt(q / r) + np.arctanh(p0 / s)), rtol=1e-7)


# --------------------------------------------------------------------------- discrete


@pytest.mark.parametrize("a21, T, Q, R", [(26.149, 0.01, 100.0, 5000.0), (0.0, 0.1, 1.0, 1.0),
                                          (2.6149, 0.05, 10.0, 0.5)])
def test_discrete_are_residual_and_forms(a21, T, Q, R):
    F = scipy.linalg.expm(osc(a21) * T)
    Gd = np.array([[T * T / 2], [T]])
    ss = discrete_steady_state(F, C2, Gd, Q, R)
    scale = np.abs(ss.P_prior).max()
    np.testing.assert_allclose(dare_residual(F, C2, Gd, Q, R, ss.P_prior), 0.0, atol=1e-9 * scale)
    # python-control's dlqe returns the predictor-form gain and the a-priori P
    L, P, E = ct.dlqe(F, Gd, C2, Q, R)
    np.testing.assert_allclose(ss.L_predictor, L, rtol=1e-8)
    np.testing.assert_allclose(ss.P_prior, P, rtol=1e-8)
    # the filter-form gain and the relation L = F K
    np.testing.assert_allclose(ss.K_filter, ss.P_prior @ C2.T / (C2 @ ss.P_prior @ C2.T + R), rtol=1e-12)
    np.testing.assert_allclose(ss.L_predictor, F @ ss.K_filter, rtol=1e-8)
    # P(k|k) = (I − K H) P⁻ and K = P(k|k) Hᵀ R⁻¹
    np.testing.assert_allclose(ss.P_post, (np.eye(2) - ss.K_filter @ C2) @ ss.P_prior, rtol=1e-10,
                               atol=1e-12 * scale)
    np.testing.assert_allclose(ss.K_filter, ss.P_post @ C2.T / R, rtol=1e-8)
    # scipy's DARE
    P_sp = scipy.linalg.solve_discrete_are(F.T, C2.T, Gd @ Gd.T * Q, np.array([[R]]))
    np.testing.assert_allclose(ss.P_prior, P_sp, rtol=1e-7)
    assert np.all(np.abs(ss.poles) < 1)


def test_batch_doubling_matches_dlqe():
    Ts = np.geomspace(1e-3, 0.3, 9)
    A = osc(26.149)
    pairs = [discretize_noise(A, G2, 100.0, T) for T in Ts]
    F = np.stack([p[0] for p in pairs])
    Qd = np.stack([p[1] for p in pairs])
    b = discrete_steady_state_batch(F, C2, Qd, 50.0 / Ts)
    for i, T in enumerate(Ts):
        one = discrete_steady_state(F[i], C2, np.eye(2), Qd[i], 50.0 / T)
        np.testing.assert_allclose(b.P_prior[i], one.P_prior, rtol=1e-8)
        np.testing.assert_allclose(b.K_filter[i], one.K_filter, rtol=1e-8)
        np.testing.assert_allclose(b.L_predictor[i], one.L_predictor, rtol=1e-8)


def test_discretize_noise_double_integrator_closed_form():
    T, q = 0.2, 3.0
    F, Qd = discretize_noise(osc(0.0), G2, q, T)
    np.testing.assert_allclose(F, [[1.0, T], [0.0, 1.0]], atol=1e-14)
    np.testing.assert_allclose(Qd, q * np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]]), rtol=1e-12)


# --------------------------------------------------------------------------- α-β


@pytest.mark.parametrize("T, sigma_w, sigma_v", [(0.01, 50.0, 0.2), (0.1, 1.0, 1.0), (1.0, 0.3, 2.0),
                                                 (0.5, 10.0, 0.1)])
def test_alpha_beta_from_dare_equals_kalata(T, sigma_w, sigma_v):
    F, Gd = dwna(T)
    ss = discrete_steady_state(F, C2, Gd, sigma_w**2, sigma_v**2)
    alpha, beta = alpha_beta_from_gain(ss.K_filter, T)
    Lam = tracking_index(sigma_w, sigma_v, T)
    ka, kb = kalata_gains(Lam)
    np.testing.assert_allclose([alpha, beta], [ka, kb], rtol=1e-8)
    # Kalata's identities
    np.testing.assert_allclose(beta**2 / (1 - alpha), Lam**2, rtol=1e-8)
    np.testing.assert_allclose(beta, 2 * (2 - alpha) - 4 * np.sqrt(1 - alpha), rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(tracking_index_from_gains(alpha, beta), Lam, rtol=1e-8)
    np.testing.assert_allclose(gain_from_alpha_beta(alpha, beta, T), ss.K_filter.ravel(), rtol=1e-12)
    # the predictor-form gain is NOT the α-β gain
    assert not np.allclose(alpha_beta_from_gain(ss.L_predictor, T), (alpha, beta), rtol=1e-3)


def test_alpha_beta_filter_ramp_zero_steady_error_and_batch():
    T, slope = 0.1, 2.0
    alpha, beta = kalata_gains(0.5)
    f = AlphaBetaFilter(alpha, beta, T)
    ys = slope * T * np.arange(400)
    x, _ = f.run(ys)
    # type-2 loop: a ramp is tracked with zero steady-state error, velocity = slope
    np.testing.assert_allclose(x[-1, 0], [ys[-1], slope], atol=1e-9)
    # batch axis: B independent ramps in one run, each equal to its single run
    slopes = np.array([-1.0, 0.0, 3.0])
    u = (slopes * T * np.arange(400)[:, None])[:, :, None]
    xb, _ = f.run(u)
    assert xb.shape == (400, 3, 2)
    np.testing.assert_allclose(xb[-1, :, 1], slopes, atol=1e-9)
    np.testing.assert_array_equal(xb[:, 2:3], f.run(u[:, 2])[0])


def test_alpha_beta_filter_constant_acceleration_lag():
    # steady-state position bias for constant acceleration a: e = (1 − α) a T² / β
    T, acc = 0.05, 4.0
    alpha, beta = 0.6, 0.3
    f = AlphaBetaFilter(alpha, beta, T)
    k = np.arange(600)
    ys = 0.5 * acc * (k * T) ** 2
    x = f.run(ys)[0][-1, 0]
    np.testing.assert_allclose(ys[-1] - x[0], (1 - alpha) * acc * T**2 / beta, rtol=1e-8)


def test_alpha_beta_stability_region_and_errors():
    assert alpha_beta_stable(0.95, 0.863)
    assert not alpha_beta_stable(0.5, 3.5)
    with pytest.raises(ValueError, match="alpha, beta must give a stable filter"):
        AlphaBetaFilter(0.5, 3.5, 0.1)
    with pytest.raises(ValueError, match="T must be > 0"):
        AlphaBetaFilter(0.5, 0.2, 0.0)
    f = AlphaBetaFilter(0.5, 0.2, 0.1)
    with pytest.raises(ValueError, match="u must be finite"):
        f.run([0.0, np.nan])
    with pytest.raises(ValueError, match="u must have shape"):
        f.run(np.zeros((2, 2)))
    with pytest.raises(ValueError, match="K must have 2 entries"):
        alpha_beta_from_gain([1.0, 2.0, 3.0], 0.1)
    with pytest.raises(ValueError, match="alpha must be in"):
        tracking_index_from_gains(1.2, 0.5)


# --------------------------------------------------------------------------- random walk


@pytest.mark.parametrize("Q, R", [(1.0, 1.0), (0.01, 3.0), (5.0, 0.2), (1e-6, 1.0)])
def test_random_walk_gain_fixed_point_and_scaling(Q, R):
    K = random_walk_gain(Q, R)
    # iterate P⁻ = P + Q, K = P⁻/(P⁻ + R), P = (1 − K) P⁻
    P = 1.0
    for _ in range(200000):
        Pm = P + Q
        Kk = Pm / (Pm + R)
        P_new = (1 - Kk) * Pm
        if abs(P_new - P) <= 1e-15 * max(P, 1e-300):
            break
        P = P_new
    np.testing.assert_allclose(K, Kk, rtol=1e-9)
    ss = discrete_steady_state([[1.0]], [[1.0]], [[1.0]], Q, R)
    np.testing.assert_allclose(K, ss.K_filter[0, 0], rtol=1e-8)
    # depends on Q/R only
    for c in (1e-3, 7.0, 1e4):
        np.testing.assert_allclose(random_walk_gain(c * Q, c * R), K, rtol=1e-12)


def test_random_walk_gain_edge_and_errors():
    assert random_walk_gain(0.0, 1.0) == 0.0
    np.testing.assert_allclose(random_walk_gain(1.0, 1.0), (np.sqrt(5) - 1) / 2, rtol=1e-14)
    np.testing.assert_allclose(random_walk_gain(np.array([1.0, 2.0]), 1.0).shape, (2,))
    with pytest.raises(ValueError, match="R must be > 0"):
        random_walk_gain(1.0, 0.0)
    with pytest.raises(ValueError, match="Q must be >= 0"):
        random_walk_gain(-1.0, 1.0)


# --------------------------------------------------------------------------- ranks and errors


def test_ranks_and_observability_matrix_order():
    A = osc(26.149)
    np.testing.assert_allclose(observability_matrix(A, C2), np.vstack([C2, C2 @ A]))
    assert observability_rank(A, C2) == 2
    assert controllability_rank(A, G2) == 2
    assert check_observable(A, C2) == 2
    assert check_controllable(A, G2) == 2
    with pytest.raises(ValueError, match=r"\(A, C\) must be observable: rank .* = 1 < n = 2"):
        check_observable(osc(0.0), [[0.0, 1.0]])
    with pytest.raises(ValueError, match=r"\(A, B\) must be controllable"):
        check_controllable(osc(0.0), [[1.0], [0.0]])


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(R=-1.0), r"R must be > 0, got -1"),
        (dict(R=0.0), r"R must be > 0, got 0"),
        (dict(Q=-1.0), r"Q must be >= 0, got -1"),
        (dict(Q=np.nan), r"Q must be finite"),
        (dict(A=[[0.0, 1.0], [np.nan, 0.0]]), r"A must be finite"),
        (dict(C=[[1.0, 0.0, 0.0]]), r"C must have 2 columns"),
        (dict(G=[[0.0], [1.0], [2.0]]), r"G must have 2 rows"),
        (dict(A=[[0.0, 1.0, 2.0], [1.0, 0.0, 0.0]]), r"A must be square"),
        (dict(Q=np.eye(2)), r"Q must have shape \(1, 1\)"),
        (dict(A=[[0.0, 1.0], [0.0, 0.0]], C=[[0.0, 1.0]]), r"\(A, C\) must be detectable.*unobservable"),
    ],
)
def test_continuous_bad_input_names_argument(kwargs, match):
    args = dict(A=osc(26.149), C=C2, G=G2, Q=100.0, R=50.0) | kwargs
    with pytest.raises(ValueError, match=match):
        continuous_steady_state(args["A"], args["C"], args["G"], args["Q"], args["R"])


def test_observable_requirement_and_discrete_errors():
    # stable unobservable mode: detectable (accepted) but not observable (rejected on request)
    A = np.array([[-1.0, 0.0], [0.0, -2.0]])
    C = np.array([[1.0, 0.0]])
    continuous_steady_state(A, C, np.eye(2), np.eye(2), 1.0)
    with pytest.raises(ValueError, match=r"\(A, C\) must be observable"):
        continuous_steady_state(A, C, np.eye(2), np.eye(2), 1.0, require="observable")
    with pytest.raises(ValueError, match="require must be one of"):
        continuous_steady_state(A, C, np.eye(2), np.eye(2), 1.0, require="maybe")
    F, Gd = dwna(0.1)
    with pytest.raises(ValueError, match=r"\(F, H\) must be detectable.* of F are unobservable from H"):
        discrete_steady_state(F, [[0.0, 1.0]], Gd, 1.0, 1.0)  # errors use the caller's names
    with pytest.raises(ValueError, match=r"H must have 2 columns \(the order of F\)"):
        discrete_steady_state(F, [[1.0, 0.0, 0.0]], Gd, 1.0, 1.0)
    with pytest.raises(ValueError, match=r"\(F, H\) must be observable"):
        discrete_steady_state(F, [[0.0, 1.0]], Gd, 1.0, 1.0, require="observable")
    with pytest.raises(ValueError, match=r"max_iter must be >= 1, got 0"):
        discrete_steady_state_batch(F[None], C2, np.eye(2), 1.0, max_iter=0)
    with pytest.raises(ValueError, match=r"tol must be finite"):
        discrete_steady_state_batch(F[None], C2, np.eye(2), 1.0, tol=float("nan"))
    with pytest.raises(ValueError, match="R must be > 0"):
        discrete_steady_state(F, C2, Gd, 1.0, -2.0)
    with pytest.raises(ValueError, match="R must be > 0"):
        discrete_steady_state_batch(F[None], C2, np.eye(2), -1.0)
    with pytest.raises(ValueError, match=r"F must have shape \(B, n, n\)"):
        discrete_steady_state_batch(F, C2, np.eye(2), 1.0)


def test_riccati_trajectory_bad_input():
    A = osc(1.0)
    t = np.linspace(0, 1, 5)
    with pytest.raises(ValueError, match="P0 must be symmetric"):
        riccati_trajectory(A, C2, G2, 1.0, 1.0, [[1.0, 2.0], [0.0, 1.0]], t)
    with pytest.raises(ValueError, match="P0 must be positive semidefinite"):
        riccati_trajectory(A, C2, G2, 1.0, 1.0, -np.eye(2), t)
    with pytest.raises(ValueError, match="t must be strictly increasing"):
        riccati_trajectory(A, C2, G2, 1.0, 1.0, np.eye(2), [0.0, 1.0, 0.5])
    with pytest.raises(ValueError, match="P0 must have shape"):
        riccati_trajectory(A, C2, G2, 1.0, 1.0, np.eye(3), t)
    with pytest.raises(ValueError, match="R must be > 0"):
        riccati_trajectory(A, C2, G2, 1.0, -1.0, np.eye(2), t)


# ------------------------------------------------------------------ compiled kernels of the filter blocks
def _rows(fn, p, x, u, n_out):
    out = np.empty((x.shape[0], n_out))
    for b in range(x.shape[0]):
        fn(0.0, x[b], u[b], p, out[b])
    return out


def _kf_state(rng, B, n):
    A = rng.standard_normal((B, n, n))
    P = A @ A.transpose(0, 2, 1) + 0.1 * np.eye(n)  # covariances
    return np.concatenate([rng.standard_normal((B, n)), P.reshape(B, -1)], axis=1)


@pytest.mark.parametrize("compiled", [False, True])
@pytest.mark.parametrize("with_b", [False, True])
def test_kalman_kernel_equals_the_block_methods_bit_for_bit(compiled, with_b):
    from ctrl_analysis.engine.codegen import _jit
    from ctrl_analysis.estimators.kalman.filter import (
        DiscreteKalmanFilter,
        kalman_output,
        kalman_update,
    )

    rng = np.random.default_rng(11)
    n, B = 3, 7
    F = np.eye(n) + 0.1 * rng.standard_normal((n, n))
    G = rng.standard_normal((n, n))
    kf = DiscreteKalmanFilter(F, rng.standard_normal(n), G @ G.T, 0.3, b=rng.standard_normal(n) if with_b else None)
    x, u = _kf_state(rng, B, n), rng.standard_normal((B, len(kf.inputs)))
    k = kf.kernel()
    out_fn, upd_fn = (_jit(kalman_output), _jit(kalman_update)) if compiled else (kalman_output, kalman_update)
    assert np.array_equal(_rows(out_fn, k.params, x, u, n), kf.output(0.0, x, u))
    assert np.array_equal(_rows(upd_fn, k.params, x, u, n + n * n), kf.update(0.0, x, u))
    # the corrector layout (no state; inputs = [state, y]) gives the same estimate
    xu = np.concatenate([x, u[:, :1]], axis=1)
    assert np.array_equal(_rows(out_fn, k.params, np.empty((B, 0)), xu, n), kf.output(0.0, x, u))


@pytest.mark.parametrize("compiled", [False, True])
def test_alpha_beta_kernel_layouts_and_update(compiled):
    from ctrl_analysis.engine.codegen import _jit
    from ctrl_analysis.estimators.kalman.alpha_beta import (
        alpha_beta_output,
        alpha_beta_update,
    )

    rng = np.random.default_rng(12)
    F = [[1.0, 0.1], [0.2, 0.9]]
    for b in (None, [0.01, 0.3]):
        f = AlphaBetaFilter(0.6, 0.3, 0.1, F=F, b=b)
        x, u = rng.standard_normal((9, 2)), rng.standard_normal((9, len(f.inputs)))
        out_fn, upd_fn = (_jit(alpha_beta_output), _jit(alpha_beta_update)) if compiled else (alpha_beta_output,
                                                                                              alpha_beta_update)
        k = f.kernel()
        xf = _rows(out_fn, k.params, x, u, 2)
        assert np.array_equal(xf, f.output(0.0, x, u))  # numpy method = the kernel on columns
        np.testing.assert_allclose(xf, x + (u[:, :1] - x[:, :1]) * f.K, rtol=0, atol=1e-15)
        xn = _rows(upd_fn, k.params, x, u, 2)
        assert np.array_equal(xn, f.update(0.0, x, u))
        expect = xf @ np.asarray(F).T + (0.0 if b is None else u[:, 1:2] * np.asarray(b))
        np.testing.assert_allclose(xn, expect, rtol=0, atol=1e-14)
        xu = np.concatenate([x, u[:, :1]], axis=1)  # the corrector layout
        assert np.array_equal(_rows(out_fn, k.params, np.empty((9, 0)), xu, 2), xf)
