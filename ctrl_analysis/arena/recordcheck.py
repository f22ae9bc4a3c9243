"""The arena's checks of a user's record before any work: its file, its cost, its scale and the stated bounds.

``ctrl-analysis arena --signal F.csv --noise-bound E --accel-bound L`` tunes every estimator family on the
record (:func:`.recommend.recommend_for_record`). Before that, this module (numpy only, so the command
line answers before its heavy imports) checks:

**The file** (``check_file``, for the command line): a regular file (not ``/dev/zero``, a FIFO or a folder) of at most
:data:`MAX_FILE_BYTES`, with at most :data:`MAX_ROWS` rows.

**The cost** (:func:`work_estimate`): the tuning evaluates a fixed number of
configurations per family (its grid and two pattern-search rounds), each on two runs (the noisy and the
noise-free record) of ``N`` samples. The engine's families cost about :data:`S_PER_ROW_RUN` core-seconds
per sample and run, and hold about :data:`BYTES_PER_ROW` bytes of their batch per sample. The causal
algebraic family is an FIR filter whose windows are set in **samples** by the bounds,
``2 √(ε/L) / dt`` times 0.1 to 10: its cost grows as ``N × window``, so the same ``N`` at a smaller
``dt`` costs more (capped at the record's length, :func:`.tuning.param_values`; before that cap, 500 rows at
``dt = 1e-9`` s with ``ε = 0.01``, ``L = 1`` asked for windows of 6·10⁸ samples and 20 GB). The
surrogate's zero-phase fit (no derivative column) is a filter of ``4 √(ε/L) / dt`` taps. A record
whose estimate exceeds :data:`MAX_WORK_S` core-seconds or :data:`MAX_MEMORY_BYTES` is refused with the
estimate, the limit and how to get under it (decimate or cut the record).

**The scale**: every value, the time step, the record's duration and the bounds
within :data:`SCALE_RANGE`, so that the arithmetic of the tuning (up to the cube of the fastest
bandwidth ``1/dt`` times the signal, and squares of errors) stays finite in float64: a non-finite
result is refused before the work, never reported as "inf × bound".

**The bounds against the record** (:func:`record_estimates`). The record's noise:
the robust spread (median absolute deviation) of its third differences, where a smooth signal leaves
almost nothing (``|Δ³f| <= 2 L dt²``) and white noise of standard deviation ``σ`` leaves ``√20 σ``;
``ε̂ = √3 σ̂``, the bound of uniform noise of that spread. The record's curvature: the second differences
``D_m`` of its moving averages over ``m`` samples, at lag ``m``, for ``m`` from 1 to a quarter of the
record. ``D_m`` of a signal is a weighted mean of its ``f''`` (so ``|D_m| <= max |f''|``), and of white
noise has standard deviation ``σ √(6/m) / (m dt)²``; ``L̂ = max over m of (max |D_m| - noise allowance)``,
the allowance being ``c σ̂ √(6/m)/(m dt)²`` (``c = √(2 ln N) + 1``, above the largest of ``N`` noise
values) or ``4ε/(m dt)²`` (the most bounded noise can put there), whichever is larger. ``L̂ > 0`` is then
curvature the record shows beyond its noise: a lower estimate of ``max |f''|``. With the true derivative
in the record, ``max |Δf'|/dt`` (a lower bound on ``max |f''|`` by the mean-value theorem) counts too.

What is refused and what is a warning, with the factor :data:`FACTOR` = 10 either way:

- ``ε < ε̂/10`` (with ``ε̂`` beyond what the signal's own third differences can reach, ``10 (ε + L dt²)``):
  an **error**: the record is noisier than the stated bound allows.
- ``L < L̂/10``: an **error**: the record bends faster than the stated bound allows (or holds a spike or a
  jump beyond the noise bound; the message says where).
- The bounds' time scale ``√(ε/L)`` longer than the record: an **error**: no estimator tuned for these
  bounds settles within the record.
- ``ε > 10 ε̂`` or ``L > 10 L̂``: a **warning**, printed and recorded in results.json. A bound is a worst
  case over every signal the estimator will meet; one record can legitimately sit far below it (a clean
  simulated record and a sensor's noise specification, quantisation on a still signal, a calm stretch of a
  manoeuvring plant), and without a derivative column the arena scores on the record's fit plus noise of the
  stated bound, a meaningful "what if". So the run goes on, and the report says that errors below the bound
  ``2√(εL)`` are then expected on this record and prove nothing.
"""

