"""The fuzzy closed loop of §5 built from library blocks through :class:`~ctrl_analysis.engine.loop.Loop`.

Signals: the cart–pendulum (continuous, linear or ``sin φ``) driven by the cart acceleration
``u`` and the process noise ``w`` (held per sample); the measurement ``y = φ + v`` (``v`` held per
sample); the fuzzy controller (discrete: sampled at ``T``) fed either by the raw error and its
backward difference (``nofilter``) or by a filter's estimate (``filter`` and the beyond-the-paper
cases).

Every block has a compiled kernel (the plant, :class:`BackwardDifference`, the gains, the fuzzy
controllers, the filters and the two halves of :func:`split_filter`), so
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
from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.blocks import (
    ContinuousBlock,
    DiscreteBlock,
    StaticBlock,
    StaticGain,
)
from ctrl_analysis.engine.kernels import (
    KernelBlock,
    Kernels,
    Layout,
    as_int,
    copy_output,
)
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.kalman import (
    AlphaBetaFilter,
    DiscreteKalmanFilter,
    discrete_steady_state,
)
from ctrl_analysis.simulate import draw_noise, gaussian_noise, run_seeds

__all__ = [
    "CASES",
    "LITERAL_CASES",
    "BackwardDifference",
    "CartPendulum",
    "CaseRuns",
    "ClosedLoopRun",
    "LoopData",
    "build_filter",
    "build_loop",
    "compute_loops",
    "compute_regime",
    "fuzzy_controller",
    "qr_sweep",
    "recovery_sweep",
    "sampled_model",
    "seeds_for",
    "simulate_case",
    "split_filter",
]


PENDULUM = Layout("a21", "b", "nonlinear")
AT = PENDULUM.at  # parameter offsets, a numba constant


def pendulum_rhs(t, x, u, p, dx):
    """``φ'' = a21 φ + b u + w`` (§3.1, ``ẋ = A x + B u + Γ w``) or, flag set, ``a21 sin φ + b cos φ · u + w``.

    The kernel of :class:`CartPendulum`: ``p`` is :data:`PENDULUM`, ``u = [u, w]``.
    """
    dx[0] = x[1]
    if as_int(p[AT.nonlinear]):
        dx[1] = p[AT.a21] * np.sin(x[0]) + p[AT.b] * np.cos(x[0]) * u[0] + u[1]
    else:
        dx[1] = p[AT.a21] * x[0] + p[AT.b] * u[0] + u[1]


class CartPendulum(KernelBlock, ContinuousBlock):
    """Pendulum on a cart driven by the cart acceleration (§3.1): ``φ'' = a21 φ + b u + w``.

    With ``nonlinear=True``: ``φ'' = a21 sin φ + b cos φ · u + w`` (the model before linearisation,
    ``φ'' = 3g/(4l) sin φ + 3/(4l) cos φ · u`` with ``a21 = 3g/(4l)``, ``b = 3/(4l)``).

    Inputs ``u`` (m/s²), ``w`` (rad/s²); states and outputs ``phi`` (rad), ``dphi`` (rad/s).
    """

    inputs = ("u", "w")
    outputs = ("phi", "dphi")
    states = ("phi", "dphi")
    kernels = Kernels(rhs=pendulum_rhs)

    def __init__(self, a21: float, b: float, nonlinear: bool = False):
        self.a21, self.b, self.nonlinear = float(a21), float(b), bool(nonlinear)
        self.kernel_params = PENDULUM.pack(a21=self.a21, b=self.b, nonlinear=1.0 if self.nonlinear else 0.0)


DIFFERENCE = Layout("T")
DT = DIFFERENCE.at  # parameter offsets, a numba constant


def difference_output(t, x, u, p, y):
    """``ec(k) = (e(k) − e(k−1)) / T``, ``p`` = :data:`DIFFERENCE`."""
    y[0] = (u[0] - x[0]) / p[DT.T]


def difference_update(t, x, u, p, x_next):
    """``e_prev(k+1) = e(k)``."""
    x_next[0] = u[0]


class BackwardDifference(KernelBlock, DiscreteBlock):
    """``ec(k) = (e(k) − e(k−1)) / T``: the rate the fuzzy controller gets without a filter (state ``e(k−1)``)."""

    inputs = ("e",)
    outputs = ("ec",)
    states = ("e_prev",)
    feedthrough = True
    kernels = Kernels(output=difference_output, update=difference_update)

    def __init__(self, T: float):
        self.T = float(T)
        self.kernel_params = DIFFERENCE.pack(T=self.T)


class _Predictor(KernelBlock, DiscreteBlock):
    """A filter block's prediction half: the filter's state and update kernel, output = its state (no feedthrough)."""

    feedthrough = False

    def __init__(self, filt: KernelBlock, prefix: str):
        self.filt = filt
        self.inputs, self.states = filt.inputs, filt.states
        self.outputs = tuple(f"{prefix}.{s}" for s in filt.states)
        self.kernel_params = filt.kernel_params

    @property
    def kernels(self) -> Kernels:
        """The filter's update kernel; output = state (:func:`~ctrl_analysis.engine.kernels.copy_output`)."""
        k = self.filt.kernels
        return Kernels(output=copy_output, update=k.update, columns=k.columns)

    def initial_state(self):
        return self.filt.initial_state()


