"""Many points of the `pendulum` study's plausible box on the batch axis of one simulation.

:func:`simulate_points` runs the §5 step at many points ``(p, a21, kind)`` at once on a loop whose time axis is
counted in samples, so that every run may have its own T, a21, noise and α-β gains (:func:`ab_gains`); the
results equal :func:`.loops.simulate_case`'s to rounding (tested).
"""

from __future__ import annotations

import functools

import numpy as np

from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.blocks import StaticGain
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.kalman import AlphaBetaFilter
from ctrl_analysis.noise import draw_noise, gaussian_noise

from .blocks import BackwardDifference, CartPendulum, _Corrector, _Predictor
from .loops import CaseRuns, ClosedLoopRun, _fuzzy, _take, sampled_pendulum

__all__ = ["ab_gains", "simulate_points"]


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
    for i, (p, _a21, kind) in enumerate(points):
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