from __future__ import annotations

import math
import os
import stat
from pathlib import Path

import numpy as np

from .._validate import check_bool, check_finite, check_int, check_positive

__all__ = ["FACTOR", "MAX_FILE_BYTES", "MAX_MEMORY_BYTES", "MAX_RECORDS", "MAX_ROWS", "MAX_WORK_S", "SCALE_RANGE",
           "check_record", "estimated_bounds", "record_estimates", "work_estimate"]

#: The largest ``--signal`` file read (bytes).
MAX_FILE_BYTES = 128 * 2**20
#: The most rows a record may have (and samples of the arena's own records, windows and adversarial pairs).
MAX_ROWS = 1_000_000
#: The most seeded records per case of the benchmark (``--runs``): every configuration runs two per record, so
#: 1000 records already make the default benchmark's tuning about 300 times its three records' work.
MAX_RECORDS = 1000
#: The most memory a record run may be estimated to need (bytes).
MAX_MEMORY_BYTES = 4 * 2**30
#: The most work a record run may be estimated to need (core-seconds at the rates below).
MAX_WORK_S = 1200.0
#: Every value, the time step, the duration and the bounds must lie within this range of magnitudes.
SCALE_RANGE = (1e-50, 1e50)
#: A stated bound further than this factor from the record's estimate is an error (tighter) or a warning (looser).
FACTOR = 10.0

# The cost model, measured on the arena's record path (jobs=1, one core of a 2-core machine; 10^5 and 4 x 10^5
# rows: 0.6 and 1.4 GB peak, 29 and 30 s) with a margin: fixed cost, batch memory per sample, engine seconds per
# sample and run, algebraic seconds per sample, run and window tap, fit seconds per sample and tap.
BASE_BYTES = 0.5e9
BYTES_PER_ROW = 3.5e3
BASE_S = 5.0
S_PER_ROW_RUN = 250e-9
S_PER_ROW_RUN_TAP = 10e-9
S_PER_ROW_FIT_TAP = 1e-9
#: Tuning rounds of :func:`.recommend.recommend_for_record`.
ROUNDS = 2
#: Per family: parameters with a pattern-search step, the grid's size (:func:`.tuning._grid`) and the pattern searches
#: per cost (one per value of its parameters without a step: a degree, Σ's order); the test suite checks this table
#: against the families.
FAMILY_GRIDS = {"sigma": (1, 9, 1), "sigma5": (1, 9, 1), "sigman": (1, 36, 4), "leso2": (1, 9, 1),
                "leso3": (1, 9, 1), "neso": (2, 25, 1), "td": (2, 25, 1), "levant": (1, 9, 1), "kalman": (1, 9, 1),
                "abg": (1, 9, 1), "singer": (2, 45, 1), "difflp": (1, 9, 1), "algebraic": (1, 10, 2),
                # the offline smoothers a --signal run tunes too (costed like an engine family: same order per row)
                "sg": (1, 15, 3), "spline": (1, 9, 1), "rts": (1, 9, 1), "rts3": (1, 9, 1)}
#: The algebraic family's window grid, as multiples of its reference ``2 √(ε/L) / dt`` samples (x 2 degrees).
WINDOW_MULTIPLES = tuple(float(v) for v in np.exp(np.linspace(np.log(0.1), np.log(10.0), 5)))


def check_file(path: Path, where: str) -> None:
    """Refuse what is not a regular file of at most :data:`MAX_FILE_BYTES` (before it is opened).

    Parameters
    ----------
    path : pathlib.Path
    where : str
        How the messages name it (e.g. ``"--signal path 'F.csv'"``).

    Raises
    ------
    ValueError
        If it does not exist, is not a regular file (``/dev/zero``, a FIFO, a folder) or is too large.
    """
    try:
        st = os.stat(path)
    except OSError as exc:
        raise ValueError(f"{where} cannot be read ({exc.strerror or exc})") from None
    if not stat.S_ISREG(st.st_mode):
        raise ValueError(f"{where} is not a regular file (a CSV file is needed, not a device, pipe or folder)")
    if st.st_size > MAX_FILE_BYTES:
        raise ValueError(f"{where} is {st.st_size / 2**20:.0f} MiB, over the limit of {MAX_FILE_BYTES / 2**20:.0f} "
                         f"MiB (and at most {MAX_ROWS} rows): decimate the record (keep every k-th row) or cut it")


