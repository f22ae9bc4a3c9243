"""The closed loops of §4 built from blocks: plant (27), (M)ESO (29), PD law (30)/(12), LSM identification, W(s).

One :class:`~ctrl_analysis.engine.loop.Loop` per situation carries every configuration on the batch axis
(ESO / MESO, identification variant, noise seed, ε, plant gain, identifiability threshold, W(s)
bypassed or not). It is stepped one identification batch (N samples) at a time, so memory stays
bounded over 210 s; after each chunk the identification's batch-end solve is applied to the final
states (:meth:`~.identification.BatchIdentification.identify`), and the table sums, the batch-end
identification records and the trajectories of a few runs kept for the figures are taken from the
named signals.

Every block has a compiled kernel, so :meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>`
runs the whole loop as one numba function; ``CTRL_ANALYSIS_ENGINE=numpy`` gives the same results bit
for bit. The blocks are built for one configuration; what differs per run (the plant gain b, the
observer's ε, the W(s) bypass flag) is given to the simulation (:func:`run_params`), and the
identification's variant and gate per run to its batch-end solve. The blocks are in :mod:`.blocks`, what each
chunk adds to the tables in :mod:`.chunk_errors`.
"""


from dataclasses import dataclass, field

import numpy as np

from ctrl_analysis.controllers.pd import PDFeedforward
from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.blocks import signal_names
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.estimators.lowpass import LowPassFilter
from ctrl_analysis.noise import draw_noise, uniform_noise
from ctrl_analysis.runs.parallel import chunk_slices, map_chunks

from .blocks import ModelledESO, ParameterPath, Plant
from .chunk_errors import METRIC_ORDER, _accumulator, full_solved
from .identification import BatchIdentification, exact_report
from .paper import GATE_RERUNS, PAPER, Paper, Situation

__all__ = [
    "Row",
    "SituationRun",
    "build_loop",
    "pick",
    "run_params",
    "simulate_situation",
    "situation_rows",
]


@dataclass(frozen=True)
class Row:
    """One configuration on the batch axis.

    observer : "eso" or "meso"; variant : identification variant (``"none"`` for the ESO); seed : noise
    seed or None (noise off); b_plant : input gain of the simulated plant; epsilon : observer ε;
    bypass_w : feed the LSM result to the observer without W(s); threshold : identifiability gate.
    """

    observer: str
    variant: str
    seed: int | None
    b_plant: float = PAPER.b
    epsilon: float = PAPER.epsilon
    bypass_w: bool = False
    threshold: float = PAPER.cond_threshold
    x0: tuple = PAPER.x0
    xhat0: tuple = PAPER.x_hat0

    @property
    def label(self) -> str:
        v = "" if self.observer == "eso" else f"-{self.variant}" + ("-noW" if self.bypass_w else "")
        extra = "".join([f"/eps={self.epsilon:g}" if self.epsilon != PAPER.epsilon else "",
                         f"/b={self.b_plant:g}" if self.b_plant != PAPER.b else "",
                         f"/gate={self.threshold:g}" if self.threshold != PAPER.cond_threshold else "",
                         f"/x0={self.x0}" if self.x0 != PAPER.x0 else "",
                         f"/xhat0={self.xhat0}" if self.xhat0 != PAPER.x_hat0 else ""])
        return f"{self.observer}{v}/" + ("no-noise" if self.seed is None else f"seed{self.seed}") + extra


