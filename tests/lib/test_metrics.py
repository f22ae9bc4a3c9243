import control as ct
import numpy as np
import pytest

from ctrl_analysis.metrics import (
    bandwidth_3db,
    mean_abs_error,
    mean_std,
    overshoot,
    resonance_peak,
    rmse,
    settling_time,
    snr_db,
)


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


@pytest.mark.parametrize("fn,names", [(mean_abs_error, ("x", "x_hat")), (rmse, ("reference", "y")),
                                      (snr_db, ("reference", "y"))])
def test_no_silent_broadcasting(fn, names):
    with pytest.raises(ValueError, match=f"{names[0]} and {names[1]} must have the same shape"):
        fn(np.ones(5), np.ones((5, 1)))  # numpy would silently make a (5, 5) error array
    with pytest.raises(ValueError, match="must have the same shape"):
        fn(np.ones(5), np.ones(4))
    with pytest.raises(TypeError, match=f"{names[1]} must be a real array"):
        fn(np.ones(5), "abc")
    # one truth against B estimates with an explicit length-1 axis, or a scalar reference, is fine
    assert fn(np.ones((5, 1)), np.full((5, 3), 2.0)).shape == (3,)
    assert np.isfinite(fn(np.ones(5), 0.5))


def test_mean_std_checks_the_mask():
    v = np.array([1.0, 2.0, 3.0, 10.0])
    assert mean_std(v, np.array([True, True, True, False]))[2] == 3
    with pytest.raises(ValueError, match=r"ok must have one entry per run of values \(4\), got shape \(3,\)"):
        mean_std(v, [True, True, True])
    with pytest.raises(TypeError, match="ok must be a boolean mask"):
        mean_std(v, np.array([0, 1, 2]))  # an index array would be read as a mask
    mean, std, n = mean_std(v[:1])
    assert (mean, n) == (1.0, 1)


def test_settling_time_rejects_nan_final_and_bad_band():
    t = np.linspace(0, 1, 11)
    y = np.ones(11)
    with pytest.raises(ValueError, match="final must be finite"):
        settling_time(t, y, float("nan"))
    with pytest.raises(ValueError, match="band must be > 0"):
        settling_time(t, y, 1.0, band=0.0)
    with pytest.raises(ValueError, match="y must have len"):
        settling_time(t, y[:5], 1.0)
    with pytest.raises(TypeError, match="final must be a real number"):
        overshoot(t, y, [1.0, 2.0])
