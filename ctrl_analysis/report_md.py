"""REPORT.md: the reproduction report of several studies, written from their results.json dicts.

The report reads on its own for someone holding only the papers: an overview of the verdict counts,
then per study a summary generated from its verdicts and findings, one side-by-side table per paper
table (printed beside reproduced), the full quantity list, reconstructions, findings with their
evidence summarised, captioned figures, and a glossary of the terms used.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ._validate import check_path
from .report import relative_error, write_text_atomic

__all__ = ["GLOSSARY", "overview_table", "summary_table", "tally", "write_report_md"]

#: Longest list quoted as is; longer numeric lists are summarised as min / median / max.
MAX_LIST = 8
#: Longest evidence text before it is cut (the full evidence stays in results.json).
MAX_EVIDENCE = 700
#: Marks of the verdicts in the side-by-side tables.
MARK = {"agrees": "✓", "differs": "✗", "diverged": "diverged", "new": ""}

#: Terms the report uses; a term is listed when it occurs in the report.
GLOSSARY = {
    "agrees / differs": "the reproduced value is within / outside the relative tolerance shown beside it "
                        "(|value − paper| / |paper|, element-wise maximum for vectors).",
    "new": "a quantity the paper does not print (a check, a sweep, a claim put into numbers).",
    "diverged": "every run of that quantity diverged (a state left the divergence bound): no value.",
    "paper cell": "one number printed in the paper (a table entry or a value in the text). A cell may be "
                  "reproduced under several readings; the headline counts score it once, by its primary reading.",
    "primary reading": "the reading of an ambiguous method the study considers the paper's intent; the other "
                       "readings of the same cell are listed but not counted.",
    "reconstruction": "a value or choice the paper does not print (or prints wrongly), chosen by the study "
                      "and justified.",
    "state reading": "reading an estimator's output as its state vector (x̂ = z) rather than the corrected "
                     "output formula the paper prints.",
    "literal": "the method run exactly as printed, even where that is ill-posed or diverges.",
    "well-posed": "the smallest change to the printed method that makes it solvable (e.g. a regression "
                  "whose columns are identifiable), used as the primary reading when the literal one fails.",
    "predictor form": "a Kalman filter written with the one-step prediction x̂(k+1|k) as its state.",
    "DWNA": "discrete white-noise acceleration: the process-noise model of an α-β tracker, Q = σ² G Gᵀ "
            "with G = [T²/2, T]ᵀ.",
    "Kalata index": "the tracking index Λ = σ_w T² / σ_v of an α-β filter, which fixes its steady-state "
                    "gains (α, β).",
    "PPD": "pseudo-partial derivative φ(k) of MFAC's compact-form dynamic linearisation, "
           "Δy(k+1) = φ(k) Δu(k), estimated on line.",
    "CFDL": "compact-form dynamic linearisation, the data model behind MFAC.",
    "MFAC": "model-free adaptive control (Hou): a controller built on the CFDL data model and its "
            "estimated PPD.",
    "TD": "tracking differentiator (Han): a nonlinear filter giving a smoothed signal and its derivative.",
    "IKF": "the improved Kalman filter of the ikf-mfac paper, a scalar random-walk Kalman filter on the "
           "measured output.",
    "CKF": "characteristic-model-based Kalman filter: a Kalman filter on the second-order characteristic "
           "model x(k) = f1 x(k−1) + f2 x(k−2) + g0 u(k−1) whose coefficients are identified on line.",
    "LPF": "low-pass filter.",
    "RLS": "recursive least squares (with forgetting factor λ).",
    "ESO": "extended state observer (Han): an observer whose extra state estimates the total disturbance.",
    "LESO": "linear ESO with gains in bandwidth form, poles at −ω_o.",
    "MESO": "modified ESO (meso paper): an ESO with a model term XᵀΘ whose parameters Θ are identified by "
            "least squares (LSM) on batches of data, so its extended state only carries what the model misses.",
    "ARE / DARE": "algebraic / discrete algebraic Riccati equation, whose solution gives a Kalman filter's "
                  "steady-state gain.",
    "α-β filter": "a two-state (position, rate) tracking filter with constant gains α and β.",
    "RK4": "the classical fourth-order Runge-Kutta integrator (fixed step).",
    "ZOH": "zero-order hold: a sampled signal held constant over each sampling period.",
    "LSM": "least-squares method (batch identification).",
    "fal": "Han's nonlinear gain function fal(e, α, δ): |e|^α sign(e) outside |e| < δ, linear inside.",
    "Σ": "the differential state estimator of the differential-estimator paper, a chain of integrators "
         "with poles designed at the root-locus breakaway point.",
    "est_xi / track_xi": "the meso tables' columns: mean |estimation error| of x_i, and mean |tracking error| of "
                         "x_i, over the run.",
    "RMSE": "root-mean-square error.",
    "SNR": "signal-to-noise ratio, 10 lg(Σ y*² / Σ e²) in dB.",
    "mean ± std": "mean and standard deviation over the Monte Carlo runs that did not diverge.",
}


def _fmt(value, std=None, digits: int = 4) -> str:
    if value is None:
        return "—"
    if isinstance(value, (list, tuple, np.ndarray)):
        flat = list(np.ravel(np.asarray(value, dtype=object)))
        if len(flat) > MAX_LIST and _numeric(flat):
            return _array_summary(flat)
        return "[" + ", ".join(_fmt(v, digits=digits) for v in flat) + "]"
    if isinstance(value, bool):
        return str(int(value))
    if isinstance(value, (int, np.integer)):
        return str(value)
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    text = f"{v:.{digits}g}"
    if std is not None:
        text += f" ± {_fmt(std)}"
    return text


def _digits(q: dict) -> int:
    """Significant digits that show a difference the tolerance can resolve (4, or 6 for tight tolerances)."""
    tol = q.get("tolerance")
    return 6 if tol is not None and tol < 1e-3 else 4


def _numeric(items) -> bool:
    return all(isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) or v is None
               for v in items)


def _array_summary(items) -> str:
    vals = np.array([np.nan if v is None else v for v in items], dtype=float)
    fin = vals[np.isfinite(vals)]
    if fin.size == 0:
        return f"[{len(items)} values, none finite]"
    return (f"[{len(items)} values: min {np.min(fin):.4g} / median {np.median(fin):.4g} / max {np.max(fin):.4g}"
            + (f"; {len(items) - fin.size} not finite" if fin.size < len(items) else "") + "]")


def summarise(value, depth: int = 0) -> str:
    """Evidence as short text: long numeric arrays as min / median / max, nested dicts and lists compact.

    Parameters
    ----------
    value : object
        A JSON-like value (dict, list, number, string, None).
    depth : int
        Nesting depth (deeper levels are abbreviated).

    Returns
    -------
    str
    """
    if isinstance(value, dict):
        if depth >= 3:
            return f"{{{len(value)} entries}}"
        return "{" + "; ".join(f"{k}: {summarise(v, depth + 1)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple, np.ndarray)):
        items = list(value) if not isinstance(value, np.ndarray) else value.tolist()
        if _numeric(items):
            return _fmt(items)
        if len(items) > MAX_LIST or depth >= 3:
            return f"[{len(items)} records]"
        return "[" + ", ".join(summarise(v, depth + 1) for v in items) + "]"
    if isinstance(value, str):
        return value
    return _fmt(value)


_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_LONG_LIST = re.compile(rf"\[\s*{_NUM}(?:\s*,\s*{_NUM}){{{MAX_LIST},}}\s*\]")


def _shorten_lists(text: str) -> str:
    """Replace numeric lists longer than :data:`MAX_LIST` inside a text by their min / median / max."""
    return _LONG_LIST.sub(lambda m: _array_summary([float(x) for x in re.findall(_NUM, m.group(0))]), text)


def _cell(text) -> str:
    """Text safe inside a Markdown table cell (pipes escaped, one line)."""
    return str(text or "").replace("|", "\\|").replace("\n", " ")


def _fmt_tolerance(q: dict) -> str:
    tol = q.get("tolerance")
    return "—" if tol is None else f"{100 * tol:.3g} %"


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
    rows = ["| id | quantity | paper cell | paper | reproduced | unit | tolerance | verdict | note |",
            "|---|---|---|---|---|---|---|---|---|"]
    for q in results["quantities"]:
        note = _cell(_shorten_lists(q.get("note") or ""))
        std = q.get("std") if (q.get("runs") or 2) > 1 else None
        cell = _cell(q.get("cell"))
        if cell and q.get("primary"):
            cell += " (primary)"
        rows.append(
            f"| `{q['id']}` | {_cell(q['label'])} | {cell} | {_fmt(q['paper'])} | {_fmt(q['value'], std)}{_runs(q)} "
            f"| {_cell(q.get('unit')) or '—'} | {_fmt_tolerance(q)} | {q['verdict']} | {note} |"
        )
    return "\n".join(rows)


def _scored(results: dict, uncelled: bool = False) -> dict:
    """``{cell: quantity}``: the quantity that scores each paper cell (primary, else the first).

    With ``uncelled``, a quantity with a paper value but no cell is its own cell (named by its label),
    as :func:`~ctrl_analysis.report.count_verdicts` counts it.
    """
    by_cell: dict = {}
    for q in results["quantities"]:
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


def _check_results(name: str, results) -> None:
    """A results.json dict: ``study`` (str) and a ``quantities`` list."""
    if not isinstance(results, dict) or not isinstance(results.get("quantities"), list) \
            or not isinstance(results.get("study"), str):
        raise TypeError(f"{name} must be a results.json dict with 'study' and a 'quantities' list, got {results!r:.80}")


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
        ``agrees``, ``differs``, ``diverged``, ``printed``, ``lost``, ``new``, ``new_diverged``.

    Raises
    ------
    TypeError
        If ``results`` is not a results.json dict with a ``quantities`` list.
    """
    _check_results("results", results)
    scored = _scored(results, uncelled=True)
    printed = [q for q in scored.values() if q["paper"] is not None]
    new = [q for q in results["quantities"] if q.get("cell") is None and q["paper"] is None]
    out = {v: sum(q["verdict"] == v for q in printed) for v in ("agrees", "differs", "diverged")}
    out.update(printed=len(printed), lost=len(scored) - len(printed), new=len(new),
               new_diverged=sum(q["verdict"] == "diverged" for q in new))
    return out