def build_loop(sit: Situation, paper: Paper = PAPER) -> Loop:
    """The loop of situation ``sit`` at the paper's configuration (per-run changes: :func:`run_params`).

    Parameters
    ----------
    sit : Situation
    paper : Paper

    Returns
    -------
    ctrl_analysis.engine.loop.Loop
        Blocks ``plant`` (27), ``observer`` (29), ``pd`` (30)/(12), ``lsm`` (Table 1), ``W`` (W(s)) and
        ``path``; external inputs ``level`` (θ4), ``v`` (noise), ``r[0..2]`` (ξ, ξ', ξ'').
    """
    pd = PDFeedforward(b0=sit.b0, omega_c=paper.omega_c, order=paper.n, model=True)
    lpf = LowPassFilter(paper.omega_f, order=2).digital(paper.h, channels=4)
    ident = BatchIdentification(sit.N, paper.h, sit.b0, pd.k, sit.regression)
    xhat = signal_names("xhat", 3)
    return Loop([
        place(Plant(paper, paper.b), "plant"),
        place(ModelledESO(paper, sit.b0, paper.epsilon), "observer"),
        place(pd, "pd", inputs=signal_names("r", 3) + xhat + signal_names("theta", 4)),
        place(ident, "lsm"),
        place(lpf, "W", inputs=signal_names("c", 4), outputs=signal_names("w", 4)),
        place(ParameterPath(), "path"),
    ], paper.h, method=paper.integrator)


def run_params(rows) -> dict:
    """The per-run block parameters of ``rows`` for :meth:`Loop.simulate <ctrl_analysis.engine.loop.Loop.simulate>`.

    Parameters
    ----------
    rows : sequence of Row
        One configuration per run of the batch.

    Returns
    -------
    dict
        ``{"plant": {"b": ...}, "observer": {"epsilon": ...}, "path": {"bypass": ...}}``, one value per run.
    """
    return {"plant": {"b": np.array([r.b_plant for r in rows], dtype=float)},
            "observer": {"epsilon": np.array([r.epsilon for r in rows], dtype=float)},
            "path": {"bypass": np.array([r.bypass_w for r in rows], dtype=bool)}}


@dataclass
class SituationRun:
    """What one situation's simulation keeps (``K`` samples, ``B`` runs, ``nb`` batches)."""

    rows: list
    t: np.ndarray                       # (K,)
    sums: dict                          # metric -> (B,) Σ|e| over the whole run
    window_sums: dict                   # metric -> (B,) Σ|e| over analysis.eps_window
    n_window: int
    sup_dx3: np.ndarray                 # (B,) sup |Δx3_true / h| (step instant excluded)
    t_batch: np.ndarray                 # (nb,)
    theta_batch: np.ndarray             # (nb, B, 4) LSM result after each batch
    log10_cond: np.ndarray              # (nb, B) online (Gram) column-scaled cond of the first regression
    rank: np.ndarray                    # (nb, B)
    exact_cond: dict = field(default_factory=dict)   # run -> (nb,) cond from the raw batch (SVD)
    exact_rank: dict = field(default_factory=dict)
    keep: dict = field(default_factory=dict)         # run -> {signal: (K,)} for the figures
    diverged: np.ndarray = None
    diverged_step: np.ndarray = None
    b0: float = 0.0
    full_solved: np.ndarray = None      # (B,) batches in which situation 2's full regression (16) was solved


_KEPT = ("x[0]", "x[1]", "xhat[0]", "xhat[1]", "xhat[2]", "u", "theta[0]", "theta[1]", "theta[2]", "theta[3]")
#: below this many run-steps (runs × samples) a situation is simulated in one process (~1 s of work)
_PARALLEL_RUN_STEPS = 1e6
#: the signals the chunk post-processing reads (errors, x3, kept runs, exact identifiability)
_STORED = _KEPT + ("level",)
#: Most rows simulated together in one process. A part holds its rows' noise over the whole horizon and a
#: batch of their signals (about 2.6 MB a row in situation 2); what it returns is the per-row reductions and
#: batch-end records (about 2 kB a row), so memory is bounded by the part, not by ``--runs``. Rows are
#: independent runs: any split gives the same numbers bit for bit (``tests/studies/test_meso.py``).
ROWS_PER_PART = 64


