"""REPORT.md parts about what a verdict rests on: the claim scorecard, checks and errata, sensitivity.

Each function takes one study's results.json dict and returns Markdown lines; :mod:`.report_md`
places them in the study's section (the scorecard first, before any table).
"""

from __future__ import annotations

from .formatting import cell as _cell
from .formatting import check_results
from .formatting import fmt as _short

__all__ = ["CLAIM_MARK", "checks_and_errata", "claim_counts", "plausible_text", "scorecard", "sensitivity_lines"]

#: How a claim verdict is shown in the scorecard.
CLAIM_MARK = {"holds": "holds", "fails": "**fails**", "depends": "**depends**", "untestable": "untestable"}


def _check(results) -> None:
    check_results("results", results)


def _paper_claims(results: dict) -> list:
    return [c for c in results.get("claims") or [] if not c.get("beyond")]


def claim_counts(results: dict) -> dict:
    """``{verdict: n}`` over the study's judged claims of the paper (not the project's own tests beyond it).

    Parameters
    ----------
    results : dict
        One results.json dict.

    Returns
    -------
    dict
        ``holds``, ``fails``, ``depends``, ``untestable``, and ``beyond`` (the project's own tests) and
        ``one_algorithm`` (paper claims whose verdict differs between the printed and the corrected algorithm).
    """
    _check(results)
    counts = dict.fromkeys(CLAIM_MARK, 0)
    for c in _paper_claims(results):
        counts[c["verdict"]] = counts.get(c["verdict"], 0) + 1
    counts["beyond"] = sum(bool(c.get("beyond")) for c in results.get("claims") or [])
    counts["one_algorithm"] = sum(_algorithm_text(c) != "" for c in _paper_claims(results))
    return counts


def _pct(x) -> str:
    return "—" if x is None else f"{100 * x:.0f} %"


def _support_text(c: dict) -> str:
    s = c.get("support")
    if not s:
        return "not explored"
    if s.get("holds") is None:
        return f"untestable at all {s.get('untestable', 0)} points"
    text = f"{_pct(s['holds'])} ± {100 * (s.get('stderr') or 0):.0f} % of {s['samples']} points"
    if s.get("untestable"):
        text += f" ({s['untestable']} untestable)"
    return text


def _algorithm_text(c: dict) -> str:
    """'holds only with the corrected algorithm (printed: fails, 0 %)' where the two algorithms disagree."""
    by = c.get("by_algorithm") or {}
    if len(by) != 2:
        return ""
    verdicts = {a: v["verdict"] for a, v in by.items()}
    if len(set(verdicts.values())) == 1:
        return ""
    for a, v in verdicts.items():
        other = "printed" if a == "corrected" else "corrected"
        if v == "holds" and verdicts[other] != "holds":
            return (f"holds only with the {a} algorithm ({other}: {verdicts[other]}, "
                    f"{_pct(by[other]['support']['holds'])})")
    parts = [f"{a}: {v} ({_pct(by[a]['support']['holds'])})" for a, v in verdicts.items()]
    return "differs between the algorithms — " + ", ".join(parts)


def _clip(label: str, limit: int = 90) -> str:
    """A quantity's label cut to ``limit`` characters at a word (the scorecard's cells stay readable)."""
    return label if len(label) <= limit else label[:limit].rsplit(" ", 1)[0].rstrip(",;:") + " …"


def _rests_on(c: dict, labels: dict, max_evidence: int) -> str:
    parts = []
    drivers = [d for d in c.get("drivers") or [] if d.get("significant", d["S1"] >= 0.05)]
    if drivers:
        parts.append("driven by " + ", ".join(f"`{d['reconstruction']}` (S1 {d['S1']:.2f})" for d in drivers[:3]))
    elif c.get("drivers"):
        parts.append("no reconstruction drives it alone (no first-order index above its noise: interactions)")
    flip = c.get("nearest_flip")
    if flip:
        moved = list(flip["point"].items())
        where = ", ".join(f"`{k}` = {_short(v)}" for k, v in moved[:3]) or "the chosen values"
        if len(moved) > 3:
            where += f" and {len(moved) - 3} more"
        parts.append(f"nearest flip ({flip['verdict_there']}) at {where}")
    elif c.get("support") and c["support"].get("holds") is not None and c["verdict"] in ("holds", "fails"):
        parts.append("no flip anywhere in the box" if c["support"]["holds"] in (0, 1) else "")
    ev = [_clip(labels.get(e, e)) for e in c.get("evidence") or []]
    if ev:
        parts.append("on " + "; ".join(ev[:max_evidence]) + (f"; and {len(ev) - max_evidence} more"
                                                              if len(ev) > max_evidence else ""))
    return " — ".join(p for p in parts if p)


