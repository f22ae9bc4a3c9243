"""What the studies give the estimator arena: two plant outputs as signal classes, and the paper claims it can judge.

The library's arena (:mod:`ctrl_analysis.arena`) never imports the studies; the CLI calls
:func:`register` before it runs ``ctrl-analysis arena``. Each signal class simulates a study's own
plant block with the study's own parameters (nothing is restated here):

* ``de-example1`` — the output ``x1`` of plant (19) of the differential-estimator paper's Example 1
  (:class:`analysis.differential_estimator.loops.Plant19` with :data:`~analysis.differential_estimator.paper.EX1`,
  its RK4 and its held process noise ξ drawn by :func:`analysis.differential_estimator.example1.draw`),
  the record starting at a seeded time in the first period of ``w = sign(cos 0.3 t)``;
* ``meso-situation1`` — the output ``x1`` of plant (27) in the meso paper's situation 1, closed by the
  paper's PD law (30) and the MESO with the study's well-posed identification
  (:func:`analysis.meso.loops.simulate_situation`), the record starting at a seeded time after 5 s.

Both are integrated at a step ``h = dt / ceil(dt / h_paper)`` (the paper's step or shorter, the
arena's samples on the grid). The bound ``L`` on ``|f''|`` is computed, not assumed: ``f'' = x2'``
is the plant's own right-hand side (``Plant19.rhs`` / ``Plant.rhs``) evaluated at the start of every
integration step of the record with the inputs held over that step (ξ, u, θ4), and ``L`` is its
largest magnitude; within a step only the state moves, by O(h).
"""

from __future__ import annotations

import functools
import math
from dataclasses import replace

import numpy as np

from ctrl_analysis.arena.claims import ClaimCheck
from ctrl_analysis.engine import Execution

from .pendulum.paper import VERIFY

__all__ = ["CLAIM_CHECKS", "MESO_GRID", "PENDULUM_GAINS", "de_example1", "meso_observer_errors", "meso_situation1",
           "register"]

#: Start of the meso record: after the loop's start-up (the observer and the first LSM batch).
MESO_START = 5.0


def _step(dt: float, h_paper: float) -> tuple:
    """Substeps per sample and the integration step ``h = dt / substeps <= h_paper``."""
    sub = max(1, math.ceil(dt / h_paper - 1e-9))
    return sub, dt / sub


def de_example1(seed: int, dt: float, n: int) -> tuple:
    """Plant (19)'s ``x1, x2, x2'`` at ``t_k = k dt`` (``k < n``), one seeded record (noise ξ and start time).

    Parameters
    ----------
    seed : int
    dt : float
        Sample period (s).
    n : int
        Samples.

    Returns
    -------
    tuple
        ``x1, x2, x2'`` (arrays, shape (n,)) and ``L = max |x2'|`` over every step of the record.
    """
    from ctrl_analysis.engine.loop import Loop, place

    from .differential_estimator.example1 import draw
    from .differential_estimator.loops import Plant19
    from .differential_estimator.paper import EX1

    sub, h = _step(dt, EX1.h)
    start = int(np.random.default_rng([seed, 1]).integers(0, round(2 * math.pi / EX1.w_freq / dt)))
    K = (start + n) * sub
    xi = draw(EX1, [seed], n_steps=K, h=h)[:, :, 0]  # ξ held over each step (η is the arena's noise)
    plant = Plant19(EX1)
    res = Loop([place(plant, "plant")], h, method=EX1.method).simulate(K, inputs={"xi": xi},
                                                                       execution=Execution(progress=False))
    steps = np.arange(start * sub, K)
    x = np.column_stack([res.signals["x[0]"][steps, 0], res.signals["x[1]"][steps, 0]])
    x2dot = np.array([plant.rhs(h * k, x[i:i + 1], xi[k:k + 1])[0, 1] for i, k in enumerate(steps)])
    return x[::sub, 0], x[::sub, 1], x2dot[::sub], float(np.max(np.abs(x2dot)))


def meso_situation1(seed: int, dt: float, n: int) -> tuple:
    """Plant (27)'s ``x1, x2, x2'`` in situation 1's MESO loop at ``t_k = k dt`` (``k < n``), one seeded record.

    Parameters
    ----------
    seed : int
        Seed of the loop's measurement noise (0.002 n0) and of the record's start time.
    dt : float
    n : int

    Returns
    -------
    tuple
        ``x1, x2, x2'`` (arrays, shape (n,)) and ``L = max |x2'|`` over every step of the record.
    """
    return _meso_record(seed, dt, n)[:4]


