"""Tests of the sympy derivations for the linear ESO (ctrl_analysis.symbolic.eso)."""

from math import comb

import numpy as np
import pytest
import sympy as sp

from ctrl_analysis.estimators.eso import ExtendedStateObserver
from ctrl_analysis.symbolic.eso import (
    EPS,
    S,
    bandwidth_match,
    bandwidth_polynomial,
    beta_symbols,
    characteristic_coefficients,
    characteristic_polynomial,
    error_dc_gains,
    error_scaling_exponents,
    error_transfer_functions,
)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_characteristic_polynomial_form(n):
    betas = beta_symbols(n)
    expected = S ** (n + 1) + sum(b / EPS**i * S ** (n + 1 - i) for i, b in enumerate(betas, start=1))
    assert sp.simplify(characteristic_polynomial(n) - expected) == 0


@pytest.mark.parametrize("n,beta", [(1, (2.0, 1.0)), (2, (3.0, 3.0, 1.0)), (3, (4.0, 6.0, 4.0, 1.0))])
def test_numeric_coefficients_match_observer(n, beta):
    eps = 0.05
    num = characteristic_coefficients(n)(eps, beta)
    obs = ExtendedStateObserver.from_epsilon(n, eps, beta)
    np.testing.assert_allclose(num, obs.characteristic_polynomial(), rtol=1e-12)
    np.testing.assert_allclose(num, np.poly(obs.ss.A), rtol=1e-9)


def test_beta_331_is_bandwidth_20():
    m = bandwidth_match((3, 3, 1), epsilon=0.05)
    assert m.is_bandwidth and m.c == 1 and m.omega_o == 20
    # symbolically (s + 1/eps)^3 equals the characteristic polynomial with beta = (3, 3, 1)
    p = characteristic_polynomial(2).subs(dict(zip(beta_symbols(2), (3, 3, 1), strict=True)))
    assert sp.simplify(p - sp.expand((S + 1 / EPS) ** 3)) == 0
    assert sp.expand(bandwidth_polynomial(2, 20) - (S**3 + 60 * S**2 + 1200 * S + 8000)) == 0


def test_bandwidth_match_other_cases():
    assert not bandwidth_match((3, 3, 2)).is_bandwidth
    m = bandwidth_match((6, 12, 8), epsilon=0.1)  # c = 2
    assert m.is_bandwidth and m.c == 2 and m.omega_o == 20
    assert bandwidth_match((2, 1)).omega_o == 1 / EPS
    with pytest.raises(ValueError, match="beta"):
        bandwidth_match((1,))
    with pytest.raises(ValueError, match="epsilon"):
        bandwidth_match((3, 3, 1), epsilon=0.0)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_error_tfs_match_python_control(n):
    L = [comb(n + 1, i) * 5.0**i for i in range(1, n + 2)]
    obs = ExtendedStateObserver(L)
    sym = error_transfer_functions(n)
    Ls = sp.symbols(f"L1:{n + 2}", positive=True)
    for g_sym, g_num in zip(sym, obs.disturbance_error_tf(), strict=True):
        f = sp.lambdify(S, g_sym.subs(dict(zip(Ls, L, strict=True))))
        for w in (0.3, 2.0, 40.0):
            np.testing.assert_allclose(complex(f(1j * w)), complex(g_num(1j * w)), rtol=1e-10)


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_error_scaling_law(n):
    assert error_scaling_exponents(n) == tuple(n + 2 - i for i in range(1, n + 2))
    betas = beta_symbols(n)
    gains = error_dc_gains(n)
    assert sp.simplify(gains[0] - EPS ** (n + 1) / betas[-1]) == 0
    for i in range(2, n + 2):
        assert sp.simplify(gains[i - 1] - betas[i - 2] / betas[-1] * EPS ** (n + 2 - i)) == 0
