"""Fair tuning: each family searched over its own parameters on the same signals and noise, for two costs.

**Cases.** A :class:`Case` is a signal class, a noise class and a noise bound ``ε``, with the
acceleration bound ``L`` and ``S`` seeded signals (and their noise draws): every family is scored
on exactly the same records.

**Costs** (of the first-derivative error ``e = f̂' - f'``, counted after the stated transient):
``worst`` = ``max |e|`` over the samples and the ``S`` noisy records; ``rms`` = the root mean
square of ``e`` over the same. Each configuration is also run on the noise-free records, which
splits its error into **lag** (the worst ``|e|`` without noise) and **noise-induced** error (the RMS of
the difference of the noisy and the noise-free estimate): the axes of the Pareto front.

**Search** (per family, case and cost), in the log of each parameter relative to its reference
(:func:`ctrl_analysis.arena.interface.scales`): a grid (9 points for one parameter, 5 per parameter
for two, unless a parameter says otherwise; a degree or order parameter takes its values), then a pattern search
from the best grid point of each value of a degree or order parameter (one search otherwise): ``±step`` along
each other parameter, move to the best if it improves, halve the step, ``rounds`` times; the best of the searches.
Every configuration evaluated counts as one tuning. The configurations of all cases of a family are
run as the runs of a few large batches (per-run parameters), split over processes with
:func:`ctrl_analysis.runs.parallel.map_chunks` (``jobs``, ``scheduler``).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from .._validate import (
    check_array,
    check_finite,
    check_in,
    check_int,
    check_nonnegative,
    check_positive,
    check_str,
)
from ..metrics import rmse
from ..runs.chains import drive
from .interface import FAMILIES, GIVEN, INITS, OFFLINE, OMEGA_DT_MAX, SIGMA_ORDER, Family, estimate, family, scales
from .recordcheck import MAX_ROWS
from .signals import (
    add_noise,
    make_signal,
    register_signal_class,
    registered_signal_classes,
)

__all__ = ["COSTS", "MAX_ROUNDS", "METRICS", "Case", "Setup", "case_records", "evaluate", "family_chain",
           "param_values", "pareto_front", "tune_families", "tune_family"]

#: Metric columns returned by :func:`evaluate`: the worst and RMS error of f̂' on the noisy records, its worst error
#: on the noise-free ones (lag), the RMS difference between the two (noise), and the RMS error of f̂ itself, all
#: after the start-up window; then f̂''s worst error on the noisy records *in* the start-up window (0 without one).
METRICS = ("worst", "rms", "lag", "noise", "rms_f", "startup")
#: The costs a family may be tuned for (:func:`tune_families`' ``costs``): f̂''s worst and RMS error, f̂'s RMS error.
COSTS = ("worst", "rms", "rms_f")
#: Runs per engine call (memory: N x runs x outputs doubles).
RUNS_PER_CALL = 480
#: The largest Kalata index Λ tuned (α-β and α-β-γ): beyond about 10^5 the gains round to α = 1, β = 2 (γ = 4),
#: the filters' stability edge, and the engine refuses them; 10^3 is already a one-sample filter (α > 0.99999).
LAMBDA_MAX = 1e3
#: The most pattern-search rounds: the step halves every round, and after 30 it is 2^-30 (about 1e-9) of the
#: first, so further rounds change no configuration (and each costs a full batch).
MAX_ROUNDS = 30
#: Records of user cases (a recorded signal), looked up by :func:`case_records` before drawing.
_USER_RECORDS: dict = {}


@dataclass(frozen=True)
class Setup:
    """Time grid and scoring window shared by all cases.

    Attributes
    ----------
    dt : float
        Sample period (s).
    n : int
        Samples per record (2 to :data:`~ctrl_analysis.arena.recordcheck.MAX_ROWS`).
    transient : float
        The start-up window (s): errors before this time are not counted in the costs, and are scored apart
        (:data:`METRICS`' ``"startup"``).
    init : {"first", "zero"}
        How the causal families start (:data:`~ctrl_analysis.arena.interface.INITS`): at rest on each record's
        first sample (default), or from the zero state.
    """

    dt: float = 0.002
    n: int = 4000
    transient: float = 2.0
    init: str = "first"

    def __post_init__(self):
        check_positive("dt", self.dt, scalar=True)
        check_int("n", self.n, minimum=2, maximum=MAX_ROWS)
        check_nonnegative("transient", self.transient, scalar=True)
        check_in("init", self.init, INITS)
        if self.k_from >= self.n:
            raise ValueError(f"transient must end before the record does (n dt = {self.n * self.dt:g} s), "
                             f"got transient = {self.transient!r}")

    @property
    def k_from(self) -> int:
        """First counted sample."""
        return round(float(self.transient / self.dt))


@dataclass(frozen=True)
class Case:
    """One scoring case: a signal class, a noise class, a noise bound and seeded records.

    Attributes
    ----------
    signal, noise : str
        A signal class (:func:`~ctrl_analysis.arena.signals.signal_classes`: built-in or registered) and a
        key of :data:`~ctrl_analysis.arena.signals.NOISE_CLASSES`.
    eps : float
        Noise bound ``ε``.
    L : float
        Bound on ``|f''|``.
    seeds : tuple of int
        One seed per record (signal and noise drawn from it).
    """

    signal: str
    noise: str
    eps: float
    L: float
    seeds: tuple

    def __post_init__(self):
        check_str("signal", self.signal)
        check_str("noise", self.noise)
        check_positive("eps", self.eps, scalar=True)
        check_positive("L", self.L, scalar=True)
        if not isinstance(self.seeds, tuple) or not self.seeds:
            raise TypeError(f"seeds must be a non-empty tuple of seeds, got {self.seeds!r:.80}")
        for seed in self.seeds:
            check_int("seeds", seed, minimum=0)

    @property
    def key(self) -> str:
        """``signal/noise/ε``."""
        return f"{self.signal}/{self.noise}/{self.eps:g}"


def case_records(case: Case, setup: Setup) -> tuple:
    """The case's records: ``(f', y_noisy, f)`` each of shape ``(N, S)``.

    Parameters
    ----------
    case : Case
    setup : Setup

    Returns
    -------
    tuple of numpy.ndarray
    """
    _check_case_setup(case, setup)
    if case in _USER_RECORDS:
        return _USER_RECORDS[case]
    t = setup.dt * np.arange(setup.n)
    sig = np.array([make_signal(case.signal, s, t, case.L) for s in case.seeds])  # (S, 3, N)
    y = np.array([add_noise(case.noise, sig[i, 0], case.eps, s + 1) for i, s in enumerate(case.seeds)])
    return sig[:, 1].T, y.T, sig[:, 0].T


def _check_case_setup(case, setup) -> None:
    if not isinstance(case, Case):
        raise TypeError(f"case must be a Case, got {case!r:.80}")
    if not isinstance(setup, Setup):
        raise TypeError(f"setup must be a Setup, got {setup!r:.80}")


def param_values(fam: Family, z, case: Case, setup: Setup) -> np.ndarray:
    """Parameter values from log-multipliers ``z`` (one row per configuration), capped for the sample period.

    Parameters
    ----------
    fam : Family
    z : array_like, shape (C, n_params)
        ``value = reference * exp(z)`` (integers rounded; a degree parameter is ``z`` itself).
    case : Case
    setup : Setup

    Returns
    -------
    numpy.ndarray, shape (C, n_params)

    Raises
    ------
    TypeError, ValueError
        ``fam``, ``case`` or ``setup`` of the wrong type, ``z`` not finite or of the wrong shape, or a ``z`` whose
        ``exp(z)`` overflows or underflows a parameter value.

    Notes
    -----
    Caps, so that no bound or sample period asks for what cannot run: the fastest pole at ``OMEGA_DT_MAX / dt``,
    a time constant at least ``dt``, Kalata's ``Λ`` at most :data:`LAMBDA_MAX` and a window at most the record's
    ``n`` samples (a longer one only repeats the first sample; uncapped, ``2√(ε/L)/dt`` at ``dt = 1e-9`` s
    asked for windows of 6·10⁸ samples and 20 GB).
    """
    if not isinstance(fam, Family):
        raise TypeError(f"fam must be a Family, got {fam!r:.80}")
    _check_case_setup(case, setup)
    z = np.atleast_2d(check_finite("z", z))
    if z.ndim != 2 or z.shape[1] != len(fam.params):
        raise ValueError(f"z must have shape (C, {len(fam.params)}) (one column per {fam.name} parameter), "
                         f"got {z.shape}")
    sc = scales(case.eps, case.L, setup.dt)
    out = np.empty_like(z)
    for j, p in enumerate(fam.params):
        if p.ref == "one":
            out[:, j] = np.clip(np.round(z[:, j]), p.lo, p.hi)
            continue
        with np.errstate(over="ignore", under="ignore"):  # a z beyond exp's range: refused below
            v = sc[p.ref] * np.exp(z[:, j])
        if p.ref == "omega":  # fastest pole ω (Σ: n0 a) at most OMEGA_DT_MAX / dt
            pole = float(SIGMA_ORDER.get(fam.name, 1))
            v = np.minimum(v, OMEGA_DT_MAX / (pole * setup.dt))
        if p.ref == "tau":
            v = np.maximum(v, setup.dt)
        if p.ref in ("lambda", "lambda3"):
            v = np.minimum(v, LAMBDA_MAX)
        if p.integer:
            v = np.maximum(np.round(v), 2.0)
        if p.ref == "window":
            v = np.minimum(v, float(setup.n))
        out[:, j] = v
    if not np.all(np.isfinite(out) & (out > 0)):
        raise ValueError(f"z must give {fam.name} parameter values reference × exp(z) that are finite and > 0 in "
                         f"double precision, got z of magnitude up to {np.max(np.abs(z)):.3g}")
    return out


def _grid(fam: Family) -> tuple:
    """Grid of ``z`` (C, n_params) and the initial pattern step per parameter."""
    axes, steps = [], []
    n = 9 if len(fam.params) == 1 else 5
    for p in fam.params:
        if p.ref == "one":
            axes.append(np.arange(p.lo, p.hi + 1))
            steps.append(0.0)
        else:
            ax = np.linspace(np.log(p.lo), np.log(p.hi), p.points or n)
            axes.append(ax)
            steps.append(0.5 * (ax[1] - ax[0]))
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([m.ravel() for m in mesh]), np.array(steps)


def evaluate(task) -> np.ndarray:
    """Metrics of configurations: ``task = (family, setup, cases, configs, engine[, classes])``.

    Parameters
    ----------
    task : tuple
        ``family`` name; :class:`Setup`; sequence of :class:`Case`; ``configs`` a list of
        ``(case index, parameter row)``; ``engine`` for :meth:`Loop.simulate`; optionally the
        registered signal classes the cases use (``{name: SignalClass}``), registered here when this
        process lacks them (a Dask worker: a forked process inherits them).

    Returns
    -------
    numpy.ndarray, shape (len(configs), len(METRICS))
        Columns :data:`METRICS`: worst, rms, lag, noise, rms_f, startup.
    """
    name, setup, cases, configs, engine = _check_task(task)
    known = registered_signal_classes()
    for cls in (task[5] if len(task) == 6 else {}).values():
        if cls.name not in known:
            register_signal_class(cls.name, cls.description, cls.generate, cls.bound_how)
    fam = family(name, given=True)  # a fixed configuration may be a given-gains estimator
    records = {}
    out = np.empty((len(configs), len(METRICS)))
    per = 2 * len(cases[0].seeds)
    step = max(1, RUNS_PER_CALL // per)
    k0 = setup.k_from
    for lo in range(0, len(configs), step):
        part = configs[lo:lo + step]
        ys, truths, signals, P = [], [], [], []
        for ci, row in part:
            if ci not in records:
                records[ci] = case_records(cases[ci], setup)
            d1, y, f = records[ci]
            ys += [y, f]
            truths.append(d1)
            signals.append(f)
            P.append(np.tile(row, (per, 1)))
        both = estimate(fam, np.vstack(P), np.hstack(ys), setup.dt, engine=engine, init=setup.init)
        est = both[:, :, 1]
        S = per // 2
        for i in range(len(part)):
            noisy = est[k0:, i * per:i * per + S]
            clean = est[k0:, i * per + S:(i + 1) * per]
            truth = truths[i][k0:]
            f_hat = both[k0:, i * per:i * per + S, 0]
            startup = np.max(np.abs(est[:k0, i * per:i * per + S] - truths[i][:k0]), initial=0.0)
            out[lo + i] = (np.max(np.abs(noisy - truth)), rmse(truth, noisy, axis=None),
                           np.max(np.abs(clean - truth)), rmse(clean, noisy, axis=None),
                           rmse(signals[i][k0:], f_hat, axis=None), startup)
    return np.where(np.isfinite(out), out, np.inf)


def _check_task(task) -> tuple:
    """:func:`evaluate`'s task, each part checked (errors name ``task`` and the part)."""
    if not isinstance(task, (tuple, list)) or len(task) not in (5, 6):
        raise TypeError(f"task must be a tuple (family, setup, cases, configs, engine[, classes]), got {task!r:.80}")
    name, setup, cases, configs, engine = task[:5]
    if len(task) == 6 and not isinstance(task[5], dict):
        raise TypeError(f"task classes must be a dict of registered signal classes, got {task[5]!r:.80}")
    fam = family(check_in("task family", name, [f.name for f in FAMILIES + OFFLINE + GIVEN]), given=True)
    if not isinstance(setup, Setup):
        raise TypeError(f"task setup must be a Setup, got {setup!r:.80}")
    if not isinstance(cases, (tuple, list)) or not cases or not all(isinstance(c, Case) for c in cases):
        raise TypeError(f"task cases must be a non-empty sequence of Case, got {cases!r:.80}")
    if len({len(c.seeds) for c in cases}) != 1:
        raise ValueError("task cases must all have the same number of seeds")
    if not isinstance(configs, (tuple, list)):
        raise TypeError(f"task configs must be a list of (case index, parameter row), got {configs!r:.80}")
    for item in configs:
        if not isinstance(item, (tuple, list)) or len(item) != 2:
            raise TypeError(f"task configs must hold (case index, parameter row) pairs, got {item!r:.80}")
        check_int("task configs case index", item[0], minimum=0, maximum=len(cases) - 1)
        row = np.asarray(check_finite("task configs parameter row", item[1]))
        if row.shape != (len(fam.params),):
            raise ValueError(f"task configs parameter row must have {len(fam.params)} entries, got shape {row.shape}")
    check_in("task engine", engine, ("auto", "numpy", "compiled"))
    return name, setup, cases, configs, engine


