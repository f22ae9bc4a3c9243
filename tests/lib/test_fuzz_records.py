"""Bad arguments that :class:`ctrl_analysis.reporting.results.Quantity` must refuse (issue 20, item 5).

What ``Quantity.__post_init__`` enforces (each error naming the argument, the value and the rule):

* ``std``: ``None``, or a finite number or array with every entry ``>= 0``
  (``check_nonnegative("std", std)``): a negative, NaN, infinite or non-numeric spread is nonsense;
* ``runs=0`` with a number as ``value``: zero healthy runs cannot give a value
  (``ValueError("runs is 0 (no run contributed), so value must be None, got 1.0")``);
* ``runs_diverged`` without ``runs``: the count of diverged runs means nothing without the total
  (``ValueError`` naming ``runs_diverged``).
"""

import math

import pytest

from ctrl_analysis.reporting.results import Quantity

VALID = dict(id="q", label="q", value=1.0, paper=1.0, tolerance=0.1, runs=3, unit="rad")


def test_valid_quantity_is_accepted():
    q = Quantity(**VALID, std=0.5)
    assert (q.runs, q.std, q.verdict) == (3, 0.5, "agrees")


@pytest.mark.parametrize("std", [-1.0, math.nan, math.inf, "abc", [0.1, -0.1]])
def test_std_must_be_finite_and_nonnegative(std):
    with pytest.raises((ValueError, TypeError), match="std"):
        Quantity(**VALID, std=std)


def test_zero_runs_cannot_carry_a_value():
    with pytest.raises(ValueError, match="runs"):
        Quantity(**dict(VALID, runs=0))


def test_runs_diverged_needs_runs():
    with pytest.raises(ValueError, match="runs_diverged"):
        Quantity(**dict(VALID, runs=None), runs_diverged=2)
