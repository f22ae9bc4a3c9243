"""Every verdict judged over the plausible box: all reconstructions varied jointly, flips located, cells searched.

A study declares each value the paper does not print with
``reconstructed(value, why, plausible=span(low, high, why))`` or ``choices(...)``
(:mod:`ctrl_analysis.reporting.study`); together those ranges span the study's *plausible box* (printed values
fixed). Its claims and primary cells are computed by an ``evaluate(params)`` function that builds a
:class:`~ctrl_analysis.reporting.results.StudyResult` with the same recording code as the study's main run.

:func:`explore` evaluates the study at the chosen values and at a Latin hypercube sample of the box
(``scipy.stats.qmc``, at least 64 points), then refines, every round one batch over processes:

* **claims** — where the claim's verdict differs between the chosen point and a sample, or between two
  neighbouring samples, the boundary is located by bisection along the segment, so a flip between samples
  cannot hide; the nearest located flip is the claim's ``nearest_flip``;
* **cells** — a printed number outside its band at the chosen point is searched for: a sample whose band
  holds it, else bisection between two samples on either side of it, else a local compass search from the
  closest sample over the reconstructions that move the cell most.

Where the study declares an :func:`~ctrl_analysis.reporting.study.algorithm` axis (the paper's printed
algorithm against the project's correction) the box is sampled under each, and each claim is judged under
both. :func:`apply` writes the outcome into the study's result: per claim its ``support`` (the share of the
box where it holds, with its standard error), its ``drivers`` (first-order Sobol' indices of the claim's
verdict, SALib's RBD-FAST on the same sample) and its nearest flip; per cell ``agrees`` / ``reachable`` (with
the point) / ``differs``. :func:`plot_sensitivity` draws the supports and the drivers.

Examples
--------
A toy study whose claim ("the gain is below 2") holds at the chosen ``k = 1`` but fails for ``k > 2``: it holds
on 60 % of the box, and the flip nearest the chosen value is located at ``k = 2``:

>>> from dataclasses import dataclass
>>> from ctrl_analysis.reporting.results import StudyInfo, StudyResult
>>> from ctrl_analysis.reporting.study import Claim, reconstructed, span
>>> CLAIM = Claim("small", "§1", "the gain is below 2")
>>> @dataclass(frozen=True)
... class P:
...     k: float = reconstructed(1.0, "not printed", plausible=span(0.5, 3.0, "typical gains"))
>>> def evaluate(params):
...     res = StudyResult(StudyInfo("toy", "", "", ""))
...     res.quantity("gain", "gain", params["p"].k, unit="")
...     res.claim(CLAIM, params["p"].k < 2, evidence=["gain"])
...     return res
>>> result = evaluate({"p": P()})
>>> apply(result, explore(evaluate, {"p": P()}))
>>> c = result.get_claim("small")
>>> c.verdict, round(c.support, 1), c.depends_on[0]["reconstruction"], round(c.depends_on[0]["flips_at"], 1)
('depends', 0.6, 'p.k', 2.0)
"""

from __future__ import annotations

import dataclasses
import math
import zlib
from collections.abc import Callable

import numpy as np

from .._validate import check_callable, check_int
from .box import Box, Dimension, _json, first_order
from .box_cells import cell_state, search_cells
from .results import StudyResult
from .support_figure import plot_sensitivity
from .verdicts import SUPPORT_HIGH, SUPPORT_LOW, claim_verdict

__all__ = ["QUICK", "SAMPLES", "Box", "Dimension", "Exploration", "apply", "caption", "explore", "plot_sensitivity"]

#: Default number of points of the box's Latin hypercube sample.
SAMPLES = 64
#: :func:`explore`'s settings for a smoke test (``--quick``): a few points, short bisections; never for a verdict.
QUICK = {"samples": 8, "refine": 2, "cell_steps": 3, "search_rounds": 1}


# ---------------------------------------------------------------------------------------------------------------
# outcomes of one evaluation


def _outcome(result) -> dict:
    """``{"claims": {id: holds}, "cells": {id: state}}`` of one evaluation."""
    if not isinstance(result, StudyResult):
        raise TypeError(f"evaluate must return a StudyResult, got {type(result).__name__}")
    cells = {}
    for q in result.quantities:
        if q.paper is not None and q.kind == "reproduction" and q.derived_from is None:
            state = cell_state(q)
            if state is not None:
                cells[q.id] = state
    return {"claims": {c.claim.id: c.holds for c in result.claims}, "cells": cells}