class _Corrector(KernelBlock, StaticBlock):
    """A filter block's correction half: its output kernel on ``(predictor state, y)``, a static block.

    The filter's output kernel reads the state from its inputs when the block has no state (the
    filters' kernels document this layout), on the batch's columns as in the compiled engine.
    """

    def __init__(self, filt: KernelBlock, pred: _Predictor):
        self.filt = filt
        self.inputs, self.outputs = pred.outputs + ("y",), tuple(filt.outputs)
        self.kernel_params = filt.kernel_params

    @property
    def kernels(self) -> Kernels:
        """The filter's output kernel (state read from the inputs)."""
        k = self.filt.kernels
        return Kernels(output=k.output, columns=k.columns)


def split_filter(filt: DiscreteBlock, name: str) -> list:
    """Place a filter whose output needs ``y(k)`` but not ``u(k)`` in a loop where ``u(k)`` depends on that output.

    :class:`~ctrl_analysis.engine.loop.Loop` treats feedthrough per block, so a filter with inputs
    ``(y, u)`` and direct feedthrough closes an algebraic loop with a controller that reads its
    estimate. The filter (a :class:`~ctrl_analysis.engine.kernels.KernelBlock`) is placed as two
    blocks that reuse its own kernels: a predictor (its state and update kernel, output = state, no
    feedthrough) and a static corrector (its output kernel evaluated on the predictor's state and ``y``).
    """
    if not isinstance(filt, KernelBlock):
        raise TypeError(f"filt must be a kernel-first filter block (KernelBlock), got {type(filt).__name__}")
    pred = _Predictor(filt, name)
    corr = _Corrector(filt, pred)
    return [place(pred, f"{name}.pred"), place(corr, f"{name}.corr")]


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


def compute_regime(p, a21: float, seeds, cases=tuple(CASES)) -> dict:
    """``{case: CaseRuns}``: each case over ``seeds`` (same noise in every case) and noise-free.

    The noise-free run rides in the same batch as one more run with zero noise (runs are independent and
    bit-identical to single runs, so this is the separate noise-free simulation at half the calls).
    """
    out = {}
    for name in cases:
        kind, nonlinear = case_kind(name, p)
        both = simulate_case(p, a21, seeds, filter_kind=kind, nonlinear=nonlinear, noise_free_extra=True)
        B = len(seeds)
        out[name] = CaseRuns(_take(both, slice(0, B)), _take(both, slice(B, B + 1)))
    return out


def _take(run: ClosedLoopRun, idx) -> ClosedLoopRun:
    """The runs ``idx`` (a slice) of a :class:`ClosedLoopRun`."""
    return ClosedLoopRun(**{f: (v if f == "t" or v is None else v[..., idx])
                            for f, v in run.__dict__.items()})


