"""The fuzzy closed loop of §5 built from library blocks through :class:`~ctrl_analysis.engine.loop.Loop`.

Signals: the cart–pendulum (continuous, linear or ``sin φ``) driven by the cart acceleration
``u`` and the process noise ``w`` (held per sample); the measurement ``y = φ + v`` (``v`` held per
sample); the fuzzy controller (discrete: sampled at ``T``) fed either by the raw error and its
backward difference (``nofilter``) or by a filter's estimate (``filter`` and the beyond-the-paper
cases).

Every block has a compiled kernel (the plant, :class:`.blocks.BackwardDifference`, the gains, the fuzzy
controllers, the filters and the two halves of :func:`.blocks.split_filter`), so
:meth:`~ctrl_analysis.engine.loop.Loop.simulate` runs these loops on the compiled engine, bit for bit the
numpy engine's results (``tests/studies/test_pendulum.py``). Three loop structures are compiled:
without filter (linear and ``sin φ`` plant: a flag parameter), with an α-β filter (every constant
gain) and with the time-varying Kalman filter.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ctrl_analysis.controllers.fuzzy import (
    FuzzyController,
    FuzzyLookupController,
    sum_rule_table,
)
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.blocks import StaticGain
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.kalman import (
    AlphaBetaFilter,
    DiscreteKalmanFilter,
    discrete_steady_state,
)
from ctrl_analysis.noise import draw_noise, gaussian_noise

from .blocks import BackwardDifference, CartPendulum, split_filter

__all__ = [
    "CASES",
    "LITERAL_CASES",
    "CaseRuns",
    "ClosedLoopRun",
    "RUNS_PER_PART",
    "StreamedRuns",
    "build_filter",
    "build_loop",
    "compute_regime",
    "fuzzy_controller",
    "recovery_sweep",
    "sampled_model",
    "simulate_case",
]


def fuzzy_controller(p, lookup: bool = True):
    """The §3.2 controller: 7×7 rule table ``U = sat(sign·(E + EC))``, factors Ke, Kec, Ku (``lookup``: query table)."""
    return _fuzzy(p.n_terms, p.rule_sign, p.Ke, p.Kec, p.Ku, p.input_range, p.output_range,
                  p.n_lookup if lookup else None)


@functools.lru_cache(maxsize=8)
def _fuzzy(n_terms, sign, Ke, Kec, Ku, input_range, output_range, n_lookup):
    """Built once per setting (the query table takes a second to compute); blocks are stateless, so sharing is safe."""
    fc = FuzzyController(sum_rule_table(n_terms, sign), Ke=Ke, Kec=Kec, Ku=Ku, input_range=input_range,
                         output_range=output_range)
    return fc if n_lookup is None else FuzzyLookupController(fc, n_lookup)


def sampled_model(a21: float, b2: float, T: float, sigma_w: float, sigma_v: float):
    """Exact discrete model of the held-input, held-noise pendulum: ``(F, g, Qd, Rd)``.

    ``x(k+1) = F x(k) + g (b2 u(k) + w(k))`` with ``F = e^{AT}``, ``g = ∫₀ᵀ e^{Aτ} dτ Γ`` (Van Loan block
    exponential), ``Qd = σ_w² g gᵀ``, ``Rd = σ_v²``.
    """
    M = np.zeros((3, 3))
    M[:2, :2] = [[0.0, 1.0], [a21, 0.0]]
    M[1, 2] = 1.0
    E = scipy.linalg.expm(M * T)
    F, g = E[:2, :2], E[:2, 2]
    return F, g, sigma_w**2 * np.outer(g, g), sigma_v**2


def sampled_pendulum(a21: float, T: float):
    """``(F, g)`` of :func:`sampled_model` in closed form (no matrix exponential), for ``a21 > 0``.

    ``A = [[0, 1], [a21, 0]]`` has ``e^{AT} = [[cosh ωT, sinh ωT / ω], [ω sinh ωT, cosh ωT]]`` with ``ω = √a21``,
    and ``g = ∫₀ᵀ e^{Aτ} dτ Γ = [(cosh ωT − 1) / a21, sinh ωT / ω]`` (equal to the Van Loan exponential to
    rounding, tested). Used where many points are set up at once: tiny matrix exponentials in a loop cost more
    in call overhead (and BLAS threads) than the simulation they set up.
    """
    w = math.sqrt(a21)
    ch, sh = math.cosh(w * T), math.sinh(w * T)
    return np.array([[ch, sh / w], [w * sh, ch]]), np.array([(ch - 1.0) / a21, sh / w])


def build_filter(kind: str, p, a21: float):
    """The filter of one case: ``alpha-beta`` (the paper's printed K as a discrete α-β filter), ``kf`` (time-varying),
    ``kf-ss`` (the correct steady-state gain for the simulated noise), ``kf-ss-qr`` (the steady-state gain of the
    paper's Q/R, σ_w/σ_v = √(Q/R)), ``continuous-printed`` (the printed continuous filter, Euler-sampled)."""
    F, g, Qd, Rd = sampled_model(a21, p.b2, p.T, p.sigma_w, p.sigma_v)
    b = g * p.b2
    if kind == "alpha-beta":
        return AlphaBetaFilter(p.K_printed[0], p.K_printed[1], p.T, F=F, b=b)
    if kind == "kf":
        return DiscreteKalmanFilter(F, [1.0, 0.0], Qd, Rd, b=b, P0=np.diag(p.P0_kf))
    if kind in ("kf-ss", "kf-ss-qr"):
        if kind == "kf-ss-qr":
            Qd = p.qr_paper * p.sigma_v**2 * np.outer(g, g)
        ss = discrete_steady_state(F, np.array([[1.0, 0.0]]), np.eye(2), Qd, Rd)
        alpha, beta = ss.K_filter[0, 0], p.T * ss.K_filter[1, 0]
        return AlphaBetaFilter(alpha, beta, p.T, F=F, b=b)
    if kind == "continuous-printed":
        # x̂' = A x̂ + B u + K (y − C x̂) sampled by forward Euler: x̂(k+1) = (I + AT) x̂ + T B u + T K (y − C x̂)
        # as an AlphaBetaFilter (x̂(k+1) = Fe (x̂ + K_f r) + b u) the correction gain is K_f = Fe⁻¹ T K
        Fe = np.eye(2) + p.T * np.array([[0.0, 1.0], [a21, 0.0]])
        Kf = np.linalg.solve(Fe, p.T * np.asarray(p.K_printed))
        return AlphaBetaFilter(Kf[0], p.T * Kf[1], p.T, F=Fe, b=[0.0, p.T * p.b2], require_stable=False)
    raise ValueError(f"kind must be one of 'alpha-beta', 'kf', 'kf-ss', 'kf-ss-qr', 'continuous-printed', got {kind!r}")


def build_loop(p, a21: float, *, filter_kind: str | None, nonlinear: bool = False, lookup: bool = True) -> Loop:
    """The §5 loop: plant, measurement, (filter or backward difference), fuzzy controller."""
    blocks = [place(CartPendulum(a21, p.b2, nonlinear), "plant"),
              place(StaticGain([[1.0, 1.0]], ("phi", "v"), ("y",)), "sensor"),
              place(fuzzy_controller(p, lookup), "fuzzy")]
    if filter_kind is None:
        blocks += [place(StaticGain([[1.0, -1.0]], ("r", "y"), ("e",)), "error"),
                   place(BackwardDifference(p.T), "diff")]
    else:
        blocks += split_filter(build_filter(filter_kind, p, a21), "filter")
        # e = r − φ̂, ec = ė = −φ̂' (r constant after the step)
        blocks.append(place(StaticGain([[1.0, -1.0, 0.0], [0.0, 0.0, -1.0]], ("r", "xhat[0]", "xhat[1]"),
                                       ("e", "ec")), "error"))
    return Loop(blocks, p.T, method="rk4", substeps=p.substeps)


@dataclass
class ClosedLoopRun:
    """One case over B runs: time, true state, measurement, estimate (or raw), control, divergence."""

    t: np.ndarray
    phi: np.ndarray
    dphi: np.ndarray
    y: np.ndarray
    e: np.ndarray
    ec: np.ndarray
    u: np.ndarray
    diverged: np.ndarray
    diverged_step: np.ndarray
    phi_hat: np.ndarray | None = None
    dphi_hat: np.ndarray | None = None


def simulate_case(p, a21: float, seeds, *, filter_kind=None, nonlinear=False, phi0=0.0, noise=True,
                  lookup=True, engine="auto", noise_free_extra=False) -> ClosedLoopRun:
    """Simulate the §5 step (r = ``p.step``) for the runs ``seeds``; same seeds, same noise in every case.

    ``engine`` as :meth:`~ctrl_analysis.engine.loop.Loop.simulate` (every block has a kernel: ``"auto"`` compiles).
    ``noise_free_extra`` appends one run without noise after the noisy ones.
    """
    loop = build_loop(p, a21, filter_kind=filter_kind, nonlinear=nonlinear, lookup=lookup)
    N = int(round(p.t_end / p.T))
    B = len(seeds)
    if noise:
        nz = draw_noise(seeds, N, gaussian_noise(p.sigma_w), gaussian_noise(p.sigma_v))
        w, v = nz[:, :, 0], nz[:, :, 1]
    else:
        w = v = np.zeros((N, B))
    if noise_free_extra:
        w, v = (np.concatenate([x, np.zeros((N, 1))], axis=1) for x in (w, v))
        B += 1
    x0 = {"plant": np.tile([phi0, 0.0], (B, 1)) if np.ndim(phi0) == 0 else np.stack([phi0, 0 * phi0], 1)}
    res = loop.simulate(N, inputs={"r": p.step, "w": w, "v": v}, x0=x0, runs=B,
                        execution=Execution(bound=p.bound, engine=engine))
    # a pendulum past |φ| = π/2 has fallen: counted as diverged from that step on (the linear model would not stop)
    fell = np.abs(res["phi"]) >= np.pi / 2
    first_fall = np.where(fell.any(axis=0), np.argmax(fell, axis=0), np.iinfo(np.int64).max)
    diverged = res.diverged | fell.any(axis=0)
    diverged_step = np.where(res.diverged, np.minimum(res.diverged_step, first_fall), first_fall)
    diverged_step = np.where(diverged, diverged_step, res.diverged_step)
    return ClosedLoopRun(t=res.t, phi=res["phi"], dphi=res["dphi"], y=res["y"], e=res["e"], ec=res["ec"],
                         u=res["u"], diverged=diverged, diverged_step=diverged_step,
                         phi_hat=res.signals.get("xhat[0]"), dphi_hat=res.signals.get("xhat[1]"))


def recovery_sweep(p, a21: float, angles, *, nonlinear: bool) -> np.ndarray:
    """Noise-free regulation (r = 0) from each initial angle in ``angles``: True where the loop recovers.

    Recovered: not flagged as diverged, ``|φ| < π/2`` throughout, and ``|φ(t_end)| < p.recover_tol``.
    """
    q = _replace(p, step=0.0)
    angles = np.asarray(angles, dtype=float)
    run = simulate_case(q, a21, list(range(angles.size)), nonlinear=nonlinear, phi0=angles, noise=False)
    ok = ~run.diverged & np.all(np.abs(run.phi) < np.pi / 2, axis=0) & (np.abs(run.phi[-1]) < p.recover_tol)
    return ok


def _replace(p, **kw):
    import dataclasses

    return dataclasses.replace(p, **kw)


#: Closed-loop cases: name -> (filter kind, nonlinear plant). ``filter`` is the paper's printed
#: (α, β) read as a discrete α-β filter (the reading under which it is stable), or with the gain reading
#: ``steady-state`` (the algorithm axis) the steady-state Kalman gain (:func:`case_kind`).
CASES = {
    "nofilter": (None, False),
    "filter": ("alpha-beta", False),
    "kf": ("kf", False),
    "kf_ss": ("kf-ss", False),
    "kf_ss_qr": ("kf-ss-qr", False),
    "paper_continuous": ("continuous-printed", False),
    "nonlinear.nofilter": (None, True),
    "nonlinear.filter": ("alpha-beta", True),
}
#: the cases simulated in the literal regime (there kf_ss_qr is kf_ss; the others as in the main regime)
LITERAL_CASES = ("nofilter", "filter", "kf", "kf_ss")


@dataclass
class CaseRuns:
    """One case of one regime: the Monte Carlo runs and the noise-free run (the step transient)."""

    noisy: ClosedLoopRun
    quiet: ClosedLoopRun

    def light(self) -> CaseRuns:
        """Only which runs diverged and when (what recording needs besides the metrics), without the signals."""
        def strip(r):
            return ClosedLoopRun(t=None, phi=None, dphi=None, y=None, e=None, ec=None, u=None, diverged=r.diverged,
                                 diverged_step=r.diverged_step)

        return CaseRuns(strip(self.noisy), strip(self.quiet))


def filter_kind(p) -> str:
    """The filter of the ``filter`` case under the gain reading ``p.gain_reading`` (the algorithm axis):
    the paper's K as an α-β filter (``"paper"``) or the steady-state Kalman gain (``"steady-state"``)."""
    return {"paper": "alpha-beta", "steady-state": "kf-ss"}[p.gain_reading]


def case_kind(name: str, p):
    """``(filter kind, nonlinear)`` of case ``name`` (:data:`CASES`; the filter case follows the gain reading)."""
    kind, nonlinear = CASES[name]
    return (filter_kind(p) if kind == "alpha-beta" else kind), nonlinear


#: Most Monte Carlo runs of one case simulated together. Up to this many, a case keeps every run's traces (the
#: default 100 runs do); above it the runs are simulated in consecutive parts and each part is reduced to its
#: runs' metrics and a running mean and variance of φ (:class:`StreamedRuns`), so memory is bounded by the part
#: (about 0.25 MB a run a case), not by ``--runs``.
RUNS_PER_PART = 256


@dataclass
class StreamedRuns(ClosedLoopRun):
    """A case's Monte Carlo runs reduced part by part (:func:`compute_regime` above :data:`RUNS_PER_PART` runs).

    ``diverged`` and ``diverged_step`` cover every run; the trace fields hold run 0 only (what the figures
    draw), so code that reads every run's trace fails on the shape instead of reading part of the runs.
    ``per_run`` holds :func:`~.regimes.case_metrics`' per-run metrics of every run; ``phi_moments`` the mean and
    variance of φ per sample over the runs that did not diverge (:class:`ctrl_analysis.streaming.Moments`).
    """

    per_run: dict | None = None
    phi_moments: object = None


def compute_regime(p, a21: float, seeds, cases=tuple(CASES)) -> dict:
    """``{case: CaseRuns}``: each case over ``seeds`` (same noise in every case) and noise-free.

    The noise-free run rides in the same batch as one more run with zero noise (runs are independent and
    bit-identical to single runs, so this is the separate noise-free simulation at half the calls). Above
    :data:`RUNS_PER_PART` runs a case's runs are simulated part by part and kept as :class:`StreamedRuns`.
    """
    out = {}
    seeds = list(seeds)
    for name in cases:
        kind, nonlinear = case_kind(name, p)
        if len(seeds) > RUNS_PER_PART:
            out[name] = _streamed_case(p, a21, seeds, kind, nonlinear)
            continue
        both = simulate_case(p, a21, seeds, filter_kind=kind, nonlinear=nonlinear, noise_free_extra=True)
        B = len(seeds)
        out[name] = CaseRuns(_take(both, slice(0, B)), _take(both, slice(B, B + 1)))
    return out


def _streamed_case(p, a21, seeds, kind, nonlinear) -> CaseRuns:
    """One case's runs in consecutive parts of at most :data:`RUNS_PER_PART`, each reduced as it ends."""
    from ctrl_analysis.runs.parallel import chunk_slices
    from ctrl_analysis.streaming import Moments

    from .regimes import PER_RUN, case_metrics

    per_run, moments, div, step, first, quiet = {}, Moments(), [], [], None, None
    for i, sl in enumerate(chunk_slices(len(seeds), chunks=-(-len(seeds) // RUNS_PER_PART))):
        B = sl.stop - sl.start
        run = simulate_case(p, a21, seeds[sl], filter_kind=kind, nonlinear=nonlinear, noise_free_extra=i == 0)
        if i == 0:  # copies: a view would keep the whole part's traces alive
            quiet = _copy(_take(run, slice(B, B + 1)))
            run = _take(run, slice(0, B))
            first = _copy(_take(run, slice(0, 1)))
        for k, v in case_metrics(CaseRuns(run, quiet), p, PER_RUN).items():
            per_run.setdefault(k, []).append(v)
        moments.add(run.phi.T, exclude=run.diverged)
        div.append(run.diverged)
        step.append(run.diverged_step)
    noisy = StreamedRuns(**{**first.__dict__, "diverged": np.concatenate(div), "diverged_step": np.concatenate(step)},
                         per_run={k: np.concatenate(v) for k, v in per_run.items()}, phi_moments=moments)
    return CaseRuns(noisy, quiet)


def _copy(run: ClosedLoopRun) -> ClosedLoopRun:
    """``run`` with its own copy of every array (not views of a larger batch)."""
    return ClosedLoopRun(**{f: (None if v is None else np.array(v)) for f, v in run.__dict__.items()})


def _take(run: ClosedLoopRun, idx) -> ClosedLoopRun:
    """The runs ``idx`` (a slice) of a :class:`ClosedLoopRun`."""
    return ClosedLoopRun(**{f: (v if f == "t" or v is None else v[..., idx])
                            for f, v in run.__dict__.items()})