def _evaluate_task(task):
    evaluate, variant = task
    return _outcome(evaluate(variant))


# ---------------------------------------------------------------------------------------------------------------
# the exploration


@dataclasses.dataclass
class Exploration:
    """What :func:`explore` found: per claim and per cell, judged over the box; :func:`apply` writes it.

    Parameters
    ----------
    box : Box
    claims : dict
        ``{claim id: dict}``: ``support``, ``drivers``, ``nearest_flip``, ``boundary``, ``depends_on``,
        ``by_algorithm``, ``baseline``.
    cells : dict
        ``{quantity id: dict}``: ``verdict`` over the box, ``reached_at`` / ``how``, ``closest``, ``range``.
    summary : dict
        ``samples``, ``evaluations``, ``dimensions``, ``algorithms``, ``note`` (written as results.json's
        ``sensitivity``).
    """

    box: Box
    claims: dict
    cells: dict
    summary: dict


class _Runner:
    """Evaluates points in rounds (one batch over processes per round) and keeps count."""

    def __init__(self, evaluate, box, jobs, scheduler, batch=None):
        from ..runs.parallel import picklable

        self.evaluate, self.box, self.jobs, self.scheduler, self.batch = evaluate, box, jobs, scheduler, batch
        fn = evaluate if batch is None else batch
        self.parallel = (jobs > 1 or scheduler is not None) and picklable(fn)
        self.count = 0

    def run(self, points) -> list:
        """Outcomes at ``[(u, algorithm)]``, in order."""
        from ..runs.parallel import map_chunks

        if not points:
            return []
        variants = [self.box.params_at(u, a) for u, a in points]
        self.count += len(variants)
        if self.batch is not None:
            # the study evaluates several points at once (e.g. on the batch axis of one simulation): one call per
            # process, each on a contiguous share of the points
            n = min(self.jobs if self.parallel else 1, len(variants))
            cuts = np.linspace(0, len(variants), n + 1).round().astype(int)
            chunks = [(self.batch, variants[a:b]) for a, b in zip(cuts[:-1], cuts[1:], strict=True) if b > a]
            if self.parallel and len(chunks) > 1:
                parts = map_chunks(_batch_task, chunks, jobs=self.jobs, scheduler=self.scheduler,
                                   desc="plausible box")
            else:
                parts = [_batch_task(c) for c in chunks]
            return [o for part in parts for o in part]
        tasks = [(self.evaluate, v) for v in variants]
        if self.parallel and len(tasks) > 1:
            return map_chunks(_evaluate_task, tasks, jobs=self.jobs, scheduler=self.scheduler, desc="plausible box")
        return [_evaluate_task(t) for t in tasks]


def _batch_task(task):
    batch, variants = task
    results = batch(variants)
    if not isinstance(results, (list, tuple)) or len(results) != len(variants):
        raise ValueError(f"batch must return one StudyResult per parameter set ({len(variants)}), got "
                         f"{type(results).__name__} of length {len(results) if hasattr(results, '__len__') else '?'}")
    return [_outcome(r) for r in results]


def _indicator(outcomes, claim_id) -> np.ndarray:
    """1 / 0 / nan (holds, fails, untestable) of a claim over outcomes."""
    return np.array([math.nan if o["claims"].get(claim_id) is None else float(o["claims"][claim_id])
                     for o in outcomes])


def _support(y) -> dict:
    ok = y[np.isfinite(y)]
    n = int(ok.size)
    if n == 0:
        return {"holds": None, "samples": 0, "stderr": None, "untestable": int(y.size)}
    s = float(ok.mean())
    # binomial standard error (a Latin hypercube's stratification makes the sampling error no larger)
    return {"holds": round(s, 4), "samples": n, "stderr": round(math.sqrt(max(s * (1 - s), 0.25 / n) / n), 4),
            "untestable": int(y.size - n)}


def _bisect(runner, segments, steps, decide) -> list:
    """Bisect every segment ``steps`` times, all segments' midpoints evaluated as one batch per round.

    ``segments``: dicts with ``a``, ``b`` (coordinates), ``algorithm``, ``key``; ``decide(seg, outcome)`` returns
    ``"a"`` (the midpoint is like end a), ``"b"``, or ``"done"`` (stop, the midpoint is the answer).
    """
    active = list(segments)
    for _ in range(steps):
        if not active:
            break
        mids = [runner.box.interpolate(s["a"], s["b"], 0.5) for s in active]
        outs = runner.run([(m, s["algorithm"]) for m, s in zip(mids, active, strict=True)])
        still = []
        for s, m, o in zip(active, mids, outs, strict=True):
            side = decide(s, o)
            if side == "done":
                s["hit"], s["hit_outcome"] = m, o
            else:
                s[side] = m
                s.setdefault("rounds", 0)
                s["rounds"] += 1
                still.append(s)
        active = still
    return segments