def simulate_situation(sit: Situation, rows, T: float, paper: Paper = PAPER, window=(5.0, 10.0),
                       keep=(), exact=(), bound: float = 1e6, progress=None, jobs: int = 1) -> SituationRun:
    """Simulate every row of situation ``sit`` over ``T`` seconds, one identification batch per chunk.

    With ``jobs > 1`` (and at least :data:`_PARALLEL_RUN_STEPS` run-steps, below which starting
    processes costs more than it saves) the rows are split into ``jobs`` consecutive parts simulated
    in parallel processes (:func:`ctrl_analysis.runs.parallel.map_chunks`) and joined; runs are
    independent, so the result equals ``jobs=1`` bit for bit.

    Parameters
    ----------
    sit : Situation
    rows : sequence of Row
    T : float
        Horizon (s).
    paper : Paper
    window : (float, float)
        Window of :attr:`SituationRun.window_sums` (the ε-scaling), ``[start, end)`` in s.
    keep : sequence of int
        Runs whose trajectories are kept (figures).
    exact : sequence of int
        MESO runs whose batch identifiability is also computed exactly from the raw batch (SVD).
    bound : float
        A run whose state (plant, observer, the identification's Gram entries) leaves ``|x| <= bound``
        is flagged as diverged.
    progress : callable, optional
        ``progress(message)`` after each chunk (with ``jobs > 1``: after each part).
    jobs : int
        Processes the rows are split over.

    Returns
    -------
    SituationRun
    """
    rows = list(rows)
    if jobs > 1 and len(rows) > 1 and len(rows) * T / paper.h >= _PARALLEL_RUN_STEPS:
        parts = chunk_slices(len(rows), chunks=jobs)
        tasks = [(sit, rows[sl], T, paper, window, [b - sl.start for b in keep if sl.start <= b < sl.stop],
                  [b - sl.start for b in exact if sl.start <= b < sl.stop], bound) for sl in parts]
        outs = map_chunks(_simulate_part, tasks, jobs=jobs, desc=f"{sit.key} runs")
        if progress is not None:
            progress(f"{sit.key}: t = {T:.0f} / {T:.0f} s")
        return _join(outs, parts, rows)
    return _simulate_bounded(sit, rows, T, paper, window, keep, exact, bound, progress)


def _simulate_bounded(sit, rows, T, paper, window, keep, exact, bound, progress) -> SituationRun:
    """:func:`_simulate_rows` over consecutive parts of at most :data:`ROWS_PER_PART` rows, joined."""
    if len(rows) <= ROWS_PER_PART:
        return _simulate_rows(sit, rows, T, paper, window, keep, exact, bound, progress)
    parts = chunk_slices(len(rows), chunk_size=ROWS_PER_PART)
    outs = []
    for i, sl in enumerate(parts):
        said = None if progress is None else (
            lambda msg, i=i: progress(f"{msg} (rows part {i + 1} of {len(parts)})"))
        outs.append(_simulate_rows(sit, rows[sl], T, paper, window,
                                   [b - sl.start for b in keep if sl.start <= b < sl.stop],
                                   [b - sl.start for b in exact if sl.start <= b < sl.stop], bound, said))
    return _join(outs, parts, rows)


