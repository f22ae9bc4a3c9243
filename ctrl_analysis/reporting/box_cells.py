"""Printed cells searched for inside the plausible box: is the paper's number reached anywhere plausible?

A cell's *band* at a point of the box is the central 95 % of its Monte Carlo runs (a number from a noisy
simulation) or half a unit of its last printed digit (a deterministic one). :func:`search_cells` looks for a
point whose band holds the paper's value: among the box's samples (and, for a cell none of them reaches, the
chosen point's one-at-a-time neighbours along each set of alternatives), then by bisection between two of those
points on either side of it (differing only along intervals, so continuity brackets a crossing), then by a
local compass search from the closest one along the reconstructions that move the cell most. Used by
:func:`ctrl_analysis.reporting.sensitivity.explore`.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .box import _json, first_order
from .verdicts import relative_error

__all__ = ["cell_state", "search_cells"]


def cell_state(q) -> dict | None:
    """A printed cell at one point: its value, whether its band holds the paper's value, and its signed gap.

    Parameters
    ----------
    q : ctrl_analysis.reporting.quantity.Quantity
        A quantity with a paper value.

    Returns
    -------
    dict or None
        ``diverged``, ``in_band``, ``gap`` (signed relative gap of the median run or the value; None for a
        vector), ``dist`` and ``value``; None when the quantity has no value.
    """
    if q.is_diverged:
        return {"diverged": True, "in_band": False, "gap": None, "dist": math.inf, "value": None}
    if q.value is None:
        return None
    paper = np.asarray(q.paper, dtype=float)
    if paper.size == 1 and np.size(q.value) == 1:
        p = float(paper.ravel()[0])
        scale = abs(p) if p != 0 else 1.0
        if q.policy == "percentile" and q.samples is not None and np.size(q.samples):
            lo, hi = q._interval
            center = float(np.median(q.samples))
            in_band = lo <= p <= hi
        else:
            center = float(np.asarray(q.value, dtype=float).ravel()[0])
            if not math.isfinite(center):
                return {"diverged": True, "in_band": False, "gap": None, "dist": math.inf, "value": None}
            in_band = abs(center - p) / scale <= q.effective_tolerance
        gap = (center - p) / scale
        return {"diverged": False, "in_band": bool(in_band), "gap": gap, "dist": abs(gap), "value": center}
    dist = relative_error(q.value, q.paper)
    return {"diverged": not math.isfinite(dist), "in_band": dist <= q.effective_tolerance, "gap": None,
            "dist": dist, "value": None}


def search_cells(runner, box, U, per, cell_steps, search_rounds, bisect) -> dict:
    """Each printed cell of the chosen point judged over the box: agrees / reachable (where, how) / differs.

    Parameters
    ----------
    runner : object
        Evaluates points: ``runner.run([(u, algorithm)]) -> [outcome]``.
    box : ctrl_analysis.reporting.box.Box
    U : numpy.ndarray
        The box sample.
    per : dict
        ``{algorithm: [outcome at the chosen point, outcome at each sample]}``.
    cell_steps, search_rounds : int
        Bisection steps and compass-search rounds.
    bisect : callable
        ``bisect(runner, segments, steps, decide)``, the exploration's batched bisection.

    Returns
    -------
    dict
        ``{quantity id: {verdict, reached_at, how, algorithm, closest, range, ...}}``.
    """
    algos = box.algorithms
    main = algos[0]
    base = per[main][0]
    out = {}
    # every sampled point of every algorithm (the chosen points included), for reachability
    pts = []
    for a in algos:
        pts.append((box.chosen, a, per[a][0]))
        pts += [(u, a, o) for u, o in zip(U, per[a][1:], strict=True)]
    # a cell no sampled point reaches: the chosen point's one-at-a-time neighbours along each set of alternatives
    # (another integrator, another reading) join the points searched from. A printed number often sits next to
    # the chosen values, where a sample spread over every combination of alternatives rarely lands
    neighbours = []
    if any(not any((o["cells"].get(qid) or {}).get("in_band") for _, _, o in pts) for qid in base["cells"]):
        for i, d in enumerate(box.dims):
            for k in range(1, 0 if d.continuous else len(d.levels)):
                u = box.chosen.copy()
                u[i] = (k + 0.5) / len(d.levels)
                neighbours.append(u)
        pts += [(u, main, o) for u, o in zip(neighbours, runner.run([(u, main) for u in neighbours]), strict=True)]
    near = {id(u) for u in neighbours}
    segments, searches = [], []
    for qid in base["cells"]:
        states = [(u, a, o["cells"].get(qid)) for u, a, o in pts]
        states = [(u, a, s) for u, a, s in states if s is not None and not s["diverged"]]
        values = [s["value"] for _, _, s in states if s["value"] is not None]
        entry = {"verdict": None, "reached_at": None, "how": None, "algorithm": None,
                 "range": [_json(min(values)), _json(max(values))] if values else None,
                 "samples": len(states), "chosen_in_band": bool((base["cells"][qid] or {}).get("in_band"))}
        out[qid] = entry
        if not states:
            entry["verdict"] = "diverged"
            continue
        best = min(states, key=lambda t: t[2]["dist"])
        entry["closest"] = {"point": box.changed(best[0]), "algorithm": best[1], "value": _json(best[2]["value"]),
                            "distance": _json(best[2]["dist"])}
        if entry["chosen_in_band"]:
            entry["verdict"], entry["how"] = "agrees", "chosen"
            continue
        hits = [(box.distance(box.chosen, u), u, a) for u, a, s in states if s["in_band"]]  # usually few
        if hits:
            _, u, a = min(hits, key=lambda t: t[0])
            entry.update(verdict="reachable", reached_at=box.changed(u), how="neighbour" if id(u) in near else "sample",
                         algorithm=a)
            continue
        # two points on either side of the paper's value, differing only along intervals: bisect between them
        straddles = _straddles(box, states)
        if straddles:
            _, u, v, a, g = min(straddles, key=lambda t: t[0])
            segments.append({"cell": qid, "a": np.asarray(u, float).copy(), "b": np.asarray(v, float).copy(),
                             "algorithm": a, "ga": g})
        else:
            searches.append((qid, best))

    def decide(seg, o):
        s = o["cells"].get(seg["cell"])
        if s is None or s["diverged"]:
            return "a"
        if s["in_band"]:
            return "done"
        return "a" if s["gap"] is not None and s["gap"] * seg["ga"] > 0 else "b"

    bisect(runner, segments, cell_steps, decide)
    for seg in segments:
        entry = out[seg["cell"]]
        if "hit" in seg:
            entry.update(verdict="reachable", reached_at=box.changed(seg["hit"]), how="bisection",
                         algorithm=seg["algorithm"])
        else:
            searches.append((seg["cell"], None))
            entry["bracket"] = {"between": [box.changed(seg["a"]), box.changed(seg["b"])],
                                "width": round(box.distance(seg["a"], seg["b"]), 6)}
    _search(runner, box, U, per, out, searches, search_rounds)
    for entry in out.values():
        if entry["verdict"] is None:
            entry["verdict"] = "differs"
    _prune(runner, box, U, per, out)
    return out


def _prune(runner, box, U, per, out) -> None:
    """Name what moves each cell: its drivers (Sobol' indices of its gap over the sample); and for a reached cell,
    only the reconstructions it needs: each one moved to the reached point is put back at its chosen value alone
    (one batch over every cell), and those the cell does not need are put back together where that still reaches
    it (a second batch)."""
    main = box.algorithms[0]
    singles = []
    for qid, entry in out.items():
        gaps = np.array([(o["cells"].get(qid) or {}).get("dist", math.nan) for o in per[main][1:]], dtype=float)
        gaps[~np.isfinite(gaps)] = math.nan
        entry["drivers"] = [d for d in first_order(box, U, gaps) if d["significant"]][:4] if len(U) else []
        if entry["verdict"] != "reachable" or len(entry["reached_at"] or {}) < 2:
            continue
        for name in entry["reached_at"]:
            singles.append((qid, {name}, _point(box, entry["reached_at"], {name}), entry["algorithm"]))
    outs = runner.run([(u, a) for _, _, u, a in singles])
    needless: dict = {}
    for (qid, names, _, _), o in zip(singles, outs, strict=True):
        s = o["cells"].get(qid)
        if s is not None and s["in_band"]:
            needless.setdefault(qid, set()).update(names)
    combined = [(qid, _point(box, out[qid]["reached_at"], names), out[qid]["algorithm"])
                for qid, names in needless.items()]
    outs = runner.run([(u, a) for _, u, a in combined])
    for (qid, u, _), o in zip(combined, outs, strict=True):
        s = o["cells"].get(qid)
        if s is not None and s["in_band"]:
            out[qid]["reached_at"] = box.changed(u)


def _point(box, point: dict, back: set) -> np.ndarray:
    """Coordinates of ``point`` (``{name: value}``, chosen values elsewhere) with the names in ``back`` at their chosen
    values."""
    return np.array([box.chosen[i] if d.name in back or d.name not in point else d.coordinate(point[d.name])
                     for i, d in enumerate(box.dims)])


def _value(box, point, i):
    """The value of dimension ``i`` in a ``{name: value}`` point (its chosen value where the point omits it)."""
    d = box.dims[i]
    return point.get(d.name, d.chosen)


def _straddles(box, states) -> list:
    """``[(distance, u, v, algorithm, gap at u)]``: the closest pair of points on either side of the paper's value
    (opposite signed gaps) under the same algorithm and alternatives, so that only intervals change between them
    (empty when there is none)."""
    gaps = np.array([np.nan if s["gap"] is None else s["gap"] for _, _, s in states])
    ok = np.flatnonzero(np.isfinite(gaps))
    if ok.size < 2:
        return []
    pts = np.array([np.asarray(states[i][0], dtype=float) for i in ok])
    keys = box.discrete_keys(pts)
    algs = [states[i][1] for i in ok]
    g = gaps[ok]
    group = {k: i for i, k in enumerate(dict.fromkeys(zip(algs, keys, strict=True)))}
    code = np.array([group[k] for k in zip(algs, keys, strict=True)])
    mask = (g[:, None] * g[None, :] < 0) & (code[:, None] == code[None, :])
    mask = np.triu(mask, 1)
    if not mask.any():
        return []
    D = np.where(mask, box.distances(pts, pts), np.inf)
    a, b = np.unravel_index(int(np.argmin(D)), D.shape)
    return [(D[a, b], pts[a], pts[b], algs[a], g[a])]


def _search(runner, box, U, per, out, searches, rounds) -> None:
    """Local compass search (batched over cells) from each unresolved cell's closest point."""
    cont = [i for i, d in enumerate(box.dims) if d.continuous]
    if not searches or not cont or not rounds:
        return
    main = box.algorithms[0]
    state = {}
    from scipy.stats import spearmanr

    for qid, _ in searches:
        outs = per[main][1:]
        gaps = np.array([(o["cells"].get(qid) or {}).get("dist", math.nan) for o in outs], dtype=float)
        ok = np.isfinite(gaps)
        if not ok.any():
            continue
        # the interval dimensions that move the cell most (rank correlation over the sample), at most three
        score = []
        for i in cont:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                r = spearmanr(U[ok, i], gaps[ok]).statistic if ok.sum() > 3 else 0.0
            score.append((0.0 if not np.isfinite(r) else abs(r), i))
        dims = [i for _, i in sorted(score, reverse=True)[:3]]
        j = int(np.argmin(np.where(ok, gaps, np.inf)))
        state[qid] = {"u": U[j].copy(), "dist": gaps[j], "step": 0.25, "dims": dims}
        out[qid].setdefault("search", {"rounds": 0, "evaluations": 0})
    for _ in range(rounds):
        batch = []
        for qid, st in state.items():
            if out[qid]["verdict"] is not None:
                continue
            for i in st["dims"]:
                for sgn in (-1.0, 1.0):
                    u = st["u"].copy()
                    u[i] = min(max(u[i] + sgn * st["step"], 0.0), 1.0)
                    if u[i] != st["u"][i]:
                        batch.append((qid, u))
        if not batch:
            break
        outs = runner.run([(u, main) for _, u in batch])
        moved = set()
        for (qid, u), o in zip(batch, outs, strict=True):
            st, e = state[qid], out[qid]
            e["search"]["evaluations"] += 1
            s = o["cells"].get(qid)
            if s is None or s["diverged"] or e["verdict"] is not None:
                continue
            if s["in_band"]:
                e.update(verdict="reachable", reached_at=box.changed(u), how="search", algorithm=main)
                continue
            if s["dist"] < st["dist"]:
                st["u"], st["dist"] = u, s["dist"]
                moved.add(qid)
                e["closest"] = {"point": box.changed(u), "algorithm": main, "value": _json(s["value"]),
                                "distance": _json(s["dist"])}
        for qid, st in state.items():
            out[qid]["search"]["rounds"] += 1
            if qid not in moved:
                st["step"] /= 2