def explore(evaluate: Callable, params: dict, *, samples: int = SAMPLES, seed: int | None = None,
            names=None, jobs: int = 1, scheduler=None, refine: int = 6, cell_steps: int = 10,
            search_rounds: int = 3, batch: Callable | None = None, note: str = "") -> Exploration:
    """Judge the study's claims and cells over its plausible box (module docstring).

    Parameters
    ----------
    evaluate : callable
        ``evaluate(params) -> StudyResult`` with ``params`` shaped like the argument below. Module-level
        (picklable) to run over processes.
    params : dict
        ``{prefix: frozen parameter dataclass}``, the prefixes those of
        :func:`ctrl_analysis.reporting.study.record_parameters`.
    samples : int
        Quasi-random points of the box per algorithm (rounded up to a power of two; at least 64 for a verdict
        the report calls robust — fewer only for smoke tests).
    seed : int, optional
        Seed of the Latin hypercube sample (default: from the reconstructions' names, so a study's sample
        is the same on every run).
    names : collection of str, optional
        Vary only these reconstructions.
    jobs : int
        Processes (:func:`ctrl_analysis.runs.parallel.map_chunks`).
    scheduler : str, optional
        A Dask scheduler address.
    refine : int
        Bisection steps per claim segment (the boundary is located to ``2**-refine`` of the segment).
    cell_steps : int
        Bisection steps per cell segment (stops early once the band holds the paper's value).
    search_rounds : int
        Rounds of the local compass search for a cell no sample straddles.
    batch : callable, optional
        ``batch([params, ...]) -> [StudyResult, ...]``: the study evaluates many points at once (e.g. every
        point's Monte Carlo runs side by side on the batch axis of one simulation), with the same results as
        ``evaluate`` point by point. Each round then makes one call per process. Module-level (picklable).
    note : str
        How each evaluation is run (runs, seeds), recorded in results.json.

    Returns
    -------
    Exploration
    """
    check_callable("evaluate", evaluate, "evaluate(params)")
    samples = check_int("samples", samples, minimum=2, maximum=1 << 14)
    jobs = check_int("jobs", jobs, minimum=1)
    refine = check_int("refine", refine, minimum=0, maximum=30)
    cell_steps = check_int("cell_steps", cell_steps, minimum=0, maximum=40)
    search_rounds = check_int("search_rounds", search_rounds, minimum=0, maximum=20)
    box = Box(params, set(names) if isinstance(names, (list, tuple, set, frozenset)) else names)
    if seed is None:
        seed = zlib.crc32(",".join(d.name for d in box.dims).encode())
    if batch is not None:
        check_callable("batch", batch, "batch([params, ...])")
    runner = _Runner(evaluate, box, jobs, scheduler, batch)
    chosen = box.chosen
    U = box.sample(samples, seed)
    # round 0: the chosen point and the sample, under each algorithm
    points = []
    for a in box.algorithms:
        points += [(chosen, a)] + [(u, a) for u in U]
    outs = runner.run(points)
    per = {a: outs[i * (len(U) + 1):(i + 1) * (len(U) + 1)] for i, a in enumerate(box.algorithms)}
    base = per[box.algorithms[0]][0]
    claims = _claims(runner, box, U, per, refine)
    cells = search_cells(runner, box, U, per, cell_steps, search_rounds, _bisect)
    summary = {"samples": len(U), "evaluations": runner.count, "dimensions": len(box.dims),
               "ranges": {d.name: d.plausible.to_dict() for d in box.dims},
               "algorithm": ({"chosen": box.algorithm, "fields": [d.name for d in box.algorithm_dims]}
                             if box.algorithm else None),
               "thresholds": [SUPPORT_LOW, SUPPORT_HIGH], "seed": int(seed), "note": note,
               "baseline_claims": base["claims"]}
    return Exploration(box, claims, cells, summary)