def _tasks(name, setup, cases, configs, engine, jobs) -> list:
    """``configs`` of family ``name`` cut into :func:`evaluate` tasks (about four per process)."""
    if not configs:
        return []
    n_chunks = max(1, min(len(configs), 4 * jobs if jobs > 1 else 1))
    bounds = np.linspace(0, len(configs), n_chunks + 1).astype(int)
    reg = registered_signal_classes()
    classes = {c.signal: reg[c.signal] for c in cases if c.signal in reg}
    return [(name, setup, tuple(cases), configs[a:b], engine, classes) for a, b in itertools.pairwise(bounds) if b > a]


def _tuning(name: str, cases: list, setup: Setup, rounds: int, costs=COSTS[:2]):
    """One family's tuning as a generator: yields ``(configs, desc)``, is sent their metrics, returns the result.

    The grid, then ``rounds`` pattern-search rounds per cost (names in :data:`COSTS`); :func:`tune_families`
    drives many side by side. Each cost's search reads only its own candidates after the grid, so adding a cost
    leaves the others' results unchanged.
    """
    costs = [METRICS.index(c) for c in costs]
    fam = family(name)
    grid, steps = _grid(fam)
    evaluated = [[] for _ in cases]

    def run(zs_per_case, desc):
        configs, owners = [], []
        for ci, zs in enumerate(zs_per_case):
            if len(zs):
                vals = param_values(fam, zs, cases[ci], setup)
                configs += [(ci, v) for v in vals]
                owners += [(ci, z, v) for z, v in zip(zs, vals, strict=True)]
        metrics = yield configs, desc
        for (ci, z, v), m in zip(owners, metrics, strict=True):
            evaluated[ci].append((z, v, m))

    yield from run([grid] * len(cases), f"{name}: grid")
    step = steps.copy()
    free, fixed = np.flatnonzero(step > 0), np.flatnonzero(step == 0)
    # one search per value of the parameters that are not stepped (a degree, Σ's order): from each value's best
    # grid point, so a categorical choice is searched exhaustively, not only the grid-best value's neighbourhood
    best = {cost: [_starts(evaluated[ci], fixed, cost) for ci in range(len(cases))] for cost in costs}
    for r in range(rounds):
        for cost in costs:
            cand, owner = [], []
            for ci in range(len(cases)):
                zs, who = [], []
                for si, (z0, _m) in enumerate(best[cost][ci]):
                    for j in free:
                        for sgn in (-1, 1):
                            z = z0.copy()
                            z[j] += sgn * step[j]
                            zs.append(z)
                            who.append(si)
                cand.append(np.array(zs))
                owner.append(who)
            start = [len(e) for e in evaluated]
            yield from run(cand, f"{name}: refine {r + 1}/{rounds} ({METRICS[cost]})")
            for ci in range(len(cases)):
                for si, (z, _v, m) in zip(owner[ci], evaluated[ci][start[ci]:], strict=True):
                    if m[cost] < best[cost][ci][si][1][cost]:
                        best[cost][ci][si] = [z, m]
        step = step / 2
    out_best = []
    for ci, case in enumerate(cases):
        row = {}
        for cost in costs:
            z, m = min(best[cost][ci], key=lambda e: e[1][cost])  # the first on a tie: the grid's order
            row[METRICS[cost]] = (param_values(fam, z, case, setup)[0], m)
        out_best.append(row)
    return {"family": name, "evaluated": [[(v, m) for _, v, m in e] for e in evaluated], "best": out_best,
            "tunings": int(sum(len(e) for e in evaluated))}


