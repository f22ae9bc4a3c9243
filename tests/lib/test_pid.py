"""DiscretePID: the recipe's kernel-first block, against python-control, a hand computation and both engines."""

from __future__ import annotations

import control as ct
import numpy as np
import pytest

from ctrl_analysis.controllers.pid import DiscretePID
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.loop import Loop, place

T = 0.05


def _error(n=80):
    k = np.arange(n)
    return np.sin(0.3 * k) + 0.5 * (k > 20)


def test_unsaturated_pid_equals_its_transfer_function_in_python_control():
    pid = DiscretePID(kp=1.5, ki=2.0, kd=0.1, T=T, Tf=0.02)
    e = _error()
    y, _ = pid.run(e)
    ref = ct.forced_response(pid.tf(), T=T * np.arange(e.size), U=e)
    assert np.allclose(y[:, 0, 0], ref.outputs, rtol=1e-12, atol=1e-12)


def test_plain_difference_when_tf_is_zero_and_nlsys_matches():
    pid = DiscretePID(kp=0.0, ki=0.0, kd=0.3, T=T)
    e = _error(10)
    y, _ = pid.run(e)
    assert np.allclose(y[:, 0, 0], 0.3 * np.diff(e, prepend=0.0) / T, rtol=1e-13)
    r = ct.input_output_response(pid.nlsys(T), T * np.arange(e.size), e)
    assert np.allclose(r.outputs, y[:, 0, 0], rtol=0, atol=1e-13)


def test_saturation_freezes_the_integral():
    pid = DiscretePID(kp=1.0, ki=10.0, T=T, u_min=-1.0, u_max=1.0)
    e = np.r_[np.full(10, 3.0), np.full(10, -0.2)]
    y, x = pid.run(e)
    assert np.all(y[:10, 0, 0] == 1.0)  # Kp e = 3 > u_max from the start
    assert np.all(x[:11, 0, 0] == 0.0)  # so the integral never wound up
    # after the error drops, the output is linear again (Kp e + I, I growing by Ki T e) until it
    # reaches u_min = -1 at the 10th sample: -0.2 - 0.1 * 9 = -1.1 is clipped
    assert np.allclose(y[10:19, 0, 0], -0.2 + 10.0 * T * (-0.2) * np.arange(9), rtol=1e-12)
    assert y[19, 0, 0] == -1.0


def test_engines_agree_bit_for_bit_and_per_run_gains_equal_single_blocks():
    e = _error()[:, None] * np.array([[1.0, 2.0, -1.0]])
    kp = np.array([0.5, 1.0, 4.0])
    loop = Loop([place(DiscretePID(ki=1.0, kd=0.05, T=T, Tf=0.01, u_min=-2.0, u_max=2.0), "pid")], dt=T)
    res = {eng: loop.simulate(e.shape[0] - 1, inputs={"e": e}, params={"pid": {"kp": kp}},
                              execution=Execution(engine=eng))
           for eng in ("numpy", "compiled")}
    assert np.array_equal(res["numpy"]["u"], res["compiled"]["u"])
    for b in range(3):
        y, _ = DiscretePID(kp=kp[b], ki=1.0, kd=0.05, T=T, Tf=0.01, u_min=-2.0, u_max=2.0).run(e[:, b])
        assert np.array_equal(res["compiled"]["u"][:, b], y[:, 0, 0])


@pytest.mark.parametrize(("kw", "match"), [({"kp": -1.0}, "kp"), ({"T": 0.0}, "T"), ({"Tf": -0.1}, "Tf"),
                                           ({"u_min": 1.0, "u_max": 1.0}, "u_min must be < u_max")])
def test_bad_arguments_are_named(kw, match):
    with pytest.raises(ValueError, match=match):
        DiscretePID(**kw)
