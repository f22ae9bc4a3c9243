"""Performance measures: errors, RMSE, SNR, step-response figures, Monte Carlo summaries, filter bandwidth."""

from __future__ import annotations

import numpy as np

from ._validate import check_finite

__all__ = [
    "mean_abs_error",
    "rmse",
    "snr_db",
    "overshoot",
    "settling_time",
    "mean_std",
    "bandwidth_3db",
    "resonance_peak",
]


def mean_abs_error(x, x_hat, axis=0):
    """Mean of ``|x - x_hat|`` over ``axis`` (time by default): the papers' "平均误差"."""
    return np.mean(np.abs(np.asarray(x, dtype=float) - np.asarray(x_hat, dtype=float)), axis=axis)


def rmse(reference, y, axis=0):
    """Root-mean-square error ``sqrt(mean((reference - y)^2))`` over ``axis``."""
    e = np.asarray(reference, dtype=float) - np.asarray(y, dtype=float)
    return np.sqrt(np.mean(e**2, axis=axis))


def snr_db(reference, y, axis=0):
    """Signal-to-noise ratio ``10 lg(Σ reference² / Σ (reference - y)²)`` in dB over ``axis``."""
    r = np.asarray(reference, dtype=float)
    e = r - np.asarray(y, dtype=float)
    return 10.0 * np.log10(np.sum(r**2, axis=axis) / np.sum(e**2, axis=axis))


def overshoot(t, y, final, initial=0.0, axis=0):
    """Percent overshoot of a step response from ``initial`` to ``final`` (0 when it never exceeds it)."""
    y = np.asarray(y, dtype=float)
    step = final - initial
    if step == 0:
        raise ValueError("final must differ from initial for an overshoot")
    peak = np.max((y - initial) / step, axis=axis)
    return np.maximum(peak - 1.0, 0.0) * 100.0


def settling_time(t, y, final, initial=0.0, band=0.02, axis=0):
    """First time after which ``y`` stays within ``band`` (relative to the step) of ``final``.

    Returns ``nan`` for a run that never settles within the record.
    """
    t = np.asarray(t, dtype=float)
    y = np.moveaxis(np.asarray(y, dtype=float), axis, 0)
    step = abs(final - initial)
    if step == 0:
        raise ValueError("final must differ from initial for a settling time")
    outside = np.abs(y - final) > band * step
    # index of the last sample outside the band; settled from the next one on
    any_out = outside.any(axis=0)
    last = outside.shape[0] - 1 - np.argmax(outside[::-1], axis=0)
    idx = np.where(any_out, last + 1, 0)
    res = np.where(idx < t.size, t[np.minimum(idx, t.size - 1)], np.nan)
    return res if res.ndim else float(res)


def mean_std(values, ok=None, axis=0):
    """Mean, standard deviation (ddof=1 when more than one run) and count over the runs in ``ok``.

    Diverged runs (``ok`` False) are excluded, never averaged; the count says how many remained.
    """
    v = np.asarray(values, dtype=float)
    if ok is not None:
        v = np.compress(np.asarray(ok, dtype=bool), v, axis=axis)
    n = v.shape[axis]
    if n == 0:
        return np.nan, np.nan, 0
    std = np.std(v, axis=axis, ddof=1) if n > 1 else np.zeros_like(np.mean(v, axis=axis))
    return np.mean(v, axis=axis), std, n


def bandwidth_3db(sys, dbdrop: float = -3.0) -> float:
    """First frequency (rad/s) where the gain falls ``dbdrop`` dB below its DC value (python-control)."""
    import control as ct

    check_finite("dbdrop", dbdrop)
    return float(ct.bandwidth(sys, dbdrop=dbdrop))


def resonance_peak(sys, omega=None):
    """Peak magnitude of a SISO system relative to its DC gain, in dB, and the frequency of the peak.

    Returns ``(peak_db, omega_peak)``; ``peak_db`` is 0 when the gain never exceeds its DC value.
    """
    import control as ct

    if omega is None:
        poles = np.abs(np.asarray(sys.poles()))
        wmax = 100.0 * max(1.0, float(poles.max(initial=1.0)))
        omega = np.logspace(np.log10(wmax) - 7, np.log10(wmax), 4000)
    resp = ct.frequency_response(sys, omega)
    mag = np.abs(np.squeeze(resp.complex))
    dc = abs(float(np.real(sys.dcgain())))
    k = int(np.argmax(mag))
    peak = 20 * np.log10(mag[k] / dc) if dc > 0 else np.inf
    return max(0.0, float(peak)), float(omega[k])
