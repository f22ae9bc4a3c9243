"""REPORT.md: the reproduction report of several studies, written from their results.json dicts.

The report reads on its own for someone holding only the papers: the verdict policy and an overview
of the claim and cell counts, then per study the scorecard of the paper's claims (what each verdict
rests on), a summary generated from its verdicts and findings, one side-by-side table per paper table
(printed beside reproduced), checks and errata, the sensitivity to the reconstructions,
reconstructions with their plausible ranges, findings with their evidence summarised and captioned
figures; an appendix lists every quantity of every study, and a glossary the terms used.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .._validate import check_path
from .claims import (
    checks_and_errata,
    claim_counts,
    plausible_text,
    scorecard,
    sensitivity_lines,
)
from .formatting import MAX_LIST, summarise  # noqa: F401 (public API)
from .formatting import cell as _cell
from .formatting import check_results as _check_results
from .formatting import fmt as _fmt
from .formatting import shorten_lists as _shorten_lists
from .glossary import GLOSSARY, glossary_lines  # noqa: F401 (GLOSSARY: public API)
from .report import relative_error, write_text_atomic
from .verdicts import VERDICT_POLICY

__all__ = ["GLOSSARY", "MAX_LIST", "not_reproduced", "overview_table", "summary_table", "tally", "write_report_md"]

#: Longest evidence text before it is cut (the full evidence stays in results.json).
MAX_EVIDENCE = 700
#: Marks of the verdicts in the side-by-side tables.
MARK = {"agrees": "✓", "reachable": "≈", "differs": "✗", "diverged": "diverged", "new": ""}

def _digits(q: dict) -> int:
    """Significant digits that show a difference the tolerance can resolve (4, or 6 for tight tolerances)."""
    tol = q.get("tolerance")
    return 6 if tol is not None and tol < 1e-3 else 4


def _fmt_tolerance(q: dict) -> str:
    tol = q.get("tolerance")
    return "—" if tol is None else f"{100 * tol:.3g} %"


def _rule(q: dict) -> str:
    """The verdict rule of a quantity: its tolerance, the central 95 % (with the percentile) or derived."""
    if q.get("paper") is None:
        return "—"
    if q.get("policy") == "percentile":
        return f"central 95 % (p = {q['percentile']:.3g} %)" if q.get("percentile") is not None else "central 95 %"
    if q.get("policy") == "derived":
        return f"as `{q.get('derived_from')}`"
    return _fmt_tolerance(q)


def _runs(q: dict) -> str:
    if not q.get("runs"):
        return ""
    n = q["runs"]
    div = q.get("runs_diverged") or 0
    return f" ({n} run{'s' if n != 1 else ''}" + (f", {div} diverged" if div else "") + ")"


def summary_table(results: dict) -> str:
    """A Markdown table of the quantities of one results.json dict (unit "—" = dimensionless).

    Parameters
    ----------
    results : dict
        A study's results.json, as loaded.

    Returns
    -------
    str
        The table: id, label, paper cell, paper, reproduced (± std, runs, diverged runs), unit,
        tolerance, verdict and note; long numeric arrays summarised as min / median / max.
    """
    if not isinstance(results, dict) or not isinstance(results.get("quantities"), list):
        raise TypeError(f"results must be a results.json dict with a 'quantities' list, got {results!r:.80}")
    rows = ["| id | quantity | paper cell | paper | reproduced | unit | verdict rule | verdict | note |",
            "|---|---|---|---|---|---|---|---|---|"]
    for q in results["quantities"]:
        note = _cell(_shorten_lists(q.get("note") or ""))
        std = q.get("std") if (q.get("runs") or 2) > 1 else None
        cell = _cell(q.get("cell"))
        if cell and q.get("primary"):
            cell += " (primary)"
        rows.append(
            f"| `{q['id']}` | {_cell(q['label'])} | {cell} | {_fmt(q['paper'])} | {_fmt(q['value'], std)}{_runs(q)} "
            f"| {_cell(q.get('unit')) or '—'} | {_rule(q)} "
            f"| {q['verdict']}{' (check)' if q.get('kind') == 'check' else ''} "
            f"| {note} |"
        )
    return "\n".join(rows)


def _scored(results: dict, uncelled: bool = False) -> dict:
    """``{cell: quantity}``: the quantity that scores each paper cell (primary, else the first).

    With ``uncelled``, a quantity with a paper value but no cell is its own cell (named by its label),
    as :func:`~ctrl_analysis.reporting.report.count_verdicts` counts it.
    """
    by_cell: dict = {}
    for q in results["quantities"]:
        if q.get("kind") == "check":
            continue
        cell = q.get("cell")
        if cell is None and uncelled and q["paper"] is not None:
            cell = q["label"]
        if cell is not None and (cell not in by_cell or (q.get("primary") and not by_cell[cell].get("primary"))):
            by_cell[cell] = q
    return by_cell


def _signed_error(value, paper) -> float:
    """(value − paper) / |paper| for scalars (sign shows the direction); the largest |relative error| for vectors."""
    if np.ndim(value) == 0 and np.ndim(paper) == 0 and value is not None and paper not in (None, 0):
        return (float(value) - float(paper)) / abs(float(paper))
    return relative_error(value, paper)


def tally(results: dict) -> dict:
    """What the overview counts for one results.json dict.

    Printed paper cells (each scored once by its primary quantity; a quantity with a paper value and
    no cell is its own cell) by verdict, cells whose printed value was lost (``paper`` None), and
    new quantities (no cell, no paper value) with how many of them diverged.

    Parameters
    ----------
    results : dict

    Returns
    -------
    dict
        ``agrees``, ``reachable``, ``differs``, ``diverged``, ``printed``, ``lost``, ``new``, ``new_diverged``,
        ``checks``, ``errata`` and ``findings`` (findings without the errata; checks and errata are never counted
        as cells, new quantities or findings).

    Raises
    ------
    TypeError
        If ``results`` is not a results.json dict with a ``quantities`` list.
    """
    _check_results("results", results)
    scored = _scored(results, uncelled=True)
    printed = [q for q in scored.values() if q["paper"] is not None]
    new = [q for q in results["quantities"] if q.get("cell") is None and q["paper"] is None
           and q.get("kind") != "check"]
    out = {v: sum(q["verdict"] == v for q in printed) for v in ("agrees", "reachable", "differs", "diverged")}
    out.update(printed=len(printed), lost=len(scored) - len(printed), new=len(new),
               new_diverged=sum(q["verdict"] == "diverged" for q in new),
               checks=sum(q.get("kind") == "check" for q in results["quantities"]),
               errata=sum(f.get("kind") == "erratum" for f in results.get("findings") or []),
               findings=sum(f.get("kind") != "erratum" for f in results.get("findings") or []))
    return out


def _reproduced(q: dict) -> str:
    if q["verdict"] == "diverged":
        return "diverged" + _runs(q)
    std = q.get("std") if (q.get("runs") or 2) > 1 else None
    text = _fmt(q["value"], std, digits=_digits(q))
    mark = MARK[q["verdict"]]
    if q["paper"] is not None and q["value"] is not None:
        err = _signed_error(q["value"], q["paper"])
        if q.get("policy") == "percentile" and q.get("percentile") is not None:
            text += f" (p = {q['percentile']:.3g} %)"
        elif np.isfinite(err) and err != 0:
            text += f" ({100 * err:+.0f} %)" if abs(err) >= 0.01 else f" ({100 * err:+.2g} %)"
    if q.get("runs_diverged") and q["verdict"] != "diverged":
        text += f" [{q['runs_diverged']} of {q['runs']} runs diverged]"
    return f"{text} {mark}".strip()


def paper_tables(results: dict) -> list[str]:
    """Side-by-side Markdown tables, one per paper table, printed beside reproduced.

    Cells named ``"<table> / <row …> / <column>"`` are laid out in rows and columns in the order
    recorded; cells with one level below the table name (``"<place> / <value>"``) and cells without
    ``" / "`` go to a table of values printed in the text. Each entry shows the cell's primary
    quantity: the printed value, the reproduced value (± std), its relative error and a mark.

    Parameters
    ----------
    results : dict
        One results.json dict.

    Returns
    -------
    list of str
        Markdown lines (empty when the study names no paper cell).
    """
    grids: dict = {}
    text_cells = []
    for cell, q in _scored(results).items():
        parts = [p.strip() for p in cell.split(" / ")]
        if len(parts) >= 3:
            g = grids.setdefault(parts[0], {"rows": {}, "cols": {}})
            row, col = " / ".join(parts[1:-1]), parts[-1]
            g["rows"].setdefault(row, {})[col] = q
            g["cols"].setdefault(col, None)
        else:
            text_cells.append((cell, q))
    lines = []
    for name, g in grids.items():
        cols = list(g["cols"])
        lines += [f"**{name}** (paper | reproduced; ✓ agrees, ≈ reachable inside the plausible box, ✗ differs "
                  "under the verdict policy; p = the paper value's percentile among the Monte Carlo runs, else the "
                  "relative error):", "",
                  "| | " + " | ".join(f"{_cell(c)} (paper) | {_cell(c)} (here)" for c in cols) + " |",
                  "|---|" + "---|---|" * len(cols)]
        for row, entries in g["rows"].items():
            cells = []
            for c in cols:
                q = entries.get(c)
                cells += ["", ""] if q is None else [_fmt(q["paper"], digits=_digits(q)), _cell(_reproduced(q))]
            lines.append(f"| {_cell(row)} | " + " | ".join(cells) + " |")
        units = {q.get("unit") or "—" for e in g["rows"].values() for q in e.values()}
        tols = {_fmt_tolerance(q) for e in g["rows"].values() for q in e.values()}
        pol = {q.get("policy") for e in g["rows"].values() for q in e.values()}
        rule = ("central 95 % of the runs" if pol == {"percentile"} else
                f"tolerance {', '.join(sorted(tols))}" + (" or the central 95 % of the runs" if "percentile" in pol
                                                          else ""))
        lines += ["", (f"Units: {', '.join(sorted(units))} (per column in the appendix); verdict rule: {rule}"
                       f"{'; SNR cells take the verdict of their RMSE' if 'derived' in pol else ''}. "
                       "Printed values lost in the extracted paper text show as —."), ""]
    if text_cells:
        lines += ["**Values printed in the text:**", "", "| paper cell | paper | reproduced | unit | tolerance |",
                  "|---|---|---|---|---|"]
        lines += [f"| {_cell(c)} | {_fmt(q['paper'], digits=_digits(q))} | {_cell(_reproduced(q))} | "
                  f"{_cell(q.get('unit')) or '—'} | {_fmt_tolerance(q)} |" for c, q in text_cells]
        lines.append("")
    return lines


#: Abbreviations a sentence does not end on ("Eq. (9)", "Fig. 3", "e.g. x").
_ABBREVIATIONS = {"eq", "eqs", "fig", "figs", "ref", "refs", "sec", "no", "vs", "e.g", "i.e", "cf", "approx"}


def _first_sentence(text: str) -> str:
    text = _shorten_lists(" ".join(str(text).split()))
    first = text
    for m in re.finditer(r"(?<=[.!?])\s+(?=[A-Z(\[*])", text):
        word = re.search(r"([\w.]*)[.!?]$", text[:m.start()])
        if word and word.group(1) and (word.group(1).lower() in _ABBREVIATIONS
                                      or (len(word.group(1)) == 1 and word.group(1).isalpha())):
            continue
        first = text[:m.start()]
        break
    return first


def study_summary(results: dict, n_findings: int = 3) -> list[str]:
    """Three lines generated from the verdicts and findings: what agrees, what does not, the main findings.

    Parameters
    ----------
    results : dict
        One results.json dict.
    n_findings : int
        How many findings the third line quotes (the first ones recorded; all are listed below it).

    Returns
    -------
    list of str
        Three Markdown list items.
    """
    scored = _scored(results, uncelled=True)
    by_table: dict = {}
    for cell, q in scored.items():
        by_table.setdefault(cell.split(" / ")[0], []).append(q)
    agree = [f"{t}: {sum(q['verdict'] == 'agrees' for q in qs)} of {sum(q['paper'] is not None for q in qs)}"
             for t, qs in by_table.items() if any(q["paper"] is not None for q in qs)]
    t = tally(results)
    lost, n_printed, n_agree = t["lost"], t["printed"], t["agrees"]
    line1 = (f"**Agrees:** {n_agree} of {n_printed} printed paper cells under the verdict policy"
             + (f" ({'; '.join(agree)})" if agree else "")
             + (f"; {t['reachable']} more are reachable inside the plausible box" if t["reachable"] else "")
             + (f"; {lost} cells whose printed values were lost in extraction are reproduced without verdict"
                if lost else "") + ".")
    bad = [(c, q) for c, q in scored.items() if q["verdict"] in ("differs", "diverged")]
    parts = []
    for c, q in bad[:6]:
        if q["verdict"] == "diverged":
            parts.append(f"{c} (all runs diverged)")
        else:
            err = _signed_error(q["value"], q["paper"]) if q["value"] is not None else np.inf
            pct = ("" if not np.isfinite(err) else
                   f", {100 * err:+.0f} %" if abs(err) >= 0.01 else f", {100 * err:+.2g} %")
            parts.append(f"{c} ({_fmt(q['value'], digits=_digits(q))} vs {_fmt(q['paper'], digits=_digits(q))}{pct})")
    if len(bad) > 6:
        parts.append(f"and {len(bad) - 6} more")
    line2 = ("**Differs (no plausible point reaches it):** " + ("; ".join(parts) if parts else "no printed cell")
             + ".")
    findings = results.get("findings") or []
    findings = [f for f in findings if f.get("kind") != "erratum"]
    quoted = " ".join(_first_sentence(f["text"]).rstrip(".") + "." for f in findings[:n_findings])
    line3 = (f"**Findings ({len(findings)}):** " + (quoted if quoted else "none")
             + (" …" if len(findings) > n_findings else ""))
    return [f"- {line1}", f"- {line2}", f"- {line3}"]


def overview_table(results: list[dict], this_run: dict) -> list[str]:
    """The opening table: per study the claim and cell verdict counts, checks, new quantities, findings, figures.

    No runtimes: the table is also the README's, and a rerun would make them stale.

    Parameters
    ----------
    results : list of dict
        One results.json dict per study, in the order shown.
    this_run : dict
        ``{study: {...}}`` for the studies written by this run (the others are marked stale).

    Returns
    -------
    list of str
        Markdown lines, counted with :func:`tally`.

    Raises
    ------
    TypeError
        If ``results`` is not a list of results.json dicts or ``this_run`` is not a dict.
    """
    if not isinstance(results, (list, tuple)):
        raise TypeError(f"results must be a list of results.json dicts, got {type(results).__name__}")
    for r in results:
        _check_results("results", r)
    if not isinstance(this_run, dict):
        raise TypeError(f"this_run must be a dict of study -> run settings, got {type(this_run).__name__}")
    rows = [("| study | paper | from this run | claims hold | claims fail | claims depend | claims untestable "
             "| beyond the paper | cells agree | cells reachable | cells differ | cells diverged "
             "| cells lost in extraction | checks, errata | new quantities | findings | figures |"),
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        c = tally(r)
        k = claim_counts(r)
        run = this_run.get(r["study"])
        fresh = "no (stale)" if run is None else ("yes (quick)" if run.get("quick") else "yes")
        new = f"{c['new']}" + (f" ({c['new_diverged']} diverged)" if c["new_diverged"] else "")
        rows.append(f"| [{r['study']}](#{_anchor(r['study'])}) | {_cell(r['paper'])} | {fresh} | {k['holds']} "
                    f"| {k['fails']} | {k['depends']} | {k['untestable']} | {k['beyond']} | {c['agrees']} "
                    f"| {c['reachable']} | {c['differs']} | {c['diverged']} | {c['lost']} "
                    f"| {c['checks']}, {c['errata']} | {new} | {c['findings']} | {len(r.get('figures') or [])} |")
    return rows


def _anchor(name: str) -> str:
    return re.sub(r"[^a-z0-9 -]", "", name.lower()).replace(" ", "-")


def _run_table(results: list[dict], this_run: dict, failed: dict) -> list[str]:
    """Which studies come from this run (with base seed, runs and per-run seeds) and which are stale.

    A stale study's base seed, runs and quick flag are those its own results.json records (the command
    line of the run that wrote it, ``settings.cli``); "—" only where the file does not record them.
    """
    rows = ["| study | from this run | base seed | runs | per-run seeds |", "|---|---|---|---|---|"]
    present = {r["study"] for r in results}
    rows += [f"| {name} | **no — failed**, and no earlier results | — | — | — |" for name in failed
             if name not in present]
    for r in results:
        name = r["study"]
        run = this_run.get(name)
        seeds = ", ".join(f"{k}: {_seed_summary(v)}" for k, v in (r.get("seeds") or {}).items()) or "—"
        if run is None:
            cli = (r.get("settings") or {}).get("cli")
            cli = cli if isinstance(cli, dict) else {}
            quick = ", quick" if cli.get("quick") else ""
            seed = _cell(str(cli["seed"])) if cli.get("seed") is not None else "—"
            runs = "—" if "runs" not in cli else ("default" if cli["runs"] is None else _cell(str(cli["runs"])))
            rows.append(f"| {name} | **no — stale** (results of an earlier run{quick}) | {seed} | {runs} | "
                        f"{_cell(seeds)} |")
        else:
            runs = "default" if run.get("runs") is None else run["runs"]
            quick = " (quick)" if run.get("quick") else ""
            rows.append(f"| {name} | yes{quick} | {run.get('seed')} | {runs} | {_cell(seeds)} |")
    return rows


def _seed_summary(seeds) -> str:
    seeds = list(np.ravel(np.asarray(seeds, dtype=object))) if isinstance(seeds, (list, tuple)) else [seeds]
    if len(seeds) <= 4:
        return "[" + ", ".join(str(s) for s in seeds) + "]"
    return f"[{seeds[0]}, {seeds[1]}, …, {seeds[-1]}] ({len(seeds)} seeds)"


def not_reproduced(results: dict) -> list[str]:
    """Everything the study does not reproduce: each printed cell that differs or diverged, then ``missing``.

    The list's length is the count the report states, so the two always add up. The cells are generated
    here (with the percentile where the percentile policy decides); a study's ``missing`` lists only the
    parts of the paper that are not cells (figures, experiments, lost equations).

    Parameters
    ----------
    results : dict
        One results.json dict.

    Returns
    -------
    list of str
    """
    _check_results("results", results)
    bad = []
    for cell, q in _scored(results, uncelled=True).items():
        if q["paper"] is None or q["verdict"] not in ("differs", "diverged"):
            continue
        what = "diverged" + _runs(q) if q["verdict"] == "diverged" else (
            f"{_fmt(q['value'], digits=_digits(q))} vs {_fmt(q['paper'], digits=_digits(q))}")
        if q["verdict"] == "differs" and q.get("policy") == "percentile" and q.get("interval"):
            what += (f"; the paper's value at percentile {q['percentile']:.3g} % of the runs, outside their central "
                     f"95 % [{_fmt(q['interval'][0])}, {_fmt(q['interval'][1])}]")
        elif q["verdict"] == "differs" and q.get("policy") == "derived":
            what += f"; takes the verdict of `{q.get('derived_from')}`"
        bad.append(f"{cell} ({what})")
    return bad + [str(m) for m in results.get("missing") or []]


def _study_section(r: dict, this_run: dict, failed: dict, claim_links: dict | None = None) -> list[str]:
    c = tally(r)
    lines = [f"## {r['study']}", ""]
    if r["study"] not in this_run:
        why = f" This run failed: {_cell(failed[r['study']])}." if r["study"] in failed else ""
        lines += [f"> **Stale:** these results are not from this run; they were written by an earlier run.{why}", ""]
    lines += [f"*{r['paper']}* — paper text `{r['seed_file']}`.", ""]
    lines += scorecard(r, links=claim_links)
    lines += [f"Paper cells: {c['agrees']} agree, {c['reachable']} reachable inside the plausible box, "
              f"{c['differs']} differ, {c['diverged']} diverged"
              + (f", {c['lost']} lost in extraction" if c["lost"] else "")
              + (f"; {c['checks']} checks and {c['errata']} errata apart" if c["checks"] or c["errata"] else "")
              + f"; {c['new']} new quantities" + (f" ({c['new_diverged']} diverged)" if c["new_diverged"] else "")
              + ".", ""]
    if r["quantities"]:
        lines += study_summary(r) + [""]
    missing = not_reproduced(r)
    if missing:
        n_cells = len(missing) - len(r.get("missing") or [])
        lines += [f"**Not reproduced ({len(missing)}: {n_cells} printed cell{'s' if n_cells != 1 else ''} that "
                  f"differ{'' if n_cells != 1 else 's'} or diverged, {len(missing) - n_cells} "
                  f"part{'s' if len(missing) - n_cells != 1 else ''} of the paper):**", ""]
        lines += [f"{i}. {_cell(_shorten_lists(m))}" for i, m in enumerate(missing, 1)] + [""]
    tables = paper_tables(r)
    if tables:
        lines += ["### The paper's tables, printed beside reproduced", "", *tables]
    lines += checks_and_errata(r)
    lines += sensitivity_lines(r)
    if r["reconstructions"]:
        lines += ["### Reconstructions", "",
                  "Values the paper does not print (or prints wrongly), why they were chosen, and their plausible "
                  "range:",
                  ""]
        lines += [f"- **{c['name']}** = `{_cell(_fmt(c['value']))}` — {_shorten_lists(c['why'])} *Plausible:* "
                  f"{plausible_text(c.get('plausible'))}"
                  + (f" — {_shorten_lists(c['plausible']['why'])}" if c.get("plausible") else "")
                  for c in r["reconstructions"]]
        lines.append("")
    findings = [f for f in r["findings"] if f.get("kind") != "erratum"]
    if findings:
        lines += ["### Findings", ""]
        for f in findings:
            text = _shorten_lists(f["text"])
            first = _first_sentence(f["text"])
            rest = text[len(first):].strip() if text.startswith(first) else text
            lines.append(f"- **{first}** {rest}".rstrip())
            if f.get("evidence") is not None:
                ev = summarise(f["evidence"])
                if len(ev) > MAX_EVIDENCE:
                    ev = ev[:MAX_EVIDENCE - 1].rstrip() + "… (full evidence in results.json)"
                lines.append(f"  - *Evidence:* {ev}")
        lines.append("")
    if r["figures"]:
        lines += ["### Figures", ""]
        captions = r.get("captions") or {}
        for name in r["figures"]:
            lines += [f"![{name}]({r['study']}/{name})", "",
                      f"*{name}* — {captions.get(name, '(no caption recorded)')}", ""]
    if r["quantities"]:
        lines += [f"Every quantity of this study: [appendix](#appendix-{_anchor(r['study'])}).", ""]
    return lines


def _appendix(results: list[dict]) -> list[str]:
    """Every quantity of every study, one table per study, at the end of the report."""
    lines = ["## Appendix: every quantity", ""]
    for r in results:
        if r["quantities"]:
            lines += [f"### Appendix: {r['study']}", "", summary_table(r), ""]
    return lines


def write_report_md(results: list[dict], out_dir: Path, *, this_run: dict | None = None,
                    failed: dict | None = None, extra: list[str] | None = None,
                    claim_links: dict | None = None) -> Path:
    """Write ``out_dir/REPORT.md`` atomically from the results.json dicts of several studies.

    Parameters
    ----------
    results : list of dict
        One results.json dict per study. Built studies (with quantities) are shown first, in the
        order given, then the others.
    out_dir : Path
        Where REPORT.md is written (the figures are linked relative to it, ``<study>/<file>``).
    this_run : dict, optional
        ``{study: {"seed": int, "runs": int | None, "quick": bool}}`` for the studies written by
        this run. When given, every other study is marked stale (its results come from an earlier
        run). ``None`` treats all studies as fresh (no provenance known).
    failed : dict, optional
        ``{study: reason}`` for studies that failed in this run; their old results (if any) are shown
        as stale with the reason.
    extra : list of str, optional
        Markdown lines of further sections (the estimator arena), placed after the studies and before
        the appendix.
    claim_links : dict, optional
        ``{"<study>/<claim id>": Markdown}`` shown beside those claims in the studies' scorecards (the
        arena's verdicts, :func:`ctrl_analysis.arena.recommend.arena_claim_links`).

    Returns
    -------
    Path
        The REPORT.md written.
    """
    if not isinstance(results, (list, tuple)) or not all(isinstance(r, dict) and "study" in r for r in results):
        raise TypeError(f"results must be a list of results.json dicts, got {results!r:.80}")
    out_dir = check_path("out_dir", out_dir)
    for name, value in (("this_run", this_run), ("failed", failed), ("claim_links", claim_links)):
        if value is not None and not isinstance(value, dict):
            raise TypeError(f"{name} must be a dict keyed by study name, got {value!r}")
    failed = dict(failed or {})
    if this_run is None:
        this_run = {r["study"]: {} for r in results}
    results = [r for r in results if r["quantities"]] + [r for r in results if not r["quantities"]]
    lines = [
        "# ctrl-analysis: reproduction report",
        "",
        ("Generated by `ctrl-analysis reproduce all` from the `results.json` of each study. Every reproduced value "
        "was computed by the code and every verdict is computed, never typed (unit — = dimensionless). The counts "
        "score each printed paper cell once, by its primary reading (cells whose printed value was lost in the "
        "extracted paper text are counted apart); checks of the paper's algebra and arithmetic are listed apart; "
        "quantities the paper does not print are counted as new. The glossary at the end explains the terms."),
        "",
        f"**Verdict policy.** {VERDICT_POLICY}",
        "",
        "## Overview",
        "",
        *overview_table(results, this_run),
        "",
        "### Provenance",
        "",
        *_run_table(results, this_run, failed),
        "",
    ]
    if failed:
        lines += ["**Failed in this run:** " + "; ".join(f"{k}: {_cell(v)}" for k, v in failed.items()), ""]
    for r in results:
        lines += _study_section(r, this_run, failed, claim_links)
    if extra is not None:
        if not isinstance(extra, (list, tuple)) or not all(isinstance(x, str) for x in extra):
            raise TypeError(f"extra must be a list of Markdown lines, got {extra!r:.80}")
        lines += [*extra, ""]
    lines += _appendix(results)
    text = "\n".join(lines)
    lines += glossary_lines(text)
    return write_text_atomic(Path(out_dir) / "REPORT.md", "\n".join(lines) + "\n")