@functools.lru_cache(maxsize=32)
def _meso_record(seed: int, dt: float, n: int) -> tuple:
    """:func:`meso_situation1`'s record and the loop's inputs to its observer at the samples: ``x1, x2, x2', L``,
    the control ``u`` (n,) and the identified, smoothed ``Θ`` (n, 4) the MESO reads (cached: one loop simulation)."""
    from .meso.blocks import Plant
    from .meso.loops import Row, simulate_situation
    from .meso.paper import PAPER, SITUATIONS

    sub, h = _step(dt, PAPER.h)
    paper = replace(PAPER, h=h)
    sit = SITUATIONS["s1"]
    span = max(0.0, sit.T - MESO_START - n * dt)
    start = round((MESO_START + np.random.default_rng([seed, 1]).uniform(0.0, span)) / dt)
    run = simulate_situation(sit, [Row("meso", "wellposed", seed)], (start + n) * dt, paper, keep=[0])
    if run.diverged[0]:
        raise ValueError(f"meso situation 1 diverged at step {run.diverged_step[0]} (seed {seed}, h = {h:g} s)")
    kept = run.keep[0]
    steps = np.arange(start * sub, (start + n) * sub)
    t = run.t[steps]
    level = np.where(t >= paper.t_step - 0.5 * h, paper.step, 0.0)  # θ4 of (31): the loop's input at t
    x = np.column_stack([kept["x[0]"][steps], kept["x[1]"][steps]])
    u = np.column_stack([kept["u"][steps], level, 0 * t])
    x2dot = Plant(paper, paper.b).rhs(0.0, x, u)[:, 1]
    theta = np.column_stack([kept[f"theta[{i}]"][steps] for i in range(4)])
    return (x[::sub, 0], x[::sub, 1], x2dot[::sub], float(np.max(np.abs(x2dot))), kept["u"][steps][::sub],
            theta[::sub])


#: The observers' bandwidths ω_o = 1/ε searched by :func:`meso_observer_errors`, as multiples of the arena's
#: reference ``√(L/ε)``: one 25-point log grid (ratio 1.21) for the MESO and the ESO alike, capped at ω_o dt <= 1.
MESO_GRID = tuple(float(v) for v in np.exp(np.linspace(np.log(0.1), np.log(10.0), 25)))


def meso_observer_errors(cases, setup) -> dict:
    """The meso paper's MESO (29) and conventional ESO (6), each given the loop's control ``u``, on the arena's records.

    On each case's records (the arena's meso-situation1 signal and noise, scaled to its ``L``; the loop's ``u`` and
    the MESO's identified ``Θ`` scaled alike: ``u`` and ``θ4`` by the same factor as the signal), the observer of the
    study (:class:`analysis.meso.blocks.ModelledESO`, ``b0 = b``, β = (3, 3, 1), poles at ``-1/ε``) runs with ``Θ``
    (the MESO) and with ``Θ = 0`` (the ESO), over :data:`MESO_GRID`; each keeps its best bandwidth for each
    measure. Errors are scored as the arena scores its families (after the transient, RMS over the records).

    Parameters
    ----------
    cases : sequence of Case
        meso-situation1 cases.
    setup : Setup

    Returns
    -------
    dict
        ``{"MESO": {"rms_f": errors, "rms": errors}, "ESO": {...}}``, one error per case.
    """
    from ctrl_analysis.arena.interface import OMEGA_DT_RK4, SUBSTEPS, scales
    from ctrl_analysis.arena.tuning import case_records
    from ctrl_analysis.engine import Save
    from ctrl_analysis.engine.blocks import signal_names
    from ctrl_analysis.engine.loop import Loop, place
    from ctrl_analysis.metrics import rmse

    from .meso.blocks import ModelledESO
    from .meso.paper import PAPER, SITUATIONS

    out = {k: {"rms_f": [], "rms": []} for k in ("MESO", "ESO")}
    k0, N = setup.k_from, setup.n
    ins = ["_y", "_u"] + [f"_theta[{i}]" for i in range(4)]
    for case in cases:
        d1, y, f = case_records(case, setup)
        u, theta = [], []
        for s in case.seeds:
            rec = _meso_record(int(s), setup.dt, N)
            scale = case.L / rec[3]  # the arena's change of units (make_signal)
            u.append(rec[4] * scale)
            theta.append(rec[5] * np.array([1.0, 1.0, 1.0, scale]))
        w = np.minimum(scales(case.eps, case.L, setup.dt)["omega"] * np.array(MESO_GRID), OMEGA_DT_RK4 / setup.dt)
        G, S = w.size, len(case.seeds)
        th = np.array(theta)  # (S, N, 4)
        for label, model in (("MESO", 1.0), ("ESO", 0.0)):
            inputs = {"_y": np.tile(y, (1, G)), "_u": np.tile(np.array(u).T, (1, G))}
            inputs.update({f"_theta[{i}]": np.tile(model * th[:, :, i].T, (1, G)) for i in range(4)})
            block = ModelledESO(PAPER, SITUATIONS["s1"].b0, 1.0 / w[0])
            loop = Loop([place(block, "obs", inputs=ins, outputs=signal_names("xhat", 3))], setup.dt,
                        substeps=SUBSTEPS)
            res = loop.simulate(N, inputs=inputs, params={"obs": {"epsilon": np.repeat(1.0 / w, S)}},
                                save=Save(states=False, keep=["xhat[0]", "xhat[1]"]),
                                execution=Execution(bound=np.inf, progress=False))
            fh, dh = res.signals["xhat[0]"][k0:N], res.signals["xhat[1]"][k0:N]
            cols = [slice(g * S, (g + 1) * S) for g in range(G)]
            out[label]["rms_f"].append(min(rmse(f[k0:], fh[:, c], axis=None) for c in cols))
            out[label]["rms"].append(min(rmse(d1[k0:], dh[:, c], axis=None) for c in cols))
    return {k: {m: np.array(v) for m, v in d.items()} for k, d in out.items()}