def _ref(dt: float, eps: float, L: float) -> float:
    """``2 √(ε/L) / dt``: the window (samples) of the best difference quotient, the families' reference."""
    with np.errstate(over="ignore"):
        return float(2.0 * np.sqrt(np.float64(eps) / L) / dt)


def _windows(n: int, dt: float, eps: float, L: float) -> np.ndarray:
    """The algebraic family's grid windows (samples), as :func:`.tuning.param_values` sets them."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.minimum(np.maximum(np.round(_ref(dt, eps, L) * np.array(WINDOW_MULTIPLES)), 2.0), float(n))


def work_estimate(n: int, dt: float, eps: float, L: float, *, derivative: bool = False) -> dict:
    """What tuning every family on a record of ``n`` samples at ``dt`` with bounds ``eps``, ``L`` costs.

    Parameters
    ----------
    n : int
        Samples (2 to :data:`MAX_ROWS`: a longer record is refused before its cost matters).
    dt : float
        Sample period (s).
    eps, L : float
        Noise bound and bound on ``|f''|``.
    derivative : bool
        Whether the record has its derivative (no surrogate fit is made).

    Returns
    -------
    dict
        ``core_s`` (estimated core-seconds), ``memory_bytes`` (estimated peak), ``window`` (the algebraic
        family's largest window, samples), ``fit_taps`` (the surrogate fit's window, 0 with a derivative),
        ``configs`` (configurations evaluated).

    Examples
    --------
    >>> w = work_estimate(500, 1e-9, 0.01, 1.0)
    >>> int(w["window"]), w["memory_bytes"] < 1e9          # capped at the record's 500 samples
    (500, True)
    """
    n = check_int("n", n, minimum=2, maximum=MAX_ROWS)
    dt = float(check_positive("dt", dt, scalar=True))
    eps = float(check_positive("eps", eps, scalar=True))
    L = float(check_positive("L", L, scalar=True))
    derivative = check_bool("derivative", derivative)
    per_family = {name: grid + ROUNDS * 2 * 2 * free * starts for name, (free, grid, starts) in FAMILY_GRIDS.items()}
    engine = sum(c for name, c in per_family.items() if name != "algebraic")
    w = _windows(n, dt, eps, L)
    free, _, starts = FAMILY_GRIDS["algebraic"]
    taps = 2.0 * float(np.sum(w)) + ROUNDS * 2 * 2 * free * starts * float(w[-1])  # grid: 5 windows x 2 degrees
    fit = 0 if derivative else int(min(max(5.0, 2 * math.floor(min(_ref(dt, eps, L), n) + 0.5) + 1), n))
    core_s = BASE_S + 2 * n * (engine * S_PER_ROW_RUN + taps * S_PER_ROW_RUN_TAP) + 2 * n * fit * S_PER_ROW_FIT_TAP
    memory = BASE_BYTES + n * BYTES_PER_ROW + 8.0 * 2 * (n + float(w[-1])) * 2
    return {"core_s": core_s, "memory_bytes": memory, "window": int(w[-1]), "fit_taps": fit,
            "configs": int(sum(per_family.values()))}


def _check_budget(n: int, dt: float, eps: float, L: float, *, derivative: bool = False,
                 max_work_s: float | None = None, max_memory_bytes: float | None = None,
                 max_rows: int | None = None, where: str = "the record") -> dict:
    """:func:`work_estimate`, refused over the limits (one sentence: the estimate, the limit, the way under it).

    Parameters
    ----------
    n, dt, eps, L, derivative
        As :func:`work_estimate`.
    max_work_s, max_memory_bytes, max_rows : float, optional
        The limits (default :data:`MAX_WORK_S`, :data:`MAX_MEMORY_BYTES`, :data:`MAX_ROWS`).
    where : str
        How the message names the record.

    Returns
    -------
    dict
        The estimate.

    Raises
    ------
    ValueError
        Over a limit.
    """
    max_work_s = MAX_WORK_S if max_work_s is None else float(max_work_s)
    max_memory_bytes = MAX_MEMORY_BYTES if max_memory_bytes is None else float(max_memory_bytes)
    max_rows = MAX_ROWS if max_rows is None else int(max_rows)
    if n > max_rows:
        raise ValueError(f"{where} has {n} rows, over the limit of {max_rows}: decimate the record (keep every k-th "
                         "row) or cut it")
    est = work_estimate(n, dt, eps, L, derivative=derivative)
    what = (f"{n} rows at dt = {dt:.3g} s with ε = {eps:.3g}, L = {L:.3g}")
    why = []
    if est["window"] > 0.05 * n:
        why.append(f"the algebraic family's windows of up to {est['window']} samples (2√(ε/L)/dt = "
                   f"{_ref(dt, eps, L):.3g} samples, × 10)")
    if est["fit_taps"] > 0.05 * n:
        why.append(f"the surrogate's fit over {est['fit_taps']} samples")
    why = f" (mostly {' and '.join(why)})" if why else ""
    how = ("decimate the record (keep every k-th row: k× fewer rows and k× shorter windows) or cut it")
    if est["memory_bytes"] > max_memory_bytes:
        raise ValueError(f"{where}: {what} need about {est['memory_bytes'] / 2**30:.3g} GiB of memory{why}, over the "
                         f"limit of {max_memory_bytes / 2**30:.3g} GiB: {how}")
    if est["core_s"] > max_work_s:
        raise ValueError(f"{where}: {what} need about {est['core_s']:.3g} core-seconds of tuning{why}, over the "
                         f"limit of {max_work_s:.4g}: {how}")
    return est


def record_estimates(y, dt: float, *, d1=None, eps: float | None = None) -> dict:
    """The record's own noise level and curvature (see the module's text for the method).

    Parameters
    ----------
    y : array_like, shape (N,)
        The measurement, uniformly sampled (``N >= 4``).
    dt : float
        Sample period (s).
    d1 : array_like, shape (N,), optional
        The true derivative, when the record has it.
    eps : float, optional
        A stated noise bound: the allowance for noise in ``D_m`` then covers the most noise of that bound can put
        there, ``4ε/(m dt)²``, too (default: only the statistical allowance; for a quantised record also the most
        its quantisation error can put there).

    Returns
    -------
    dict
        ``noise_sigma`` (σ̂), ``noise_bound`` (ε̂ = √3 σ̂), ``accel`` (L̂, 0 when the record shows no curvature
        beyond its noise), ``accel_time`` (the sample time offset, s, where it is largest, or None),
        ``accel_scale_s`` (the averaging span ``m dt`` it was seen at), ``quantum`` (the step of a quantised
        record, else 0).

    Raises
    ------
    TypeError, ValueError
        ``y`` not a finite 1-D array of at least 4 samples, ``d1`` not of its shape, ``dt`` or ``eps`` not > 0, or a
        magnitude of ``y``, ``d1``, ``dt`` or ``eps`` outside :data:`SCALE_RANGE` (where the differences stay finite).

    Examples
    --------
    >>> t = 0.01 * np.arange(2000)
    >>> e = record_estimates(np.sin(t) + 0.01 * np.random.default_rng(0).uniform(-1, 1, t.size), 0.01)
    >>> 0.5 < e["noise_bound"] / 0.01 < 2, 0.3 < e["accel"] < 1.0
    (True, True)
    """
    y = np.asarray(check_finite("y", y))
    if y.ndim != 1 or y.size < 4:
        raise ValueError(f"y must be a 1-D array of at least 4 samples, got shape {y.shape}")
    dt = float(check_positive("dt", dt, scalar=True))
    if d1 is not None:
        d1 = np.asarray(check_finite("d1", d1))
        if d1.shape != y.shape:
            raise ValueError(f"d1 must have the shape of y {y.shape}, got {d1.shape}")
    if eps is not None:
        eps = float(check_positive("eps", eps, scalar=True))
    _scale("y's largest magnitude", float(np.max(np.abs(y))))  # where the differences below stay finite
    _scale("dt", dt)
    if d1 is not None:
        _scale("d1's largest magnitude", float(np.max(np.abs(d1))))
    if eps is not None:
        _scale("eps", eps)
    n = y.size
    y = y - np.median(y)
    d3 = np.diff(y, 3)
    sigma = 1.4826 * float(np.median(np.abs(d3 - np.median(d3)))) / math.sqrt(20.0) if d3.size else 0.0
    q = _quantum(y)
    sigma = max(sigma, q / math.sqrt(12.0))  # a quantiser of step q: noise uniform on ±q/2 where the signal moves
    rigid = max(q / 2.0, float(eps) if eps is not None else 0.0)  # bounded noise: at most 4 rigid/(m dt)² in D_m
    c = math.sqrt(2.0 * math.log(max(n, 2))) + 1.0
    cs = np.concatenate([[0.0], np.cumsum(y)])
    best, at, scale = 0.0, None, None
    ms = np.unique(np.round(np.geomspace(1, max(1, n // 4), 40)).astype(int))
    for m in (int(v) for v in ms):
        if 3 * m > n:
            continue
        a = (cs[m:] - cs[:-m]) / m if m > 1 else y  # moving averages over m samples
        D = (a[2 * m:] - 2.0 * a[m:-m] + a[:-2 * m]) / (m * dt) ** 2
        allowance = max(c * sigma * math.sqrt(6.0 / m), 4.0 * rigid) / (m * dt) ** 2
        k = int(np.argmax(np.abs(D)))
        lo = float(abs(D[k])) - allowance
        if lo > best:
            best, at, scale = lo, float((k + 1.5 * m - 0.5) * dt), float(m * dt)
    if d1 is not None:
        dd = np.abs(np.diff(d1)) / dt
        k = int(np.argmax(dd))
        if dd[k] > best:
            best, at, scale = float(dd[k]), float((k + 0.5) * dt), dt
    return {"noise_sigma": sigma, "noise_bound": math.sqrt(3.0) * sigma, "accel": best, "accel_time": at,
            "accel_scale_s": scale, "quantum": q}


def estimated_bounds(t, y, d1=None) -> dict:
    """Noise bound ε and bound L on |f''| from the record alone (:func:`record_estimates`), for a run without them.

    ``ε̂ = √3 σ̂`` (uniform noise of the spread the record's third differences show: for Gaussian noise of standard
    deviation σ it is √3 σ, not a bound, since Gaussian noise has none); ``L̂`` the curvature the record shows beyond
    its noise, a lower estimate of ``max |f''|`` (smoothed second differences, or the true derivative's differences
    where the record has it). The tuning's reference bandwidth ``√(L/ε)`` and the surrogate it is scored on come
    from them; the bound ``2√(εL)`` computed from them is an estimate too.

    Parameters
    ----------
    t, y : array_like, shape (N,)
        Uniformly sampled time and measurement.
    d1 : array_like, shape (N,), optional
        The true derivative, when the record has it.

    Returns
    -------
    dict
        ``noise_bound``, ``accel_bound`` and :func:`record_estimates`' values (``estimates``).

    Raises
    ------
    ValueError
        A record with no resolvable noise (ε̂ = 0: give the noise bound) or no curvature beyond its noise (L̂ = 0: give
        the bound on |f''|), naming what to give.
    """
    t = np.asarray(check_finite("t", t), dtype=float)
    if t.ndim != 1 or t.size < 4:
        raise ValueError(f"t must be a 1-D array of at least 4 samples, got shape {t.shape}")
    if np.shape(y) != t.shape:
        raise ValueError(f"y must have the shape of t {t.shape}, got {np.shape(y)}")
    dt = float(check_positive("t's median step", float(np.median(np.diff(t))), scalar=True))
    est = record_estimates(y, dt, d1=d1)
    # a smooth signal's own third differences reach 2 L dt²: a spread below that is not resolved noise
    if not est["noise_bound"] > 2.0 * est["accel"] * dt * dt:
        raise ValueError(f"the record shows no noise beyond its signal's own third differences (ε̂ = "
                         f"{est['noise_bound']:.3g}), so the noise bound cannot be estimated from it: give it")
    if not est["accel"] > 0:
        raise ValueError(f"the record shows no curvature beyond its noise (ε̂ = {est['noise_bound']:.3g}), so the "
                         "bound on |f''| cannot be estimated from it: give it")
    return {"noise_bound": float(est["noise_bound"]), "accel_bound": float(est["accel"]), "estimates": est}


def _quantum(y: np.ndarray) -> float:
    """The step of a quantised record (most steps zero, the others whole multiples of the smallest), else 0."""
    dy = np.abs(np.diff(y))
    steps = dy[dy > 0]
    if steps.size < 3 or np.mean(dy == 0) < 0.2:
        return 0.0
    r = steps / steps.min()
    return float(steps.min()) if np.mean(np.abs(r - np.round(r)) < 1e-3) > 0.9 else 0.0


def _scale(name: str, value: float, note: str = "") -> None:
    lo, hi = SCALE_RANGE
    if value != 0 and not lo <= abs(value) <= hi:
        raise ValueError(f"{name} is {value:.3g}, outside the magnitudes {lo:g} to {hi:g} in which the arena's "
                         f"arithmetic stays finite{note}: rescale the record (other units of time or of the signal) "
                         "and the bounds with it")


def _times(x: float) -> str:
    """A ratio as ``'1.2e+06×'`` or ``'35×'`` ('infinitely' past the float range)."""
    return f"{x:.3g}×" if math.isfinite(x) else "infinitely"


def _check_bounds(t, y, d1, eps: float, L: float, *, where: str, names: tuple) -> dict:
    """The stated bounds held against the record: errors raised, warnings returned.

    Parameters
    ----------
    t, y : numpy.ndarray, shape (N,)
        Uniformly sampled time and measurement (finite, ``N >= 4``).
    d1 : numpy.ndarray or None
        The true derivative, when the record has it.
    eps, L : float
        The stated noise bound and bound on ``|f''|``.
    where : str
        How the messages name the record.
    names : tuple of str
        How the messages name the bounds.

    Returns
    -------
    dict
        ``stated`` (``noise_bound``, ``accel_bound``), ``estimates`` (:func:`record_estimates`), ``warnings``
        (sentences), ``factor``.

    Raises
    ------
    ValueError
        A value, the time step, the duration or a bound outside :data:`SCALE_RANGE`; a bound tighter than the
        record by more than :data:`FACTOR`; the bounds' time scale ``√(ε/L)`` longer than the record.
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    eps, L = float(eps), float(L)
    dt = float(np.median(np.diff(t)))
    duration = float(t[-1] - t[0])
    for name, v in (("the largest |time| (t)", float(np.max(np.abs(t)))), ("the time step (t)", dt),
                    ("the record's duration (t)", duration),
                    ("the largest |measurement| (y)", float(np.max(np.abs(y)))),
                    *((("the largest |derivative| (d1)", float(np.max(np.abs(d1)))),) if d1 is not None else ())):
        _scale(f"{where}: {name}", v)
    est = record_estimates(y, dt, d1=d1)
    e_hat, l_hat = est["noise_bound"], est["accel"]
    own = f" (the record's own estimates: ε ≈ {e_hat:.3g}, |f''| ≈ {l_hat:.3g})"
    ne, nl = names
    _scale(ne, eps, own)
    _scale(nl, L, own)
    sure = record_estimates(y, dt, d1=d1, eps=eps)  # the curvature that not even noise of the stated bound explains
    problems = []
    if e_hat > FACTOR * (eps + max(L, l_hat) * dt * dt):
        problems.append(f"{ne} {eps:.3g} is far below the record's own noise: the spread of its third differences "
                        f"gives ε ≈ {e_hat:.3g} ({_times(e_hat / eps)} the bound); state a bound near it")
    if sure["accel"] > FACTOR * L:
        problems.append(f"{nl} {L:.3g} is far below what the record's y shows: beyond its noise, its smoothed second "
                        f"differences reach |f''| ≈ {sure['accel']:.3g} ({_times(sure['accel'] / L)} the bound, at "
                        f"t ≈ {t[0] + sure['accel_time']:.4g} s over {sure['accel_scale_s']:.3g} s); state a bound "
                        "near it (or, if that is a spike or a jump, remove it: it is beyond the noise bound)")
    if not problems and math.sqrt(eps / L) > duration:
        problems.append(f"the bounds' time scale √(ε/L) = {math.sqrt(eps / L):.3g} s is longer than the record "
                        f"({duration:.3g} s): no estimator tuned for them settles within it{own}; give a longer "
                        "record or check the bounds")
    if problems:
        raise ValueError(f"{where}: " + "; ".join(problems))
    warnings = []
    if eps > FACTOR * e_hat:
        warnings.append(f"{ne} {eps:.3g} is {_times(eps / e_hat) if e_hat > 0 else 'far'} above the record's own "
                        f"noise (ε ≈ {e_hat:.3g} from its third differences): the ranking is tuned for noise of the "
                        "stated bound, and errors below the bound 2√(εL) are to be expected on this record")
    if L > FACTOR * l_hat:
        seen = (f"|f''| ≈ {l_hat:.3g} beyond its noise" if l_hat > 0 else "no curvature beyond its noise")
        warnings.append(f"{nl} {L:.3g} is {_times(L / l_hat) if l_hat > 0 else 'far'} above what the record "
                        f"shows ({seen}): the ranking is tuned for the stated bound, and errors below the bound "
                        "2√(εL) are to be expected on this record")
    return {"stated": {"noise_bound": eps, "accel_bound": L}, "estimates": est, "warnings": warnings,
            "factor": FACTOR}