def qr_sweep(p, a21: float, seeds) -> dict:
    """Beyond the paper: σ_w/σ_v swept at the main σ_v and T; per ratio, the steady angle-estimate error RMS and the
    steady angle RMS of no filter, the paper's K and the steady-state gain optimal for that ratio, and its α; the share of
    healthy (not diverged) runs each mean is taken over."""
    ratios = np.geomspace(p.qr_sweep[0], p.qr_sweep[1], int(p.qr_sweep[2]))
    names = ("nofilter", "filter", "kf_ss")
    kinds = {"nofilter": None, "filter": "alpha-beta", "kf_ss": "kf-ss"}  # "filter": the paper's K, always
    qs = [_replace(p, sigma_w=float(r * p.sigma_v)) for r in ratios]
    # every ratio and case side by side on the batch axis (:func:`simulate_points`; same runs as simulate_case)
    runs = simulate_points([(q, a21, kinds[n]) for q in qs for n in names], seeds)
    out = {"ratios": ratios, "alpha_opt": [g[0] for g in ab_gains([(q, a21, "kf-ss") for q in qs])],
           "est": {k: [] for k in names}, "angle": {k: [] for k in names}, "healthy": {k: [] for k in names}}
    for i, _q in enumerate(qs):
        for j, name in enumerate(names):
            run = runs[i * len(names) + j].noisy
            ss = (run.t >= p.t_ss)
            ok = ~run.diverged
            out["healthy"][name].append(float(np.mean(ok)))
            if not ok.any():
                out["est"][name].append(np.nan)
                out["angle"][name].append(np.nan)
                continue
            angle_in = p.step - run.e[ss][:, ok]
            out["est"][name].append(float(np.sqrt(np.mean((angle_in - run.phi[ss][:, ok]) ** 2))))
            out["angle"][name].append(float(np.sqrt(np.mean((run.phi[ss][:, ok] - p.step) ** 2))))
    return {k: (np.asarray(v) if not isinstance(v, dict) else {n: np.asarray(x) for n, x in v.items()})
            for k, v in out.items()}


@dataclass
class LoopData:
    """Everything the closed-loop part computes: both regimes over the Monte Carlo runs, the checks and sweeps."""

    p: object
    a21: float
    seeds: list
    main: dict
    literal: dict
    sign_check: dict
    period_check: dict
    angles: np.ndarray
    recovered: dict
    lookup_error: float
    kf_ss_gain: tuple
    kf_ss_qr_gain: tuple
    qr: dict

    @property
    def lit(self):
        """The literal regime's parameters."""
        return self.p.literal()


def compute_loops(p, a21: float, seeds, progress=lambda msg: None, qr_seeds=None) -> LoopData:
    """Both regimes (main: every case of :data:`CASES`; literal: :data:`LITERAL_CASES`) on the same noise, the
    rule-sign and sampling-period checks (noise-free, one run), the recovery sweeps and the σ_w/σ_v sweep."""
    progress(f"closed loop, main regime: {len(CASES)} cases × {len(seeds)} runs")
    main = compute_regime(p, a21, seeds)
    progress(f"closed loop, literal regime: {len(LITERAL_CASES)} cases × {len(seeds)} runs")
    literal = compute_regime(p.literal(), a21, seeds, LITERAL_CASES)
    sign = {s: simulate_case(_replace(p, rule_sign=s), a21, [0], noise=False) for s in (1, -1)}
    period = {T: simulate_case(_replace(p, T=T), a21, [0], noise=False) for T in p.period_check}
    angles = np.linspace(*p.recover_angles[:2], int(p.recover_angles[2]))
    progress("recovery sweeps (linear, nonlinear) and the σ_w/σ_v sweep")
    recovered = {nl: recovery_sweep(p, a21, angles, nonlinear=nl) for nl in (False, True)}
    qr = qr_sweep(p, a21, seeds[:30] if qr_seeds is None else qr_seeds)
    direct, table = fuzzy_controller(p, lookup=False), fuzzy_controller(p, lookup=True)
    e, ec = np.meshgrid(np.linspace(-0.1, 0.1, 97), np.linspace(-1.5, 1.5, 97))
    err = float(np.max(np.abs(direct.evaluate(e, ec) - table.evaluate(e, ec))))
    ss, ssq = build_filter("kf-ss", p, a21), build_filter("kf-ss-qr", p, a21)
    return LoopData(p=p, a21=a21, seeds=list(seeds), main=main, literal=literal, sign_check=sign,
                    period_check=period, angles=angles, recovered=recovered, lookup_error=err,
                    kf_ss_gain=(ss.alpha, ss.beta), kf_ss_qr_gain=(ssq.alpha, ssq.beta), qr=qr)


