"""Unstable designs are rejected consistently across blocks, each with a named opt-out; blocks keep
their state when a bad sample is rejected."""

import numpy as np
import pytest

from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.estimators.eso import ExtendedStateObserver
from ctrl_analysis.estimators.kalman import AlphaBetaFilter
from ctrl_analysis.identification import RecursiveLeastSquares
from ctrl_analysis.symbolic.differential import MAX_ORDER

# s^3 + s^2 + s + 10: positive gains, but not Hurwitz (Routh: 1·1 < 10)
NON_HURWITZ = [1.0, 1.0, 10.0]


def test_eso_rejects_non_hurwitz_gains_unless_allowed():
    with pytest.raises(ValueError, match=r"gains must make the error dynamics .* Hurwitz"):
        ExtendedStateObserver(NON_HURWITZ)
    obs = ExtendedStateObserver(NON_HURWITZ, allow_unstable=True)
    assert np.max(obs.poles.real) > 0  # the opt-out builds the unstable design as given


def test_fal_eso_is_checked_in_its_linear_zone():
    # fal(e) = e / δ^(1-α) for |e| <= δ: gains Hurwitz as given, but not once scaled by δ^(α-1)
    gains, alpha, delta = [3.0, 3.0, 1.0], [1.0, 0.5, 0.0], 0.01  # linear zone: s^3 + 3s^2 + 30s + 100
    ExtendedStateObserver(gains)  # the linear ESO with these gains is fine
    with pytest.raises(ValueError, match="linear zone of fal"):
        ExtendedStateObserver(gains, alpha=alpha, delta=delta)
    ExtendedStateObserver(gains, alpha=alpha, delta=delta, allow_unstable=True)


def test_differential_estimator_rejects_an_explicit_unstable_gain_unless_allowed():
    with pytest.raises(ValueError, match=r"K = 1 makes Σ unstable .* allow_unstable=True"):
        DifferentialEstimator(5, 2.0, K=1.0)
    est = DifferentialEstimator(5, 2.0, K=1.0, allow_unstable=True)
    assert est.poles[0].real > 0
    assert DifferentialEstimator(5, 2.0, K=100.0).poles[0].real < 0


def test_alpha_beta_filter_has_the_same_rule_under_its_own_keyword():
    with pytest.raises(ValueError, match="stable filter"):
        AlphaBetaFilter(1.5, 3.0, 0.1)
    assert np.max(np.abs(AlphaBetaFilter(1.5, 3.0, 0.1, require_stable=False).poles)) >= 1


def test_differential_estimator_order_has_a_documented_maximum():
    DifferentialEstimator(MAX_ORDER, 1.0)
    with pytest.raises(ValueError, match=f"n0 must be <= {MAX_ORDER}, got 400"):
        DifferentialEstimator(400, 1.0)


@pytest.mark.parametrize("h,z,name", [([np.nan, 1.0], 1.0, "h"), ([1.0, 2.0], np.inf, "z"),
                                      ([1.0, 2.0], np.nan, "z")])
def test_rls_rejects_non_finite_data_and_keeps_its_estimate(h, z, name):
    rls = RecursiveLeastSquares(2, P0=100.0)
    rls.step([1.0, 2.0], 5.0)
    theta, P = rls.theta.copy(), rls.P.copy()
    with pytest.raises(ValueError, match=f"{name} must be finite"):
        rls.step(h, z)
    np.testing.assert_array_equal(rls.theta, theta)
    np.testing.assert_array_equal(rls.P, P)
    rls.step([2.0, 1.0], 4.0)
    assert np.all(np.isfinite(rls.theta))
