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

import math
from dataclasses import replace

import numpy as np

from ctrl_analysis.arena.claims import ClaimCheck
from ctrl_analysis.engine import Execution

from .pendulum.paper import VERIFY

__all__ = ["CLAIM_CHECKS", "PENDULUM_GAINS", "de_example1", "meso_situation1", "register"]

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
    return x[::sub, 0], x[::sub, 1], x2dot[::sub], float(np.max(np.abs(x2dot)))


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
    ClaimCheck("meso/s1-meso-better", (), (), ("meso-situation1",),
               "the modified ESO (MESO) estimates more accurately than the ESO (situation 1, Table 2)",
               "the MESO's advantage is the known model part XᵀΘ (the plant's input u and the identified "
               "parameters) fed into the observer; a signal-only estimator has no u, and without it the MESO is "
               "the linear ESO (leso3), so the arena cannot judge the claim"),
    ClaimCheck("meso/s2-meso-better", (), (), ("meso-situation1",),
               "the modified ESO estimates more accurately than the ESO (situation 2, Table 3)",
               "as in situation 1 the difference is the model input, which the arena's estimators do not get"),
    ClaimCheck("pendulum/true-state", (("ab", PENDULUM_GAINS), "kalman"), (("algebraic", (2.0, 1.0)),), (),
               "the α-β filter gives a state closer to the true one than the noisy measurement (Fig. 3)",
               f"the paper's filter, its printed gains α, β = {PENDULUM_GAINS} as given (per sample, on each record's "
               "sample period), and the α-β filter at its best tuning (Kalata's Λ), each against the measurement's "
               "own derivative, its backward difference (the algebraic differentiator with window 2, degree 1, "
               "untuned; its f̂ is the measurement itself), on every signal class, for the angle and its rate",
               ("rms_f", "rms")),
)