def _starts(evaluated: list, fixed: np.ndarray, cost: int) -> list:
    """``[z, metrics]`` of the best grid point per value of the ``fixed`` (not stepped) parameters, best first."""
    best = {}
    for z, _v, m in evaluated:
        key = tuple(z[fixed])
        if key not in best or m[cost] < best[key][1][cost]:
            best[key] = [z, m]
    return sorted(best.values(), key=lambda e: e[1][cost])


def _check_tuning(cases, setup, rounds, engine, jobs) -> tuple:
    rounds = check_int("rounds", rounds, minimum=0, maximum=MAX_ROUNDS)
    if isinstance(cases, (str, bytes)) or not hasattr(cases, "__iter__"):
        raise TypeError(f"cases must be a sequence of Case, got {cases!r:.80}")
    cases = list(cases)
    if not cases or not all(isinstance(c, Case) for c in cases):
        raise TypeError(f"cases must be a non-empty sequence of Case, got {cases!r:.80}")
    if len({len(c.seeds) for c in cases}) != 1:
        raise ValueError("cases must all have the same number of seeds (they are run as one batch)")
    if not isinstance(setup, Setup):
        raise TypeError(f"setup must be a Setup, got {setup!r:.80}")
    check_in("engine", engine, ("auto", "numpy", "compiled"))
    check_int("jobs", jobs, minimum=1)
    return cases, rounds