def _simulate_rows(sit, rows, T, paper, window, keep, exact, bound, progress) -> SituationRun:
    """:func:`simulate_situation` in this process: the loop stepped one identification batch per chunk."""
    h, N, B = paper.h, sit.N, len(rows)
    K = round(T / h)
    t_all = h * np.arange(K + 1)
    level = np.where(t_all >= paper.t_step - 0.5 * h, paper.step, 0.0)
    noise = _situation_noise(rows, K, paper)
    loop = build_loop(sit, paper)
    params = run_params(rows)
    ident = loop.placed[3].block
    variants, thresholds = [r.variant for r in rows], [r.threshold for r in rows]
    in_window = (t_all[:K] >= window[0]) & (np.arange(K) < round(window[1] / h))
    metrics = METRIC_ORDER
    out = SituationRun(rows=list(rows), t=t_all[:K], sums={m: np.zeros(B) for m in metrics},
                       window_sums={m: np.zeros(B) for m in metrics}, n_window=int(in_window.sum()),
                       sup_dx3=np.zeros(B), t_batch=np.empty(0), theta_batch=np.empty((0, B, 4)),
                       log10_cond=np.empty((0, B)), rank=np.empty((0, B)),
                       keep={b: {s: np.empty(K) for s in _KEPT} for b in keep},
                       diverged=np.zeros(B, dtype=bool), diverged_step=np.full(B, -1), b0=sit.b0)
    out.exact_cond = {b: [] for b in exact}
    out.exact_rank = {b: [] for b in exact}
    # per-run initial states of plant and observer (Row.x0, Row.xhat0); the other blocks start at their defaults
    x0 = {"plant": np.array([r.x0 for r in rows], dtype=float),
          "observer": np.array([r.xhat0 for r in rows], dtype=float)}
    k0, x3_last, tb, thb, lc, rk = 0, np.full(B, np.nan), [], [], [], []
    b_plant = np.array([r.b_plant for r in rows], dtype=float)
    while k0 < K:
        n = min(N, K - k0)
        sl = slice(k0, k0 + n + 1)
        inputs = {"level": level[sl], "v": noise[sl], "r[0]": np.sin(t_all[sl]), "r[1]": np.cos(t_all[sl]),
                  "r[2]": -np.sin(t_all[sl])}
        # a run that diverged is not stepped again (its records end where it diverged, _cut_at_divergence): the
        # chunk runs the others only (``act``); the signals below are theirs, the states are all runs'
        act = np.flatnonzero(~out.diverged)
        sig, states, div, div_step = _step(loop, n, inputs, x0, params, act, B, t_all[k0], bound)
        new = div & ~out.diverged
        out.diverged_step[new] = k0 + div_step[new]
        out.diverged |= div
        if n == N:  # a full batch ended at the chunk's last sample: solve it before the next sample
            _end_batch(out, states, ident, (variants, thresholds), div, k0 + n, bound)
        if act.size:
            # the table sums, the ε window's sums and sup |Δx3/h| of the stepped runs, in one compiled pass
            sums, wsums = np.zeros((6, act.size)), np.zeros((6, act.size))
            sup, prev = out.sup_dx3[act], x3_last[act]
            _accumulator()(sig["x[0]"], sig["x[1]"], sig["xhat[0]"], sig["xhat[1]"], sig["xhat[2]"], sig["u"],
                           sig["level"], sig["theta[0]"], sig["theta[1]"], sig["theta[2]"], sig["theta[3]"],
                           t_all[k0:k0 + n], in_window[k0:k0 + n], b_plant[act], sit.b0, paper.theta1, paper.theta2,
                           paper.b - sit.b0, paper.t_step, h, 2 * N * h, prev, k0 > 0, sums, wsums, sup)
            for i, m in enumerate(METRIC_ORDER):
                out.sums[m][act] += sums[i]
                out.window_sums[m][act] += wsums[i]
            out.sup_dx3[act], x3_last[act] = sup, prev
        col = {b: i for i, b in enumerate(act)}
        for b in keep:
            for s in _KEPT:
                out.keep[b][s][k0:k0 + n] = sig[s][:, col[b]] if b in col else np.nan
        if n == N:  # the batch's result is the next sample's output
            tb.append(t_all[k0 + n - 1])
            thb.append(states["lsm"][:, :4].copy())
            lc.append(states["lsm"][:, 4].copy())
            rk.append(states["lsm"][:, 5].copy())
            _record_exact(out, sig, col, ident, rows, sit, exact)
        x0 = {name: np.nan_to_num(x, nan=0.0, posinf=0.0, neginf=0.0) for name, x in states.items()}
        k0 += n
        if progress is not None:
            progress(f"{sit.key}: t = {k0 * h:.0f} / {T:.0f} s")
    # a diverged run's whole-run sums are not defined (its signals end where it diverged)
    for m in metrics:
        out.sums[m][out.diverged] = np.nan
    _finish(out, tb, thb, lc, rk, B)
    out.full_solved = full_solved(rows, sit.regression, out.log10_cond, out.rank)
    return out


