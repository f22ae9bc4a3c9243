"""Levant's robust exact differentiator: exact without noise up to its Euler step, √(εL) with noise, its engines."""

import numpy as np
import pytest

from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.levant import LEVANT_GAINS, MAX_ORDER, LevantDifferentiator


def _sup_error(order, L, h, f, d, T=8.0, settle=3.0, noise=0.0, seed=0):
    """Largest |z_i - f^(i)| after ``settle`` s, i = 1 .. order, on ``f`` sampled every ``h`` (plus uniform noise)."""
    t = h * np.arange(round(T / h))
    y = f(t) + noise * np.random.default_rng(seed).uniform(-1, 1, t.size)
    z, _ = LevantDifferentiator(order, L=L, h=h).run(y)
    k = t >= settle
    # the output at sample k is the state after the inputs up to k - 1: it estimates the derivatives at t_k
    return [float(np.max(np.abs(z[k, 0, i] - d[i - 1](t[k])))) for i in range(1, order + 1)]


def test_first_order_is_exact_up_to_the_euler_step():
    # f = sin t, |f''| <= 1 <= L: in finite time z_1 = f' exactly in continuous time; Euler's chattering is O(L h)
    errs = [_sup_error(1, 2.0, h, np.sin, [np.cos])[0] for h in (2e-3, 1e-3, 5e-4)]
    assert errs[-1] < 4 * 2.0 * 5e-4
    assert 1.5 < errs[0] / errs[1] < 2.6 and 1.5 < errs[1] / errs[2] < 2.6  # first order in h


def test_second_order_estimates_the_second_derivative():
    errs = _sup_error(2, 2.0, 5e-4, np.sin, [np.cos, lambda t: -np.sin(t)])  # |f'''| <= 1
    assert errs[0] < 2e-3 and errs[1] < 2e-2


def test_noise_error_scales_as_the_square_root_of_the_noise():
    # with noise of bound ε the first derivative errs by O(√(ε L)): 100x the noise, about 10x the error (6.7x
    # measured: the smaller noise's error still holds the Euler step's, about 0.003 here); a linear filter's
    # noise error would grow 100x
    small, large = (_sup_error(1, 2.0, 5e-4, np.sin, [np.cos], noise=e)[0] for e in (1e-4, 1e-2))
    assert 5.0 < large / small < 15.0
    assert large < np.sqrt(1e-2 * 2.0)


def test_compiled_equals_numpy_and_per_run_L():
    h = 1e-3
    t = h * np.arange(2000)
    y = np.column_stack([np.sin(t), np.cos(2 * t)])
    loop = Loop([place(LevantDifferentiator(1, L=2.0, h=h), "lev", inputs=["_f"])], h)
    out = {}
    for engine in ("compiled", "numpy"):
        res = loop.simulate(1999, inputs={"_f": y}, params={"lev": {"L": np.array([2.0, 5.0])}},
                            save=Save(states=False, keep=["z[1]"]), execution=Execution(engine=engine))
        out[engine] = res.signals["z[1]"]
    np.testing.assert_array_equal(out["compiled"], out["numpy"])
    alone, _ = LevantDifferentiator(1, L=5.0, h=h).run(y[:, 1])
    np.testing.assert_array_equal(out["numpy"][:2000, 1], alone[:, 0, 1])


@pytest.mark.parametrize("kw, match", [
    ({"order": 0}, "order"), ({"order": MAX_ORDER + 1}, "order"), ({"L": 0.0}, "L"), ({"h": -1.0}, "h"),
    ({"substeps": 0}, "substeps"), ({"gains": [1.0]}, "gains"), ({"gains": [1.1, -1.5]}, "gains"),
    ({"x0": [0.0]}, "x0"),
])
def test_bad_arguments_name_themselves(kw, match):
    args = {"order": 1, "L": 1.0, "h": 0.01, **kw}
    with pytest.raises(ValueError, match=match):
        LevantDifferentiator(**args)


def test_default_gains_are_levants():
    d = LevantDifferentiator(2, L=3.0, h=0.01)
    np.testing.assert_array_equal(d.gains, LEVANT_GAINS[:3])
    assert d.outputs == ("z[0]", "z[1]", "z[2]")
