"""Tests of batch least squares with identifiability checks and recursive least squares."""

import warnings

import numpy as np
import pytest

from ctrl_analysis.identification import (
    IdentifiabilityWarning,
    RecursiveLeastSquares,
    batch_least_squares,
    identifiability,
)


def _data(N=400, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 6, N)
    H = np.column_stack([np.sin(t), np.cos(t), rng.normal(size=N), np.ones(N)])
    theta = np.array([1.3, -1.6, 0.95, 1.8])
    return H, H @ theta + noise * rng.normal(size=N), theta


def test_ls_recovers_parameters():
    H, z, theta = _data()
    res = batch_least_squares(H, z)
    np.testing.assert_allclose(res.theta, theta, rtol=1e-10)
    assert res.report.rank == 4 and res.report.full_rank and res.report.well_conditioned
    assert res.residual_rms < 1e-10
    H, z, theta = _data(N=4000, noise=0.01, seed=1)
    np.testing.assert_allclose(batch_least_squares(H, z).theta, theta, atol=5e-3)


def test_collinear_regressor_rejected_or_warned():
    H, z, _ = _data()
    Hc = H.copy()
    Hc[:, 2] = 2 * Hc[:, 0] - Hc[:, 3]  # exactly collinear
    rep = identifiability(Hc)
    assert rep.rank == 3 and not rep.full_rank
    with pytest.raises(ValueError, match="rank-deficient"):
        batch_least_squares(Hc, z, strict=True)
    with pytest.warns(IdentifiabilityWarning, match="rank-deficient"):
        batch_least_squares(Hc, z)
    # nearly collinear: full rank but ill-conditioned
    Hn = H.copy()
    Hn[:, 2] = Hn[:, 0] + 1e-9 * np.random.default_rng(3).normal(size=len(H))
    rep = identifiability(Hn)
    assert rep.full_rank and rep.cond_scaled > 1e6 and not rep.well_conditioned
    with pytest.warns(IdentifiabilityWarning, match="ill-conditioned"):
        batch_least_squares(Hn, z)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        batch_least_squares(Hn, z, warn=False)


def test_condition_number_is_scale_invariant():
    H, _, _ = _data()
    rep1 = identifiability(H)
    rep2 = identifiability(H * np.array([1e4, 1.0, 1e-3, 1.0]))
    assert rep2.cond > 100 * rep1.cond
    np.testing.assert_allclose(rep2.cond_scaled, rep1.cond_scaled, rtol=1e-8)


def test_rls_converges_to_ls():
    H, z, theta = _data(N=300, noise=0.01, seed=2)
    rls = RecursiveLeastSquares(4, forgetting=1.0, P0=1e8)
    hist = rls.run(H, z)
    np.testing.assert_allclose(rls.theta, batch_least_squares(H, z).theta, atol=1e-5)
    np.testing.assert_allclose(hist[-1], theta, atol=0.02)


def test_rls_forgetting_tracks_jump_and_batch():
    rng = np.random.default_rng(4)
    N = 600
    H = np.column_stack([rng.normal(size=N), np.ones(N)])
    th = np.where(np.arange(N)[:, None] < 300, [2.0, 1.0], [2.0, -1.0])
    z = np.sum(H * th, axis=1)
    slow = RecursiveLeastSquares(2, forgetting=1.0).run(H, z)
    fast = RecursiveLeastSquares(2, forgetting=0.95).run(H, z)
    assert abs(fast[-1, 1] + 1.0) < 1e-6  # forgetting: follows the jump
    assert abs(slow[-1, 1] + 1.0) > 0.3  # no forgetting: averages both halves
    # batch of two independent runs equals the two single runs
    Hb = np.stack([H, H[::-1]], axis=1)
    zb = np.stack([z, z[::-1]], axis=1)
    rb = RecursiveLeastSquares(2, forgetting=0.95, batch=2).run(Hb, zb)
    np.testing.assert_allclose(rb[:, 0], fast, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(n_params=0), "n_params"),
        (dict(n_params=2, forgetting=0.0), "forgetting"),
        (dict(n_params=2, forgetting=1.1), "forgetting"),
        (dict(n_params=2, P0=-1.0), "P0"),
        (dict(n_params=2, P0=np.eye(3)), "P0"),
        (dict(n_params=2, theta0=[1.0]), "theta0"),
    ],
)
def test_rls_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        RecursiveLeastSquares(**kwargs)


def test_ls_bad_input():
    H, z, _ = _data()
    with pytest.raises(ValueError, match="z must have shape"):
        batch_least_squares(H, z[:-1])
    with pytest.raises(ValueError, match="H must be"):
        batch_least_squares(z, z)
    with pytest.raises(ValueError, match="finite"):
        batch_least_squares(H, np.full(len(z), np.nan))
    with pytest.raises(ValueError, match="h must have shape"):
        RecursiveLeastSquares(3).step(np.ones(2), 1.0)
