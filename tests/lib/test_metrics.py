import control as ct
import numpy as np
import pytest

from ctrl_analysis.metrics import (bandwidth_3db, mean_abs_error, mean_std, overshoot, resonance_peak, rmse,
                                   settling_time, snr_db)


def test_error_measures_closed_forms():
    ref = np.ones(4)
    y = np.array([1.0, 0.0, 1.0, 2.0])
    assert mean_abs_error(ref, y) == pytest.approx(0.5)
    assert rmse(ref, y) == pytest.approx(np.sqrt(0.5))
    # for |y*| = 1: SNR = -20 lg(RMSE) exactly
    assert snr_db(ref, y) == pytest.approx(-20 * np.log10(rmse(ref, y)))


def test_second_order_step_figures():
    zeta, wn = 0.3, 2.0
    sys = ct.tf([wn**2], [1, 2 * zeta * wn, wn**2])
    t = np.linspace(0, 20, 20001)
    _, y = ct.step_response(sys, t)
    assert overshoot(t, y, 1.0) == pytest.approx(100 * np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2)), rel=1e-3)
    ts = settling_time(t, y, 1.0)
    info = ct.step_info(sys, T=t)
    assert ts == pytest.approx(info["SettlingTime"], abs=0.01)


def test_mean_std_excludes_diverged_runs():
    m, s, n = mean_std([1.0, 3.0, np.nan], ok=[True, True, False])
    assert (m, n) == (2.0, 2) and s == pytest.approx(np.sqrt(2))
    assert mean_std([np.nan], ok=[False])[2] == 0


def test_bandwidth_and_peak_of_second_order():
    zeta, wn = 0.2, 3.0
    sys = ct.tf([wn**2], [1, 2 * zeta * wn, wn**2])
    peak, w = resonance_peak(sys)
    assert peak == pytest.approx(-20 * np.log10(2 * zeta * np.sqrt(1 - zeta**2)), rel=1e-3)
    assert w == pytest.approx(wn * np.sqrt(1 - 2 * zeta**2), rel=1e-2)
    bw = wn * np.sqrt(1 - 2 * zeta**2 + np.sqrt(4 * zeta**4 - 4 * zeta**2 + 2))
    assert bandwidth_3db(sys) == pytest.approx(bw, rel=1e-3)
    assert resonance_peak(ct.tf([1], [1, 1]))[0] == 0.0
