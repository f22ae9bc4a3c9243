"""The best worst-case accuracy of any causal differentiator, and the adversarial pair of its proof.

**Statement.** Let ``f`` have ``|f''(t)| <= L`` and be measured as ``y = f + η`` with ``|η(t)| <= ε``,
``ε`` and ``L`` known. For every causal differentiator ``D`` (its output at ``t`` depends on ``y`` up
to ``t`` only)::

    sup over admissible (f, η) of  sup_t |D[y](t) - f'(t)|  >=  2 √(ε L).

The constant 2 is tight: the difference quotient over a window ``T_w = 2√(ε/L)`` errs by at most
``ε·2/T_w + L T_w/2 = 2√(εL)`` (sampled every ``Δ``, with the window rounded up to whole samples, by at
most ``2√(εL) + LΔ/2``).

**Sources, and what the search found.** Seeber & Haimovich, "Optimal robust exact differentiation
via linear adaptive techniques", Automatica 148 (2023) 110725, arXiv:2111.12638 (continuous-time and
sampled-data limits on the smallest achievable worst-case error of causal differentiators, and a
linear adaptive differentiator that attains them); Haimovich, Seeber, Aldana-López, Gómez-Gutiérrez,
"Differentiator for noisy sampled signals with best worst-case accuracy", IEEE Control Systems
Letters 6 (2022), DOI 10.1109/LCSYS.2021.3087542, arXiv:2106.05320; Aldana-López, Seeber, Haimovich,
Gómez-Gutiérrez, "Optimal robust exact first-order differentiators with Lipschitz-continuous output",
IEEE TAC (2025), DOI 10.1109/TAC.2025.3555481, arXiv:2404.05863. The library's search reached
these papers' abstracts and the authors' code for the TAC paper (github.com/RodrigoAldana/OREdiff),
not the theorems' text, so the constant is derived here (the proof below is Landau's sharp
half-line inequality ``‖d'‖ <= 2√(‖d‖ ‖d''‖)`` for ``d = f+ - f-``, ``‖d‖ <= 2ε``, ``‖d''‖ <= 2L``)
and checked against the TAC paper's example as the authors' testbench runs it (``f = L sin t``,
``L = 1``, uniform noise bounded by ``N = 0.08``, ``Δ = 0.01`` s). That example draws the accuracy
guaranteed by the paper's differentiator, ``2√(2NL) + LΔ/2 = 0.805``: √2 times this bound plus the
sampling term, the price of not knowing ``N`` (the differentiator estimates it). With ``N`` known,
the fixed window above, ``⌈2√(N/L)/Δ⌉ = 57`` samples, errs by ``2√(NL) = 0.566`` on the
construction below and by at most ``2√(NL) + LΔ/2 = 0.571`` on any admissible signal
(``tests/lib/test_arena_bound.py``).

**Proof (the construction coded here).** Take ``d(t) = -2ε`` before ``t0``, ``d = -2ε + L (t-t0)²`` on
``[t0, t*]`` with ``t* = t0 + 2√(ε/L)`` (so ``d(t*) = 2ε``, ``d'(t*) = 4√(εL)``), and the two signals
``f± = g ± d/2`` around any ramp ``g`` (``|f±''| = L``). The measurement ``y = g`` is admissible for
both (``η± = ∓d/2``, ``|η±| <= ε``) up to ``t*``; a causal estimator returns the same value at
``t*`` for both, while ``f+'(t*) - f-'(t*) = 4√(εL)``, so it errs by at least ``2√(εL)`` on one of
them. After ``t*`` each signal bends back with ``f'' = ∓L`` until its slope is ``g'`` again and
is measured exactly, so the error after ``t*`` also shows how fast the estimator recovers.

**What the pair can and cannot show.** Every causal estimator, good or bad, errs by at least the
bound on it: a tuned estimator measured there below the bound exposes a bug (in the construction,
the error measure or the estimator's causality), never a good estimator. An estimator that has
converged on the common ramp returns ``g'`` at ``t*``, midway between the two derivatives, and errs
by exactly the bound: the pair does not rank estimators.
"""

from __future__ import annotations

import numpy as np

from .._validate import check_array, check_finite, check_int, check_positive
from .recordcheck import MAX_ROWS

__all__ = ["adversarial_error", "adversarial_pair", "difference_quotient", "lower_bound"]