def _claim_rows(results: dict, claims: list, max_evidence: int, links: dict | None) -> list[str]:
    labels = {q["id"]: q["label"] for q in results["quantities"]}
    rows = ["| claim | where | verdict | support over the box | what it rests on |", "|---|---|---|---|---|"]
    for c in claims:
        verdict = CLAIM_MARK.get(c["verdict"], c["verdict"])
        if c["verdict"] != c["base_verdict"]:
            verdict += f" ({c['base_verdict']} at the chosen values)"
        alg = _algorithm_text(c)
        if alg:
            verdict += f"; {alg}"
        rests = _rests_on(c, labels, max_evidence)
        if c["verdict"] == "untestable" and c.get("note"):
            rests = c["note"] + (f" — {rests}" if rests else "")
        extra = (links or {}).get(f"{results['study']}/{c['id']}")
        if extra:
            rests = f"{rests} — {extra}" if rests else extra
        rows.append(f"| {_cell(c['statement'])} | {_cell(c['section'])} | {verdict} | {_support_text(c)} "
                    f"| {_cell(rests) or '—'} |")
    return rows


def scorecard(results: dict, max_evidence: int = 2, links: dict | None = None) -> list[str]:
    """The paper's claims judged over the plausible box, then the project's own tests beyond the paper.

    Each row: statement, section, verdict (with the verdict at the chosen values where it differs, and the
    algorithm under which it holds where the printed and the corrected algorithm disagree), the support
    over the box, and what it rests on (the driving reconstructions, the nearest flip, the quantities).

    Parameters
    ----------
    results : dict
        One results.json dict.
    max_evidence : int
        Quantities named per claim.
    links : dict, optional
        ``{"<study>/<claim id>": Markdown}`` added to that claim's row (another section's finding about
        it, e.g. the estimator arena's verdict at each family's best tuning).

    Returns
    -------
    list of str
        Markdown lines (empty without claims).
    """
    _check(results)
    claims = results.get("claims") or []
    if not claims:
        return []
    paper = [c for c in claims if not c.get("beyond")]
    beyond = [c for c in claims if c.get("beyond")]
    lines = []
    if paper:
        lines += ["**The paper's claims**, each judged over the plausible box (support: the share of the box where "
                  "it holds; the policy's thresholds decide the verdict):", ""]
        lines += _claim_rows(results, paper, max_evidence, links) + [""]
    if beyond:
        lines += ["**Beyond the paper** — the project's own tests, not claims of the paper (not counted above):", ""]
        lines += _claim_rows(results, beyond, max_evidence, links) + [""]
    return lines


def checks_and_errata(results: dict) -> list[str]:
    """Checks (algebraic identities, the paper's own arithmetic) and errata, apart from the reproduced cells.

    Parameters
    ----------
    results : dict
        One results.json dict.

    Returns
    -------
    list of str
        Markdown lines (empty when there is none).
    """
    _check(results)
    checks = [q for q in results["quantities"] if q.get("kind") == "check"]
    errata = [f for f in results.get("findings") or [] if f.get("kind") == "erratum"]
    if not checks and not errata:
        return []
    lines = ["### Checks and errata", "",
             "Algebraic identities and the paper's own arithmetic, not counted as reproduced cells:", ""]
    if checks:
        lines += ["| check | paper | computed | unit | verdict | note |", "|---|---|---|---|---|---|"]
        lines += [f"| {_cell(q['label'])} | {_short(q['paper'])} | {_short(q['value'])} "
                  f"| {_cell(q.get('unit')) or '—'} | {q['verdict']} | {_cell(q.get('note'))} |" for q in checks]
        lines.append("")
    lines += [f"- **Erratum** — {_cell(f['text'])}" for f in errata]
    return lines + ([""] if errata else [])


