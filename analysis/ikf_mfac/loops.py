"""The four closed loops of §4 (MFAC, TD-MFAC, D-MFAC, IKF-MFAC) from library blocks, and their Monte Carlo runs."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ctrl_analysis.controllers.mfac import (
    CFDLLaw,
    DecreasingGainLaw,
    PPDEstimator,
    mfac_controller,
)
from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.blocks import StaticGain
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.kalman import ImprovedKalmanFilter
from ctrl_analysis.estimators.tracking import TrackingDifferentiator
from ctrl_analysis.noise import draw_noise, gaussian_noise

from .paper import Example
from .plants import SwitchedPlant, plant_start_state, reference, reference_next

__all__ = ["RUN_TIME", "SchemeRuns", "build_loop", "effective", "noise_draws", "run_batch", "run_params", "run_scheme",
           "structure"]

#: A run whose plant or controller state leaves |x| <= BOUND is flagged as diverged: in a working
#: loop the outputs stay O(1-10), the TD rate O(100) and the D-MFAC age counter <= N = 1000.
BOUND = 1e4


def _measurement() -> StaticGain:
    # (5) y_m(k) = y(k) + v(k); one block for every loop (it holds no state and no run's values)
    global _MEAS
    if _MEAS is None:
        _MEAS = StaticGain([[1.0, 1.0]], inputs=("y", "v"), outputs=("y_m",))
    return _MEAS


_MEAS = None


#: The parameters the sweeps vary per run (attribute of :class:`~.paper.Example` -> block and constructor
#: argument of :func:`~ctrl_analysis.controllers.mfac.mfac_controller`'s blocks).
RUN_TIME = {"rho": ("law", "rho"), "lam": ("law", "lam"), "Q": ("filter", "Q"), "R": ("filter", "R")}


def run_params(ex: Example, scheme: str) -> tuple[Example, dict]:
    """``ex`` with one value of each parameter given per run, and the per-run values for ``simulate(params=...)``.

    A sweep sets ρ, λ, Q or R of ``ex`` to one value per run (a 1-D array); the loop is built with
    the first and the values go to :meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>` (Q and
    R only where the scheme has the IKF). Every batch therefore runs the same compiled loop.

    Parameters
    ----------
    ex : Example
    scheme : str

    Returns
    -------
    ex : Example
        Scalars only.
    params : dict
        ``{block: {argument: per-run values}}`` (empty when nothing varies per run).
    """
    fixed, params = {}, {}
    for name, (block, arg) in RUN_TIME.items():
        value = np.asarray(getattr(ex, name), dtype=float)
        if value.ndim == 0:
            continue
        fixed[name] = float(value.reshape(-1)[0])
        if block != "filter" or scheme == "ikf_mfac":
            params.setdefault(block, {})[arg] = value
    return dataclasses.replace(ex, **fixed), params


def effective(ex: Example) -> Example:
    """``ex`` with the TD the study runs: eq. (37) as printed (one step per sample, ``x1`` before it) under
    ``td_reading = "literal"``, else ``td_substeps`` steps with ``td_feedthrough``."""
    if ex.td_reading == "literal":
        return dataclasses.replace(ex, td_substeps=1, td_feedthrough=False, td_reading="substeps")
    return ex


def _controller(ex: Example, scheme: str) -> list:
    """The placed blocks of ``scheme`` for ``ex`` (scalars; :func:`effective` applied by the caller)."""
    y0, u0 = ex.y_init, ex.u_init
    ppd = PPDEstimator(ex.eta, ex.mu, ex.epsilon, ex.phi0, ex.phi_reset, y0=y0, u0=u0)
    law = CFDLLaw(ex.rho, ex.lam)
    filt = None
    if scheme == "td_mfac":
        filt = TrackingDifferentiator(ex.td_r, ex.td_h, ex.td_h0, substeps=ex.td_substeps, x0=(y0, 0.0),
                                      feedthrough=ex.td_feedthrough)
    elif scheme == "d_mfac":
        law = DecreasingGainLaw(ex.rho, ex.lam, ex.e_m, rearm=ex.rearm)
    elif scheme == "ikf_mfac":
        filt = ImprovedKalmanFilter(ex.Q, ex.R, y0=y0, P0=ex.P0)
    elif scheme != "mfac":
        raise ValueError(f"scheme must be one of mfac, td_mfac, d_mfac, ikf_mfac, got {scheme!r}")
    plant = SwitchedPlant(ex.switch_k)
    blocks = [place(plant, "plant"), place(_measurement(), "meas")]
    blocks += mfac_controller(ppd, law, filt, u0=u0)
    return blocks


def build_loop(ex: Example, scheme: str) -> Loop:
    """The closed loop of ``scheme`` for example ``ex``: plant, y_m = y + v, and the controller blocks.

    External inputs: ``v`` (measurement noise) and ``y_ref_next`` (``y*(k+1)``). ``ex`` holds one value
    per parameter (per-run values: :func:`run_params`); its TD is the one :func:`effective` gives.
    """
    return Loop(_controller(effective(ex), scheme), dt=1.0)


#: Fields that shape the loop or its inputs (one simulation each); every other field of an example is a
#: block's constructor argument or initial state, given per run by :func:`run_batch`.
_STRUCTURE = ("n", "switch_k", "reference", "y_init", "u_init", "k_start", "td_r", "td_h", "td_h0", "td_substeps",
              "td_feedthrough")


def structure(ex: Example, scheme: str) -> tuple:
    """What ``scheme``'s loop for ``ex`` shares with every run of one :func:`run_batch` call."""
    ex = effective(ex)
    own_td = scheme == "td_mfac"
    return (type(ex).__name__, scheme) + tuple(getattr(ex, f) for f in _STRUCTURE
                                                if own_td or not f.startswith("td_"))


def noise_draws(ex: Example, seeds, noise_std: float | None = None) -> np.ndarray:
    """``v(k)``, ``k = 1..N``, per run: shape ``(N, B)`` (``noise_std`` default: the example's)."""
    std = ex.noise_std if noise_std is None else noise_std
    return draw_noise(seeds, ex.n, gaussian_noise(std))[:, :, 0]


#: The signals a run keeps (every other one is only stepped): outputs, measurement, input, and the filter's output.
_STORED = ("y", "y_m", "u")
_FILTERED = ("td_mfac", "ikf_mfac")


@dataclass
class SchemeRuns:
    """Outputs of one scheme over a batch: ``y``, ``y_m``, ``u`` at ``k = 1..N`` (shape ``(N, B)``)."""

    k: np.ndarray
    y_ref: np.ndarray
    y: np.ndarray
    y_m: np.ndarray
    u: np.ndarray
    y_f: np.ndarray
    diverged: np.ndarray
    diverged_step: np.ndarray


def run_scheme(ex: Example, scheme: str, v: np.ndarray, engine: str = "auto") -> SchemeRuns:
    """Run ``scheme`` for every column of the noise ``v`` (shape ``(N, B)``, ``v[k−1] = v(k)``).

    ``engine`` is :meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>`'s (``"auto"``: compiled,
    every block has a kernel; ``"numpy"``: the blocks' batched methods, the same numbers).

    The engine starts at ``k = ex.k_start`` with ``y(k_start)`` from the plant; the given
    ``y(1:k_start−1)``, ``u(1:k_start−1)`` are put in front, so every returned row is ``k = 1..N``.
    """
    ex, params = run_params(ex, scheme)
    loop = build_loop(ex, scheme)
    ks, n = ex.k_start, ex.n
    n_steps = n - ks
    plant = loop.placed[0].block
    k_eng = ks + np.arange(n_steps + 1)
    keep = _STORED + (("y_f",) if scheme in _FILTERED else ())
    res = loop.simulate(n_steps, t0=float(ks),
                        inputs={"v": v[ks - 1:], "y_ref_next": reference_next(ex.reference, k_eng)},
                        x0={"plant": plant_start_state(plant, ex.y_init, ex.u_init, ks)}, params=params,
                        save=Save(states=False, keep=keep), execution=Execution(bound=BOUND, engine=engine))
    B = v.shape[1]
    head = np.full((ks - 1, B), ex.y_init)
    y = np.vstack([head, res["y"]])
    y_m = np.vstack([head + v[:ks - 1], res["y_m"]])
    u = np.vstack([np.full((ks - 1, B), ex.u_init), res["u"]])
    y_f = np.vstack([head, res.signals.get("y_f", res["y_m"])])
    return SchemeRuns(k=np.arange(1, n + 1), y_ref=reference(ex.reference, n), y=y, y_m=y_m, u=u, y_f=y_f,
                      diverged=res.diverged, diverged_step=np.where(res.diverged, res.diverged_step + ks, -1))


def _same(a, b) -> bool:
    """Equal constructor arguments: numbers and arrays by value, blocks (a TD step's TD) by kernel parameters."""
    if a is b:
        return True
    if hasattr(a, "kernel_params"):
        return (type(a) is type(b) and np.array_equal(a.kernel_params, b.kernel_params)
                and np.array_equal(getattr(a, "x0", None), getattr(b, "x0", None)))
    try:
        return bool(np.array_equal(np.asarray(a), np.asarray(b)))
    except (TypeError, ValueError):
        return a == b


def _number(v) -> bool:
    return isinstance(v, (int, float, bool, np.number, np.bool_))


def run_batch(exs, scheme: str, vs, engine: str = "auto", keep=("y",)) -> SchemeRuns:
    """Run ``scheme`` for several parameter sets side by side: ``exs[i]`` on the noise columns ``vs[i]``.

    The parameter sets must share :func:`structure` (plant, reference, initial values, the TD's step count);
    everything else (the estimator's, the law's and the filter's constructor arguments, and the initial
    states they set, e.g. φ̂(1) or P(0|0)) goes to one :meth:`Loop.simulate
    <ctrl_analysis.engine.loop.Loop.simulate>` as per-run values, so every run equals the loop built with
    its own ``exs[i]`` (the compiled engine reads run ``b``'s parameter row; tested).

    Parameters
    ----------
    exs : sequence of Example
    scheme : str
    vs : sequence of numpy.ndarray
        Noise ``v`` per parameter set, shape ``(N, B_i)``.
    engine : str
    keep : tuple of str
        Signals stored (``"y"`` at least).

    Returns
    -------
    SchemeRuns
        The runs of every set, in order (``y_m``, ``u``, ``y_f`` are those of ``keep``, else empty).
    """
    exs = [effective(e) for e in exs]
    if len(exs) != len(vs) or not exs:
        raise ValueError(f"exs and vs must be non-empty and of the same length, got {len(exs)} and {len(vs)}")
    shapes = {structure(e, scheme) for e in exs}
    if len(shapes) != 1:
        raise ValueError(f"run_batch runs one loop structure at a time; the parameter sets give {len(shapes)}")
    placed = [_controller(e, scheme) for e in exs]
    counts = [np.shape(v)[1] for v in vs]
    params, x0 = {}, {}
    for j, p in enumerate(placed[0]):
        blocks = [pl[j].block for pl in placed]
        args = [b.init_args() for b in blocks]
        for name in args[0]:
            values = [a[name] for a in args]
            if not all(_same(values[0], v) for v in values[1:]):
                if not all(_number(v) for v in values):
                    raise ValueError(f"{p.name}.{name} differs between the parameter sets and is not a number")
                params.setdefault(p.name, {})[name] = np.repeat(np.asarray(values), counts)
    ex = exs[0]
    loop = Loop(placed[0], dt=1.0)
    for j, p in enumerate(placed[0]):
        if p.name in loop.slices and p.name != "plant":
            states = np.array([pl[j].block.initial_state() for pl in placed], dtype=float).reshape(len(placed), -1)
            if np.ptp(states, axis=0).any():
                x0[p.name] = np.repeat(states, counts, axis=0)
    v = np.concatenate([np.asarray(x, dtype=float) for x in vs], axis=1)
    ks, n = ex.k_start, ex.n
    plant = loop.placed[0].block
    k_eng = ks + np.arange(n - ks + 1)
    x0["plant"] = plant_start_state(plant, ex.y_init, ex.u_init, ks)
    res = loop.simulate(n - ks, t0=float(ks),
                        inputs={"v": v[ks - 1:], "y_ref_next": reference_next(ex.reference, k_eng)},
                        x0=x0, params=params, save=Save(states=False, keep=tuple(keep)),
                        execution=Execution(bound=BOUND, engine=engine))
    B = v.shape[1]
    head = np.full((ks - 1, B), ex.y_init)
    empty = np.empty((0, B))
    y = np.vstack([head, res["y"]])
    y_m = np.vstack([head + v[:ks - 1], res["y_m"]]) if "y_m" in keep else empty
    u = np.vstack([np.full((ks - 1, B), ex.u_init), res["u"]]) if "u" in keep else empty
    y_f = np.vstack([head, res.signals["y_f"]]) if "y_f" in keep and "y_f" in res.signals else empty
    return SchemeRuns(k=np.arange(1, n + 1), y_ref=reference(ex.reference, n), y=y, y_m=y_m, u=u, y_f=y_f,
                      diverged=res.diverged, diverged_step=np.where(res.diverged, res.diverged_step + ks, -1))