def register() -> None:
    """Register the two plant signal classes and the claim checks with the arena (idempotent)."""
    from ctrl_analysis.arena.claims import register_claim_check
    from ctrl_analysis.arena.signals import register_signal_class

    how = ("L = max of |x2'| over every integration step of the record, x2' evaluated by the plant's own kernel "
           "({}) at the step's start with the inputs held over the step")
    register_signal_class("de-example1", "differential-estimator Example 1: x1 of plant (19), w = sign(cos 0.3 t), "
                          "process noise ξ ~ U[-0.1, 0.1] held per step, from a seeded time", de_example1,
                          how.format("Plant19.rhs, ξ included"))
    register_signal_class("meso-situation1", "meso situation 1: x1 of plant (27) tracking sin t under PD (30) + "
                          "MESO (29), d = 1.3 x1 - 1.6 x2 (+1.8 after 30 s), from a seeded time after 5 s",
                          meso_situation1, how.format("Plant.rhs with the held control u and θ4"))
    for check in CLAIM_CHECKS:
        register_claim_check(check)


#: The pendulum paper's printed α-β gains K = [α, β] (§4), as the arena's given-gains filter ``ab`` runs them.
PENDULUM_GAINS = tuple(float(v) for v in VERIFY.K_printed)

#: The paper claims of one estimator against another that the arena judges at each family's best tuning.
CLAIM_CHECKS = (
    ClaimCheck("differential-estimator/sigma-beats-eso", ("sigma5",), ("neso",), ("de-example1",),
               "Σ estimates x1 = f and x2 = f' more accurately than Han's fal ESO (Example 1, Fig. 3-4)",
               "the paper's Σ, n0 = 5 (family sigma5), against the 3-state fal ESO, on both states, each family "
               "tuned to its own best for each; Σ with n0 = 3 (family sigma) is in the arena's table beside it",
               ("rms_f", "rms")),
    ClaimCheck("differential-estimator/sigma-beats-eso-fair", ("sigma5",), ("leso3", "neso"), ("de-example1",),
               "Σ estimates x1 = f and x2 = f' more accurately than an ESO (linear and fal) tuned as fairly",
               "the paper's Σ, n0 = 5 (family sigma5), on both states; the study equalises the -3 dB bandwidth, the "
               "arena tunes each family to its own best for each state", ("rms_f", "rms")),
    ClaimCheck("meso/s1-meso-better", ("MESO",), ("ESO",), ("meso-situation1",),
               "the modified ESO (MESO) estimates x1 and x2 more accurately than the ESO (situation 1, Table 2)",
               "the study's observer (29) with the loop's control u and its identified, smoothed Θ (the MESO) and "
               "with Θ = 0 (the conventional ESO (6), b0 u only), both fed the arena's noisy record of the same loop, "
               "each at its best bandwidth 1/ε on one 25-point grid per measure (meso_observer_errors); x1 and x2 "
               "only (the paper's Table 2 also compares x3, the total disturbance, which the arena does not score)",
               ("rms_f", "rms"), meso_observer_errors),
    ClaimCheck("meso/s2-meso-better", (), (), ("meso-situation1",),
               "the modified ESO estimates more accurately than the ESO (situation 2, Table 3)",
               "situation 2's loop (b0 = 3 against b = 3.95, the 0.95 u term) is not an arena signal class; "
               "situation 1's verdict is claim s1-meso-better"),
    ClaimCheck("pendulum/true-state", (("ab", PENDULUM_GAINS), "kalman"), (("algebraic", (2.0, 1.0)),), (),
               "the α-β filter gives a state closer to the true one than the noisy measurement (Fig. 3)",
               f"the paper's filter, its printed gains α, β = {PENDULUM_GAINS} as given (per sample, on each record's "
               "sample period), and the α-β filter at its best tuning (Kalata's Λ), each against the measurement's "
               "own derivative, its backward difference (the algebraic differentiator with window 2, degree 1, "
               "untuned; its f̂ is the measurement itself), on every signal class, for the angle and its rate",
               ("rms_f", "rms")),
)
