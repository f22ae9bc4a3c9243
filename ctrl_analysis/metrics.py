"""Performance measures: errors, RMSE, SNR, step-response figures, Monte Carlo summaries, filter bandwidth."""

from __future__ import annotations

import numpy as np

from ._validate import check_array, check_finite, check_int, check_positive

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


def _pair(names: tuple[str, str], a, b, axis) -> tuple[np.ndarray, np.ndarray]:
    """Two signals of the same shape, or the same number of axes with explicit length-1 axes, or a scalar.

    ``(N, 1)`` against ``(N, B)`` (one truth, B estimates) is allowed; ``(N,)`` against ``(N, 1)``
    (which numpy would silently broadcast to ``(N, N)``) is not.
    """
    a, b = check_array(names[0], a), check_array(names[1], b)
    if a.shape != b.shape and a.ndim and b.ndim and (
            a.ndim != b.ndim or any(m != n and 1 not in (m, n) for m, n in zip(a.shape, b.shape, strict=True))):
        raise ValueError(f"{names[0]} and {names[1]} must have the same shape (or the same number of axes with "
                         f"length-1 axes to broadcast), got {a.shape} and {b.shape}")
    _check_axis(axis, max(a.ndim, b.ndim))
    return a, b


def _no_overflow(names: str, result, *inputs):
    """``result``; a ``ValueError`` naming ``names`` where finite inputs gave a NaN or inf (an overflow)."""
    parts = result if isinstance(result, tuple) else (result,)
    if all(np.all(np.isfinite(a)) for a in inputs) and not all(np.all(np.isfinite(p)) for p in parts):
        raise ValueError(f"{names} overflow double precision (finite values, a result that is not finite)")
    return result


def _check_axis(axis, ndim: int, allow_none: bool = True) -> None:
    if axis is None and allow_none:
        return
    axis = check_int("axis", axis)
    if not -max(ndim, 1) <= axis < max(ndim, 1):
        raise ValueError(f"axis must be in [-{max(ndim, 1)}, {max(ndim, 1)}) for {ndim}-D data, got {axis}")


def mean_abs_error(x, x_hat, axis=0):
    """Mean of ``|x - x_hat|`` over ``axis`` (time by default): the papers' "平均误差".

    ``x`` and ``x_hat`` must have the same shape, or the same number of axes with explicit length-1
    axes (e.g. a truth of shape ``(N, 1)`` against estimates ``(N, B)``), or one may be a scalar;
    nothing else broadcasts.

    Parameters
    ----------
    x, x_hat : array_like
        True values and estimates.
    axis : int or None
        Axis averaged over (time by default); ``None`` for all.

    Returns
    -------
    float or numpy.ndarray
        The mean absolute error, with ``axis`` removed.

    Raises
    ------
    ValueError
        Shapes that would broadcast silently, or an ``axis`` out of range.
    """
    x, x_hat = _pair(("x", "x_hat"), x, x_hat, axis)
    return np.mean(np.abs(x - x_hat), axis=axis)


def rmse(reference, y, axis=0):
    """Root-mean-square error ``sqrt(mean((reference - y)^2))`` over ``axis`` (same shapes, finite).

    Parameters
    ----------
    reference, y : array_like
        Reference and signal, shapes as in :func:`mean_abs_error`.
    axis : int or None
        Axis averaged over (time by default); ``None`` for all.

    Returns
    -------
    float or numpy.ndarray
        The RMSE, with ``axis`` removed.
    """
    reference, y = _pair(("reference", "y"), reference, y, axis)
    with np.errstate(over="ignore", invalid="ignore"):
        return _no_overflow("reference and y", np.sqrt(np.mean((reference - y) ** 2, axis=axis)), reference, y)