def _reproduced(q: dict) -> str:
    if q["verdict"] == "diverged":
        return "diverged" + _runs(q)
    std = q.get("std") if (q.get("runs") or 2) > 1 else None
    text = _fmt(q["value"], std, digits=_digits(q))
    mark = MARK[q["verdict"]]
    if q["paper"] is not None and q["value"] is not None:
        err = _signed_error(q["value"], q["paper"])
        if np.isfinite(err) and err != 0:
            text += f" ({100 * err:+.0f} %)" if abs(err) >= 0.01 else f" ({100 * err:+.2g} %)"
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
        lines += [f"**{name}** (paper | reproduced; ✓ within tolerance, ✗ outside, percentage = relative error):", "",
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
        lines += ["", (f"Units: {', '.join(sorted(units))} (per column in the quantity list); tolerance "
                       f"{', '.join(sorted(tols))}. Printed values lost in the extracted text show as —."), ""]
    if text_cells:
        lines += ["**Values printed in the text:**", "", "| paper cell | paper | reproduced | unit | tolerance |",
                  "|---|---|---|---|---|"]
        lines += [f"| {_cell(c)} | {_fmt(q['paper'], digits=_digits(q))} | {_cell(_reproduced(q))} | {_cell(q.get('unit')) or '—'} | "
                  f"{_fmt_tolerance(q)} |" for c, q in text_cells]
        lines.append("")
    return lines


#: Abbreviations a sentence does not end on ("Eq. (9)", "Fig. 3", "e.g. x").
_ABBREVIATIONS = {"eq", "eqs", "fig", "figs", "ref", "refs", "sec", "no", "vs", "e.g", "i.e", "cf", "approx"}


def _first_sentence(text: str, limit: int = 180) -> str:
    text = _shorten_lists(" ".join(str(text).split()))
    first = text
    for m in re.finditer(r"(?<=[.!?])\s+(?=[A-Z(\[*])", text):
        word = re.search(r"([\w.]*)[.!?]$", text[:m.start()])
        if word and word.group(1) and (word.group(1).lower() in _ABBREVIATIONS
                                      or (len(word.group(1)) == 1 and word.group(1).isalpha())):
            continue
        first = text[:m.start()]
        break
    return first if len(first) <= limit else first[:limit - 1].rstrip(" ,;") + "…"


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
    line1 = (f"**Agrees:** {n_agree} of {n_printed} printed paper cells within tolerance"
             + (f" ({'; '.join(agree)})" if agree else "")
             + (f"; {lost} cells whose printed values were lost in extraction are reproduced without verdict"
                if lost else "") + ".")
    bad = [(c, q) for c, q in scored.items() if q["verdict"] in ("differs", "diverged")]
    parts = []
    for c, q in bad[:6]:
        if q["verdict"] == "diverged":
            parts.append(f"{c} (all runs diverged)")
        else:
            err = _signed_error(q["value"], q["paper"]) if q["value"] is not None else np.inf
            pct = "" if not np.isfinite(err) else (f", {100 * err:+.0f} %" if abs(err) >= 0.01 else f", {100 * err:+.2g} %")
            parts.append(f"{c} ({_fmt(q['value'], digits=_digits(q))} vs {_fmt(q['paper'], digits=_digits(q))}{pct})")
    if len(bad) > 6:
        parts.append(f"and {len(bad) - 6} more")
    line2 = "**Does not agree:** " + ("; ".join(parts) if parts else "no printed cell differs") + "."
    findings = results.get("findings") or []
    quoted = "; ".join(f"*{f['id']}*: {_first_sentence(f['text']).rstrip('.')}" for f in findings[:n_findings])
    line3 = (f"**Findings ({len(findings)}):** " + (quoted if quoted else "none")
             + (" …" if len(findings) > n_findings else ""))
    return [f"- {line1}", f"- {line2}", f"- {line3}"]


def overview_table(results: list[dict], this_run: dict) -> list[str]:
    """The opening table: per study the cell verdict counts, new quantities, findings, runtime, provenance.

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
    rows = [("| study | paper | from this run | cells agree | cells differ | cells diverged | cells not printed "
             "| new quantities | findings | figures | runtime |"), "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        c = tally(r)
        run = this_run.get(r["study"])
        fresh = "no (stale)" if run is None else ("yes (quick)" if run.get("quick") else "yes")
        new = f"{c['new']}" + (f" ({c['new_diverged']} diverged)" if c["new_diverged"] else "")
        rows.append(f"| [{r['study']}](#{_anchor(r['study'])}) | {_cell(r['paper'])} | {fresh} | {c['agrees']} "
                    f"| {c['differs']} | {c['diverged']} | {c['lost']} | {new} | {len(r.get('findings') or [])} "
                    f"| {len(r.get('figures') or [])} | {r['runtime_s']:.0f} s |")
    return rows


def _anchor(name: str) -> str:
    return re.sub(r"[^a-z0-9 -]", "", name.lower()).replace(" ", "-")


def _run_table(results: list[dict], this_run: dict, failed: dict) -> list[str]:
    """Which studies come from this run (with base seed, runs and per-run seeds) and which are stale."""
    rows = ["| study | from this run | base seed | runs | per-run seeds |", "|---|---|---|---|---|"]
    present = {r["study"] for r in results}
    rows += [f"| {name} | **no — failed**, and no earlier results | — | — | — |" for name in failed
             if name not in present]
    for r in results:
        name = r["study"]
        run = this_run.get(name)
        seeds = ", ".join(f"{k}: {_seed_summary(v)}" for k, v in (r.get("seeds") or {}).items()) or "—"
        if run is None:
            rows.append(f"| {name} | **no — stale** (results of an earlier run) | — | — | {_cell(seeds)} |")
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


def _study_section(r: dict, this_run: dict, failed: dict) -> list[str]:
    c = tally(r)
    lines = [f"## {r['study']}", ""]
    if r["study"] not in this_run:
        why = f" This run failed: {_cell(failed[r['study']])}." if r["study"] in failed else ""
        lines += [f"> **Stale:** these results are not from this run; they were written by an earlier run.{why}", ""]
    lines += [f"*{r['paper']}* — seed `{r['seed_file']}`. Paper cells: {c['agrees']} agree, {c['differs']} differ, "
              f"{c['diverged']} diverged"
              + (f", {c['lost']} without a printed value (lost in extraction)" if c["lost"] else "")
              + f"; {c['new']} new quantities" + (f" ({c['new_diverged']} diverged)" if c["new_diverged"] else "")
              + f"; runtime {r['runtime_s']:.1f} s.", ""]
    if r["quantities"]:
        lines += study_summary(r) + [""]
    if r.get("missing"):
        lines += ["**Not reproduced:** " + "; ".join(r["missing"]), ""]
    tables = paper_tables(r)
    if tables:
        lines += ["### The paper's tables, printed beside reproduced", "", *tables]
    if r["quantities"]:
        lines += ["### All quantities", "", summary_table(r), ""]
    if r["reconstructions"]:
        lines += ["### Reconstructions", "", "Values the paper does not print (or prints wrongly), and why they were chosen:",
                  ""]
        lines += [f"- **{c['name']}** = `{_cell(_fmt(c['value']))}` — {_shorten_lists(c['why'])}"
                  for c in r["reconstructions"]]
        lines.append("")
    if r["findings"]:
        lines += ["### Findings", ""]
        for f in r["findings"]:
            lines.append(f"- **{f['id']}**: {_shorten_lists(f['text'])}")
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
    return lines


#: Patterns of glossary terms whose name is not the text they stand for.
_GLOSSARY_PATTERNS = {"est_xi / track_xi": r"(?:est|track)_x\d", "Kalata index": r"Kalata"}


def _glossary(text: str) -> list[str]:
    def used_in(term):
        if term in _GLOSSARY_PATTERNS:
            return re.search(_GLOSSARY_PATTERNS[term], text)
        return any(re.search(rf"(?<![A-Za-z]){re.escape(t.strip())}(?![A-Za-z])", text) for t in term.split("/"))

    used = [(term, what) for term, what in GLOSSARY.items() if used_in(term)]
    # terms the listed definitions themselves use (e.g. MFAC's CFDL and PPD)
    text = text + " " + " ".join(what for _, what in used)
    used = [(term, what) for term, what in GLOSSARY.items() if used_in(term)]
    if not used:
        return []
    return ["## Glossary", "", *[f"- **{term}**: {what}" for term, what in used], ""]


def write_report_md(results: list[dict], out_dir: Path, *, this_run: dict | None = None,
                    failed: dict | None = None) -> Path:
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

    Returns
    -------
    Path
        The REPORT.md written.
    """
    if not isinstance(results, (list, tuple)) or not all(isinstance(r, dict) and "study" in r for r in results):
        raise TypeError(f"results must be a list of results.json dicts, got {results!r:.80}")
    out_dir = check_path("out_dir", out_dir)
    for name, value in (("this_run", this_run), ("failed", failed)):
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
        "was computed by the code; every verdict is computed from the relative tolerance shown beside the value "
        "(unit — = dimensionless). The counts score each printed paper cell once, by its primary reading "
        "(cells whose printed value was lost in the extracted text are counted apart); quantities the paper does "
        "not print are counted as new. The glossary at the end explains the terms."),
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
        lines += _study_section(r, this_run, failed)
    text = "\n".join(lines)
    lines += _glossary(text)
    return write_text_atomic(Path(out_dir) / "REPORT.md", "\n".join(lines) + "\n")
