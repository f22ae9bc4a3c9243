"""The arena's start: every causal family at rest on the first sample, and the start-up window scored apart."""

import numpy as np
import pytest

from ctrl_analysis.arena.algebraic import algebraic_derivative
from ctrl_analysis.arena.interface import FAMILIES, INITS, estimate
from ctrl_analysis.arena.tuning import METRICS, Case, Setup, case_records, evaluate, param_values

DT = 0.01
SETUP = Setup(dt=DT, n=300, transient=1.0)
CASE = Case("sines", "uniform", 0.01, 2.0, (5, 6))


def _params(fam, runs=2):
    return param_values(fam, np.zeros((runs, len(fam.params))), CASE, SETUP)


@pytest.mark.parametrize("fam", FAMILIES, ids=lambda f: f.name)
def test_a_constant_record_leaves_a_family_started_on_it_at_rest(fam):
    # the state a constant record holds: f̂ = c and every derivative 0 at every sample; from the zero state it is not
    y = np.full((200, 2), 3.7)
    at_rest = estimate(fam, _params(fam), y, DT)
    np.testing.assert_allclose(at_rest[:, :, 0], 3.7, rtol=1e-12)
    np.testing.assert_allclose(at_rest[:, :, 1:], 0.0, atol=1e-9)
    zero = estimate(fam, _params(fam), y, DT, init="zero")
    assert np.max(np.abs(zero[:, :, 0] - 3.7)) > 1.0


@pytest.mark.parametrize("fam", FAMILIES, ids=lambda f: f.name)
def test_every_family_starts_with_a_zero_derivative_on_any_record(fam):
    # at sample 0 nothing but y_0 is known: a family at rest there estimates f' = 0, whatever the record
    _, y, _ = case_records(CASE, SETUP)
    est = estimate(fam, _params(fam), y, DT)
    np.testing.assert_allclose(est[0, :, 1], 0.0, atol=1e-9)
    assert np.all(est[0, :, 0] == pytest.approx(y[0], rel=1e-12))


def test_the_fir_window_sees_the_first_sample_or_zeros_before_the_record():
    y = np.full((30, 1), 2.0)
    first = algebraic_derivative(y, [5], [1], DT)
    zero = algebraic_derivative(y, [5], [1], DT, before="zero")
    np.testing.assert_allclose(first[:, 0, 1], 0.0, atol=1e-9)
    # from zeros, the ramp-up of a 5-sample least-squares line: slope 2/(5 dt) ... then 0 once the window is full
    assert zero[0, 0, 1] == pytest.approx(np.polyfit(np.arange(5) * DT, [0, 0, 0, 0, 2.0], 1)[0], rel=1e-9)
    np.testing.assert_allclose(zero[4:, 0, 1], 0.0, atol=1e-9)
    with pytest.raises(ValueError, match="before"):
        algebraic_derivative(y, [5], [1], DT, before="last")


def test_the_startup_column_is_the_worst_error_before_the_scoring_window():
    fam = FAMILIES[2]  # leso2
    row = _params(fam, 1)[0]
    d1, y, _ = case_records(CASE, SETUP)
    for setup in (SETUP, Setup(dt=DT, n=300, transient=1.0, init="zero")):
        m = evaluate((fam.name, setup, (CASE,), [(0, row)], "numpy"))
        est = estimate(fam, np.tile(row, (2, 1)), y, DT, init=setup.init)[:, :, 1]
        k = setup.k_from
        assert m[0, METRICS.index("startup")] == pytest.approx(np.max(np.abs(est[:k] - d1[:k])), rel=1e-12)
        assert m[0, METRICS.index("worst")] == pytest.approx(np.max(np.abs(est[k:] - d1[k:])), rel=1e-12)
    none = evaluate((fam.name, Setup(dt=DT, n=300, transient=0.0), (CASE,), [(0, row)], "numpy"))
    assert none[0, METRICS.index("startup")] == 0.0  # no start-up window, nothing scored there


def test_init_is_checked_where_it_is_given():
    assert INITS == ("first", "zero")
    with pytest.raises(ValueError, match="init"):
        Setup(dt=DT, n=300, transient=1.0, init="rest")
    with pytest.raises(ValueError, match="init"):
        estimate("leso2", [[5.0]], np.zeros((10, 1)), DT, init=0)