def sensitivity_lines(results: dict) -> list[str]:
    """How the plausible box was explored, what drives the verdicts, and where the printed cells are reached.

    Parameters
    ----------
    results : dict
        One results.json dict.

    Returns
    -------
    list of str
        Markdown lines (empty when the study explored no box).
    """
    _check(results)
    sens = results.get("sensitivity") or {}
    if not sens:
        return []
    ranges = sens.get("ranges") or {}
    alg = sens.get("algorithm")
    lines = ["### The plausible box", "",
             f"{sens.get('samples', 0)} points of a Latin hypercube sample of the box spanned by "
             f"{len(ranges)} reconstructions, all varied jointly"
             + (f", under the paper's printed and the corrected algorithm (`{'`, `'.join(alg['fields'])}`)"
                if alg else "")
             + f"; {sens.get('evaluations', 0)} evaluations in all with the bisections and the cell search"
             + (f"; each evaluation: {sens['note']}" if sens.get("note") else "") + ".", ""]
    drives: dict = {}
    for c in results.get("claims") or []:
        for d in c.get("drivers") or []:
            if d["S1"] >= 0.1 and d.get("significant", True):
                drives.setdefault(d["reconstruction"], []).append(f"“{c['id']}” ({d['S1']:.2f})")
    for name in ranges:
        if name in drives:
            lines.append(f"- `{name}` ({plausible_text(ranges[name])}) drives " + "; ".join(drives[name]))
    quiet = [n for n in ranges if n not in drives]
    if quiet:
        lines.append(f"- No claim's verdict has a first-order Sobol' index of 0.1 or more on: "
                     f"{', '.join(f'`{n}`' for n in quiet)}")
    # a derived cell (SNR from RMSE) takes its source's verdict and has no box of its own: its source is listed
    reached = [q for q in results["quantities"] if q.get("verdict") == "reachable" and q.get("box")]
    if reached:
        lines += ["", "Printed cells outside their band at the chosen values but reached inside the box:", ""]
        for q in reached:
            b = q["box"]
            where = ", ".join(f"`{k}` = {_short(v)}" for k,
                              v in (b.get("reached_at") or {}).items()) or "the chosen values"
            how = {"sample": "a sample", "neighbour": "switching one alternative of the chosen values",
                   "bisection": "bisection between samples on either side",
                   "search": "the local search"}.get(b.get("how"), b.get("how"))
            lines.append(f"- {_cell(q['label'])}: at {where}" + (f" ({b['algorithm']} algorithm)" if b.get("algorithm")
                                                                 else "") + f", found by {how}")
    far = [q for q in results["quantities"] if q.get("verdict") == "differs" and q.get("box")]
    if far:
        lines += ["", "Printed cells no plausible point reaches (closest point found):", ""]
        for q in far:
            b = q["box"]
            close = b.get("closest") or {}
            drivers = [d["reconstruction"] for d in b.get("drivers") or []]
            point = close.get("point") or {}
            shown = [k for k in drivers if k in point] or list(point)[:4]
            where = ", ".join(f"`{k}` = {_short(point[k])}" for k in shown) or "the chosen values"
            if len(point) > len(shown):
                where += f" (and {len(point) - len(shown)} more reconstructions that barely move it)"
            rng = b.get("range")
            lines.append(f"- {_cell(q['label'])}: paper {_short(q['paper'])}"
                         + (f", box range {_short(rng[0])} … {_short(rng[1])}" if rng else "")
                         + (f"; closest {_short(close.get('value'))} at {where}" if close else ""))
    return lines + [""]


def plausible_text(p: dict | None) -> str:
    """A plausible range as a short phrase: ``0.5 … 3 (log)``, ``one of a, b``, or ``not varied``.

    Parameters
    ----------
    p : dict or None
        A reconstruction's ``plausible`` as results.json records it.

    Returns
    -------
    str
    """
    if p is not None and not isinstance(p, dict):
        raise TypeError(f"p must be a plausible-range dict or None, got {type(p).__name__}")
    if not p:
        return "no plausible range stated"
    if p.get("axis") == "algorithm":
        return f"algorithm axis: printed {_short(p['printed'])}, corrected {_short(p['corrected'])}"
    if "options" in p:
        return "one of " + ", ".join(_short(v) for v in p["options"])
    if p.get("fixed"):
        return "not varied"
    if "low" not in p or "high" not in p:
        raise ValueError(f"p must hold options, fixed, or low and high, got keys {sorted(p)}")
    scale = "" if p.get("scale", "linear") == "linear" else f", {p['scale']}"
    return f"{_short(p['low'])} … {_short(p['high'])}{scale}"
