"""The `ckf` closed loops, built from library blocks through :class:`ctrl_analysis.engine.loop.Loop`.

One loop holds every case side by side on the batch axis: plant, measurement, the digital LPF (and one
at half its cut-off, never fed back, for the bandwidth claim), the CKF, the identification (regressor +
RLS) and the golden-section controller all run in every run; per-run selection weights (given to the
simulation, :func:`run_params`) say which signal is fed back (raw, LPF or CKF, raw before ``t_filter``)
and which one forms the identification's ``z`` and ``h``. Run ``b`` of the batch is therefore exactly the
loop of its case alone, and the three cases see the same noise.

The reconstructions the plausible box varies that do not change the loop's structure (:data:`PER_RUN`:
the LPF's cut-off, the CKF's Q and P0, every RLS setting, the controller's k_I, c2 and μ, the
identification signals) are per-run parameters too, so :func:`simulate_specs` runs many points of the
box on the batch axis of one simulation (:func:`analysis.ckf.evaluate_many`).
"""

from __future__ import annotations

import functools

import numpy as np

from ctrl_analysis._validate import check_finite, check_names
from ctrl_analysis.controllers.golden_section import GoldenSectionController
from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.blocks import DiscreteBlock, StaticBlock, StaticGain
from ctrl_analysis.engine.kernels import KernelBlock, Kernels, Layout
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.kalman import CharacteristicKalmanFilter
from ctrl_analysis.estimators.lowpass import DiscreteLowPass, LowPassFilter
from ctrl_analysis.identification import ArxRegressor, RecursiveLeastSquaresBlock
from ctrl_analysis.noise import draw_noise, gaussian_noise, run_seeds
from ctrl_analysis.plants import DiscreteLTI

__all__ = [
    "BOX_SIGNALS",
    "CASES",
    "ID_OPTIONS",
    "PER_RUN",
    "SIGNALS",
    "STATS",
    "STATS_SUMS",
    "SWITCH",
    "T_TRANSIENT",
    "CutoffLowPass",
    "FeedbackSwitch",
    "RunStats",
    "build_loop",
    "case_id",
    "gated_gain_output",
    "no_output",
    "plant_tf",
    "run_params",
    "run_stats_update",
    "simulate_cases",
    "simulate_specs",
    "stats_scale",
    "structure_key",
]

#: Feedback cases: (selector of the LPF signal, selector of the CKF signal).
CASES = {"nofilter": (0.0, 0.0), "lpf": (1.0, 0.0), "ckf": (0.0, 1.0)}
#: Identification options, the signal forming z and h of (9): (selector of the LPF output, of the fed-back
#: signal); "raw" is the measurement, "lpf" the LPF output in every case, "feedback" what the controller sees.
ID_OPTIONS = {"raw": (0.0, 0.0), "lpf": (1.0, 0.0), "feedback": (0.0, 1.0)}


#: Signals kept from a run of the main batch (the others are dropped to save memory).
SIGNALS = ("y", "y_m", "y_fb", "y_lpf", "y_ckf", "u", "u_prev", "f1", "f2", "g0")
#: Signals an evaluation of the plausible box stores: none, the claims read the window sums of :class:`RunStats`.
BOX_SIGNALS = ()
#: Fields of :class:`~analysis.ckf.paper.CKFStudy` that may differ from run to run of one simulation (they change
#: block parameters, initial states or selection weights, not the loop's structure).
PER_RUN = ("Q", "P0_ckf", "lpf_omega", "P0_rls", "forgetting", "max_trace", "theta0", "project", "k_I", "c2", "mu",
           "id_signal", "nofilter_id")


def plant_tf(name: str):
    """The plant ``name`` as a continuous ``control.TransferFunction`` (unit DC gain)."""
    import control as ct

    s = ct.tf("s")
    if name == "interlaced":
        return 2.285714 * (s + 2) * (s + 3) * (s + 5) * (s + 7) / ((s + 1) * (s + 2.5) * (s + 4) * (s + 6) * (s + 8))
    if name == "resonant-delay":
        w, z = 3.0, 0.15
        num, den = ct.pade(0.1, 2)
        return w**2 / (s**2 + 2 * z * w * s + w**2) / (s + 1) * ct.tf(num, den)
    raise ValueError(f"plant must be 'interlaced' or 'resonant-delay', got {name!r}")


