"""Tests of ctrl_analysis.symbolic.riccati against the numeric Riccati solvers."""

import numpy as np
import pytest
import sympy as sp

from ctrl_analysis.estimators.kalman import (
    continuous_steady_state,
    discrete_steady_state,
    kalata_gains,
    random_walk_gain,
)
from ctrl_analysis.symbolic.riccati import (
    A21,
    LAMBDA,
    QR,
    derive_kalata_gains,
    derive_random_walk_gain,
    derive_second_order_gain,
    kalata_gains_closed_form,
    random_walk_gain_closed_form,
    second_order_gain,
)

C2 = np.array([[1.0, 0.0]])
G2 = np.array([[0.0], [1.0]])


@pytest.mark.parametrize("a21, Q, R", [(26.14934, 100.0, 50.0), (2.6149, 100.0, 50.0), (0.0, 2.0, 1.0),
                                       (-3.0, 0.5, 2.0), (10.0, 1e-3, 1.0), (0.5, 1e3, 0.1)])
def test_closed_form_gain_matches_numeric_are(a21, Q, R):
    A = np.array([[0.0, 1.0], [a21, 0.0]])
    ss = continuous_steady_state(A, C2, G2, Q, R)
    np.testing.assert_allclose(second_order_gain(a21, Q / R), ss.K.ravel(), rtol=1e-9)
    d = derive_second_order_gain()
    np.testing.assert_allclose(d.numeric_P(a21, Q / R, R), ss.P, rtol=1e-8)
    # the unsimplified sympy root gives the same P
    np.testing.assert_allclose(np.array(d.numeric_P.derived(a21, Q / R), dtype=float) * R,
                               [ss.P[0, 0], ss.P[0, 1], ss.P[1, 1]], rtol=1e-8)


def test_closed_form_structure():
    d = derive_second_order_gain()
    # the chosen root satisfies the three scalar ARE equations identically
    subs = dict(zip(sp.symbols("p11 p12 p22", real=True), [d.p[0, 0], d.p[0, 1], d.p[1, 1]], strict=True))
    for eq in d.equations:
        val = eq.subs(subs)
        for a, q in [(26.1, 2.0), (-1.0, 0.3), (0.0, 5.0)]:
            assert abs(complex(val.subs({A21: a, QR: q}))) < 1e-9
    # simplified forms equal the derived ones; k1² = 2 k2
    assert sp.simplify(d.k2 - d.k2_simple) == 0
    assert sp.simplify(d.k1**2 - d.k1_simple**2) == 0
    assert sp.simplify(d.k1_simple**2 - 2 * d.k2_simple) == 0
    assert len(d.solutions) == 4  # two signs each for p12 and p11


def test_closed_form_vectorised_and_errors():
    K = second_order_gain(np.array([0.0, 1.0, 26.0]), 2.0)
    assert K.shape == (3, 2)
    with pytest.raises(ValueError, match="q must be > 0"):
        second_order_gain(1.0, 0.0)
    with pytest.raises(ValueError, match="a21 must be finite"):
        second_order_gain(np.nan, 1.0)


def test_random_walk_depends_on_ratio_only():
    d = derive_random_walk_gain()
    assert d.K_of_q.free_symbols == {QR}
    assert d.R not in d.K_of_q.free_symbols
    assert sp.simplify(d.K_of_q - d.K_canonical) == 0
    # the fixed-point equation P⁻² − Q P⁻ − Q R = 0 holds at the chosen root
    Pm = list(d.fixed_point_equation.free_symbols - {d.Q, d.R})[0]
    assert sp.simplify(d.fixed_point_equation.subs(Pm, d.P_prior)) == 0


@pytest.mark.parametrize("Q, R", [(1.0, 1.0), (0.02, 4.0), (30.0, 0.5)])
def test_random_walk_closed_form_vs_numeric(Q, R):
    k = random_walk_gain_closed_form(Q / R)
    np.testing.assert_allclose(k, random_walk_gain(Q, R), rtol=1e-12)
    ss = discrete_steady_state([[1.0]], [[1.0]], [[1.0]], Q, R)
    np.testing.assert_allclose(k, ss.K_filter[0, 0], rtol=1e-8)
    # scaling Q and R together leaves K∞ unchanged
    np.testing.assert_allclose(random_walk_gain(10 * Q, 10 * R), k, rtol=1e-12)
    with pytest.raises(ValueError, match="q must be >= 0"):
        random_walk_gain_closed_form(-1.0)


@pytest.mark.parametrize("Lam", [1e-4, 0.05, 1.0, 3.86, 40.0])
def test_kalata_closed_form_vs_dare(Lam):
    a, b = kalata_gains_closed_form(Lam)
    np.testing.assert_allclose((a, b), kalata_gains(Lam), rtol=1e-12)
    # the discrete Riccati solution of the DWNA model with T = 1, σ_v = 1, σ_w = Λ
    F = np.array([[1.0, 1.0], [0.0, 1.0]])
    g = np.array([[0.5], [1.0]])
    ss = discrete_steady_state(F, [[1.0, 0.0]], g, Lam**2, 1.0)
    np.testing.assert_allclose((a, b), ss.K_filter.ravel(), rtol=1e-7)
    d = derive_kalata_gains()
    np.testing.assert_allclose(complex(d.alpha.subs(LAMBDA, Lam)).real, a, rtol=1e-9)
    np.testing.assert_allclose(complex(d.beta.subs(LAMBDA, Lam)).real, b, rtol=1e-9)
