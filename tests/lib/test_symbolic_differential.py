"""Tests for ctrl_analysis.symbolic.differential: breakaway point, gain and coefficients of Σ."""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest
import sympy as sp

from ctrl_analysis.symbolic import differential as sym

N0_VALUES = list(range(2, 9))
A_VALUES = [0.5, 2.0, 7.3]


def test_derivation_general_n0_a():
    d = sym.derive_breakaway()
    assert sp.simplify(d.breakaway + sym.A * sym.N0) == 0
    assert sp.simplify(d.dK_ds_reduced + sym.S + sym.N0 * sym.A) == 0
    assert d.critical_points == (0, d.breakaway)
    closed_form = sym.A * sym.N0**sym.N0 / (sym.N0 - 1) ** (sym.N0 - 1)
    assert sp.simplify(sp.powsimp(d.gain / closed_form, force=True)) == 1
    # the gain carries a^1 (units 1/s, like a)
    assert sp.simplify(d.gain.diff(sym.A) * sym.A - d.gain) == 0


@pytest.mark.parametrize("n0", N0_VALUES)
def test_derivation_matches_concrete_solution(n0):
    """For each concrete n0, solve dK/ds = 0 from scratch and compare with the general result."""
    d = sym.derive_breakaway()
    s, a = sym.S, sym.A
    k_s = -(s**n0) / (s + a) ** (n0 - 1)
    numerator = sp.numer(sp.together(sp.diff(k_s, s)))
    roots = sp.roots(sp.Poly(numerator, s))
    assert roots == {0: n0 - 1, -n0 * a: 1}
    gain_here = sp.simplify(k_s.subs(s, -n0 * a))
    assert sp.simplify(gain_here - d.gain.subs(sym.N0, n0)) == 0
    assert sp.simplify(d.second_derivative.subs(sym.N0, n0) - sp.diff(k_s, s, 2).subs(s, -n0 * a)) == 0
    assert d.second_derivative.subs({sym.N0: n0, sym.A: 1}) > 0  # double, not triple, pole


@pytest.mark.parametrize("a", A_VALUES)
@pytest.mark.parametrize("n0", N0_VALUES)
def test_numeric_functions_vs_python_control(n0, a):
    s_b = sym.breakaway_point(n0, a)
    k_b = sym.breakaway_gain(n0, a)
    assert s_b == pytest.approx(-n0 * a, rel=1e-14)
    assert k_b == pytest.approx(n0**n0 * a / (n0 - 1) ** (n0 - 1), rel=1e-13)
    assert sym.locus_gain(s_b, n0, a) == pytest.approx(k_b, rel=1e-12)

    # dK/ds = 0 at s_b, numerically: K(s) = -D(s)/N(s), D = s^n0, N = (s + a)^(n0-1)
    num = np.poly(-a * np.ones(n0 - 1))
    den = np.zeros(n0 + 1)
    den[0] = 1.0
    dk = -(np.polyval(np.polyder(den), s_b) * np.polyval(num, s_b)
           - np.polyval(den, s_b) * np.polyval(np.polyder(num), s_b)) / np.polyval(num, s_b) ** 2
    scale = abs(k_b / s_b)  # natural size of dK/ds
    assert abs(dk) < 1e-10 * scale

    # python-control: feedback(K G, 1) has a double pole at s_b
    g_unit = ct.tf(num, den)
    poles = ct.feedback(k_b * g_unit, 1).poles()
    dist = np.sort(np.abs(poles - s_b))
    assert dist[1] < 1e-5 * abs(s_b), poles  # two poles at s_b (a double root splits ~ sqrt(eps))
    if n0 > 2:
        assert dist[2] > 1e-2 * abs(s_b), poles  # and only two
    assert np.all(poles.real < 0)


@pytest.mark.parametrize("n0", N0_VALUES)
def test_coefficients_closed_form_vs_expansion(n0):
    a_val, k_val = 3.0, 1.7
    expected = k_val * np.poly(-a_val * np.ones(n0 - 1))  # (4) K (s + a)^(n0-1)
    np.testing.assert_allclose(sym.differential_coefficients(n0, a_val, k_val), expected, rtol=1e-13)
    symbolic = sym.coefficients_from_zeros([-sym.A] * (n0 - 1))
    formula = sym.coefficient_formula()
    for i, c in enumerate(symbolic, start=1):
        assert sp.simplify(c - formula.subs({sym.N0: n0, sym.I: i})) == 0


@pytest.mark.parametrize("n0", N0_VALUES)
def test_vieta_sign_pattern(n0):
    zs = sp.symbols(f"z1:{n0}")
    coeffs = sym.coefficients_from_zeros(zs)
    assert len(coeffs) == n0
    assert coeffs[0] == sym.KGAIN
    assert sp.expand(coeffs[-1] - (-1) ** (n0 - 1) * sym.KGAIN * sp.prod(zs)) == 0
    if n0 >= 3:
        assert sp.expand(coeffs[1] + sym.KGAIN * sum(zs)) == 0


def test_large_n0_does_not_overflow():
    assert sym.breakaway_gain(20, 1.0) == pytest.approx(20**20 / 19**19, rel=1e-12)
    assert math.isfinite(sym.breakaway_gain(sym.MAX_ORDER, 1.0))
    # beyond the documented maximum order a clear error, not an OverflowError from generated code
    with pytest.raises(ValueError, match=f"n0 must be <= {sym.MAX_ORDER}, got 400"):
        sym.breakaway_gain(400, 1.0)


@pytest.mark.parametrize(
    "func, args, exc, name",
    [
        (sym.breakaway_gain, (1, 2.0), ValueError, "n0"),
        (sym.breakaway_gain, (2.5, 2.0), TypeError, "n0"),
        (sym.breakaway_point, ("5", 2.0), TypeError, "n0"),
        (sym.breakaway_gain, (5, 0.0), ValueError, "a"),
        (sym.breakaway_point, (5, -1.0), ValueError, "a"),
        (sym.breakaway_gain, (5, float("nan")), ValueError, "a"),
        (sym.breakaway_gain, (5, float("inf")), ValueError, "a"),
        (sym.differential_coefficients, (5, 2.0, 0.0), ValueError, "K"),
        (sym.differential_coefficients, (5, 2.0, -3.0), ValueError, "K"),
        (sym.coefficients_from_zeros, ([],), ValueError, "zeros"),
    ],
)
def test_bad_input_names_the_argument(func, args, exc, name):
    with pytest.raises(exc, match=rf"^{name} "):
        func(*args)


def test_n0_must_be_at_least_two_message():
    with pytest.raises(ValueError, match=r"n0 must be >= 2, got 1"):
        sym.breakaway_gain(1, 2.0)