#: The kernel parameters of :class:`FeedbackSwitch`: the switching time and the weights of its 3 inputs.
SWITCH = Layout("t_on", ("weights", 3))
AT = SWITCH.at


def gated_gain_output(t, x, u, p, y):
    """``y = u[0]`` before ``t_on``, then ``y = Σ_j w_j u_j`` (summed left to right); :class:`FeedbackSwitch`'s kernel.

    Parameters
    ----------
    t : float
        Time.
    x : numpy.ndarray
        No state.
    u : numpy.ndarray
        The candidate signals, the raw one first.
    p : numpy.ndarray
        :data:`SWITCH`: ``t_on``, then the weights ``w_0 .. w_2``.
    y : numpy.ndarray
        The selected signal, written in place.
    """
    acc = 0.0
    for j in range(u.shape[0]):
        acc += p[AT.weights + j] * u[j]
    y[0] = u[0] if t < p[AT.t_on] - 1e-9 else acc  # an expression, not an if statement: numba compiles it leaner


class FeedbackSwitch(KernelBlock, StaticBlock):
    """The fed-back signal: the raw measurement (first input) before ``t_on``, then ``Σ_j w_j u_j``.

    Kernel :func:`gated_gain_output` (a branch on the time against a parameter: the batched methods
    call it run by run).

    Parameters
    ----------
    weights : array_like, shape (3,)
        Weights of the three inputs (e.g. ``[0, 1, 0]``: the LPF output); per run through
        ``Loop.simulate(params={"select": {"weights": ...}})``.
    t_on : float
        When the selected signal replaces the raw one (the paper's 2 s).
    inputs, outputs : sequence of str
        Three inputs (the raw signal first), one output.
    """

    kernels = Kernels(output=gated_gain_output, columns=False)

    def __init__(self, weights, t_on, inputs, outputs):
        self.inputs, self.outputs = check_names("inputs", inputs), check_names("outputs", outputs)
        if len(self.inputs) != 3 or len(self.outputs) != 1:
            raise ValueError(f"FeedbackSwitch has 3 inputs and 1 output, got {self.inputs} and {self.outputs}")
        self.t_on = check_finite("t_on", t_on, scalar=True)
        self.kernel_params = SWITCH.pack(t_on=self.t_on, weights=check_finite("weights", weights))


#: The kernel parameters of :class:`RunStats`: the window edges, the reference and the weights of the filters.
STATS = Layout("t_steady", "t_filter", "t_transient", "ref", "scale", ("w", 3))
STATS_AT = STATS.at
#: What :class:`RunStats` accumulates (its states), each a sum over the samples of a window.
STATS_SUMS = ("dy_st", "dy2_st", "du_st", "du2_st", "e2_all", "e2_tr", "e2_used", "e2_st", "h2_tr", "h2_used")


def run_stats_update(t, x, u, p, x_next):
    """Add sample ``k`` to the window sums of :data:`STATS_SUMS`; the update of :class:`RunStats`.

    Inputs ``u = [y, u, y_lpf, y_ckf, y_lpf_half]``. With ``dy = y − ref``, ``du = u − ref`` (offsets for
    precision; they change no variance), the filter error ``e = w0 y_lpf + w1 y_ckf − (w0 + w1) y`` and the
    half-bandwidth error ``h = w2 (y_lpf_half − y)``: sums of ``dy, dy², du, du²`` over the steady stage
    ``[t_steady, ∞)``, of ``e²`` over the whole run, ``[0, t_transient)``, ``[t_filter, t_transient)`` and the
    steady stage, of ``h²`` over the two transient windows. A window ``[a, b)`` holds ``a − 1e-9 <= t < b − 1e-9``.
    Every term is multiplied by ``scale`` (one over the run's samples), so the sums stay below the loop's
    divergence bound unless the run itself diverges.

    Parameters
    ----------
    t : float
    x : numpy.ndarray
        The sums so far.
    u : numpy.ndarray
        ``y, u, y_lpf, y_ckf, y_lpf_half`` at sample ``t``.
    p : numpy.ndarray
        :data:`STATS`.
    x_next : numpy.ndarray
        The sums with this sample, written in place.
    """
    ref, c = p[STATS_AT.ref], p[STATS_AT.scale]
    w0, w1, w2 = p[STATS_AT.w], p[STATS_AT.w + 1], p[STATS_AT.w + 2]
    dy = u[0] - ref
    du = u[1] - ref
    e = w0 * u[2] + w1 * u[3] - (w0 + w1) * u[0]
    h = w2 * (u[4] - u[0])
    st = c if t >= p[STATS_AT.t_steady] - 1e-9 else 0.0
    tr = c if t < p[STATS_AT.t_transient] - 1e-9 else 0.0
    used = tr if t >= p[STATS_AT.t_filter] - 1e-9 else 0.0
    x_next[0] = x[0] + st * dy
    x_next[1] = x[1] + st * dy * dy
    x_next[2] = x[2] + st * du
    x_next[3] = x[3] + st * du * du
    x_next[4] = x[4] + c * e * e
    x_next[5] = x[5] + tr * e * e
    x_next[6] = x[6] + used * e * e
    x_next[7] = x[7] + st * e * e
    x_next[8] = x[8] + tr * h * h
    x_next[9] = x[9] + used * h * h