def _claims(runner, box, U, per, refine) -> dict:
    main = box.algorithms[0]
    base = per[main][0]
    outs = per[main][1:]
    out = {}
    segments = []
    D = box.distances(U, U)  # every pair of samples, and the chosen point to each, computed once
    Dc = box.distances(box.chosen[None], U)[0]
    np.fill_diagonal(D, np.inf)
    for cid, holds0 in base["claims"].items():
        y = _indicator(outs, cid)
        entry = {"support": _support(y), "baseline": None if holds0 is None else ("holds" if holds0 else "fails"),
                 "drivers": first_order(box, U, y) if len(U) else [], "nearest_flip": None, "boundary": [],
                 "depends_on": []}
        if len(box.algorithms) > 1:
            entry["by_algorithm"] = {}
            for a in box.algorithms:
                s = _support(_indicator(per[a][1:], cid))
                b0 = per[a][0]["claims"].get(cid)
                base_a = "untestable" if b0 is None else ("holds" if b0 else "fails")
                # the verdict from the support alone: the chosen point's own judgement is ``at_chosen`` (for the
                # study's algorithm apply() puts the main run's verdict here, judged on more runs)
                entry["by_algorithm"][a] = {"support": s, "at_chosen": base_a,
                                            "verdict": claim_verdict(s["holds"],
                                                                     "untestable" if s["holds"] is None else "holds")}
        out[cid] = entry
        if holds0 is None or not len(U):
            continue
        # the nearest sample where the claim takes the other definite verdict: bisect chosen -> it
        other = [i for i in range(len(U)) if np.isfinite(y[i]) and bool(y[i]) != holds0]
        if other:
            j = min(other, key=lambda i: Dc[i])
            segments.append({"claim": cid, "kind": "nearest", "a": box.chosen.copy(), "b": U[j].copy(),
                             "va": holds0, "algorithm": main})
        # neighbouring samples with different verdicts: the closest such pair
        pairs = []
        ok = np.isfinite(y)
        Dy = np.where(ok[None, :], D, np.inf)
        for i in np.flatnonzero(ok):
            j = int(np.argmin(Dy[i]))
            if np.isfinite(Dy[i, j]) and y[j] != y[i] and i < j:
                pairs.append((D[i, j], i, j))
        for _, i, j in sorted(pairs)[:1]:
            segments.append({"claim": cid, "kind": "pair", "a": U[i].copy(), "b": U[j].copy(), "va": bool(y[i]),
                             "algorithm": main})

    def decide(seg, o):
        v = o["claims"].get(seg["claim"])
        return "a" if v is None or v == seg["va"] else "b"

    _bisect(runner, segments, refine, decide)
    _prune(runner, box, out, segments, refine, decide)
    for seg in segments:
        entry = out[seg["claim"]]
        point = box.changed(seg["b"])  # the first point past the boundary
        flipped = "fails" if seg["va"] else "holds"
        if seg["kind"] == "nearest":
            entry["nearest_flip"] = {"point": point, "distance": round(box.distance(box.chosen, seg["b"]), 4),
                                     "verdict_there": flipped,
                                     "bracket": round(box.distance(seg["a"], seg["b"]), 4)}
            entry["depends_on"] = [{"reconstruction": name, "chosen": _json(_dim(box, name).chosen),
                                    "flips_at": value, "verdict_there": flipped}
                                   for name, value in sorted(point.items(),
                                                             key=lambda kv: -_moved(box, seg["b"], kv[0]))]
        entry["boundary"].append({"kind": seg["kind"],
                                  "at": box.changed(box.interpolate(seg["a"], seg["b"], 0.5)),
                                  "bracket": round(box.distance(seg["a"], seg["b"]), 4)})
    return out