def seeds_for(base_seed: int, runs: int) -> list:
    """Per-run seeds (recorded in results.json)."""
    return run_seeds(base_seed, runs)


# ---------------------------------------------------------------------------------------------------------------
# many points of the plausible box on the batch axis of one simulation


class _ABPredictor(_Predictor):
    """:class:`_Predictor` of an :class:`AlphaBetaFilter` built from numbers, so that every run may have its own
    gains, ``F`` and ``b`` (``Loop.simulate(params={"filter.pred": {...}})``)."""

    def __init__(self, alpha, beta, T, F, b):
        super().__init__(AlphaBetaFilter(alpha, beta, T, F=F, b=b, require_stable=False), "filter")


class _ABCorrector(_Corrector):
    """:class:`_Corrector` of an :class:`AlphaBetaFilter` built from numbers (see :class:`_ABPredictor`)."""

    def __init__(self, alpha, beta, T, F, b):
        filt = AlphaBetaFilter(alpha, beta, T, F=F, b=b, require_stable=False)
        super().__init__(filt, _Predictor(filt, "filter"))


#: the time unit of the scaled loops (:func:`simulate_points`): one loop step is one sample of every run
_UNIT = 1.0


@functools.lru_cache(maxsize=16)
def _scaled_loop(filtered: bool, fuzzy_key: tuple, substeps: int) -> Loop:
    """The §5 loop on a time axis counted in samples (``dt = 1``): plant and filter parameters are given per run.

    Built once per structure and reused (its compiled plan too); :func:`simulate_points` sets the per-run values.
    """
    blocks = [place(CartPendulum(1.0, 1.0), "plant"),
              place(StaticGain([[1.0, 1.0]], ("phi", "v"), ("y",)), "sensor"),
              place(_fuzzy(*fuzzy_key), "fuzzy")]
    if not filtered:
        blocks += [place(StaticGain([[1.0, -1.0]], ("r", "y"), ("e",)), "error"),
                   place(BackwardDifference(_UNIT), "diff")]
    else:
        ab = (0.5, 0.1, _UNIT, np.eye(2), np.zeros(2))
        blocks += [place(_ABPredictor(*ab), "filter.pred"), place(_ABCorrector(*ab), "filter.corr"),
                   place(StaticGain([[1.0, -1.0, 0.0], [0.0, 0.0, -1.0]], ("r", "xhat[0]", "xhat[1]"),
                                    ("e", "ec")), "error")]
    return Loop(blocks, _UNIT, method="rk4", substeps=substeps)


def _fuzzy_key(p) -> tuple:
    return (p.n_terms, p.rule_sign, p.Ke, p.Kec, p.Ku, p.input_range, p.output_range, p.n_lookup)


@functools.lru_cache(maxsize=256)
def _unit_noise(seeds: tuple, n_steps: int) -> np.ndarray:
    """Unit-variance draws ``(n_steps, runs, 2)`` of the runs' seeds (process, measurement), as :func:`simulate_case`
    draws them: ``σ·z`` is bit for bit its noise of standard deviation σ."""
    return draw_noise(list(seeds), n_steps, gaussian_noise(1.0), gaussian_noise(1.0))