def _check_arrays(t, y, d1, eps, L) -> tuple:
    """``(t, y, d1, eps, L)`` as float arrays and floats, each checked as a CSV's columns are (errors name them)."""
    out = []
    for name, v in (("t", t), ("y", y), ("d1", d1)):
        if v is None and name == "d1":
            out.append(None)
            continue
        if isinstance(v, (str, bytes)):
            raise TypeError(f"{name} must be a 1-D array of real numbers, got {v!r:.80}")
        try:
            if np.iscomplexobj(v):  # asarray(dtype=float) would drop the imaginary part
                raise TypeError
            a = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be a 1-D array of real numbers, got {v!r:.80}") from None
        if a.ndim != 1:
            raise ValueError(f"{name} must be a 1-D array, got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name} contains NaN or infinite values")
        out.append(a)
    t, y, d1 = out
    if t.size < 20:
        raise ValueError(f"t must have at least 20 samples, got {t.size}")
    for name, a in (("y", y), ("d1", d1)):
        if a is not None and a.shape != t.shape:
            raise ValueError(f"{name} must have the length of t ({t.size}), got {a.size}")
    step = np.diff(t)
    if np.any(step <= 0):
        raise ValueError(f"t must be strictly increasing (sample {int(np.argmax(step <= 0)) + 1})")
    if np.max(np.abs(step - np.median(step))) > 0.01 * np.median(step):
        raise ValueError("t must be uniformly sampled (steps within 1 %)")
    eps = float(check_positive("eps", eps, scalar=True))
    L = float(check_positive("L", L, scalar=True))
    return t, y, d1, eps, L