def no_output(t, x, u, p, y):
    """:class:`RunStats` has no output (its sums are read from the final state)."""


class RunStats(KernelBlock, DiscreteBlock):
    """Window sums of one run's output, control and filter errors: what the claims read, without storing signals.

    Kernel :func:`run_stats_update` (branches on the time against parameters: compiled run by run). Storing a
    signal of every run costs about as much as a fifth of the loop's own work per signal; the box needs only
    these sums, read from the final state (``LoopResponse.final_states["stats"]``). The samples are
    ``t_0 .. t_{N−1}``: the state after the last update holds every sample but the final one.

    Parameters
    ----------
    t_steady, t_filter, t_transient : float
        Window edges (s): the steady stage from ``t_steady``, the transient up to ``t_transient``, the filters
        fed back from ``t_filter``.
    reference : float
        The output's reference (the offsets of the sums).
    scale : float
        The factor of every term (one over the run's samples).
    w : array_like, shape (3,)
        Weights of the LPF and CKF outputs in the filter error and of the half-bandwidth LPF's error (per run:
        ``Loop.simulate(params={"stats": {"w": (B, 3)}})``).
    """

    inputs = ("y", "u", "y_lpf", "y_ckf", "y_lpf_half")
    outputs = ()
    states = STATS_SUMS
    kernels = Kernels(output=no_output, update=run_stats_update, columns=False)

    def __init__(self, t_steady, t_filter, t_transient, reference, scale, w=(0.0, 0.0, 0.0)):
        self.kernel_params = STATS.pack(t_steady=check_finite("t_steady", t_steady, scalar=True),
                                        t_filter=check_finite("t_filter", t_filter, scalar=True),
                                        t_transient=check_finite("t_transient", t_transient, scalar=True),
                                        ref=check_finite("reference", reference, scalar=True),
                                        scale=check_finite("scale", scale, scalar=True),
                                        w=check_finite("w", w, shape=(3,)))


def stats_scale(p) -> float:
    """The factor of :class:`RunStats`' terms: one over the run's samples."""
    return 1.0 / round(p.t_end / p.Ts)


#: Per case, the weights of :class:`RunStats`: the case's own filter in the filter error, and (LPF loop) the
#: half-bandwidth LPF.
STATS_WEIGHTS = {"nofilter": (0.0, 0.0, 0.0), "lpf": (1.0, 0.0, 1.0), "ckf": (0.0, 1.0, 0.0)}
#: The transient window's end (s): the paper's Fig. 6-7 show 0-10 s.
T_TRANSIENT = 10.0


class CutoffLowPass(DiscreteLowPass):
    """The digital LPF of the study, built from its cut-off: a cut-off per run on one batch.

    :class:`~ctrl_analysis.estimators.lowpass.DiscreteLowPass` of ``LowPassFilter(omega, order)`` at the sample
    period ``h``; its constructor takes the cut-off as a number, so ``Loop.simulate(params={"lpf": {"omega":
    per_run}})`` gives each run its own filter (the same kernel, one parameter row per run).

    Parameters
    ----------
    omega : float
        Cut-off (rad/s, > 0).
    order : int
        Filter order.
    h : float
        Sample period (s).
    """

    def __init__(self, omega: float, order: int, h: float):
        super().__init__(_CachedLowPass(omega, order), h)