def snr_db(reference, y, axis=0):
    """Signal-to-noise ratio ``10 lg(Σ reference² / Σ (reference - y)²)`` in dB over ``axis`` (same shapes).

    Parameters
    ----------
    reference, y : array_like
        Clean reference and noisy (or estimated) signal, shapes as in :func:`mean_abs_error`.
    axis : int or None
        Axis averaged over (time by default); ``None`` for all.

    Returns
    -------
    float or numpy.ndarray
        The SNR in dB (``inf`` when ``y`` equals ``reference``), with ``axis`` removed.
    """
    r, y = _pair(("reference", "y"), reference, y, axis)
    e = r - y
    with np.errstate(over="ignore", invalid="ignore"):
        power, noise = np.sum(r**2, axis=axis), np.sum(e**2, axis=axis)
    _no_overflow("reference and y", (power, noise), r, y)
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(power / noise)


def overshoot(t, y, final, initial=0.0, axis=0):
    """Percent overshoot of a step response from ``initial`` to ``final`` (0 when it never exceeds it).

    Parameters
    ----------
    t : array_like or None
        Sample times (unused; kept for a signature shared with :func:`settling_time`; None is accepted).
    y : array_like
        The response.
    final, initial : float
        Final and initial values of the step (different).
    axis : int
        Time axis of ``y``.

    Returns
    -------
    float or numpy.ndarray
        ``max(peak − 1, 0) · 100`` with the peak relative to the step, per run.
    """
    if t is not None:
        check_array("t", t)  # unused, but a real array when given
    y = check_array("y", y)
    final = check_finite("final", final, scalar=True)
    initial = check_finite("initial", initial, scalar=True)
    _check_axis(axis, y.ndim)
    if y.size == 0:
        raise ValueError(f"y must hold at least one sample, got shape {y.shape}")
    step = final - initial
    if step == 0:
        raise ValueError("final must differ from initial for an overshoot")
    peak = np.max((y - initial) / step, axis=axis)
    return np.maximum(peak - 1.0, 0.0) * 100.0


def settling_time(t, y, final, initial=0.0, band=0.02, axis=0):
    """First time after which ``y`` stays within ``band`` (relative to the step) of ``final``.

    Parameters
    ----------
    t : array_like, shape (N,)
        Strictly increasing sample times.
    y : array_like
        The response, ``N`` samples along ``axis``.
    final, initial : float
        Final and initial values of the step (different).
    band : float
        Half-width of the band, relative to the step size (> 0; 0.02 = 2 %).
    axis : int
        Time axis of ``y``.

    Returns
    -------
    float or numpy.ndarray
        The settling time per run; ``nan`` for a run that never settles within the record. A NaN
        sample of ``y`` (a diverged run) counts as outside the band: a run that is NaN at its last
        sample has no settling time.

    Raises
    ------
    ValueError
        ``final``, ``initial`` or ``band`` not finite (``band`` must be > 0), ``t`` not 1-D and
        strictly increasing, or ``t`` and ``y`` of different lengths along ``axis``.
    """
    t = np.atleast_1d(check_finite("t", t))
    final = check_finite("final", final, scalar=True)
    initial = check_finite("initial", initial, scalar=True)
    band = check_positive("band", band, scalar=True)
    y = check_array("y", y)
    _check_axis(axis, y.ndim, allow_none=False)
    y = np.moveaxis(y, axis, 0)
    if t.ndim != 1 or np.any(np.diff(t) <= 0):
        raise ValueError(f"t must be 1-D and strictly increasing, got shape {t.shape}")
    if y.shape[0] != t.size:
        raise ValueError(f"y must have len(t) = {t.size} samples along axis {axis}, got {y.shape[0]}")
    step = abs(final - initial)
    if step == 0:
        raise ValueError("final must differ from initial for a settling time")
    with np.errstate(invalid="ignore"):
        outside = ~(np.abs(y - final) <= band * step)  # a NaN sample is outside the band, never settled
    # index of the last sample outside the band; settled from the next one on
    any_out = outside.any(axis=0)
    last = outside.shape[0] - 1 - np.argmax(outside[::-1], axis=0)
    idx = np.where(any_out, last + 1, 0)
    res = np.where(idx < t.size, t[np.minimum(idx, t.size - 1)], np.nan)
    return res if res.ndim else float(res)