def _prune(runner, box, out, segments, refine, decide) -> None:
    """Bring each nearest flip closer: move only the reconstructions that matter away from their chosen values.

    A bisection from the chosen point towards a sample moves every reconstruction at once. Keeping only the
    ``k`` reconstructions with the largest first-order indices (k = 1, 2, 3, 5, 8) moved to the point just
    past the boundary, the smallest ``k`` that still flips the claim is found (one batch over every claim),
    and the boundary is located again along those alone. A flip that needs two reconstructions together
    (each with a small first-order index) keeps both.
    """
    tries = []
    for seg in segments:
        if seg["kind"] != "nearest":
            continue
        moved = box.changed(seg["b"])  # {name: value}, in the box's dimension order
        ranked = [d["reconstruction"] for d in out[seg["claim"]]["drivers"] if d["reconstruction"] in moved]
        # the rest in the box's order: a set's order of strings changes with each process's hash seed
        ranked += [name for name in moved if name not in ranked]
        for k in sorted({k for k in (1, 2, 3, 5, 8) if k < len(ranked)}):
            keep = set(ranked[:k])
            c = np.array([b if d.name in keep else a for d, a, b in zip(box.dims, box.chosen, seg["b"], strict=True)])
            tries.append((seg, k, c))
    outs = runner.run([(c, seg["algorithm"]) for seg, _, c in tries])
    best: dict = {}
    for (seg, k, c), o in zip(tries, outs, strict=True):
        v = o["claims"].get(seg["claim"])
        if v is not None and v != seg["va"] and (id(seg) not in best or k < best[id(seg)][0]):
            best[id(seg)] = (k, c, seg)
    again = [{**seg, "a": box.chosen.copy(), "b": c, "_of": seg} for _, c, seg in best.values()]
    _bisect(runner, again, refine, decide)
    for new in again:
        new["_of"].update(a=new["a"], b=new["b"])


def _dim(box, name) -> Dimension:
    return next(d for d in box.dims if d.name == name)


def _moved(box, u, name) -> float:
    """How far dimension ``name`` moved from the chosen value at ``u`` (coordinates; an alternative 1/2)."""
    i = [d.name for d in box.dims].index(name)
    d, c = box.dims[i], box.chosen[i]
    if d.continuous and math.isfinite(c) and math.isfinite(u[i]):
        return abs(u[i] - c)
    return 0.5


# ---------------------------------------------------------------------------------------------------------------
# writing it into the result


def apply(result: StudyResult, exploration: Exploration) -> None:
    """Write an exploration into ``result``: each claim's support, drivers and nearest flip; each cell's box verdict.

    A claim's verdict then follows from its support by the policy's thresholds
    (:func:`~ctrl_analysis.reporting.verdicts.claim_verdict`). Where the exploration's own baseline (evaluated
    with its own, usually fewer, runs) judges the claim differently from the main run, the claim's note says so.

    Parameters
    ----------
    result : StudyResult
        The study's main result, its claims already judged.
    exploration : Exploration
        From :func:`explore`.
    """
    if not isinstance(result, StudyResult) or not isinstance(exploration, Exploration):
        raise TypeError("apply(result, exploration) takes a StudyResult and an Exploration")
    for c in result.claims:
        entry = exploration.claims.get(c.claim.id)
        if entry is None:
            continue
        c.box = {k: v for k, v in entry.items()}
        if "by_algorithm" in c.box:  # the study's own algorithm: the claim's verdict, main run included
            main = exploration.box.algorithms[0]
            c.box["by_algorithm"] = {a: dict(v) for a, v in c.box["by_algorithm"].items()}
            c.box["by_algorithm"][main]["verdict"] = c.verdict
        b = entry["baseline"]
        if b != (None if c.holds is None else ("holds" if c.holds else "fails")):
            c.note = (c.note + " " if c.note else "") + (
                "The box exploration's own evaluation at the chosen values "
                f"({exploration.summary['note'] or 'its own settings'}) judges it {b or 'untestable'}.")
    for q in result.quantities:
        entry = exploration.cells.get(q.id)
        if entry is not None:
            q.box = dict(entry)
    result.sensitivity = dict(exploration.summary)


def caption(result: StudyResult, detail: str = "") -> str:
    """The caption of :func:`plot_sensitivity`'s figure for ``result`` (after :func:`apply`).

    Parameters
    ----------
    result : StudyResult
    detail : str
        How each evaluation was run (runs, seeds), added to the caption.

    Returns
    -------
    str
    """
    if not isinstance(result, StudyResult):
        raise TypeError(f"result must be a StudyResult, got {type(result).__name__}")
    if not isinstance(detail, str):
        raise TypeError(f"detail must be a string, got {type(detail).__name__}")
    s = result.sensitivity or {}
    return (f"Each claim judged over the plausible box ({s.get('samples', 0)} points of a Latin hypercube, all "
            f"{s.get('dimensions', 0)} reconstructions with a plausible range varied jointly"
            + (f"; {detail}" if detail else "") + "): left, its support (the share of the box where it holds, "
            f"± standard error) against the policy's thresholds ({100 * SUPPORT_LOW:.0f} % and "
            f"{100 * SUPPORT_HIGH:.0f} %), coloured by verdict; right, the first-order Sobol' index of the "
            "reconstructions that drive it (blank where the claim does not flip anywhere in the box).")