def check_record(t, y, d1, eps: float, L: float, *, where: str = "the record",
                 names: tuple = ("eps", "L")) -> dict:
    """Every check of a record before the arena's work: its arrays, its scale, the bounds, the cost.

    Parameters
    ----------
    t, y : array_like, shape (N,)
        Time (strictly increasing, uniform steps within 1 %) and measurement, ``N >= 20``, finite.
    d1 : array_like, shape (N,), or None
        The true derivative, when the record has it.
    eps, L : float
        The stated noise bound and bound on ``|f''|`` (finite, > 0).
    where : str
        How the messages name the record.
    names : tuple of str
        How the messages name the two bounds (the command line: ``("--noise-bound", "--accel-bound")``).

    Returns
    -------
    dict
        ``stated`` (``noise_bound``, ``accel_bound``), ``estimates`` (:func:`record_estimates`), ``warnings``
        (sentences: a bound looser than the record by more than :data:`FACTOR`), ``factor``, ``cost``
        (:func:`work_estimate`).

    Raises
    ------
    TypeError, ValueError
        A malformed array or bound (naming it); one sentence for a refused record: a value, the time step, the
        duration or a bound outside :data:`SCALE_RANGE`, a bound tighter than the record by more than
        :data:`FACTOR` (with the record's own estimate), the bounds' time scale longer than the record, or a
        run over :data:`MAX_ROWS`, :data:`MAX_WORK_S` or :data:`MAX_MEMORY_BYTES` (with the estimate, the
        limit and how to get under it).

    Examples
    --------
    >>> t = 0.01 * np.arange(600)
    >>> y = np.sin(t) + 0.01 * np.random.default_rng(0).uniform(-1, 1, t.size)
    >>> check_record(t, y, None, 0.01, 1.0)["warnings"]
    []
    >>> check_record(t, y, None, 0.01, 1e-6)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: the record: L 1e-06 is far below what the record's y shows: ...
    """
    t, y, d1, eps, L = _check_arrays(t, y, d1, eps, L)
    if not isinstance(where, str) or not isinstance(names, tuple) or len(names) != 2 \
            or not all(isinstance(x, str) for x in names):
        raise TypeError(f"where must be a string and names two strings, got {where!r:.40} and {names!r:.40}")
    checked = _check_bounds(t, y, d1, eps, L, where=where, names=names)
    dt = float(np.median(np.diff(t)))
    checked["cost"] = _check_budget(t.size, dt, eps, L, derivative=d1 is not None, where=where)
    return checked