def mean_std(values, ok=None, axis=0):
    """Mean, standard deviation (ddof=1 when more than one run) and count over the runs in ``ok``.

    Diverged runs (``ok`` False) are excluded, never averaged; the count says how many remained.
    ``ok`` must be a boolean mask with one entry per run (an index array is rejected: it would be
    read as a mask silently).

    Parameters
    ----------
    values : array_like
        One value per run along ``axis``.
    ok : array_like of bool, shape (runs,), optional
        Which runs to keep (default all).
    axis : int
        The run axis.

    Returns
    -------
    mean, std : float or numpy.ndarray
        ``nan`` when no run is kept; ``std`` is 0 for a single run.
    count : int
        Runs kept.
    """
    v = check_array("values", values)
    _check_axis(axis, v.ndim, allow_none=False)
    if ok is not None:
        ok = np.asarray(ok)
        if ok.dtype != bool:
            raise TypeError(f"ok must be a boolean mask (one entry per run), got dtype {ok.dtype}")
        n_runs = v.shape[axis] if v.ndim else 1
        if ok.shape != (n_runs,):
            raise ValueError(f"ok must have one entry per run of values ({n_runs}), got shape {ok.shape}")
        v = np.compress(ok, v, axis=axis)
    n = v.shape[axis]
    if n == 0:
        return np.nan, np.nan, 0
    with np.errstate(over="ignore", invalid="ignore"):
        std = np.std(v, axis=axis, ddof=1) if n > 1 else np.zeros_like(np.mean(v, axis=axis))
        mean = np.mean(v, axis=axis)
    _no_overflow("values", (mean, std), v)
    return mean, std, n


def bandwidth_3db(sys, dbdrop: float = -3.0) -> float:
    """First frequency (rad/s) where the gain falls ``dbdrop`` dB below its DC value (python-control).

    Parameters
    ----------
    sys : control.LTI
        A SISO system with a finite, non-zero DC gain.
    dbdrop : float
        The drop in dB (< 0).

    Returns
    -------
    float
        The bandwidth in rad/s (``control.bandwidth``).
    """
    import control as ct

    dbdrop = check_finite("dbdrop", dbdrop, scalar=True)
    if not -300.0 <= dbdrop < 0:
        raise ValueError(f"dbdrop must be in [-300, 0) (a drop in dB within double precision), got {dbdrop!r}")
    return float(ct.bandwidth(sys, dbdrop=dbdrop))


def _check_lti(sys):
    import control as ct

    if not isinstance(sys, ct.LTI):
        raise TypeError(f"sys must be a python-control LTI system (TransferFunction or StateSpace), got {sys!r}")
    return sys


def resonance_peak(sys, omega=None):
    """Peak magnitude of a SISO system relative to its DC gain, in dB, and the frequency of the peak.

    Parameters
    ----------
    sys : control.LTI
        A SISO system with a finite, non-zero DC gain.
    omega : array_like, optional
        Frequencies (rad/s, > 0) to search; default a log grid up to 100× the largest pole modulus.

    Returns
    -------
    peak_db : float
        Peak gain over the DC gain in dB; 0 when the gain never exceeds its DC value.
    omega_peak : float
        Frequency of the peak (rad/s).
    """
    import control as ct

    _check_lti(sys)
    if omega is not None:
        omega = np.atleast_1d(check_positive("omega", omega))
        if omega.ndim != 1 or omega.size == 0:
            raise ValueError(f"omega must be a non-empty 1-D array of frequencies, got shape {omega.shape}")
    if omega is None:
        poles = np.abs(np.asarray(sys.poles()))
        wmax = 100.0 * max(1.0, float(poles.max(initial=1.0)))
        omega = np.logspace(np.log10(wmax) - 7, np.log10(wmax), 4000)
    resp = ct.frequency_response(sys, omega)
    mag = np.atleast_1d(np.abs(np.squeeze(resp.complex)))
    dc = abs(float(np.real(sys.dcgain())))
    k = int(np.argmax(mag))
    peak = 20 * np.log10(mag[k] / dc) if dc > 0 else np.inf
    return max(0.0, float(peak)), float(omega[k])