def ab_gains(points) -> list:
    """``(alpha, beta, F, b)`` of the α-β filter of each point ``(p, a21, kind)`` (kind "alpha-beta" or "kf-ss").

    As :func:`build_filter`, with every steady-state gain of the points solved at once
    (:func:`~ctrl_analysis.estimators.kalman.discrete_steady_state_batch`; equal to ``build_filter``'s to 1e-9, tested).
    """
    from ctrl_analysis.estimators.kalman.discrete import discrete_steady_state_batch

    models = [sampled_pendulum(a21, p.T) for p, a21, _ in points]
    out = [None] * len(points)
    ss = [i for i, (_, _, k) in enumerate(points) if k == "kf-ss"]
    if ss:
        F = np.stack([models[i][0] for i in ss])
        Qd = np.stack([points[i][0].sigma_w ** 2 * np.outer(models[i][1], models[i][1]) for i in ss])
        Rd = np.array([points[i][0].sigma_v ** 2 for i in ss], dtype=float)
        K = discrete_steady_state_batch(F, np.array([[1.0, 0.0]]), Qd, Rd).K_filter.reshape(len(ss), 2)
        for j, i in enumerate(ss):
            p = points[i][0]
            out[i] = (float(K[j, 0]), float(p.T * K[j, 1]), models[i][0], models[i][1] * p.b2)
    for i, (p, _, k) in enumerate(points):
        if k == "alpha-beta":
            out[i] = (float(p.K_printed[0]), float(p.K_printed[1]), models[i][0], models[i][1] * p.b2)
        elif k != "kf-ss":
            raise ValueError(f"kind must be 'alpha-beta' or 'kf-ss' for a filtered box point, got {k!r}")
    return out


def simulate_points(points, seeds, *, ratio: float = 1.25, on_point=None, keep=None) -> list:
    """The §5 step at many points of the plausible box at once: ``[CaseRuns]``, one per point ``(p, a21, kind)``.

    ``kind`` is ``None`` (no filter), ``"alpha-beta"`` (the paper's K) or ``"kf-ss"`` (the steady-state gain).
    Every point runs ``seeds`` (its noise scaled from the same unit draws: common random numbers) plus one
    noise-free run, side by side on the batch axis of one simulation per loop structure (filtered or not, fuzzy
    controller): the per-run parameters (``Loop.simulate(params=...)``) carry each point's a21, b2, T, gains.

    Points with different sampling periods T share a simulation on a time axis counted in samples: with
    ``τ = t/T`` the pendulum ``φ'' = a21 φ + b2 u + w`` reads ``d²φ/dτ² = T²(a21 φ + b2 u + w)``, so a run with
    its own T has plant parameters ``T² a21``, ``T² b2``, process noise ``T² w`` and rate state ``T φ'``; the
    held inputs, the filter (its own F, b) and the backward difference (its own T) see the same samples. This is
    the same RK4 on the same samples (to rounding, tested against :func:`simulate_case`). A run is simulated for
    its own ``t_end / T`` samples; points are chunked by T (at most ``ratio`` apart) so short-T runs do not
    make long-T runs step far past their horizon.

    ``on_point(i, case_runs)``: called for each point as soon as its chunk is simulated; the runs are then not
    kept (the list returned holds None), so memory stays at one chunk's. ``keep``: the signals stored (default
    all that :class:`ClosedLoopRun` holds; ``phi_hat``/``dphi_hat`` are None without ``xhat``).
    """
    seeds = tuple(int(s) for s in seeds)
    out = [None] * len(points)
    groups: dict = {}
    for i, (p, a21, kind) in enumerate(points):
        key = (kind is not None, _fuzzy_key(p), p.substeps, p.step, p.bound)
        groups.setdefault(key, []).append(i)
    for (filtered, fkey, substeps, step, bound), idx in groups.items():
        idx = sorted(idx, key=lambda i: points[i][0].T)
        chunks, cur = [], []
        for i in idx:
            if cur and points[i][0].T > ratio * points[cur[0]][0].T:
                chunks.append(cur)
                cur = []
            cur.append(i)
        chunks.append(cur)
        loop = _scaled_loop(filtered, fkey, substeps)
        for chunk in chunks:
            _simulate_chunk(loop, [points[i] for i in chunk], seeds, step, bound, filtered, out, chunk, on_point, keep)
    return out


