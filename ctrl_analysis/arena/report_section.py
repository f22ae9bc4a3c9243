"""The arena's part of REPORT.md: its section, with where it comes from, and its verdicts on the studies' claims.

``reproduce`` builds REPORT.md from the studies' results.json files; the arena is a separate command
(``ctrl-analysis arena``) whose ``OUT/arena/results.json``, when present, adds a section and links.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..reporting.formatting import one_line

__all__ = ["arena_links", "arena_section"]


def arena_links(out: Path) -> dict:
    """The arena's verdicts on the studies' claims, ``{"<study>/<claim id>": text}``, linked to its section.

    Parameters
    ----------
    out : Path
        The output folder holding ``arena/results.json`` (or not).

    Returns
    -------
    dict
    """
    path = out / "arena" / "results.json"
    if not path.exists():
        return {}
    from .recommend import arena_claim_links

    try:
        links = arena_claim_links(json.loads(path.read_text(encoding="utf-8")))
    except (ValueError, TypeError):
        return {}
    return {k: f"[{v}](#estimator-arena)" for k, v in links.items()}


def arena_section(out: Path) -> list[str] | None:
    """The arena's REPORT.md section from ``out/arena/results.json`` (written by ``ctrl-analysis arena``), if any.

    The section says it comes from a separate ``ctrl-analysis arena`` run (with its seed and options); a folder
    holding a run on a user's record is pointed to, not shown as the benchmark.

    Parameters
    ----------
    out : Path

    Returns
    -------
    list of str or None
        Markdown lines; None without ``arena/results.json``.
    """
    path = out / "arena" / "results.json"
    if not path.exists():
        return None
    from .recommend import arena_report_lines

    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        settings = data.get("settings") or {}
        if settings.get("mode") == "record":
            return ["## Estimator arena", "", f"`{out / 'arena'}` holds an arena run on a record "
                    f"(`{settings.get('signal')}`), not the benchmark: its ranking is in `arena/REPORT.md`."]
        lines = arena_report_lines(data)
    except (ValueError, TypeError, AttributeError) as exc:
        return ["## Estimator arena", "", f"The arena's results.json could not be read: {one_line(exc)}"]
    cli = settings.get("cli") or {}
    where = (f"seed {cli.get('seed')}" + (", --quick" if cli.get("quick") else "")
             + (f", --runs {cli['runs']}" if cli.get("runs") else "")) if cli else "settings not recorded"
    return lines[:2] + [f"*From a separate `ctrl-analysis arena` run ({where}), not from this `reproduce` run: "
                        "rerun `ctrl-analysis arena` to refresh it.*", ""] + lines[2:]