def _step(loop, n, inputs, x0, params, act, B, t0, bound):
    """One chunk of ``n`` samples for the runs ``act`` of ``B``.

    Returns the signals of the runs ``act`` (``(n, len(act))`` each), the final states of all ``B`` runs (NaN
    for the runs not stepped) and the divergence flags and steps of all ``B`` runs.
    """
    if act.size == B:
        res = loop.simulate(n, inputs=inputs, x0=x0, runs=B, t0=t0, params=params,
                            save=Save(states=False, keep=_STORED), execution=Execution(bound=bound))
        return {s: res[s][:n] for s in res.signals}, res.final_states, res.diverged, res.diverged_step
    div, div_step = np.zeros(B, dtype=bool), np.full(B, -1)
    states = {name: np.full((B,) + np.shape(x)[1:], np.nan) for name, x in x0.items()}
    if act.size == 0:
        return {s: np.empty((n, 0)) for s in _STORED}, states, div, div_step
    sub_in = {k: (v[:, act] if np.ndim(v) == 2 else v) for k, v in inputs.items()}
    sub_params = {blk: {k: np.asarray(v)[act] for k, v in ps.items()} for blk, ps in params.items()}
    res = loop.simulate(n, inputs=sub_in, x0={k: v[act] for k, v in x0.items()}, runs=act.size, t0=t0,
                        params=sub_params, save=Save(states=False, keep=_STORED), execution=Execution(bound=bound))
    for name, x in res.final_states.items():
        if name not in states:
            states[name] = np.full((B,) + x.shape[1:], np.nan)
        states[name][act] = x
    div[act], div_step[act] = res.diverged, res.diverged_step
    return {s: res[s][:n] for s in res.signals}, states, div, div_step


def _end_batch(out, states, ident, configs, chunk_diverged, k: int, bound: float) -> None:
    """The identification's batch-end solve on the final states (in place), with the loop's divergence test.

    ``configs`` is ``(variants, thresholds)``, one of each per run.

    A run (not yet diverged in this chunk) whose new LSM result leaves ``|x| <= bound`` is flagged
    as diverged at step ``k`` and its states set to NaN, as the loop does when a state leaves the
    bound in an update.
    """
    x = states["lsm"]
    ident.identify(x, *configs)
    bad = ~np.all(np.abs(x) <= bound, axis=1) & ~chunk_diverged
    new = bad & ~out.diverged
    out.diverged_step[new] = k
    out.diverged |= new
    for name in states:
        states[name][bad] = np.nan


def _simulate_part(task) -> SituationRun:
    """:func:`simulate_situation` of one part of the rows (a worker's task)."""
    return _simulate_bounded(*task, None)


def _join(outs, parts, rows) -> SituationRun:
    """The parts' :class:`SituationRun` as one, runs in the order of ``rows``."""
    first = outs[0]

    def cat(name, axis=0):
        return np.concatenate([getattr(o, name) for o in outs], axis=axis)

    def renumber(name):
        return {b + sl.start: v for o, sl in zip(outs, parts, strict=True) for b, v in getattr(o, name).items()}

    return SituationRun(
        rows=rows, t=first.t, n_window=first.n_window, t_batch=first.t_batch, b0=first.b0,
        sums={m: np.concatenate([o.sums[m] for o in outs]) for m in first.sums},
        window_sums={m: np.concatenate([o.window_sums[m] for o in outs]) for m in first.window_sums},
        sup_dx3=cat("sup_dx3"), theta_batch=cat("theta_batch", 1), log10_cond=cat("log10_cond", 1),
        rank=cat("rank", 1), exact_cond=renumber("exact_cond"), exact_rank=renumber("exact_rank"),
        keep=renumber("keep"), diverged=cat("diverged"), diverged_step=cat("diverged_step"),
        full_solved=cat("full_solved"))


def _finish(out, tb, thb, lc, rk, B: int) -> None:
    """Stack the per-batch records and cut every diverged run's records at its divergence."""
    out.t_batch, out.theta_batch = np.array(tb), np.array(thb).reshape(-1, B, 4)
    out.log10_cond, out.rank = np.array(lc).reshape(-1, B), np.array(rk).reshape(-1, B)
    out.exact_cond = {b: np.array(v) for b, v in out.exact_cond.items()}
    out.exact_rank = {b: np.array(v) for b, v in out.exact_rank.items()}
    _cut_at_divergence(out)


