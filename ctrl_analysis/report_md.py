"""REPORT.md: the reproduction report of several studies, written from their results.json dicts."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._validate import check_path
from .report import count_verdicts, write_text_atomic

__all__ = ["summary_table", "write_report_md"]


def _fmt(value, std=None) -> str:
    if value is None:
        return "—"
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_fmt(v) for v in np.ravel(np.asarray(value, dtype=object))) + "]"
    if isinstance(value, bool):
        return str(int(value))
    if isinstance(value, (int, np.integer)):
        return str(value)
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    text = f"{v:.4g}"
    if std is not None:
        text += f" ± {_fmt(std)}"
    return text


def _cell(text) -> str:
    """Text safe inside a Markdown table cell (pipes escaped, one line)."""
    return str(text or "").replace("|", "\\|").replace("\n", " ")


def _fmt_tolerance(q: dict) -> str:
    tol = q.get("tolerance")
    return "—" if tol is None else f"{100 * tol:.3g} %"


def summary_table(results: dict) -> str:
    """A Markdown table of the quantities of one results.json dict (unit "—" = dimensionless).

    Parameters
    ----------
    results : dict
        One study's results.json dict (its ``quantities`` are read).

    Returns
    -------
    str
        The table, one row per quantity.
    """
    if not isinstance(results, dict) or not isinstance(results.get("quantities"), list):
        raise TypeError(f"results must be a results.json dict with a 'quantities' list, got {results!r:.80}")
    rows = ["| id | quantity | paper cell | paper | reproduced | unit | tolerance | verdict | note |",
            "|---|---|---|---|---|---|---|---|---|"]
    for q in results["quantities"]:
        note = _cell(q.get("note"))
        std = q.get("std") if (q.get("runs") or 2) > 1 else None
        runs = f" ({q['runs']} run{'s' if q['runs'] != 1 else ''})" if q.get("runs") else ""
        cell = _cell(q.get("cell"))
        if cell and q.get("primary"):
            cell += " (primary)"
        rows.append(
            f"| `{q['id']}` | {_cell(q['label'])} | {cell} | {_fmt(q['paper'])} | {_fmt(q['value'], std)}{runs} "
            f"| {_cell(q.get('unit')) or '—'} | {_fmt_tolerance(q)} | {q['verdict']} | {note} |"
        )
    return "\n".join(rows)


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


def write_report_md(results: list[dict], out_dir: Path, *, this_run: dict | None = None,
                    failed: dict | None = None) -> Path:
    """Write ``out_dir/REPORT.md`` atomically from the results.json dicts of several studies.

    Parameters
    ----------
    results : list of dict
        One results.json dict per study.
    out_dir : str or os.PathLike
        Directory of REPORT.md (non-empty path).
    this_run : dict, optional
        ``{study: {"seed": int, "runs": int | None, "quick": bool}}`` for the studies written by
        this run. When given, every other study is marked stale (its results come from an earlier
        run). ``None`` treats all studies as fresh (no provenance known).
    failed : dict, optional
        ``{study: reason}`` for studies that failed in this run; their old results (if any) are shown
        as stale with the reason.

    Returns
    -------
    pathlib.Path
        The file written.
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
    lines = [
        "# ctrl-analysis: reproduction report",
        "",
        "Generated by `ctrl-analysis reproduce all`. Every reproduced value below was computed by the code;",
        "verdicts are computed from the relative tolerance shown beside each value (unit — = dimensionless).",
        "Headline counts count paper cells, each scored once by its primary quantity.",
        "",
        "## Provenance",
        "",
        *_run_table(results, this_run, failed),
        "",
    ]
    if failed:
        lines += ["**Failed in this run:** " + "; ".join(f"{k}: {_cell(v)}" for k, v in failed.items()), ""]
    for r in results:
        counts = count_verdicts(r)
        lines += [f"## {r['study']}", ""]
        if r["study"] not in this_run:
            why = f" This run failed: {_cell(failed[r['study']])}." if r["study"] in failed else ""
            lines += [f"> **Stale:** these results are not from this run; they were written by an earlier run.{why}",
                      ""]
        lines += [
            f"*{r['paper']}* — seed `{r['seed_file']}`. "
            f"{counts['agrees']} agree, {counts['differs']} differ, {counts['diverged']} diverged, "
            f"{counts['new']} new; runtime {r['runtime_s']:.1f} s.",
            "",
        ]
        if r.get("missing"):
            lines += ["**Not built yet:** " + "; ".join(r["missing"]), ""]
        if r["quantities"]:
            lines += [summary_table(r), ""]
        if r["reconstructions"]:
            lines += ["### Reconstructions", ""]
            lines += [f"- **{c['name']}** = `{_fmt(c['value'])}` — {c['why']}" for c in r["reconstructions"]]
            lines.append("")
        if r["findings"]:
            lines += ["### Findings", ""]
            lines += [f"- **{f['id']}**: {f['text']}" for f in r["findings"]]
            lines.append("")
        if r["figures"]:
            lines += ["### Figures", ""]
            lines += [f"![{name}]({r['study']}/{name})" for name in r["figures"]]
            lines.append("")
    return write_text_atomic(out_dir / "REPORT.md", "\n".join(lines) + "\n")