class _CachedLowPass(LowPassFilter):
    """:class:`LowPassFilter` whose discretisation is computed once per (cut-off, order, period): the box rebuilds
    the filter for every point's cut-off, and the matrix exponential would cost more than the rest."""

    def discretize(self, h: float):
        Ad, Bd = _discretize(float(self.omega), int(self.order), float(h))
        return Ad.copy(), Bd.copy()


@functools.lru_cache(maxsize=1024)
def _discretize(omega, order, h):
    """``LowPassFilter(omega, order).discretize(h)`` (exact zero-order hold), in closed form for orders 1 and 2.

    The phase-variable form of ``ω^m / (s + ω)^m``: order 1, ``Ad = e^(−ωh)``, ``Bd = 1 − e^(−ωh)``; order 2,
    ``Ad = e^(−ωh) [[1 + ωh, h], [−ω² h, 1 − ωh]]``, ``Bd = [1 − e^(−ωh) (1 + ωh), ω² h e^(−ωh)]``. Equal to the
    matrix exponential to rounding (tested); it needs no BLAS call, which on a loaded machine with threaded BLAS
    costs milliseconds per 2x2 exponential, and the box builds the filter for every point's cut-off.
    """
    if order == 1:
        a = np.exp(-omega * h)
        return np.array([[a]]), np.array([1.0 - a])
    if order == 2:
        a, wh = np.exp(-omega * h), omega * h
        return (a * np.array([[1.0 + wh, h], [-omega * omega * h, 1.0 - wh]]),
                np.array([1.0 - a * (1.0 + wh), omega * omega * h * a]))
    return LowPassFilter.discretize(LowPassFilter(omega, order), h)


def case_id(p, case: str) -> str:
    """The identification option (:data:`ID_OPTIONS`) of ``case`` in the study ``p``: ``p.id_signal``, except in the
    no-filter loop with ``p.nofilter_id == "raw"`` (its own measurement)."""
    return "raw" if case == "nofilter" and p.nofilter_id == "raw" else p.id_signal


def structure_key(p):
    """``p`` with every :data:`PER_RUN` field at the paper study's value: points with equal keys share one loop."""
    import dataclasses

    from .paper import PAPER

    return dataclasses.replace(p, **{f: getattr(PAPER, f) for f in PER_RUN})


def build_loop(p, plant=None) -> Loop:
    """Plant, measurement, LPF, CKF, identification and golden-section control wired by signal names.

    The case (which signal is fed back and which one is identified) is the weights of ``select``
    and ``idsignal``, the raw measurement here; :func:`run_params` gives them per run. ``lpf_half`` is the
    LPF at half the cut-off on the same measurement, never fed back.

    Parameters
    ----------
    p : CKFStudy
    plant : control.TransferFunction or StateSpace, optional
        Default ``plant_tf(p.plant)``.

    Returns
    -------
    Loop
    """
    import control as ct

    sys = plant_tf(p.plant) if plant is None else plant
    lo, hi = (p.lower, p.upper) if p.project else (None, None)
    raw = [1.0, 0.0, 0.0]
    blocks = [
        place(DiscreteLTI(sys, p.Ts), "plant", inputs=["u"], outputs=["y"]),
        place(StaticGain([[1.0, 1.0]], ("y", "v"), ("y_m",)), "meas"),
        place(CutoffLowPass(p.lpf_omega, p.lpf_order, p.Ts), "lpf", inputs=["y_m"], outputs=["y_lpf"]),
        place(CutoffLowPass(p.lpf_omega / 2, p.lpf_order, p.Ts), "lpf_half", inputs=["y_m"], outputs=["y_lpf_half"]),
        place(DiscreteLTI(ct.tf([1.0], [1.0, 0.0], True), p.Ts), "delay", inputs=["u"], outputs=["u_prev"]),
        place(CharacteristicKalmanFilter(Q=p.Q, R=p.R, P0=p.P0_ckf), "ckf",
              inputs=["y_m", "u_prev", "f1", "f2", "g0"], outputs=["y_ckf", "y_ckf_prev"]),
        place(FeedbackSwitch(raw, p.t_filter, ("y_m", "y_lpf", "y_ckf"), ("y_fb",)), "select"),
        place(StaticGain([raw], ("y_m", "y_lpf", "y_fb"), ("s_id",)), "idsignal"),
        place(ArxRegressor(2, 1, lag=0), "regressor", inputs=["s_id", "u"]),  # outputs z, h[0], h[1], h[2]
        place(RecursiveLeastSquaresBlock(3, p.forgetting, p.P0_rls, p.theta0, lower=lo, upper=hi,
                                         max_trace=p.max_trace, feedthrough=False), "rls",
              outputs=["f1", "f2", "g0"]),  # reads z, h[0..2]; θ = [f1, f2, g0], the characteristic model's names
        place(GoldenSectionController(p.k_I, p.c2, mu=p.mu, l1=p.l1, l2=p.l2), "ctrl",
              inputs=["y_fb", "r", "f1", "f2", "g0"], outputs=["u"]),
        place(RunStats(p.t_steady, p.t_filter, T_TRANSIENT, p.reference, stats_scale(p)), "stats"),
    ]
    return Loop(blocks, p.Ts)