def lower_bound(eps, L):
    """``2 √(ε L)``: no causal differentiator has a smaller worst-case error.

    Parameters
    ----------
    eps : float or array_like
        Noise bound ``ε`` (> 0).
    L : float or array_like
        Bound on ``|f''|`` (> 0).

    Returns
    -------
    float or numpy.ndarray

    Examples
    --------
    >>> lower_bound(0.01, 1.0)   # ε = 0.01, L = 1: 2 √0.01 = 0.2
    0.2
    """
    eps = check_positive("eps", eps)
    L = check_positive("L", L)
    out = 2.0 * np.sqrt(np.asarray(eps, dtype=float) * np.asarray(L, dtype=float))
    return float(out) if out.ndim == 0 else out


def difference_quotient(y, dt: float, eps: float, L: float) -> tuple:
    """The bound-attaining causal differentiator: the difference quotient over ``m = ⌈2√(ε/L)/dt⌉`` samples.

    ``f̂'_k = (y_k - y_(k-m)) / (m dt)`` errs on any signal with ``|f''| <= L`` measured with noise ``|η| <= ε``
    by at most ``2ε/(m dt) + L m dt / 2`` (the noise of two samples over the window, plus the Taylor remainder),
    which is ``2√(εL)`` when the window ``2√(ε/L)`` is a whole number of samples and at most ``2√(εL) + L dt/2``
    otherwise: the lower bound is attained. A reference entry beside tuned estimators: what knowing ε and L
    guarantees without any tuning.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, B)
        Samples at ``t_k = k dt`` (records on axis 1).
    dt : float
        Sample period (> 0).
    eps, L : float
        Noise bound and bound on ``|f''|`` (> 0).

    Returns
    -------
    estimate : numpy.ndarray
        ``f̂'`` of ``y``'s shape, NaN for the first ``m`` samples (no window yet).
    m : int
        The window in samples.
    guarantee : float
        ``2ε/(m dt) + L m dt/2``: its worst-case error on every admissible record.

    Examples
    --------
    >>> import numpy as np
    >>> t = 0.01 * np.arange(400)
    >>> d, m, g = difference_quotient(np.sin(t), 0.01, 0.01, 1.0)
    >>> m, round(g, 4), bool(np.nanmax(np.abs(d - np.cos(t))) <= g)
    (20, 0.2, True)
    """
    y = np.asarray(check_finite("y", y), dtype=float)
    if y.ndim not in (1, 2) or y.shape[0] < 2:
        raise ValueError(f"y must have shape (N,) or (N, B) with N >= 2, got {y.shape}")
    dt = float(check_positive("dt", dt, scalar=True))
    eps = float(check_positive("eps", eps, scalar=True))
    L = float(check_positive("L", L, scalar=True))
    m = int(max(1, np.ceil(2.0 * np.sqrt(eps / L) / dt - 1e-9)))
    if m >= y.shape[0]:
        raise ValueError(f"the window 2√(ε/L) = {2.0 * np.sqrt(eps / L):.3g} s ({m} samples) must be shorter than y "
                         f"({y.shape[0]} samples)")
    out = np.full(y.shape, np.nan)
    out[m:] = (y[m:] - y[:-m]) / (m * dt)
    return out, m, 2.0 * eps / (m * dt) + L * m * dt / 2.0


