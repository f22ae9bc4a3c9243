"""Run the arena, rank the families per class against the bound, and recommend one; results.json contract.

:func:`run_arena` tunes every family (:mod:`.tuning`) on every case (signal class × noise class ×
noise bound), measures each tuned estimator on the adversarial pair of the bound (:mod:`.bound`),
and records quantities (units, tolerances), findings generated from the numbers and figures with
captions in a :class:`~ctrl_analysis.reporting.results.StudyResult`. :func:`recommend_for_record` runs the
same tuning on a user's recorded signal.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_bool, check_in, check_int, check_positive
from ..noise import run_seeds
from ..reporting.report import StudyContext
from ..reporting.results import StudyInfo, StudyResult
from ..runs.chains import drive, lockstep, pool_here
from ..runs.parallel import chunk_slices
from .bound import adversarial_error, adversarial_pair, lower_bound
from .claims import MEASURES, VERDICT_TEXT, fixed_configurations, judge_claims, tuned_for_signal
from .interface import FAMILIES, OFFLINE, estimate, family
from .recordcheck import MAX_RECORDS
from .signals import (
    NOISE_CLASSES,
    SIGNAL_CLASSES,
    native_bound,
    registered_signal_classes,
    signal_classes,
    simulate_registered,
)
from .startup import record_startup, startup_calls
from .tuning import COSTS, MAX_ROUNDS, METRICS, Case, Setup, case_records, evaluate, family_chain, tune_families

__all__ = [
    "DEFAULT",
    "QUICK",
    "ArenaSettings",
    "arena_claim_links",
    "arena_report_lines",
    "default_settings",
    "run_arena",
]

INFO = StudyInfo("arena", "", "Seeber & Haimovich (bound); the five papers' estimators",
                 "every estimator family tuned fairly on common signals and noise, scored against 2√(εL)")


@dataclass(frozen=True)
class ArenaSettings:
    """What the arena runs.

    Attributes
    ----------
    signals, noises : tuple of str
        Signal and noise classes.
    eps : tuple of float
        Noise bounds ``ε``.
    L : float
        Bound on ``|f''|`` of every signal.
    records : int
        Seeded records per case (1 to :data:`~ctrl_analysis.arena.recordcheck.MAX_RECORDS`).
    setup : Setup
    rounds : int
        Pattern-search rounds (0 to :data:`~ctrl_analysis.arena.tuning.MAX_ROUNDS`).
    families : tuple of str
    """

    signals: tuple = tuple(SIGNAL_CLASSES)
    noises: tuple = tuple(NOISE_CLASSES)
    eps: tuple = (0.002, 0.01, 0.05)
    L: float = 4.0
    records: int = 3
    setup: Setup = field(default_factory=Setup)
    rounds: int = 3
    families: tuple = tuple(f.name for f in FAMILIES)

    def __post_init__(self):
        for name, allowed in (("signals", signal_classes()), ("noises", NOISE_CLASSES),
                              ("families", [f.name for f in FAMILIES])):
            value = getattr(self, name)
            if not isinstance(value, tuple) or not value:
                raise TypeError(f"{name} must be a non-empty tuple of names, got {value!r:.80}")
            for item in value:
                check_in(name, item, list(allowed))
        if not isinstance(self.eps, tuple) or not self.eps:
            raise TypeError(f"eps must be a non-empty tuple of noise bounds, got {self.eps!r:.80}")
        for e in self.eps:
            check_positive("eps", e, scalar=True)
        check_positive("L", self.L, scalar=True)
        check_int("records", self.records, minimum=1, maximum=MAX_RECORDS)
        if not isinstance(self.setup, Setup):
            raise TypeError(f"setup must be a Setup, got {self.setup!r:.80}")
        check_int("rounds", self.rounds, minimum=0, maximum=MAX_ROUNDS)


#: The defaults with the built-in signal classes (:func:`default_settings` adds the registered ones).
DEFAULT = ArenaSettings()
QUICK = ArenaSettings(signals=("sines", "steps"), noises=("uniform",), eps=(0.01,), records=1,
                      setup=Setup(dt=0.004, n=1000, transient=1.0), rounds=1)


def default_settings() -> ArenaSettings:
    """:data:`DEFAULT` with every signal class, the registered ones (the studies' plant outputs) included.

    Returns
    -------
    ArenaSettings
    """
    from dataclasses import replace

    return replace(DEFAULT, signals=tuple(signal_classes()))


def _cases(s: ArenaSettings, seed: int) -> list:
    seeds = tuple(run_seeds(seed, s.records))
    return [Case(sig, noi, e, s.L, seeds) for sig in s.signals for noi in s.noises for e in s.eps]


def _adversarial_task(task):
    """:func:`_adversarial` of one family (a call of a map: module level, run in a worker)."""
    return _adversarial(*task)


def _adversarial(name, cases, rows, setup):
    """Adversarial worst-case error of each tuned configuration (one per case)."""
    k_star = setup.k_from + (setup.n - setup.k_from) // 3
    pairs = [adversarial_pair(c.eps, c.L, setup.dt, setup.n, k_star) for c in cases]
    y = np.hstack([p["y"].T for p in pairs])
    P = np.repeat(np.array(rows), 2, axis=0)
    est = estimate(family(name), P, y, setup.dt, init=setup.init)[:, :, 1]
    return np.array([adversarial_error(est[:, 2 * i:2 * i + 2], p, setup.k_from) for i, p in enumerate(pairs)])


def run_arena(ctx: StudyContext, settings: ArenaSettings | None = None) -> tuple:
    """Tune every family on every case, score against the bound, record results and figures.

    Parameters
    ----------
    ctx : StudyContext
        Output directory, seed, quick, jobs, scheduler, progress.
    settings : ArenaSettings, optional
        Default :func:`default_settings` (``QUICK`` with ``ctx.quick``).

    Returns
    -------
    (StudyResult, dict)
        The record for results.json and the raw tables (``table[family][case key]``).
    """
    if not isinstance(ctx, StudyContext):
        raise TypeError(f"ctx must be a StudyContext, got {ctx!r:.80}")
    if settings is not None and not isinstance(settings, ArenaSettings):
        raise TypeError(f"settings must be an ArenaSettings or None, got {settings!r:.80}")
    s = settings or (QUICK if ctx.quick else default_settings())
    t0 = time.perf_counter()
    cases = _cases(s, ctx.seed)
    plants = [c for c in cases if c.signal in registered_signal_classes()]
    if plants:  # simulated once, side by side; this process and the workers forked below keep the records
        ctx.progress(f"simulating the plant signals ({', '.join(sorted({c.signal for c in plants}))})")
        simulate_registered([c.signal for c in plants], cases[0].seeds, s.setup.dt * np.arange(s.setup.n),
                            jobs=ctx.jobs)
    for c in cases:
        case_records(c, s.setup)
    result = StudyResult(INFO)
    result.settings.update({"signals": list(s.signals), "noises": list(s.noises), "eps": list(s.eps), "L": s.L,
                            "records": s.records, "dt": s.setup.dt, "samples": s.setup.n,
                            "transient_s": s.setup.transient, "rounds": s.rounds, "families": list(s.families),
                            "costs": "worst = max |f̂' - f'|, rms = RMS of f̂' - f', after the transient, "
                                     "over the case's noisy records"})
    result.seeds["records"] = list(cases[0].seeds)
    ctx.progress(f"tuning {len(s.families)} families on {len(cases)} cases, their rounds side by side")
    # one pool for every map below, opened after the records are cached (its forked workers inherit them)
    with pool_here(ctx.jobs, ctx.scheduler):
        out = _tune_and_draw(ctx, result, s, cases, t0)
        ctx.wait_figures()
    return out


def _apply(call):
    """``fn(arg)`` of ``call = (fn, arg)``: the tuning's and the adversarial check's calls in one chain."""
    fn, arg = call
    return fn(arg)


def _as_calls(fn, chain):
    """A chain of ``fn``'s arguments as a chain of ``(fn, arg)`` calls (:func:`_apply`); returns its result."""
    try:
        args = next(chain)
        while True:
            args = chain.send((yield [(fn, a) for a in args]))
    except StopIteration as done:
        return done.value


def _adversarial_calls(names, cases, tuned, setup) -> list:
    return [(_adversarial_task, (n, cases, [b["worst"][0] for b in tuned[n]["best"]], setup)) for n in names]


def _costs(name) -> tuple:
    """What family ``name`` is tuned for: f̂''s worst and RMS error, and f̂'s RMS error where a claim is judged on it."""
    return COSTS if name in tuned_for_signal() else COSTS[:2]


def _family_chain(name, cases, s, jobs):
    """One family tuned on ``cases``, then its adversarial check there: one chain of :func:`drive`."""
    tuned = yield from _as_calls(evaluate, family_chain(name, cases, s.setup, rounds=s.rounds, jobs=jobs,
                                                        costs=_costs(name)))
    adv, *zero = yield (_adversarial_calls([name], cases, {name: tuned}, s.setup)
                        + startup_calls([name], cases, {name: tuned}, s.setup))
    return tuned, (adv, np.vstack(zero))


def _pareto_chain(ctx, result, s, cases, jobs):
    """Every family tuned on the Pareto figure's cases (one per signal class), that figure sent to the pool,
    then the families' adversarial checks there.

    One chain of :func:`drive` (the families in lockstep: a ninth of the work), so the figure, the slowest to
    render, is drawn while the other cases are still being tuned.
    """
    from . import figures

    tuned = yield from _as_calls(evaluate, lockstep({n: family_chain(n, cases, s.setup, rounds=s.rounds, jobs=jobs,
                                                                     costs=_costs(n)) for n in s.families}))
    figures.save_pareto(ctx, result, s, cases, tuned)
    calls = [_adversarial_calls([n], cases, tuned, s.setup) + startup_calls([n], cases, tuned, s.setup)
             for n in s.families]
    got = iter((yield [c for group in calls for c in group]))
    out = {}
    for n, group in zip(s.families, calls, strict=True):
        adv, *zero = [next(got) for _ in group]
        out[n] = (tuned[n], (adv, np.vstack(zero)))
    return out


def _fixed_chain(cases, setup):
    """The claim checks' fixed configurations evaluated on every case (a chain of :func:`drive`, beside the
    tuning): ``{(family, params): {case key: {"rms": RMS error of f̂', "rms_f": of f̂}}}`` for :func:`judge_claims`."""
    confs = fixed_configurations()
    calls = [(conf, list(range(len(cases)))[sl]) for conf in confs for sl in chunk_slices(len(cases), chunks=4)]
    parts = yield [(evaluate, (name, setup, tuple(cases), [(i, np.array(params)) for i in idx], "auto"))
                   for (name, params), idx in calls]
    out = {conf: {} for conf in confs}
    for (conf, idx), m in zip(calls, parts, strict=True):
        out[conf].update({cases[i].key: {k: float(m[j, METRICS.index(k)]) for k in MEASURES}
                          for j, i in enumerate(idx)})
    return out


def _merged(parts: list, n_cases: int) -> tuple:
    """One family's tuning, adversarial errors and zero-state metrics on all cases from parts:
    ``[(case indices, (result, (adv, zero-state metrics)))]``."""
    evaluated, best, adv, zero = [None] * n_cases, [None] * n_cases, np.empty(n_cases), [None] * n_cases
    for idx, (r, (a, z)) in parts:
        for j, i in enumerate(idx):
            evaluated[i], best[i], adv[i], zero[i] = r["evaluated"][j], r["best"][j], a[j], z[j]
    return {"family": parts[0][1][0]["family"], "evaluated": evaluated, "best": best,
            "tunings": sum(r["tunings"] for _, (r, _a) in parts)}, adv, np.array(zero)


def _tune_and_draw(ctx, result, s, cases, t0) -> tuple:
    """run_arena's tuning, adversarial check, records and figures (inside its pool).

    The cases of the Pareto figure are tuned in a chain of their own, so that figure renders while the
    other cases are tuned; every case's tuning (and adversarial check) is independent of the others', so
    the result is the same.
    """
    from . import figures

    table, tunings = {}, 0
    mid = s.eps[len(s.eps) // 2]
    front = [i for i, c in enumerate(cases) if c.noise == s.noises[0] and c.eps == mid]
    rest = [i for i in range(len(cases)) if i not in front]
    chains = {n: _family_chain(n, [cases[i] for i in rest], s, ctx.jobs) for n in s.families} if rest else {}
    chains = {"pareto figure": _pareto_chain(ctx, result, s, [cases[i] for i in front], max(1, ctx.jobs // 4)),
              **chains, "fixed configurations": _fixed_chain(cases, s.setup)}
    # the Pareto chain first in the pool: its figure then renders while the other cases are tuned
    parts = drive(_apply, chains, jobs=ctx.jobs, scheduler=ctx.scheduler, desc="tuning", unit="batch",
                  priority={"pareto figure": -1})
    merged = {n: _merged([(front, parts["pareto figure"][n])] + ([(rest, parts[n])] if rest else []), len(cases))
              for n in s.families}
    peaks = [float(np.max(np.abs(case_records(c, s.setup)[0]))) for c in cases]  # max |f'|: a start-up error's scale
    start = METRICS.index("startup")
    for name in s.families:
        r, adv, zero = merged[name]
        tunings += r["tunings"]
        table[name] = {}
        for c, b, a, z, peak in zip(cases, r["best"], adv, zero, peaks, strict=True):
            bound = lower_bound(c.eps, c.L)
            table[name][c.key] = {"params": b["worst"][0].tolist(), "worst": b["worst"][1][0],
                                  "rms_params": b["rms"][0].tolist(), "rms": b["rms"][1][1],
                                  "ratio": b["worst"][1][0] / bound, "adv": a, "adv_ratio": a / bound,
                                  "bound": bound, "startup": b["worst"][1][start] / peak,
                                  "startup_zero": z[start] / peak}
            if "rms_f" in b:  # tuned for the signal estimate too (tuned_for_signal)
                table[name][c.key]["rms_f"] = b["rms_f"][1][METRICS.index("rms_f")]
    elapsed = time.perf_counter() - t0
    _record(result, s, cases, table, tunings)
    record_startup(result, s.setup, cases, table)
    judge_claims(result, cases, table, s.setup, fixed=parts["fixed configurations"])
    figures.save_all(ctx, result, s, cases, table)
    return result, {"table": table, "tunings": tunings, "seconds": elapsed}


def _record(result, s, cases, table, tunings):
    fams = list(table)
    for c in cases:
        for name in fams:
            row = table[name][c.key]
            cid = f"{c.signal}.{c.noise}.{c.eps:g}.{name}"
            params = dict(zip([p.name for p in family(name).params], row["params"], strict=True))
            result.quantity(f"{cid}.worst", f"{c.key}, {name}: tuned worst-case |f̂' - f'|", row["worst"],
                            unit="1/s", note=f"params {params}")
            result.quantity(f"{cid}.adv_ratio", f"{c.key}, {name}: adversarial worst case / 2√(εL)", row["adv_ratio"],
                            unit="")
    result.quantity("tunings", "configurations evaluated (tunings)", float(tunings), unit="")
    _signal_bounds(result, s, cases)
    adv = np.array([[table[n][c.key]["adv_ratio"] for c in cases] for n in fams])
    rnd = np.array([[table[n][c.key]["ratio"] for c in cases] for n in fams])
    med = np.median(adv, axis=1)
    spread = ("every family's median ratio is 1.00: a converged estimator fed the common measurement (the ramp) "
              "returns the ramp's slope at t*, midway between the two true derivatives, so the construction gives "
              "them all exactly the bound and ranks none of them" if np.all(np.abs(med - 1) < 0.005) else
              "median ratios " + ", ".join(f"{n} {m:.2f}" for n, m in zip(fams, med, strict=True)))
    result.finding("causality-check",
                   f"Causality check of the bound's adversarial construction, not evidence that the estimators are "
                   f"good: on the two signals of the proof (measurements identical up to t*, derivatives 4√(εL) apart "
                   f"there) every tuned estimator errs by at least 2√(εL) on one of them (smallest ratio "
                   f"{adv.min():.3f} over {len(fams)} families and {len(cases)} cases), as any causal estimator must, "
                   f"however badly tuned; a ratio below 1 would expose a bug in the construction, the error measure or "
                   f"an estimator's causality. On this construction {spread}. On the random records the tuned worst "
                   f"errors are {rnd.min():.2f}..{rnd.max():.2f}× the bound"
                   + (" (below 1 because a random draw is not the worst case, not because an estimator beats the "
                      "bound)." if rnd.min() < 1 else "."),
                   {"adversarial_ratio_min": float(adv.min()), "random_ratio_min": float(rnd.min())})
    for sig in s.signals:
        for noi in s.noises:
            keys = [c.key for c in cases if c.signal == sig and c.noise == noi]
            score = {n: float(np.mean([table[n][k]["ratio"] for k in keys])) for n in fams}
            rank = sorted(fams, key=score.get)
            win = rank[0]
            mid = keys[len(keys) // 2]
            params = dict(zip([p.name for p in family(win).params],
                              [float(f"{v:.4g}") for v in table[win][mid]["params"]], strict=True))
            margin = score[rank[1]] / score[win] if len(rank) > 1 else 1.0
            result.finding(f"recommend-{sig}-{noi}",
                           f"For {sig} signals with {noi} noise use {family(win).label}: mean worst-case error "
                           f"{score[win]:.2f}× the bound over ε = {', '.join(f'{e:g}' for e in s.eps)} "
                           f"({margin:.2f}× better than {rank[1] if len(rank) > 1 else '-'}). Ranking: "
                           + ", ".join(f"{n} {score[n]:.2f}" for n in rank)
                           + f". Tuned at ε = {table[win][mid]['bound'] ** 2 / (4 * s.L):g}: {params}.")
    _consistency(result, s, cases, table)


def _signal_bounds(result, s, cases):
    """The registered (plant) classes' own bound L: how it is computed, and its value per record."""
    reg = registered_signal_classes()
    t = s.setup.dt * np.arange(s.setup.n)
    for sig in s.signals:
        if sig in reg:
            Ls = [native_bound(sig, seed, t) for seed in cases[0].seeds]
            result.quantity(f"signal.{sig}.L_native", f"{sig}: bound L on |f''| in the plant's own units, "
                            "median over the records", float(np.median(Ls)), unit="1/s²",
                            note=f"{reg[sig].bound_how}; records {', '.join(f'{v:.4g}' for v in Ls)}; the arena "
                                 f"scales each record to L = {s.L:g}")


def _consistency(result, s, cases, table):
    """Σ against the 3-state linear ESO at their best tunings (the library reads no study's results)."""
    if not {"sigma", "leso3"} <= set(table):
        return
    ratios = [table["leso3"][c.key]["rms"] / table["sigma"][c.key]["rms"] for c in cases]
    result.quantity("consistency.leso3_over_sigma_rms", "linear ESO (3 states) / Σ (n0 = 3), tuned RMS of f̂' - f', "
                    "median over cases", float(np.median(ratios)), unit="")
    five = ""
    if "sigma5" in table:
        r5 = [table["leso3"][c.key]["rms"] / table["sigma5"][c.key]["rms"] for c in cases]
        result.quantity("consistency.leso3_over_sigma5_rms", "linear ESO (3 states) / Σ (n0 = 5, the "
                        "differential-estimator paper's order), tuned RMS of f̂' - f', median over cases",
                        float(np.median(r5)), unit="")
        five = (f"; against Σ of the paper's order n0 = 5 it is {np.min(r5):.2f}..{np.max(r5):.2f}× (median "
                f"{np.median(r5):.2f}; Σ better in {int(np.sum(np.array(r5) > 1))} of {len(cases)})")
    result.finding("consistency-sigma-eso",
                   f"Each tuned to its best RMS, the 3-state linear ESO's derivative error is "
                   f"{np.min(ratios):.2f}..{np.max(ratios):.2f}× that of Σ with n0 = 3 (median "
                   f"{np.median(ratios):.2f}) over {len(cases)} cases{five}: at their best tunings neither dominates "
                   "by an order of magnitude (compare the differential-estimator study's equal-bandwidth comparison "
                   "in its section of the report).")


def arena_report_lines(results: dict) -> list:
    """Markdown lines of the arena section of REPORT.md from an arena results.json dict.

    Parameters
    ----------
    results : dict
        The arena's results.json.

    Returns
    -------
    list of str
    """
    if not isinstance(results, dict):
        raise TypeError(f"results must be the arena's results.json dict, got {results!r:.80}")
    for key, kind, needs in (("quantities", dict, ("id", "value")), ("findings", dict, ("text",)),
                             ("figures", str, ())):
        items = results.get(key, [])
        if not isinstance(items, list) or not all(isinstance(x, kind) and all(k in x for k in needs) for x in items):
            raise ValueError(f"results[{key!r}] must be a list of {kind.__name__}"
                             + (f" with keys {needs}" if needs else "") + f", got {items!r:.80}")
    lines = ["## Estimator arena", ""]
    q = {x["id"]: x for x in results.get("quantities", [])}
    if "tunings" in q:
        lines.append(f"{int(q['tunings']['value'])} tunings (the wall time is in the arena's timing.json).")
        lines.append("")
    claims = [f for f in results.get("findings", []) if f.get("claim")]
    for f in results.get("findings", []):
        if not f.get("claim"):
            lines.append(f"- {f['text']}")
    if claims:
        lines += ["", "### The papers' claims at each family's best tuning", "",
                  "| claim | arena | finding |", "|---|---|---|"]
        lines += [f"| {f['claim']} | {VERDICT_TEXT.get(f['claim_verdict'], f['claim_verdict'])} | "
                  f"{' '.join(f['text'].split()).replace('|', '/')} |" for f in claims]
    for fig in results.get("figures", []):
        lines += ["", f"![{fig}](arena/{fig})", "", results.get("captions", {}).get(fig, "")]
    return lines


def arena_claim_links(results: dict) -> dict:
    """``{"<study>/<claim id>": text}`` of the arena's claim findings, for the studies' scorecards in REPORT.md.

    Parameters
    ----------
    results : dict
        The arena's results.json.

    Returns
    -------
    dict
    """
    if not isinstance(results, dict):
        raise TypeError(f"results must be the arena's results.json dict, got {results!r:.80}")
    return {f["claim"]: f"arena: {VERDICT_TEXT.get(f.get('claim_verdict'), f.get('claim_verdict'))}"
            for f in results.get("findings", []) if isinstance(f, dict) and f.get("claim")}


def record_case(t, y, d1, eps: float, L: float) -> tuple:
    """A user's record as a case: ``(setup, records)`` for :func:`recommend_for_record`.

    Parameters
    ----------
    t, y : numpy.ndarray, shape (N,)
        Uniformly sampled time and measurement.
    d1 : numpy.ndarray or None
        The true derivative, when known.
    eps, L : float
        Noise bound and bound on ``|f''|``.

    Returns
    -------
    tuple
        ``(Setup, (f', y, f))``: with ``d1`` the record itself; without it a zero-phase
        Savitzky–Golay fit of the record stands in for ``f`` and ``f'`` and ``y`` is the fit plus
        uniform noise of bound ``eps`` (the tuning then sees the record's shape and the stated noise).
    """
    import scipy.signal

    from .signals import add_noise

    dt = float(np.median(np.diff(t)))
    n = y.size
    setup = Setup(dt=dt, n=n, transient=min(0.25 * (t[-1] - t[0]), 20.0 / np.sqrt(L / eps)))
    if d1 is not None:
        return setup, (d1[:, None], y[:, None], y[:, None])
    w = int(max(5, 2 * round(2.0 * np.sqrt(eps / L) / dt) + 1))
    w = min(w, n - (1 - n % 2))
    f = scipy.signal.savgol_filter(y, w, 2)
    fd = scipy.signal.savgol_filter(y, w, 2, deriv=1, delta=dt)
    return setup, (fd[:, None], add_noise("uniform", f, eps, 0)[:, None], f[:, None])


def recommend_for_record(t, y, d1, eps: float, L: float, *, rounds: int = 2, jobs: int = 1,
                         offline: bool = False) -> list:
    """Tune every family on one recorded signal; the ranking by worst-case error.

    The record and the bounds are checked first (:func:`~ctrl_analysis.arena.recordcheck.check_record`): bounds
    that the record contradicts by more than an order of magnitude, values whose arithmetic would not stay finite,
    and records whose tuning would cost more work or memory than the limits are refused before any work (the
    warnings of a looser bound are not raised here: ``check_record`` returns them).

    Parameters
    ----------
    t, y : numpy.ndarray, shape (N,)
        Time (uniform steps) and measurement.
    d1 : numpy.ndarray or None
        True derivative, if known.
    eps, L : float
        Noise bound and bound on ``|f''|``.
    rounds : int
        Pattern-search rounds (0 to :data:`~ctrl_analysis.arena.tuning.MAX_ROUNDS`).
    jobs : int
        Processes.
    offline : bool
        Tune the offline smoothers (:data:`~ctrl_analysis.arena.interface.OFFLINE`) too.

    Returns
    -------
    list of dict
        One per family, best first by worst-case error: ``family``, ``label``, ``params``, ``worst``, ``ratio``,
        ``causal``, ``startup`` (its worst error in the start-up window / ``max |f'|``, for the offline smoothers too),
        ``rms`` / ``rms_params`` (the family tuned for its RMS error instead) and ``pareto`` (the Pareto front of every
        configuration it evaluated: ``[lag, noise-induced error]`` pairs on the surrogate, as in the benchmark's Pareto
        figure; empty with ``d1``, where no noise-free signal separates the lag from the noise).

    Raises
    ------
    TypeError, ValueError
        A malformed record or bound, a refused record (above), or a family whose every tuning gave a
        non-finite error on the record (never ranked as "inf × bound").
    """
    from . import tuning
    from .recordcheck import check_record

    check_record(t, y, d1, eps, L)  # errors name t, y, d1, eps, L; a refused record is one sentence
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    d1 = None if d1 is None else np.asarray(d1, dtype=float)
    eps, L = float(eps), float(L)
    rounds = check_int("rounds", rounds, minimum=0, maximum=MAX_ROUNDS)
    jobs = check_int("jobs", jobs, minimum=1)
    fams = FAMILIES + (OFFLINE if check_bool("offline", offline) else ())
    setup, rec = record_case(t, y, d1, eps, L)
    case = Case("user", "user", float(eps), float(L), (0,))
    tuning._USER_RECORDS[case] = rec
    peak = max(float(np.max(np.abs(rec[0]))), np.finfo(float).tiny)  # max |f'|: a start-up error's scale
    try:
        out = []
        # every family side by side in one pool, opened after the record is set (its workers inherit it)
        with pool_here(jobs):
            done = tune_families([fam.name for fam in fams], [case], setup, rounds=rounds, jobs=jobs)
        for fam in fams:
            v, m = done[fam.name]["best"][0]["worst"]
            if not np.isfinite(m[0]):
                raise ValueError(f"every tuning of the {fam.name} family gave a non-finite derivative error on this "
                                 f"record (ε = {eps:.3g}, L = {L:.3g}, dt = {setup.dt:.3g} s); the arena cannot "
                                 "rank it")
            vr, mr = done[fam.name]["best"][0]["rms"]
            pts = np.array([[m_[2], m_[3]] for _, m_ in done[fam.name]["evaluated"][0]])  # lag, noise-induced
            pts = pts[np.all(np.isfinite(pts), axis=1)]
            out.append({"family": fam.name, "label": fam.label, "params": dict(zip([p.name for p in fam.params],
                                                                                   v.tolist(), strict=True)),
                        "worst": float(m[0]), "ratio": float(m[0] / lower_bound(eps, L)), "causal": fam.causal,
                        "startup": float(m[METRICS.index("startup")] / peak),
                        "rms": float(mr[1]), "rms_params": dict(zip([p.name for p in fam.params], vr.tolist(),
                                                                    strict=True)),
                        "pareto": pts[tuning.pareto_front(pts)].tolist() if pts.size and d1 is None else []})
    finally:
        tuning._USER_RECORDS.pop(case, None)
    return sorted(out, key=lambda r: r["worst"])