def _situation_noise(rows, K: int, paper: Paper) -> np.ndarray:
    """Measurement noise ``(K + 1, B)``: one draw per seed (ESO and MESO runs with one seed share it)."""
    seeds = sorted({r.seed for r in rows if r.seed is not None})
    if not seeds:
        return np.zeros((K + 1, len(rows)))
    drawn = draw_noise(seeds, K, uniform_noise(-1.0, 1.0))[:, :, 0]
    # column 0 of the padded draw is the noise-free run's zeros
    padded = np.zeros((K + 1, len(seeds) + 1))
    padded[:K, 1:] = paper.noise_amp * drawn
    return np.ascontiguousarray(padded[:, [0 if r.seed is None else 1 + seeds.index(r.seed) for r in rows]])


def _record_exact(out, sig, col, ident, rows, sit, exact) -> None:
    """Exact (SVD) identifiability of the batch that just ended, for the runs in ``exact`` (``col``: run -> column
    of ``sig``; a run not stepped in this chunk gets NaN)."""
    for b in exact:
        ok = b in col
        if ok:
            phi = ident.phi(np.stack([sig[s][:, col[b]] for s in ident.inputs], axis=1))
            ok = bool(np.all(np.isfinite(phi)))
        rep = exact_report(rows[b].variant, sit.regression, phi, rows[b].threshold) if ok else None
        out.exact_cond[b].append(rep.cond_scaled if ok else np.nan)
        out.exact_rank[b].append(rep.rank if ok else -1)


def _cut_at_divergence(out):
    """A diverged run's records end where it diverged (later chunks restart it from 0; never shown)."""
    for b in np.flatnonzero(out.diverged):
        k = out.diverged_step[b]
        after = out.t_batch >= out.t[min(k, len(out.t) - 1)] - 0.5 * (out.t[1] - out.t[0])
        out.theta_batch[after, b] = np.nan
        out.log10_cond[after, b] = np.nan
        out.rank[after, b] = -1
        if b in out.exact_cond:
            out.exact_cond[b] = np.where(after, np.nan, out.exact_cond[b])
        if b in out.keep:
            for s in _KEPT:
                out.keep[b][s][k - 1:] = np.nan


def situation_rows(key: str, seeds, paper: Paper = PAPER) -> list:
    """The configurations of situation ``key`` on the batch axis.

    Tables: ESO, MESO well-posed and MESO literal, each with every noise seed and noise off. Claims
    (noise off): situation 1 — the ESO at the other ε of the scaling grid, the MESO at ε = 0.1 (§5),
    the MESO without θ4 (Conclusion 3), the literal rule without W(s); situation 2 — the direct
    regression (10) (first seed and noise off), the ESO on the plant with 0.95 u as an extra term,
    the well-posed MESO with other identifiability thresholds, the literal rule without W(s).
    """
    rows = [Row(o, v, s) for o, v in (("eso", "none"), ("meso", "wellposed"), ("meso", "literal"))
            for s in list(seeds) + [None]]
    if key == "s1":
        rows += [Row("eso", "none", None, epsilon=e) for e in (0.1, 0.025, 0.0125)]
        rows += [Row("meso", "wellposed", None, epsilon=0.1), Row("meso", "no_const", None),
                 Row("meso", "literal", None, bypass_w=True)]
    else:
        rows += [Row("meso", "direct", seeds[0]), Row("meso", "direct", None),
                 Row("eso", "none", None, b_plant=paper.b + 0.95)]
        rows += [Row("meso", "wellposed", None, threshold=g) for g in GATE_RERUNS]
        rows += [Row("meso", "literal", None, bypass_w=True)]
    return rows


def pick(rows, observer, variant, noise: bool, **extra) -> list:
    """Indices of the rows with these settings (``extra`` fields default to the paper's values)."""
    base = {"b_plant": PAPER.b, "epsilon": PAPER.epsilon, "bypass_w": False, "threshold": PAPER.cond_threshold,
            "x0": PAPER.x0, "xhat0": PAPER.x_hat0}
    base.update(extra)
    return [i for i, r in enumerate(rows) if r.observer == observer and r.variant == variant
            and (r.seed is not None) == noise and all(getattr(r, k) == v for k, v in base.items())]