def tune_families(names, cases, setup: Setup, *, rounds: int = 3, engine: str = "auto", jobs: int = 1,
                  scheduler=None, costs=COSTS[:2]) -> dict:
    """Tune several families on every case, their rounds side by side (:func:`tune_family` for each).

    Each family's rounds are one chain of :func:`ctrl_analysis.runs.chains.drive`: in a pool each
    family starts its next round as soon as its own round is back (no family waits for a slower one);
    elsewhere round ``r`` of every family goes into one map. The families are independent, so the result
    is each family's :func:`tune_family` exactly (the same configurations, cut into the same tasks).

    Parameters
    ----------
    names : sequence of str
        Family names.
    cases, setup, rounds, engine, jobs, scheduler
        As :func:`tune_family`.
    costs : tuple of str
        What each family is tuned for, names in :data:`COSTS` (default f̂''s worst and RMS error).

    Returns
    -------
    dict of str -> dict
        :func:`tune_family`'s result per family, in the order of ``names``.
    """
    if isinstance(names, (str, bytes)) or not hasattr(names, "__iter__"):
        raise TypeError(f"names must be a sequence of family names, got {names!r:.80}")
    names = list(names)
    for i, n in enumerate(names):
        try:
            family(n)
        except (TypeError, ValueError) as exc:
            raise type(exc)(f"names[{i}]: {exc}") from None
    if not names or len(set(names)) != len(names):
        raise ValueError(f"names must be distinct family names, at least one, got {names}")
    cases, rounds = _check_tuning(cases, setup, rounds, engine, jobs)
    costs = _check_costs(costs)
    return drive(evaluate, {n: _chain(n, cases, setup, rounds, engine, jobs, costs) for n in names}, jobs=jobs,
                 scheduler=scheduler, desc="tuning" if len(names) > 1 else names[0], unit="batch")


