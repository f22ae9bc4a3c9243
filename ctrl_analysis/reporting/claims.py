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


def claim_counts(results: dict) -> dict:
    """``{verdict: n}`` over the study's judged claims (holds, fails, depends, untestable).

    Parameters
    ----------
    results : dict
        One results.json dict.

    Returns
    -------
    dict
    """
    _check(results)
    counts = dict.fromkeys(CLAIM_MARK, 0)
    for c in results.get("claims") or []:
        counts[c["verdict"]] = counts.get(c["verdict"], 0) + 1
    return counts


def _depends_text(c: dict) -> str:
    parts = []
    for d in c.get("depends_on") or []:
        there = sorted(set(d.get("verdict_there") or []))
        parts.append(f"`{d['reconstruction']}` (chosen {_short(d['chosen'])}): {'/'.join(there) or 'flips'} at "
                     f"{', '.join(_short(v) for v in d['flips_at'])}")
    return "; ".join(parts)


def scorecard(results: dict, max_evidence: int = 3, links: dict | None = None) -> list[str]:
    """The study's claims: statement, section, verdict, and what the verdict rests on.

    A ``depends`` verdict names its base verdict (at the chosen reconstructions) and each reconstruction
    that flips it, with the values where it flips; otherwise the quantities that decide it (by label).

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
    labels = {q["id"]: q["label"] for q in results["quantities"]}
    lines = ["**The paper's claims** (verdict at the chosen reconstructions; *depends*: flips inside a plausible "
             "range):", "", "| claim | where | verdict | rests on |", "|---|---|---|---|"]
    for c in claims:
        verdict = CLAIM_MARK.get(c["verdict"], c["verdict"])
        if c["verdict"] == "depends":
            verdict += f" ({c['base_verdict']} as chosen)"
            rests = _depends_text(c)
        else:
            ev = [labels.get(e, e) for e in c.get("evidence") or []]
            rests = "; ".join(ev[:max_evidence]) + (f"; and {len(ev) - max_evidence} more" if len(ev) > max_evidence
                                                    else "")
            robust = c.get("robust_to") or []
            if robust and c["verdict"] in ("holds", "fails"):
                rests += f" — robust to {len(robust)} reconstruction{'s' if len(robust) != 1 else ''}"
        extra = (links or {}).get(f"{results['study']}/{c['id']}")
        if extra:
            rests = f"{rests} — {extra}" if rests else extra
        lines.append(f"| {_cell(c['statement'])} | {_cell(c['section'])} | {verdict} | {_cell(rests) or '—'} |")
    return lines + [""]


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
        lines += [f"| {_cell(q['label'])} | {_short(q['paper'])} | {_short(q['value'])} | {_cell(q.get('unit')) or '—'} "
                  f"| {q['verdict']} | {_cell(q.get('note'))} |" for q in checks]
        lines.append("")
    lines += [f"- **Erratum** — {_cell(f['text'])}" for f in errata]
    return lines + ([""] if errata else [])


def sensitivity_lines(results: dict) -> list[str]:
    """What the sensitivity sweep tried and which reconstructions flip a claim or a paper cell's verdict.

    Parameters
    ----------
    results : dict
        One results.json dict.

    Returns
    -------
    list of str
        Markdown lines (empty when the study ran no sweep).
    """
    _check(results)
    sens = results.get("sensitivity") or {}
    if not sens:
        return []
    ranges = sens.get("ranges") or {}
    claim_flips: dict = {}
    for c in results.get("claims") or []:
        for d in c.get("depends_on") or []:
            claim_flips.setdefault(d["reconstruction"], []).append(f"“{c['statement']}”")
    cell_flips: dict = {}
    for q in results["quantities"]:
        for name, s in ((q.get("sensitivity") or {}).get("by") or {}).items():
            if s.get("verdict_flips_at"):
                cell_flips.setdefault(name, []).append(q["label"])
    lines = ["### Sensitivity to the reconstructions", "",
             f"{sens.get('evaluations', 0)} evaluations, each reconstruction varied alone across its plausible "
             f"range ({len(ranges)} varied){'; ' + sens['note'] if sens.get('note') else ''}.", ""]
    for name in ranges:
        if name in claim_flips or name in cell_flips:
            what = []
            if name in claim_flips:
                what.append(f"flips the claim{'s' if len(claim_flips[name]) > 1 else ''} "
                            + "; ".join(claim_flips[name]))
            if name in cell_flips:
                n = len(cell_flips[name])
                what.append(f"flips the verdict of {n} paper cell{'s' if n > 1 else ''}"
                            + (f" ({'; '.join(cell_flips[name][:3])}{'; …' if n > 3 else ''})"))
            lines.append(f"- `{name}` ({plausible_text(ranges[name])}): {'; '.join(what)}")
    robust = [n for n in ranges if n not in claim_flips and n not in cell_flips]
    if robust:
        lines.append(f"- No claim or cell verdict flips across the ranges of: {', '.join(f'`{n}`' for n in robust)}")
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
    if "options" in p:
        return "one of " + ", ".join(_short(v) for v in p["options"])
    if p.get("fixed"):
        return "not varied"
    scale = "" if p.get("scale", "linear") == "linear" else f", {p['scale']}"
    return f"{_short(p['low'])} … {_short(p['high'])}{scale}"