def _simulate_chunk(loop, pts, seeds, step, bound, filtered, out, where, on_point=None, keep=None) -> None:
    R = len(seeds)
    per = R + 1  # the noisy runs and one noise-free run
    Ns = [round(p.t_end / p.T) for p, _, _ in pts]
    N = max(Ns)
    B = per * len(pts)
    w, v = np.zeros((N, B)), np.zeros((N, B))
    Ts = np.array([p.T for p, _, _ in pts])
    for j, (p, _, _) in enumerate(pts):
        z = _unit_noise(seeds, Ns[j])
        n, cols = Ns[j], slice(j * per, j * per + R)
        w[:n, cols] = (p.sigma_w * z[:, :, 0]) * p.T ** 2
        v[:n, cols] = p.sigma_v * z[:, :, 1]
        if n < N:  # the run's last instant repeats its last sample, as Loop.simulate does at the end of a record
            w[n, cols], v[n, cols] = w[n - 1, cols], v[n - 1, cols]
    def rep(x):
        return np.repeat(np.asarray(x, dtype=float), per, axis=0)

    params = {"plant": {"a21": rep([a21 * p.T ** 2 for p, a21, _ in pts]),
                        "b": rep([p.b2 * p.T ** 2 for p, _, _ in pts])}}
    if filtered:
        g = ab_gains(pts)
        vals = {"alpha": rep([x[0] for x in g]), "beta": rep([x[1] for x in g]), "T": rep(Ts),
                "F": rep([x[2] for x in g]), "b": rep([x[3] for x in g])}
        params["filter.pred"] = params["filter.corr"] = vals
    else:
        params["diff"] = {"T": rep(Ts)}
    keep = (["phi", "dphi", "y", "e", "ec", "u"] + (["xhat[0]", "xhat[1]"] if filtered else [])) if keep is None \
        else ["phi"] + [k for k in keep if k != "phi" and (filtered or not k.startswith("xhat"))]
    res = loop.simulate(N, inputs={"r": step, "w": w, "v": v}, params=params, runs=B,
                        save=Save(keep=keep, states=False), execution=Execution(bound=bound))
    for j, (p, _, _) in enumerate(pts):
        n, sl = Ns[j], slice(j * per, (j + 1) * per)
        T = p.T
        phi = res["phi"][:n + 1, sl]
        flagged = res.diverged[sl] & (res.diverged_step[sl] <= n)
        fell = np.abs(phi) >= np.pi / 2
        first_fall = np.where(fell.any(axis=0), np.argmax(fell, axis=0), np.iinfo(np.int64).max)
        diverged = flagged | fell.any(axis=0)
        dstep = np.where(flagged, np.minimum(res.diverged_step[sl], first_fall), first_fall)
        dstep = np.where(diverged, dstep, -1)
        def sig(k, scale=None, n=n, sl=sl):
            if k not in keep:
                return None
            return res[k][:n + 1, sl] if scale is None else res[k][:n + 1, sl] / scale

        run = ClosedLoopRun(t=T * np.arange(n + 1), phi=phi, dphi=sig("dphi", T), y=sig("y"), e=sig("e"), ec=sig("ec"),
                            u=sig("u"), diverged=diverged, diverged_step=dstep, phi_hat=sig("xhat[0]"),
                            dphi_hat=sig("xhat[1]"))
        c = CaseRuns(_take(run, slice(0, per - 1)), _take(run, slice(per - 1, per)))
        if on_point is None:
            out[where[j]] = c
        else:
            on_point(where[j], c)