@functools.lru_cache(maxsize=16)
def _loop(key):
    """:func:`build_loop` of a structure (:func:`structure_key`), built once: the box simulates many batches of it."""
    return build_loop(key)


def run_params(sel) -> dict:
    """The per-run weights of ``select`` and ``idsignal`` from the selectors, for :meth:`Loop.simulate`.

    Parameters
    ----------
    sel : numpy.ndarray, shape (4, B)
        Per-run selectors: LPF / CKF fed back, LPF / fed-back signal identified (:data:`CASES`,
        :data:`ID_OPTIONS`).

    Returns
    -------
    dict
        ``{"select": {"weights": (B, 3)}, "idsignal": {"D": (B, 1, 3)}}``: rows ``[raw, LPF, CKF]``
        (fed back) and ``[raw, LPF, fed back]`` (identified), ``1 − s1 − s2, s1, s2`` per run.
    """
    w_fb = np.stack([1.0 - sel[0] - sel[1], sel[0], sel[1]], axis=1)
    w_id = np.stack([1.0 - sel[2] - sel[3], sel[2], sel[3]], axis=1)
    return {"select": {"weights": w_fb}, "idsignal": {"D": w_id[:, None, :]}}


def _point_params(ps, runs):
    """Per-run block parameters and initial states of the points ``ps`` (each repeated over ``runs`` runs)."""

    def rep(vals):
        return np.repeat(np.asarray(vals, dtype=float), runs, axis=0)

    inf = np.full(3, np.inf)
    lo = rep([p.lower if p.project else -inf for p in ps])
    hi = rep([p.upper if p.project else inf for p in ps])
    omega = rep([p.lpf_omega for p in ps])
    params = {"lpf": {"omega": omega}, "lpf_half": {"omega": omega / 2},
              "ckf": {"Q": rep([p.Q for p in ps])},
              "rls": {"forgetting": rep([p.forgetting for p in ps]), "max_trace": rep([p.max_trace for p in ps]),
                      "lower": lo, "upper": hi},
              "ctrl": {"k_I": rep([p.k_I for p in ps]), "c2": rep([p.c2 for p in ps]), "mu": rep([p.mu for p in ps])}}
    x0 = {"rls": rep([np.concatenate([p.theta0, (p.P0_rls * np.eye(3)).ravel()]) for p in ps]),
          "ckf": rep([[0.0, 0.0, p.P0_ckf, 0.0, p.P0_ckf] for p in ps])}
    return params, x0


