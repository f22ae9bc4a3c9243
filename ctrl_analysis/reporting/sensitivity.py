"""Sensitivity of a study's verdicts to its reconstructions: every plausible value tried, one at a time.

A study declares each value the paper does not print with
``reconstructed(value, why, plausible=span(low, high, why))`` (:mod:`ctrl_analysis.reporting.study`). Its
claims and primary cells are computed by an ``evaluate(params)`` function that builds a
:class:`~ctrl_analysis.reporting.results.StudyResult` with the same recording code as the study's main run.
:func:`sweep` calls it at the chosen values (the baseline) and once per plausible value of each
reconstruction, the others held at their chosen values; :func:`apply` then marks every claim whose
verdict flips inside a plausible range as ``depends`` (naming the reconstruction and the values where
it flips) and records, per primary cell, its spread and verdict flips; :func:`plot_sensitivity`
draws the most influential reconstructions.

Examples
--------
A toy study whose claim ("the gain is below 2") holds at the chosen ``k = 1`` but fails for
``k`` near the top of its plausible range:

>>> from dataclasses import dataclass
>>> from ctrl_analysis.reporting.report import StudyInfo, StudyResult
>>> from ctrl_analysis.reporting.study import Claim, reconstructed, span
>>> CLAIM = Claim("small", "§1", "the gain is below 2")
>>> @dataclass(frozen=True)
... class P:
...     k: float = reconstructed(1.0, "not printed", plausible=span(0.5, 3.0, "typical gains", points=3))
>>> def evaluate(params):
...     res = StudyResult(StudyInfo("toy", "", "", ""))
...     res.quantity("gain", "gain", params["p"].k, unit="")
...     res.claim(CLAIM, params["p"].k < 2, evidence=["gain"])
...     return res
>>> result = evaluate({"p": P()})
>>> apply(result, sweep(evaluate, {"p": P()}))
>>> c = result.get_claim("small")
>>> c.verdict, c.depends_on[0]["reconstruction"], c.depends_on[0]["flips_at"]
('depends', 'p.k', [3.0])
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from .._validate import check_callable, check_int
from .results import StudyResult
from .study import reconstructions_of

__all__ = ["Sensitivity", "apply", "plot_sensitivity", "sweep"]


@dataclasses.dataclass
class Sensitivity:
    """What :func:`sweep` tried and what each evaluation judged.

    Parameters
    ----------
    baseline : dict
        The outcome at the chosen values: ``{"claims": {id: True/False/None}, "cells": {id: (value, verdict)}}``.
    rows : list of dict
        One per tried value: ``{"reconstruction", "chosen", "value", "claims", "cells"}``.
    ranges : dict
        ``{reconstruction name: plausible range as results.json records it}``.
    note : str
        How the sweep was run (e.g. the number of Monte Carlo runs of each evaluation).
    """

    baseline: dict
    rows: list
    ranges: dict
    note: str = ""


def _outcome(result) -> dict:
    """``{"claims": {id: holds}, "cells": {id: (value, verdict)}}`` of a StudyResult or an outcome dict."""
    if isinstance(result, StudyResult):
        cells = {}
        for q in result.to_dict()["quantities"]:
            if q["paper"] is not None and q.get("kind", "reproduction") == "reproduction":
                cells[q["id"]] = (q["value"], q["verdict"])
        return {"claims": {c.claim.id: c.holds for c in result.claims}, "cells": cells}
    if isinstance(result, dict) and set(result) <= {"claims", "cells"}:
        return {"claims": dict(result.get("claims", {})), "cells": dict(result.get("cells", {}))}
    raise TypeError(f"evaluate must return a StudyResult or a dict with 'claims' and 'cells', got {type(result).__name__}")


def _same(a, b) -> bool:
    try:
        return bool(np.all(np.isclose(np.asarray(a, dtype=float), np.asarray(b, dtype=float), rtol=1e-9, atol=0)))
    except (TypeError, ValueError):
        return a == b


def _evaluate_task(task):
    evaluate, variant = task
    return _outcome(evaluate(variant))


def _variants(params: dict, names) -> list:
    """``[(name, chosen, value, variant params)]`` for every tried value of every varied reconstruction."""
    out, ranges = [], {}
    for prefix, obj in params.items():
        for rec in reconstructions_of(obj):
            name = f"{prefix}.{rec['name']}" if prefix else rec["name"]
            plaus = rec.get("plausible")
            if plaus is None or not plaus.varied or (names is not None and name not in names):
                continue
            ranges[name] = plaus.to_dict()
            for v in plaus.values():
                if _same(v, rec["value"]):
                    continue
                variant = dict(params)
                variant[prefix] = dataclasses.replace(obj, **{rec["name"]: v})
                out.append((name, rec["value"], v, variant))
    return out, ranges


def sweep(evaluate: Callable, params: dict, *, names=None, jobs: int = 1, scheduler=None,
          note: str = "") -> Sensitivity:
    """Evaluate the study at its chosen values and at each plausible value of each reconstruction, one at a time.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(params) -> StudyResult`` (or ``{"claims": ..., "cells": ...}``), with ``params`` shaped
        like the argument below. Module-level (picklable) to run over processes.
    params : dict
        ``{prefix: frozen parameter dataclass}``, the prefixes those of
        :func:`ctrl_analysis.reporting.study.record_parameters` (so names match results.json's reconstructions).
    names : collection of str, optional
        Only these reconstructions (``"prefix.field"``); default every varied one.
    jobs : int
        Processes (:func:`ctrl_analysis.parallel.map_chunks`).
    scheduler : str, optional
        A Dask scheduler address.
    note : str
        How the evaluations were run, recorded in results.json.

    Returns
    -------
    Sensitivity
    """
    from ..parallel import map_chunks, picklable

    check_callable("evaluate", evaluate, "evaluate(params)")
    if not isinstance(params, dict) or not params or not all(
            dataclasses.is_dataclass(p) and not isinstance(p, type) for p in params.values()):
        raise TypeError("params must be a non-empty dict {prefix: dataclass instance}")
    jobs = check_int("jobs", jobs, minimum=1)
    variants, ranges = _variants(params, None if names is None else set(names))
    if names is not None and set(names) - set(ranges):
        raise ValueError(f"names {sorted(set(names) - set(ranges))} are not varied reconstructions of params")
    tasks = [(evaluate, params)] + [(evaluate, v[3]) for v in variants]
    if (jobs > 1 or scheduler is not None) and picklable(evaluate):
        outcomes = map_chunks(_evaluate_task, tasks, jobs=jobs, scheduler=scheduler, desc="sensitivity")
    else:
        outcomes = [_evaluate_task(t) for t in tasks]
    rows = [{"reconstruction": name, "chosen": chosen, "value": value, **o}
            for (name, chosen, value, _), o in zip(variants, outcomes[1:])]
    return Sensitivity(outcomes[0], rows, ranges, note)


def _jsonable_value(v):
    if isinstance(v, (float, np.floating)):
        return float(f"{float(v):.6g}") if math.isfinite(float(v)) else None
    return v


def apply(result: StudyResult, sens: Sensitivity) -> None:
    """Write a sweep into ``result``: claims that flip become ``depends``; cells get their spread.

    A claim flips when its judgement at a tried value is the opposite definite verdict of the sweep's
    baseline (evaluated with the same settings, so Monte Carlo noise does not pass for a flip); a value
    where the claim cannot be judged (``None``, e.g. the method breaks down there) is recorded as
    ``untestable_at``, not as a flip. Where the baseline itself differs from the main run's judgement
    the claim's note says so.

    Parameters
    ----------
    result : StudyResult
        The study's main result, its claims already judged.
    sens : Sensitivity
        From :func:`sweep`.
    """
    if not isinstance(result, StudyResult) or not isinstance(sens, Sensitivity):
        raise TypeError("apply(result, sens) takes a StudyResult and a Sensitivity")
    by_name: dict = {}
    for row in sens.rows:
        by_name.setdefault(row["reconstruction"], []).append(row)
    for c in result.claims:
        base = sens.baseline["claims"].get(c.claim.id, c.holds)
        c.depends_on, c.robust_to = [], []
        if base != c.holds:
            c.note = (c.note + " " if c.note else "") + (
                f"The sensitivity sweep's baseline ({sens.note or 'its own settings'}) judges it "
                f"{'untestable' if base is None else ('holds' if base else 'fails')}.")
        for name, rows in by_name.items():
            if c.claim.id not in rows[0]["claims"]:
                continue
            # a flip is the opposite definite verdict; a value where the claim cannot be judged (None) is no flip
            flips = [r for r in rows if r["claims"].get(c.claim.id) is not None and r["claims"][c.claim.id] != base]
            blind = [_jsonable_value(r["value"]) for r in rows
                     if r["claims"].get(c.claim.id) is None and base is not None]
            if flips and base is not None:
                c.depends_on.append({
                    "reconstruction": name, "chosen": _jsonable_value(rows[0]["chosen"]),
                    "flips_at": [_jsonable_value(r["value"]) for r in flips],
                    "verdict_there": ["holds" if r["claims"][c.claim.id] else "fails" for r in flips],
                    "untestable_at": blind, "tried": [_jsonable_value(r["value"]) for r in rows]})
            else:
                c.robust_to.append(name)
                if blind:
                    c.note = (c.note + " " if c.note else "") + (
                        f"Untestable at {name} = {', '.join(str(v) for v in blind)} (no flip).")
    for q in result.quantities:
        if q.id not in sens.baseline["cells"]:
            continue
        base_value, base_verdict = sens.baseline["cells"][q.id]
        spread = {}
        for name, rows in by_name.items():
            vals = [r["cells"][q.id] for r in rows if q.id in r["cells"]]
            if not vals:
                continue
            numeric = [np.asarray(v, dtype=float).ravel()[0] for v, _ in vals
                       if v is not None and np.size(v) >= 1 and np.all(np.isfinite(np.asarray(v, dtype=float)))]
            spread[name] = {"min": _jsonable_value(min(numeric)) if numeric else None,
                            "max": _jsonable_value(max(numeric)) if numeric else None,
                            "verdict_flips_at": [_jsonable_value(r["value"]) for r, (_, vd) in zip(rows, vals)
                                                 if vd != base_verdict]}
        q.sensitivity = {"baseline": {"value": base_value, "verdict": base_verdict}, "by": spread}
    result.sensitivity = {"note": sens.note, "evaluations": 1 + len(sens.rows), "ranges": sens.ranges,
                          "baseline_claims": sens.baseline["claims"]}


def _short_value(v) -> str:
    """A tried value in a grid cell: numbers to 3 digits, vectors as (a, b, …)."""
    if isinstance(v, (list, tuple)):
        return "(" + ", ".join(_short_value(x) for x in v) + ")"
    return f"{v:.3g}" if isinstance(v, float) else str(v)[:10]


def _influence(result: StudyResult) -> list:
    """``[(name, largest relative cell change, claim flips, cell verdict flips)]``, most influential first."""
    names = list(result.sensitivity.get("ranges", {}))
    rows = []
    for name in names:
        change, cell_flips = 0.0, 0
        for q in result.quantities:
            s = (q.sensitivity or {}).get("by", {}).get(name)
            if not s:
                continue
            base = q.sensitivity["baseline"]["value"]
            b = np.asarray(base, dtype=float).ravel()[0] if base is not None and np.size(base) >= 1 else math.nan
            for ext in (s["min"], s["max"]):
                if ext is not None and math.isfinite(b) and b != 0:
                    change = max(change, abs(ext - b) / abs(b))
            cell_flips += bool(s["verdict_flips_at"])
        claim_flips = sum(any(d["reconstruction"] == name for d in c.depends_on) for c in result.claims)
        rows.append((name, change, claim_flips, cell_flips))
    rows.sort(key=lambda r: (r[2], r[3], r[1]), reverse=True)
    return rows


def plot_sensitivity(result: StudyResult, top: int = 12):
    """The most influential reconstructions: cell spread and claim flips across each plausible range.

    Left: the largest relative change of any paper cell across the range (bars), with the number of
    cells whose verdict flips. Right: claims × reconstructions, marked where the claim's verdict flips.

    Parameters
    ----------
    result : StudyResult
        After :func:`apply`.
    top : int
        Reconstructions shown.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .report import new_figure

    top = check_int("top", top, minimum=1)
    if not isinstance(result, StudyResult):
        raise TypeError(f"result must be a StudyResult, got {type(result).__name__}")
    if not result.sensitivity:
        raise ValueError("result has no sensitivity sweep: call apply(result, sweep(...)) first")
    rows = _influence(result)[:top]
    claims = [c for c in result.claims if c.holds is not None]
    n = max(len(rows), 1)
    width = max(12.0, 6.0 + 1.0 * len(claims))
    fig, (ax, bx) = new_figure(1, 2, size=(width, 2.6 + 0.5 * n), gridspec_kw={"width_ratios": [1.0, max(1.0, len(claims) / 5)]},
                               title=f"{result.info.name}: sensitivity of the verdicts to each reconstruction "
                                     "(one at a time, across its plausible range)")
    labels = [r[0] for r in rows]
    y = np.arange(len(rows))[::-1]
    change = [100 * r[1] for r in rows]
    ax.barh(y, change, color=["tab:red" if r[3] else "tab:blue" for r in rows], alpha=0.8)
    for yi, r, ch in zip(y, rows, change):
        if r[3]:  # inside the bar's end when the bar is long, else after it
            inside = ch > 0.6 * max(change)
            ax.text(ch, yi, f"{r[3]} cell verdict(s) flip " if inside else f"  {r[3]} cell verdict(s) flip",
                    va="center", ha="right" if inside else "left", fontsize=8, color="white" if inside else "black")
        elif ch == 0:
            ax.text(0, yi, "  no paper cell moves", va="center", fontsize=7, color="0.4")
    ax.set_yticks(y, labels, fontsize=8)
    ax.set_xlabel("largest change of a paper cell across the range\n(% of its value at the chosen reconstruction)")
    ax.set_title("Paper cells (red: some cell's verdict flips)", fontsize=10)
    if claims:
        grid = np.zeros((len(rows), len(claims)))
        for i, r in enumerate(rows):
            for j, c in enumerate(claims):
                tried = r[0] in c.robust_to or any(d["reconstruction"] == r[0] for d in c.depends_on)
                grid[i, j] = 2 if any(d["reconstruction"] == r[0] for d in c.depends_on) else (1 if tried else 0)
        from matplotlib.colors import ListedColormap

        bx.imshow(grid, cmap=ListedColormap(["#eeeeee", "#9fd49f", "#e8743b"]), vmin=0, vmax=2, aspect="auto")
        for i, r in enumerate(rows):
            for j, c in enumerate(claims):
                dep = next((d for d in c.depends_on if d["reconstruction"] == r[0]), None)
                if dep is not None:
                    there = "/".join(sorted(set(dep["verdict_there"])))
                    at = ", ".join(_short_value(v) for v in dep["flips_at"][:2])
                    bx.text(j, i, f"{there}\nat {at}{'…' if len(dep['flips_at']) > 2 else ''}", ha="center",
                            va="center", fontsize=6.5)
        bx.set_yticks(np.arange(len(rows)), labels, fontsize=8)
        bx.set_xticks(np.arange(len(claims)), [c.claim.id for c in claims], rotation=40, ha="right", fontsize=8)
        bx.set_title("Claims: green robust, orange verdict flips, grey not affected", fontsize=10)
        bx.grid(False)
    else:
        bx.text(0.5, 0.5, "no testable claim", ha="center", va="center", transform=bx.transAxes)
        bx.set_axis_off()
    return fig