def _check_costs(costs) -> tuple:
    if not isinstance(costs, tuple) or not costs or len(set(costs)) != len(costs):
        raise TypeError(f"costs must be a non-empty tuple of distinct names from {COSTS}, got {costs!r:.80}")
    for c in costs:
        check_in("costs", c, COSTS)
    return costs


def family_chain(name: str, cases, setup: Setup, *, rounds: int = 3, engine: str = "auto", jobs: int = 1,
                 costs=COSTS[:2]):
    """One family's tuning as a chain of :func:`ctrl_analysis.runs.chains.drive` (``fn`` = :func:`evaluate`).

    The generator yields lists of :func:`evaluate` tasks, is sent their results, and returns what
    :func:`tune_family` returns; a caller can follow it with work of its own in the same chain.

    Parameters
    ----------
    name : str
        Family name.
    cases, setup, rounds, engine
        As :func:`tune_family`.
    jobs : int
        Processes the tasks are cut for (about four tasks per process).
    costs : tuple of str
        As :func:`tune_families`.

    Returns
    -------
    generator
    """
    family(name)
    cases, rounds = _check_tuning(cases, setup, rounds, engine, jobs)
    return _chain(name, cases, setup, rounds, engine, jobs, _check_costs(costs))


def _chain(name, cases, setup, rounds, engine, jobs, costs=COSTS[:2]):
    tuner = _tuning(name, cases, setup, rounds, costs)
    configs, _ = next(tuner)
    while True:
        tasks = _tasks(name, setup, cases, configs, engine, jobs)
        parts = yield tasks
        try:
            configs, _ = tuner.send(np.vstack(parts) if tasks else np.empty((0, len(METRICS))))
        except StopIteration as done:
            return done.value


