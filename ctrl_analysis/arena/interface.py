"""The arena's common interface: every estimator family estimates ``f`` and ``f'`` from noisy samples.

A :class:`Family` names an estimator of the library, its tuning parameters (each with a reference
value set by the case's noise bound ``ε``, acceleration bound ``L`` and sample period ``dt``, and a
search range around it) and a runner: :func:`estimate` takes one row of parameters per run and one
measured record per run and returns the estimates of the signal and its first derivative (and, where
the family can, its second) at every sample, from all runs in one batch.

The batch is run by the library's engine (:class:`~ctrl_analysis.engine.loop.Loop`, ``engine="auto"``: the
compiled path with **per-run kernel parameters**), so a tuning grid is one simulation of many runs:
each family is a library block (:class:`~ctrl_analysis.estimators.differential.DifferentialEstimator`,
:class:`~ctrl_analysis.estimators.eso.ExtendedStateObserver`,
:class:`~ctrl_analysis.estimators.tracking.TrackingDifferentiator`,
:class:`~ctrl_analysis.estimators.kalman.alpha_beta.AlphaBetaFilter`,
:class:`~ctrl_analysis.estimators.lowpass.DiscreteLowPass`,
:class:`~ctrl_analysis.estimators.levant.LevantDifferentiator`, and the α-β-γ kernels ``alpha_beta_gamma_output``
and ``singer_update`` (constant acceleration at ``τ_m = ∞``, Singer's model otherwise) in a small block here) whose
per-run values go through ``Loop.simulate(params={"est": {...}})``. The continuous families' runs are grouped by
their RK4 substeps (:func:`substeps_for`) and ``sigman``'s by Σ's order, one loop per group. The algebraic
differentiator (:mod:`.algebraic`) is an FIR filter run with vectorised numpy; the offline smoothers
(:data:`OFFLINE`, :mod:`.offline`) read the whole record.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_finite, check_in, check_positive
from ..engine import Execution, Save
from ..engine.blocks import DiscreteBlock, signal_names
from ..engine.kernels import KernelBlock, Kernels
from ..engine.loop import Loop, place
from ..estimators.differential import DifferentialEstimator
from ..estimators.eso import ExtendedStateObserver
from ..estimators.kalman.alpha_beta import (
    AlphaBetaFilter,
    alpha_beta_gamma_gains,
    alpha_beta_gamma_output,
    kalata_gains,
)
from ..estimators.kalman.singer import singer_gains, singer_transition, singer_update
from ..estimators.levant import LevantDifferentiator
from ..estimators.lowpass import DiscreteLowPass, LowPassFilter
from ..estimators.tracking import TrackingDifferentiator
from ..polynomials import repeated_pole_coefficients
from .algebraic import MAX_WINDOW, algebraic_derivative
from .offline import rts_smoother, savgol_smoother, spline_smoother

__all__ = ["FAMILIES", "GIVEN", "INITS", "OFFLINE", "SIGMA_ORDER", "SIGMA_ORDERS_TUNED", "Family", "Param", "estimate",
           "family", "scales", "substeps_for"]

#: Integration substeps (RK4) per sample for the continuous families whose fastest pole has ``ω dt <= OMEGA_DT_RK4``;
#: a faster run takes ``SUBSTEPS`` more per ``OMEGA_DT_RK4`` (:func:`substeps_for`).
SUBSTEPS = 2
#: The fastest pole that RK4 with :data:`SUBSTEPS` substeps per sample integrates accurately: ``ω h <= 0.5`` per step.
OMEGA_DT_RK4 = 1.0
#: The fastest pole any family is tuned to, ``OMEGA_DT_MAX / dt``: far beyond the Nyquist rate ``π/dt`` a faster
#: estimator only follows the held samples more closely, with the error of a one-sample difference.
OMEGA_DT_MAX = 8.0
#: How a causal family starts (:func:`estimate`'s ``init``): ``"first"``, at rest on the first sample (the state a
#: constant record ``y_0`` holds: ``f̂ = y_0``, every derivative 0; the FIR window sees ``y_0`` before the record);
#: ``"zero"``, from the zero state (the FIR window sees zeros before the record), as the papers' estimators start.
INITS = ("first", "zero")
#: A pole capped at ``OMEGA_DT_MAX / (n0 dt)`` gives back ``n0 a dt`` a few ulps above the cap: accepted.
_CAP_ROUNDING = 1.0 + 1e-12


@dataclass(frozen=True)
class Param:
    """One tuning parameter: a reference value (from the case's scales) and a search range around it.

    Attributes
    ----------
    name : str
    ref : str
        Which scale sets the reference: ``"omega"`` (``√(L/ε)``, rad/s), ``"tau"`` (``1/√(L/ε)``, s),
        ``"eps"``, ``"L"``, ``"lambda"`` (Kalata's α-β index at ``ω = √(L/ε)``: ``(ω dt)²``),
        ``"lambda3"`` (the α-β-γ index at that ``ω``: ``(ω dt)³``, for small ``Λ`` the third gain is
        ``γ/(2T²) ≈ ω³ T``), ``"window"`` (samples spanning ``2/ω``), ``"lam"`` (a smoothing spline's penalty
        with cut-off ``ω``: ``1/(dt ω⁴)``) or ``"given"`` (no reference: a value
        of an estimator run at given parameters only, :data:`GIVEN`).
    lo, hi : float
        Search range as multiples of the reference (log scale); for ``"given"``, the values allowed,
        ``(lo, hi]``.
    integer : bool
        Rounded to an integer (and to ``>= 2`` for a window).
    points : int, optional
        Grid points over the range (:func:`~ctrl_analysis.arena.tuning.param_values`' search); default 9 for a
        family's only parameter, 5 for each of two.
    """

    name: str
    ref: str
    lo: float
    hi: float
    integer: bool = False
    points: int | None = None


@dataclass(frozen=True)
class Family:
    """An estimator family of the arena: a library estimator, its tuning parameters and its outputs.

    Attributes
    ----------
    name : str
        Short name (CLI, results ids).
    label : str
        What it is, for reports and figures.
    params : tuple of Param
    second : bool
        Whether it also estimates ``f''``.
    source : str
        The library code it runs.
    fixed : dict
        Settings that are not tuned.
    causal : bool
        Whether its estimate at ``t`` uses the samples up to ``t`` only (:data:`FAMILIES`), or the whole record
        (:data:`OFFLINE`).
    """

    name: str
    label: str
    params: tuple
    second: bool
    source: str
    fixed: dict = field(default_factory=dict)
    causal: bool = True


#: Σ's order ``n0`` per family; its fastest closed-loop pole is the breakaway double pole ``-n0 a``.
SIGMA_ORDER = {"sigma": 3, "sigma5": 5}
#: The orders the family ``sigman`` chooses from (tuned; parameterised by its fastest pole ``n0 a``).
SIGMA_ORDERS_TUNED = (3, 6)
#: Han's fal exponents of the 3-state NESO (Han 2009; the textbook choice 1, 1/2, 1/4).
NESO_ALPHA = (1.0, 0.5, 0.25)

FAMILIES = (
    Family("sigma", "Σ, n0 = 3 (breakaway gain)", (Param("a", "omega", 0.1 / 3, 10.0 / 3),), True,
           "estimators.differential.DifferentialEstimator + _kernels.sigma_rhs"),
    # the differential-estimator paper's own order: its double pole at the breakaway point -5a is the fastest
    Family("sigma5", "Σ, n0 = 5 (breakaway gain; the differential-estimator paper's order)",
           (Param("a", "omega", 0.1 / 5, 10.0 / 5),), True,
           "estimators.differential.DifferentialEstimator(5) + _kernels.sigma_rhs"),
    # n0 as a tuned choice: the fastest pole p = n0 a and n0 itself (a = p / n0), every order on the same pole grid
    Family("sigman", f"Σ, n0 tuned ({SIGMA_ORDERS_TUNED[0]} to {SIGMA_ORDERS_TUNED[1]}; breakaway gain, pole n0 a)",
           (Param("pole", "omega", 0.1, 10.0, points=9), Param("n0", "one", *SIGMA_ORDERS_TUNED, integer=True)),
           True, "estimators.differential.DifferentialEstimator(n0, pole / n0) + _kernels.sigma_rhs"),
    Family("leso2", "linear ESO, 2 states (ω_o)", (Param("omega_o", "omega", 0.1, 10.0),), False,
           "estimators.eso.ExtendedStateObserver.from_bandwidth(1, ω_o) + _kernels.eso_rhs"),
    Family("leso3", "linear ESO, 3 states (ω_o)", (Param("omega_o", "omega", 0.1, 10.0),), True,
           "estimators.eso.ExtendedStateObserver.from_bandwidth(2, ω_o) + _kernels.eso_rhs"),
    Family("neso", "fal ESO (NESO), α = 1, 1/2, 1/4", (Param("omega_o", "omega", 0.1, 10.0),
                                                        Param("delta", "eps", 0.3, 100.0)), True,
           "estimators.eso.ExtendedStateObserver(alpha, delta) + _kernels.eso_rhs",
           {"alpha": NESO_ALPHA}),
    Family("td", "Han's tracking differentiator (r, h0)", (Param("r", "L", 0.5, 50.0),
                                                           Param("h0", "tau", 0.1, 10.0)), False,
           "estimators.tracking.TrackingDifferentiator (td_output, td_update)"),
    Family("levant", "Levant's robust exact differentiator, order 1 (L)", (Param("L", "L", 0.5, 50.0),), False,
           "estimators.levant.LevantDifferentiator(1, L, dt) (explicit Euler, one step per sample)"),
    Family("kalman", "steady-state Kalman α-β (Kalata's Λ)", (Param("Lambda", "lambda", 0.001, 1000.0),), False,
           "estimators.kalman.AlphaBetaFilter with kalata_gains(Λ)"),
    Family("abg", "steady-state Kalman α-β-γ (Kalata's Λ, constant acceleration)",
           (Param("Lambda", "lambda3", 0.001, 1000.0),), True,
           "estimators.kalman: alpha_beta_gamma_gains(Λ) + alpha_beta_gamma_output, singer_update (τ_m = ∞)"),
    # beyond constant acceleration: Singer's manoeuvre model, from near-white acceleration (τ_m ~ dt, an α-β-like
    # filter) to constant acceleration (τ_m >> the record, the abg family)
    Family("singer", "steady-state Kalman α-β-γ, Singer manoeuvre model (Kalata's Λ, time constant τ_m)",
           # Λ on abg's 9-point grid: the constant-acceleration filter (τ_m large) is then among the grid's points
           (Param("Lambda", "lambda3", 0.001, 1000.0, points=9), Param("tau_m", "tau", 0.1, 1000.0)), True,
           "estimators.kalman.singer: singer_gains(Λ, dt/τ_m) + alpha_beta_gamma_output, singer_update"),
    Family("difflp", "backward difference + low-pass, order 2 (ω)", (Param("omega", "omega", 0.1, 10.0),), False,
           "estimators.lowpass.DiscreteLowPass on [y, Δy/dt]"),
    Family("algebraic", "causal Savitzky–Golay / algebraic (window, degree)",
           (Param("window", "window", 0.1, 10.0, integer=True), Param("degree", "one", 1.0, 2.0, integer=True)),
           True, "arena.algebraic.algebraic_derivative (FIR, vectorised numpy)"),
)

#: Offline smoothers of a whole record (:mod:`.offline`), tuned like the causal families and ranked apart from them:
#: what a recorded signal's derivative is, not what an online filter can know.
OFFLINE = (
    Family("sg", "Savitzky–Golay, centred (window, degree)",
           (Param("window", "window", 0.3, 30.0, integer=True), Param("degree", "one", 2.0, 4.0, integer=True)),
           True, "scipy.signal.savgol_filter (mode='interp')", causal=False),
    Family("spline", "smoothing spline (λ of ∫ s''²)", (Param("lam", "lam", 1e-4, 1e4),), True,
           "scipy.interpolate.make_smoothing_spline", causal=False),
    Family("rts", "RTS smoother, constant velocity, steady state (Kalata's Λ)",
           (Param("Lambda", "lambda", 0.001, 1000.0),), False,
           "arena.offline.rts_smoother: steady α-β filter forward, steady RTS gain backward", causal=False),
    Family("rts3", "RTS smoother, constant acceleration, steady state (Kalata's Λ)",
           (Param("Lambda", "lambda3", 0.001, 1000.0),), True,
           "arena.offline.rts_smoother(order=3): steady α-β-γ filter forward, steady RTS gain backward",
           causal=False),
)

#: Estimators run at given parameters only, never tuned: a paper's printed gains, as a fixed configuration
#: ``(name, parameters)`` of a claim check (:mod:`.claims`) or :func:`estimate`. A ``"given"`` parameter is used as
#: given, within ``(lo, hi]``.
GIVEN = (
    Family("ab", "α-β filter at given gains (α, β), e.g. a paper's printed ones",
           (Param("alpha", "given", 0.0, 2.0), Param("beta", "given", 0.0, 4.0)), False,
           "estimators.kalman.AlphaBetaFilter(α, β, dt)"),
)


def family(name: str, *, given: bool = False) -> Family:
    """The family called ``name``.

    Parameters
    ----------
    name : str
        One of the names in :data:`FAMILIES` or :data:`OFFLINE` (or :data:`GIVEN` with ``given=True``).
    given : bool
        Accept the estimators run at given parameters only (:data:`GIVEN`), which are not tuned.

    Returns
    -------
    Family

    Raises
    ------
    ValueError
        For an unknown name (the message lists the names).
    """
    known = FAMILIES + OFFLINE + GIVEN if given else FAMILIES + OFFLINE
    names = [f.name for f in known]
    check_in("family name", name, names)
    return known[names.index(name)]


def scales(eps: float, L: float, dt: float) -> dict:
    """Reference values of the tuning parameters for noise bound ``eps`` and acceleration bound ``L``.

    ``ω = √(L/ε)`` balances a linear differentiator's lag error (``∝ L/ω``) against its noise error
    (``∝ ε ω``); every family's search range is set around it (and capped at ``ω dt <=`` :data:`OMEGA_DT_MAX`).

    Parameters
    ----------
    eps, L, dt : float
        Noise bound, bound on ``|f''|``, sample period (all > 0).

    Returns
    -------
    dict
        ``omega, tau, eps, L, lambda, lambda3, window, one, dt``, and ``lam`` (the smoothing spline's penalty
        ``1/(dt ω⁴)``, whose cut-off is ``ω``; it may be 0 or infinite at extreme magnitudes, where only the
        spline family cannot run).

    Raises
    ------
    TypeError, ValueError
        A bound or ``dt`` that is not a number > 0, or magnitudes whose references overflow or underflow.

    Examples
    --------
    >>> s = scales(0.01, 4.0, 0.002)
    >>> round(s["omega"], 6), s["window"]
    (20.0, 50.0)
    """
    eps = float(check_positive("eps", eps, scalar=True))
    L = float(check_positive("L", L, scalar=True))
    dt = float(check_positive("dt", dt, scalar=True))
    try:
        omega = float(np.sqrt(L / eps))
        out = {"omega": omega, "tau": 1.0 / omega, "eps": eps, "L": L, "lambda": (omega * dt) ** 2,
               "lambda3": (omega * dt) ** 3, "window": round(2.0 / omega / dt, 6), "one": 1.0, "dt": dt}
    except (OverflowError, ZeroDivisionError):
        out = {"omega": math.nan}
    # the smoothing spline's λ (cut-off ω: λ dt ω⁴ = 1), only the spline needs it: its own check is param_values'
    with np.errstate(over="ignore", under="ignore", divide="ignore"):
        lam = float(1.0 / (dt * np.float64(out.get("omega", math.nan)) ** 4))
    if not all(math.isfinite(v) and (v > 0 or k == "window") for k, v in out.items()):
        raise ValueError(f"eps, L and dt (eps = {eps:.3g}, L = {L:.3g}, dt = {dt:.3g}) give reference values beyond "
                         "double precision (ω = √(L/ε), 1/ω and (ω dt)³ must be finite and > 0): express the signal "
                         "and time in other units")
    out["lam"] = lam
    return out


def substeps_for(omega_dt) -> np.ndarray:
    """RK4 substeps per sample for a continuous family whose fastest pole is ``omega_dt / dt``.

    :data:`SUBSTEPS` for every :data:`OMEGA_DT_RK4` of ``ω dt`` begun (``ω h <= 0.5`` per substep), at least
    :data:`SUBSTEPS`: a run's integration accuracy does not depend on the other runs of its batch.

    Parameters
    ----------
    omega_dt : array_like
        ``ω dt`` per run (finite, > 0, at most :data:`OMEGA_DT_MAX`).

    Returns
    -------
    numpy.ndarray of int

    Raises
    ------
    TypeError, ValueError
        If ``omega_dt`` is not numbers > 0 and at most :data:`OMEGA_DT_MAX`.

    Examples
    --------
    >>> substeps_for([0.3, 1.0, 1.5, 8.0]).tolist()
    [2, 2, 4, 16]
    """
    w = np.asarray(check_positive("omega_dt", omega_dt), dtype=float)
    if np.any(w > OMEGA_DT_MAX * _CAP_ROUNDING):
        raise ValueError(f"omega_dt must be <= OMEGA_DT_MAX = {OMEGA_DT_MAX:g}, got up to {np.max(w):.4g}")
    return SUBSTEPS * np.maximum(1, np.ceil(w / OMEGA_DT_RK4 - 1e-12)).astype(int)


# ---------------------------------------------------------------------------------------- blocks
class _AlphaBetaGamma(KernelBlock, DiscreteBlock):
    """Constant-gain α-β-γ filter: the library's kernels ``alpha_beta_gamma_output`` and ``singer_update`` with gains
    ``α, β, γ`` and Singer's decay ``s = T/τ_m`` (0, the default: constant acceleration, ``alpha_beta_gamma_update``'s
    prediction to the last bit).

    Block signals: input ``y``; states ``xpred[0..2]``; outputs ``xhat[0..2]``.
    """

    inputs, states, outputs = ("y",), ("xpred[0]", "xpred[1]", "xpred[2]"), ("xhat[0]", "xhat[1]", "xhat[2]")
    feedthrough = True
    kernels = Kernels(output=alpha_beta_gamma_output, update=singer_update)

    def __init__(self, alpha: float, beta: float, gamma: float, T: float, decay: float = 0.0):
        T = float(check_positive("T", T, scalar=True))
        a, b, rho = singer_transition(decay)
        self.kernel_params = np.array([alpha, beta / T, gamma / (2.0 * T * T), T, a * T * T, b * T, rho], dtype=float)

    def initial_state(self):
        return np.zeros(3)


class _LowPass(DiscreteLowPass):
    """:class:`~ctrl_analysis.estimators.lowpass.DiscreteLowPass` from its corner ``omega`` (a number, per run)."""

    def __init__(self, omega: float, h: float, order: int = 2, channels: int = 2):
        super().__init__(LowPassFilter(omega, order), h, channels=channels)


def _abg_gains(lam: np.ndarray) -> tuple:
    """α, β, γ per run from :func:`~ctrl_analysis.estimators.kalman.alpha_beta.alpha_beta_gamma_gains` (one batched
    DARE solve for the values not seen before; cached per ``Λ``)."""
    new = sorted({float(x) for x in lam} - _ABG_CACHE.keys())
    if new:
        for x, *g in zip(new, *alpha_beta_gamma_gains(np.array(new)), strict=True):
            _ABG_CACHE[x] = tuple(float(v) for v in g)
    return tuple(np.array(v) for v in zip(*(_ABG_CACHE[float(x)] for x in lam), strict=True))


#: Λ -> (α, β, γ), filled by :func:`_abg_gains`
_ABG_CACHE: dict = {}


def _singer_gains(lam: np.ndarray, decay: np.ndarray) -> tuple:
    """α, β, γ per run from :func:`~ctrl_analysis.estimators.kalman.singer.singer_gains` (cached per ``(Λ, s)``)."""
    keys = list(zip(lam.tolist(), decay.tolist(), strict=True))
    new = sorted(set(keys) - _SINGER_CACHE.keys())
    if new:
        got = singer_gains(np.array([k[0] for k in new]), np.array([k[1] for k in new]))
        for k, *g in zip(new, *got, strict=True):
            _SINGER_CACHE[k] = tuple(float(v) for v in g)
    return tuple(np.array(v) for v in zip(*(_SINGER_CACHE[k] for k in keys), strict=True))


#: (Λ, s) -> (α, β, γ), filled by :func:`_singer_gains`
_SINGER_CACHE: dict = {}


# ---------------------------------------------------------------------------------------- running
def _build(fam: Family, P: np.ndarray, dt: float):
    """``(block, input names, output names, per-run values)`` for the family with per-run parameter rows ``P``.

    The block is built with the first run's values; the per-run values (``Loop.simulate(params=...)``)
    rebuild it per distinct value, one kernel parameter row per run.
    """
    if fam.name in SIGMA_ORDER or fam.name == "sigman":
        # f, f', f'' are its first three estimates; sigman's runs share one n0 here (estimate groups them)
        n0 = SIGMA_ORDER[fam.name] if fam.name in SIGMA_ORDER else int(P[0, 1])
        a = P[:, 0] / (1 if fam.name in SIGMA_ORDER else n0)
        return DifferentialEstimator(n0, a[0]), ("y",), signal_names("xhat", n0), {"a": a}
    if fam.name in ("leso2", "leso3", "neso"):
        m = 2 if fam.name == "leso2" else 3
        gains = np.array([repeated_pole_coefficients(m, w)[1:] for w in P[:, 0]])
        if fam.name != "neso":
            eso = ExtendedStateObserver(gains[0], allow_unstable=True)
            return eso, ("y", "u"), signal_names("xhat", m), {"gains": gains}
        alpha = np.array(fam.fixed["alpha"])
        delta = P[:, 1]
        # linear zone (|e| <= δ) equal to the linear ESO of bandwidth ω_o: L_i δ^(α_i - 1) = C(3, i) ω_o^i
        gains = gains * np.power(delta[:, None], 1.0 - alpha)
        eso = ExtendedStateObserver(gains[0], alpha=alpha, delta=delta[0], allow_unstable=True)
        return eso, ("y", "u"), signal_names("xhat", 3), {"gains": gains, "delta": delta}
    if fam.name == "td":
        td = TrackingDifferentiator(P[0, 0], dt, P[0, 1])
        return td, ("v",), ("x[0]", "x[1]"), {"r": P[:, 0], "h0": P[:, 1]}
    if fam.name == "kalman":
        alpha, beta = kalata_gains(P[:, 0])
        return AlphaBetaFilter(alpha[0], beta[0], dt), ("y",), ("xhat[0]", "xhat[1]"), {"alpha": alpha, "beta": beta}
    if fam.name == "levant":
        return LevantDifferentiator(1, P[0, 0], dt), ("f",), ("z[0]", "z[1]"), {"L": P[:, 0]}
    if fam.name == "ab":
        return (AlphaBetaFilter(P[0, 0], P[0, 1], dt), ("y",), ("xhat[0]", "xhat[1]"),
                {"alpha": P[:, 0], "beta": P[:, 1]})
    if fam.name == "abg":
        alpha, beta, gamma = _abg_gains(P[:, 0])
        block = _AlphaBetaGamma(alpha[0], beta[0], gamma[0], dt)
        return block, ("y",), ("xhat[0]", "xhat[1]", "xhat[2]"), {"alpha": alpha, "beta": beta, "gamma": gamma}
    if fam.name == "singer":
        decay = dt / P[:, 1]
        alpha, beta, gamma = _singer_gains(P[:, 0], decay)
        block = _AlphaBetaGamma(alpha[0], beta[0], gamma[0], dt, decay[0])
        return block, ("y",), ("xhat[0]", "xhat[1]", "xhat[2]"), {"alpha": alpha, "beta": beta, "gamma": gamma,
                                                                   "decay": decay}
    if fam.name == "difflp":
        return _LowPass(P[0, 0], dt), ("u[0]", "u[1]"), ("w[0]", "w[1]"), {"omega": P[:, 0]}
    raise ValueError(f"family {fam.name!r} has no loop")  # pragma: no cover


def _check_params(fam: Family, P: np.ndarray) -> None:
    """Every tuning parameter > 0; integer parameters integral; a degree (reference ``"one"``) within its range, a
    window at most :data:`~ctrl_analysis.arena.algebraic.MAX_WINDOW`."""
    for j, p in enumerate(fam.params):
        col = P[:, j]
        if np.any(col <= 0):
            raise ValueError(f"P column {j} ({fam.name} parameter {p.name}) must be > 0, got {col.tolist()!r:.80}")
        if p.integer and np.any(col != np.round(col)):
            raise ValueError(f"P column {j} ({fam.name} parameter {p.name}) must be integers, got {col.tolist()!r:.80}")
        if p.ref == "one" and np.any((col < p.lo) | (col > p.hi)):
            raise ValueError(f"P column {j} ({fam.name} parameter {p.name}) must be in [{p.lo:g}, {p.hi:g}], "
                             f"got {col.tolist()!r:.80}")
        if p.ref == "given" and np.any(col > p.hi):
            raise ValueError(f"P column {j} ({fam.name} parameter {p.name}) must be in ({p.lo:g}, {p.hi:g}], "
                             f"got {col.tolist()!r:.80}")
        if p.ref == "window" and np.any(col > MAX_WINDOW):
            raise ValueError(f"P column {j} ({fam.name} parameter {p.name}) must be <= MAX_WINDOW = {MAX_WINDOW} "
                             f"samples, got {col.tolist()!r:.80}")


def estimate(fam, P, y, dt: float, *, engine: str = "auto", init: str = "first") -> np.ndarray:
    """Estimates of ``f``, ``f'`` (and ``f''`` where the family gives it) from the records ``y``, one run per column.

    Parameters
    ----------
    fam : Family or str
        The estimator family.
    P : array_like, shape (B, n_params)
        One row of tuning parameters per run (the family's ``params`` order).
    y : array_like, shape (N, B)
        Measured samples at ``t_k = k dt``, one record per run.
    dt : float
        Sample period (> 0).
    engine : {"auto", "numpy", "compiled"}
        The engine of :meth:`Loop.simulate` (the algebraic family always runs vectorised numpy).
    init : {"first", "zero"}
        How a causal family starts (:data:`INITS`): at rest on each record's first sample (default: ``f̂ = y_0``
        and every derivative estimate 0, so the start-up error of ``f̂'`` begins at ``|f'(0)|``), or from the zero
        state (``f̂ = 0``: a start-up peak that grows with ``|y_0|``). The derivative is not started from a
        difference of the first samples: with noise bound ``ε`` that difference errs by up to ``2ε/dt``. The
        offline families (:data:`OFFLINE`) read the whole record and ignore it.

    Returns
    -------
    numpy.ndarray, shape (N, B, k)
        ``k = 3`` (``f, f', f''``) for families with ``second``, else 2; row ``k`` uses the samples
        up to ``t_k`` only (causal).

    Raises
    ------
    TypeError, ValueError
        If ``fam`` is not a family, the shapes of ``P`` and ``y`` disagree, a value is not finite, a
        parameter is not > 0 (an integer parameter not an integer, a degree not 1 or 2, a window over
        :data:`~ctrl_analysis.arena.algebraic.MAX_WINDOW`) or builds no valid estimator (gains that overflow),
        ``dt <= 0``, ``engine`` or ``init`` is unknown, or a continuous family's fastest pole is beyond
        :data:`OMEGA_DT_MAX` ``/ dt`` (it is integrated with :func:`substeps_for` RK4 steps per sample).

    Examples
    --------
    >>> import numpy as np
    >>> t = 0.01 * np.arange(400)
    >>> est = estimate("leso2", [[20.0]], (2.0 * t)[:, None], 0.01)
    >>> round(float(est[-1, 0, 1]), 2)   # a ramp of slope 2 (the input is held over each sample)
    1.99
    """
    if isinstance(fam, str):
        fam = family(check_in("fam (family name)", fam, [f.name for f in FAMILIES + OFFLINE + GIVEN]), given=True)
    elif not isinstance(fam, Family):
        raise TypeError(f"fam must be a Family or a family name, got {fam!r:.80}")
    dt = float(check_positive("dt", dt, scalar=True))
    check_in("engine", engine, ("auto", "numpy", "compiled"))
    check_in("init", init, INITS)
    P = np.atleast_2d(check_finite("P", P))
    y = np.asarray(check_finite("y", y))
    if y.ndim != 2 or P.ndim != 2 or P.shape != (y.shape[1], len(fam.params)):
        raise ValueError(f"P must have shape (B, {len(fam.params)}) and y shape (N, B) with the same B, "
                         f"got P {P.shape} and y {y.shape}")
    _check_params(fam, P)
    N, B = y.shape
    k = 3 if fam.second else 2
    if fam.name == "algebraic":
        return algebraic_derivative(y, P[:, 0].astype(int), P[:, 1].astype(int), dt, before=init)
    if fam.name == "sg":
        return savgol_smoother(y, P[:, 0].astype(int), P[:, 1].astype(int), dt)
    if fam.name == "spline":
        return spline_smoother(y, P[:, 0], dt)
    if fam.name in ("rts", "rts3"):
        return rts_smoother(y, P[:, 0], dt, order=2 if fam.name == "rts" else 3)
    if fam.name not in SIGMA_ORDER and fam.name not in ("sigman", "leso2", "leso3", "neso"):
        return _run(fam, P, y, dt, engine, init, 1)
    # continuous: RK4 substeps per run from its fastest pole (Σ: the double pole -n0 a, sigman's first parameter;
    # the ESOs: -ω_o); runs grouped by their substeps (and sigman's by n0: one block order per loop)
    fastest = P[:, 0] * SIGMA_ORDER.get(fam.name, 1) * dt
    if np.any(fastest > OMEGA_DT_MAX * _CAP_ROUNDING):
        raise ValueError(f"P column 0 ({fam.name} parameter {fam.params[0].name}) must put the fastest pole within "
                         f"OMEGA_DT_MAX / dt (ω dt <= {OMEGA_DT_MAX:g}: beyond the sample rate a faster estimator "
                         f"only follows the held samples), got ω dt up to {np.max(fastest):.4g}")
    steps = substeps_for(fastest)
    group = steps * 100 + (P[:, 1].astype(int) if fam.name == "sigman" else 0)
    if np.all(group == group[0]):
        return _run(fam, P, y, dt, engine, init, int(steps[0]))
    out = np.empty((N, B, k))
    for g in np.unique(group):
        cols = np.flatnonzero(group == g)
        out[:, cols] = _run(fam, P[cols], y[:, cols], dt, engine, init, int(steps[cols[0]]))
    return out


def _run(fam, P, y, dt, engine, init, substeps) -> np.ndarray:
    """:func:`estimate` of a loop family (checked arguments), every run with ``substeps`` per sample."""
    N, B = y.shape
    k = 3 if fam.second else 2
    try:
        block, ins, outs, per_run = _build(fam, P, dt)
    except ValueError as exc:  # a block's own check (gains overflowing, an unstable filter): the values come from P
        raise ValueError(f"P ({fam.name} parameters {', '.join(p.name for p in fam.params)}) gives no valid "
                         f"estimator: {exc}") from None
    loop = Loop([place(block, "est", inputs=[f"_{s}" for s in block.inputs], outputs=list(outs))], dt,
                substeps=substeps)
    inputs = {f"_{ins[0]}": y}
    if fam.name in ("leso2", "leso3", "neso"):
        inputs["_u"] = 0.0
    if fam.name == "difflp":
        dy = np.zeros_like(y)
        dy[1:] = np.diff(y, axis=0) / dt  # backward difference (y_k - y_(k-1)) / dt
        inputs = {"_u[0]": y, "_u[1]": dy}
    x0 = None
    if init == "first":  # at rest on y_0: every block's state 0 is its estimate of f, the others its derivatives
        x0 = np.zeros((B, len(block.states)))
        x0[:, 0] = y[0]
        x0 = {"est": x0}
    res = loop.simulate(N, inputs=inputs, x0=x0, save=Save(states=False, keep=list(outs[:k])),
                        execution=Execution(chunk_runs=B, engine=engine, progress=False, bound=np.inf),
                        params={"est": per_run})
    out = np.empty((N, B, k))
    for j, s in enumerate(outs[:k]):
        out[:, :, j] = res.signals[s][:N]
    return out