def adversarial_pair(eps: float, L: float, dt: float, n_samples: int, k_star: int, slope: float = 1.0) -> dict:
    """The two admissible signals of the proof, whose measurements coincide up to sample ``k_star``.

    Parameters
    ----------
    eps, L : float
        Noise bound and bound on ``|f''|`` (> 0).
    dt : float
        Sample period (> 0).
    n_samples : int
        Samples ``N`` (at most :data:`~ctrl_analysis.arena.recordcheck.MAX_ROWS`, a record's most rows).
    k_star : int
        The sample ``t* = k_star dt`` where the two derivatives differ most; needs
        ``t* >= 2√(ε/L)`` and ``k_star < N``.
    slope : float
        Slope of the ramp ``g`` both signals are built around.

    Returns
    -------
    dict
        ``t`` (N,); ``f``, ``f1``, ``f2``, ``y``, ``noise`` of shape (2, N) (row 0: ``f+``, row 1:
        ``f-``); ``k_star``; ``bound`` = :func:`lower_bound`.

    Raises
    ------
    TypeError, ValueError
        If ``eps``, ``L`` or ``dt`` is not a number > 0, ``n_samples`` (1 to ``MAX_ROWS``) or ``k_star`` (>= 0)
        not an integer, ``slope`` not finite, or ``t*`` is too early or outside the record.

    Examples
    --------
    >>> p = adversarial_pair(0.01, 1.0, 0.01, 100, 50)
    >>> bool(np.all(p["y"][0, :51] == p["y"][1, :51])), round(float(p["f1"][0, 50] - p["f1"][1, 50]), 9)
    (True, 0.4)
    """
    eps = float(check_positive("eps", eps, scalar=True))
    L = float(check_positive("L", L, scalar=True))
    dt = float(check_positive("dt", dt, scalar=True))
    n_samples = check_int("n_samples", n_samples, minimum=1, maximum=MAX_ROWS)
    k_star = check_int("k_star", k_star, minimum=0)
    slope = float(check_finite("slope", slope, scalar=True))
    tau = 2.0 * np.sqrt(eps / L)
    t = dt * np.arange(n_samples)
    if not (0 <= k_star < t.size) or t[k_star] < tau:
        raise ValueError(f"k_star must be a sample with t* = k_star dt >= 2 sqrt(eps/L) = {tau:.4g} s and "
                         f"k_star < n_samples = {n_samples}, got k_star = {k_star}")
    ts = t[k_star]
    t0 = ts - tau
    s = t - t0
    # d: -2ε, then +L curvature up to t*, then -L curvature until d' = 0, then constant (6ε)
    d = np.where(t < t0, -2 * eps, -2 * eps + L * s**2)
    d1 = np.where(t < t0, 0.0, 2 * L * s)
    d2 = np.where(t < t0, 0.0, 2 * L)
    a = t - ts
    back = (t > ts) & (a <= tau)
    d = np.where(back, 2 * eps + 4 * np.sqrt(eps * L) * a - L * a**2, d)
    d1 = np.where(back, 4 * np.sqrt(eps * L) - 2 * L * a, d1)
    d2 = np.where(back, -2 * L, d2)
    after = a > tau
    d, d1, d2 = np.where(after, 6 * eps, d), np.where(after, 0.0, d1), np.where(after, 0.0, d2)
    g = slope * t
    sign = np.array([1.0, -1.0])[:, None]
    f = g + sign * d / 2
    f1 = slope + sign * d1 / 2
    f2 = sign * d2 / 2
    y = np.where(t <= ts, g, f)  # g for both up to t*, then each signal measured exactly
    return {"t": t, "f": f, "f1": f1, "f2": f2, "y": y, "noise": y - f, "k_star": int(k_star),
            "bound": lower_bound(eps, L)}


def adversarial_error(est_d1, pair: dict, k_from: int = 0) -> float:
    """Worst-case first-derivative error over both signals of the pair, from sample ``k_from`` on.

    Parameters
    ----------
    est_d1 : array_like, shape (N, 2) or (N, 2, B)
        Estimates of ``f'`` for the two measurements (column 0: ``y`` of ``f+``, 1: of ``f-``),
        optionally for ``B`` estimators.
    pair : dict
        From :func:`adversarial_pair`.
    k_from : int
        First sample counted (after the estimator's start-up transient; ``<= k_star``).

    Returns
    -------
    float or numpy.ndarray
        ``max_{±, k >= k_from} |f̂'± - f±'|`` (one per estimator).

    Raises
    ------
    TypeError, ValueError
        If ``pair`` is not :func:`adversarial_pair`'s dict, ``est_d1`` not a real array of its shape,
        or ``k_from`` not an integer in ``[0, k_star]``.
    """
    if not isinstance(pair, dict) or not {"f1", "k_star"} <= pair.keys():
        raise TypeError(f"pair must be the dict returned by adversarial_pair, got {pair!r:.80}")
    truth = np.asarray(pair["f1"]).T  # (N, 2)
    est = check_array("est_d1", est_d1)  # NaN/inf pass: a diverged estimator's error is not finite
    if est.ndim not in (2, 3) or est.shape[:2] != truth.shape:
        raise ValueError(f"est_d1 must have shape {truth.shape} or {truth.shape + ('B',)} (the pair's samples "
                         f"and its two signals), got {est.shape}")
    k_from = check_int("k_from", k_from, minimum=0)
    if k_from > pair["k_star"]:
        raise ValueError(f"k_from must be in [0, k_star = {pair['k_star']}], got {k_from}")
    if est.ndim == 3:
        truth = truth[:, :, None]
    err = np.abs(est - truth)[k_from:]
    out = err.max(axis=(0, 1))
    return float(out) if np.ndim(out) == 0 else out
