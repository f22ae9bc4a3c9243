"""The `ckf` closed loops, built from library blocks through :class:`ctrl_analysis.engine.loop.Loop`.

One loop holds every case side by side on the batch axis: plant, measurement, the digital LPF,
the CKF, the identification (regressor + RLS) and the golden-section controller all run in every
run; per-run selection weights (given to the simulation, :func:`run_params`) say which signal is fed
back (raw, LPF or CKF, raw before ``t_filter``) and which one forms the identification's ``z`` and
``h``. Run ``b`` of the batch is therefore exactly the loop of its case alone, and the three cases
see the same noise.
"""

from __future__ import annotations

import numpy as np

from ctrl_analysis._validate import check_finite
from ctrl_analysis.controllers.golden_section import GoldenSectionController
from ctrl_analysis.engine.blocks import StaticBlock, StaticGain
from ctrl_analysis.engine.kernels import KernelBlock, Kernels, Layout
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.kalman import CharacteristicKalmanFilter
from ctrl_analysis.estimators.lowpass import LowPassFilter
from ctrl_analysis.identification import ArxRegressor, RecursiveLeastSquaresBlock
from ctrl_analysis.plants import DiscreteLTI
from ctrl_analysis.simulate import draw_noise, gaussian_noise, run_seeds

__all__ = ["CASES", "ID_OPTIONS", "SIGNALS", "SWITCH", "FeedbackSwitch", "build_loop", "gated_gain_output", "plant_tf",
           "run_params", "simulate_cases", "split_cases"]

#: Feedback cases: (selector of the LPF signal, selector of the CKF signal).
CASES = {"nofilter": (0.0, 0.0), "lpf": (1.0, 0.0), "ckf": (0.0, 1.0)}
#: Identification options, the signal forming z and h of (9): (selector of the LPF output, of the fed-back
#: signal); "raw" is the measurement, "lpf" the LPF output in every case, "feedback" what the controller sees.
ID_OPTIONS = {"raw": (0.0, 0.0), "lpf": (1.0, 0.0), "feedback": (0.0, 1.0)}


#: Signals kept from a run (the others are dropped to save memory).
SIGNALS = ("y", "y_m", "y_fb", "y_lpf", "y_ckf", "u", "u_prev", "f1", "f2", "g0")


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
    """``y = u[0]`` before ``t_on``, then ``y = Σ_j w_j u_j`` (summed left to right); the kernel of :class:`FeedbackSwitch`.

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
        super().__init__(self._select, inputs, outputs)
        if len(self.inputs) != 3 or len(self.outputs) != 1:
            raise ValueError(f"FeedbackSwitch has 3 inputs and 1 output, got {self.inputs} and {self.outputs}")
        self.t_on = check_finite("t_on", t_on, scalar=True)
        self.kernel_params = SWITCH.pack(t_on=self.t_on, weights=check_finite("weights", weights))

    def _select(self, t, u):  # StaticBlock's fn (python-control): the kernel on the batch
        return self.output(t, np.zeros((u.shape[0], 0)), u)


def build_loop(p, plant=None) -> Loop:
    """Plant, measurement, LPF, CKF, identification and golden-section control wired by signal names.

    The case (which signal is fed back and which one is identified) is the weights of ``select``
    and ``idsignal``, the raw measurement here; :func:`run_params` gives them per run.

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
        place(LowPassFilter(p.lpf_omega, p.lpf_order).digital(p.Ts), "lpf", inputs=["y_m"], outputs=["y_lpf"]),
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
    ]
    return Loop(blocks, p.Ts)


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


def simulate_cases(p, runs: int, seed: int, *, options=None, plant=None, noise_std=None, engine="auto"):
    """Run every case x identification option over ``runs`` Monte Carlo runs in one batch.

    Parameters
    ----------
    p : CKFStudy
    runs : int
        Monte Carlo runs per case and option.
    seed : int
        Base seed of the measurement noise (the same noise in every case and option).
    options : sequence of str, optional
        Identification options (default ``(p.id_signal,)``).
    plant : control.TransferFunction or StateSpace, optional
    noise_std : float, optional
        Default ``p.noise_std``.
    engine : {"auto", "compiled", "numpy"}
        Passed to :meth:`Loop.simulate`.

    Returns
    -------
    res : LoopResponse
        Batch of ``len(options) * len(CASES) * runs`` runs, ordered option, case, run.
    index : dict
        ``(option, case) -> slice`` of the batch.
    """
    options = (p.id_signal,) if options is None else tuple(options)
    n = round(p.t_end / p.Ts)
    seeds = run_seeds(seed, runs)
    std = p.noise_std if noise_std is None else noise_std
    v = draw_noise(seeds, n + 1, gaussian_noise(std))[:, :, 0]
    combos = [(o, c) for o in options for c in CASES]
    B = len(combos) * runs
    sel = np.empty((4, B))
    index = {}
    for i, (o, c) in enumerate(combos):
        sl = slice(i * runs, (i + 1) * runs)
        index[(o, c)] = sl
        sel[:, sl] = np.array(CASES[c] + ID_OPTIONS[o])[:, None]
    loop = build_loop(p, plant)
    res = loop.simulate(n, inputs={"v": np.tile(v, (1, len(combos))), "r": p.reference}, runs=B,
                        params=run_params(sel), store_states=False, keep=SIGNALS, seeds=seeds * len(combos),
                        engine=engine)
    return res, index


def split_cases(res, index) -> dict:
    """``{(option, case): {"t", "ok", "diverged_step", signal: (N+1, runs)}}`` from :func:`simulate_cases`."""
    out = {}
    for key, sl in index.items():
        d = {s: res[s][:, sl] for s in SIGNALS}
        d["t"] = res.t
        d["ok"] = ~res.diverged[sl]
        d["diverged_step"] = res.diverged_step[sl]
        out[key] = d
    return out