def simulate_specs(specs, runs: int, seed: int, *, keep=SIGNALS, plant=None, noise_std=None, engine="auto",
                   max_runs: int = 640, seeds=None) -> list:
    """Run loops ``(p, case, option)`` over ``runs`` Monte Carlo runs each, many on the batch axis of one simulation.

    Specs whose studies share a structure (:func:`structure_key`) run side by side, their differences as
    per-run parameters (:data:`PER_RUN`), at most ``max_runs`` runs per simulation; every spec sees the same
    noise (the seeds of ``seed``), so run ``b`` of every spec is the same draw (common random numbers).

    Parameters
    ----------
    specs : sequence of (CKFStudy, str, str)
        The study's settings, the case (:data:`CASES`) and the identification option (:data:`ID_OPTIONS`).
    runs : int
    seed : int
        Base seed of the measurement noise.
    keep : sequence of str
        Signals kept.
    plant : control.TransferFunction or StateSpace, optional
        Default each spec's ``plant_tf(p.plant)``.
    noise_std : float, optional
        Default each spec's ``p.noise_std``.
    engine : {"auto", "compiled", "numpy"}
    max_runs : int
        Largest batch of one simulation (memory: ``8 (N + 1) len(keep)`` bytes per run).
    seeds : sequence of int, optional
        The runs' seeds, ``runs`` of them (default ``run_seeds(seed, runs)``): a part of a larger set of runs,
        simulated bit for bit as in the whole set.

    Returns
    -------
    list of dict
        Per spec ``{"t", "ok", "diverged_step", signal: (N + 1, runs)}``.
    """
    if seeds is None:
        seeds = run_seeds(seed, runs)
    elif len(seeds) != runs:
        raise ValueError(f"seeds must hold one seed per run ({runs}), got {len(seeds)}")
    seeds = [int(s) for s in seeds]
    groups: dict = {}
    for i, (p, case, opt) in enumerate(specs):
        if case not in CASES or opt not in ID_OPTIONS:
            raise ValueError(f"a spec's case must be one of {list(CASES)} and its option one of {list(ID_OPTIONS)}, "
                             f"got {case!r}, {opt!r}")
        groups.setdefault(structure_key(p), []).append(i)
    out = [None] * len(specs)
    per = max(1, max_runs // runs)
    for key, idx in groups.items():
        n = round(key.t_end / key.Ts)
        std = key.noise_std if noise_std is None else noise_std
        v = draw_noise(seeds, n + 1, gaussian_noise(std))[:, :, 0]
        loop = _loop(key) if plant is None else build_loop(key, plant)
        for c0 in range(0, len(idx), per):
            chunk = idx[c0:c0 + per]
            ps = [specs[i][0] for i in chunk]
            sel = np.repeat(np.array([CASES[specs[i][1]] + ID_OPTIONS[specs[i][2]] for i in chunk]).T, runs, axis=1)
            params, x0 = _point_params(ps, runs)
            params.update(run_params(sel))
            params["stats"] = {"w": np.repeat(np.array([STATS_WEIGHTS[specs[i][1]] for i in chunk]), runs, axis=0)}
            B = len(chunk) * runs
            res = loop.simulate(n, inputs={"v": np.tile(v, (1, len(chunk))), "r": key.reference}, runs=B, x0=x0,
                                params=params, save=Save(states=False, keep=list(keep)),
                                execution=Execution(engine=engine), seeds=seeds * len(chunk))
            for j, i in enumerate(chunk):
                sl = slice(j * runs, (j + 1) * runs)
                d = {s: res[s][:, sl] for s in keep}
                d["t"] = res.t
                d["stats"] = res.final_states["stats"][sl]
                d["ok"] = ~res.diverged[sl]
                d["diverged_step"] = res.diverged_step[sl]
                out[i] = d
    return out


def simulate_cases(p, runs: int, seed: int, *, options=None, plant=None, noise_std=None, engine="auto",
                   keep=SIGNALS, seeds=None) -> dict:
    """Run the three cases of ``p`` over ``runs`` Monte Carlo runs, side by side (:func:`simulate_specs`).

    Parameters
    ----------
    p : CKFStudy
    runs : int
        Monte Carlo runs per case and option.
    seed : int
        Base seed of the measurement noise (the same noise in every case and option).
    options : sequence of str, optional
        Identification options run in every case (the comparison of the options). Default: the study's own,
        ``p.id_signal`` in the filtered loops and ``p.nofilter_id`` in the no-filter loop (:func:`case_id`),
        keyed ``(p.id_signal, case)``.
    plant : control.TransferFunction or StateSpace, optional
    noise_std : float, optional
        Default ``p.noise_std``.
    engine : {"auto", "compiled", "numpy"}
        Passed to :meth:`Loop.simulate`.
    keep : sequence of str
        Signals kept.
    seeds : sequence of int, optional
        The runs' seeds (default ``run_seeds(seed, runs)``; :func:`simulate_specs`).

    Returns
    -------
    dict
        ``{(option, case): {"t", "ok", "diverged_step", signal: (N + 1, runs)}}``.
    """
    if options is None:
        keys = [((p.id_signal, c), (p, c, case_id(p, c))) for c in CASES]
    else:
        keys = [((o, c), (p, c, o)) for o in options for c in CASES]
    data = simulate_specs([s for _, s in keys], runs, seed, keep=keep, plant=plant, noise_std=noise_std,
                          engine=engine, seeds=seeds)
    return {k: d for (k, _), d in zip(keys, data, strict=True)}