def tune_family(name: str, cases, setup: Setup, *, rounds: int = 3, engine: str = "auto", jobs: int = 1,
                scheduler=None) -> dict:
    """Tune one family on every case for both costs (grid, then pattern-search refinement).

    Parameters
    ----------
    name : str
        Family name.
    cases : sequence of Case
    setup : Setup
    rounds : int
        Pattern-search rounds after the grid (0 to :data:`MAX_ROUNDS`).
    engine : {"auto", "numpy", "compiled"}
    jobs : int
        Processes (:func:`ctrl_analysis.runs.parallel.map_chunks`).
    scheduler : optional
        A Dask scheduler address.

    Returns
    -------
    dict
        ``evaluated``: per case, the list of ``(values, metrics)`` of every configuration;
        ``best``: per case and cost (``"worst"``, ``"rms"``; :func:`tune_families` may add ``"rms_f"``),
        ``(values, metrics)``; ``tunings``: configurations evaluated.
    """
    family(name)
    return tune_families([name], cases, setup, rounds=rounds, engine=engine, jobs=jobs, scheduler=scheduler)[name]


def pareto_front(points) -> np.ndarray:
    """Indices of the non-dominated points (smaller is better in both coordinates), sorted by the first.

    Parameters
    ----------
    points : array_like, shape (n, 2)

    Returns
    -------
    numpy.ndarray of int

    Examples
    --------
    >>> pareto_front([[1, 5], [2, 2], [3, 3], [4, 1]]).tolist()
    [0, 1, 3]
    """
    p = check_array("points", points)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"points must have shape (n, 2), got {p.shape}")
    if np.any(np.isnan(p)):
        raise ValueError("points must not contain NaN (inf is a valid, dominated coordinate)")
    order = np.lexsort((p[:, 1], p[:, 0]))
    keep, best = [], np.inf
    for i in order:
        if p[i, 1] < best:
            keep.append(i)
            best = p[i, 1]
    return np.array(keep, dtype=int)



