"""The output folder of one ``ctrl-analysis reproduce`` run: studies swapped in whole, REPORT.md rebuilt from the disk.

:class:`RunFolder` is the command's bookkeeping (the CLI makes one per run): each study is committed by one
atomic swap of its staged folder, and REPORT.md is rendered from the ``results.json`` files on disk (with the
staged one in place of the old) and swapped in right after, so the two always agree.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

from .atomic import _sigint_deferred as sigint_deferred
from .atomic import remove_tree, swap_in
from .formatting import one_line
from .markdown import write_report_md
from .report import validate_results

__all__ = ["RunFolder", "read_results"]


def read_results(path: Path, name: str) -> dict:
    """A study's results.json read back; ValueError (one line) when unreadable or not a results record.

    Parameters
    ----------
    path : Path
        The results.json.
    name : str
        The study it must be the record of.

    Returns
    -------
    dict
    """
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ValueError(f"unreadable results.json: {one_line(exc)}") from None
    try:
        validate_results(data)
        if data["study"] != name:
            raise ValueError(f"it is the record of study {data['study']!r}")
    except (ValueError, TypeError, KeyError, AttributeError) as exc:
        raise ValueError(f"{path} is not a results record of {name}: {one_line(exc)}") from None
    return data


class RunFolder:
    """What the main process of ``ctrl-analysis reproduce`` knows of its run: studies committed, failed, the report.

    ``failed`` holds this run's failed studies only (study -> one line); ``left_out`` the other studies
    of the folder whose results.json cannot be read as a results record (left out of REPORT.md, not a
    failure of this run); ``report_error`` why REPORT.md could not be written (None once it is).

    Parameters
    ----------
    out : Path
        The output folder (``--out``).
    report : bool
        Whether REPORT.md is (re)written.
    studies : list of str
        Every registered study, in the report's order.
    extra : callable, optional
        ``extra(out) -> Markdown lines or None`` added to the report (the arena's section).
    links : callable, optional
        ``links(out) -> {"<study>/<claim id>": text}`` shown beside claims (the arena's verdicts).
    """

    def __init__(self, out: Path, report: bool, studies: list, extra=None, links=None):
        self.out = out
        self.studies = list(studies)  # every registered study, in the report's order
        # extra(out) -> Markdown lines added to the report (the arena's section), links(out) -> {claim: text}
        self.extra = extra or (lambda out: None)
        self.links = links or (lambda out: {})
        self.report = report  # whether REPORT.md is (re)written
        self.committed: list[str] = []
        self.failed: dict = {}
        self.left_out: dict = {}
        self.report_error: str | None = None
        self.report_path = None

    def _on_disk(self, replace: dict) -> tuple[list, dict]:
        """results.json dicts of every registered study as on disk (``replace``: about to be), and the unreadable."""
        results, bad = [], {}
        for name in self.studies:
            if name in replace:
                results.append(replace[name])
                continue
            path = self.out / name / "results.json"
            if not path.exists():
                continue
            try:
                results.append(read_results(path, name))
            except ValueError as exc:
                bad[name] = str(exc)
        return results, bad

    def _render(self, replace: dict, committed: list[str]) -> Path | None:
        """REPORT.md of the folder as it is (or will be, with ``replace``), written into a hidden folder in ``out``.

        Provenance comes from the files: a study counts as this run's when this run committed it,
        and its seed, runs and quick flag are those its results.json records (``settings.cli``).
        A study whose results.json is unreadable is left out, and the report says so in a section of
        its own (it is not a failure of this run).
        """
        results, self.left_out = self._on_disk(replace)
        this_run = {r["study"]: dict((r.get("settings") or {}).get("cli") or {}) for r in results
                    if r["study"] in committed}
        extra = [*_left_out_lines(self.left_out), *(self.extra(self.out) or [])]
        tmp = Path(tempfile.mkdtemp(dir=self.out, prefix=".REPORT.md.new-"))
        try:
            write_report_md(results, tmp, this_run=this_run, failed=dict(self.failed), extra=extra or None,
                            claim_links=self.links(self.out))
        except BaseException:
            remove_tree(tmp)
            raise
        return tmp

    def _publish(self, tmp: Path | None) -> None:
        """Move the rendered REPORT.md into place (OSError when it cannot be; ``tmp`` is removed either way)."""
        if tmp is None:
            return
        try:
            os.replace(tmp / "REPORT.md", self.out / "REPORT.md")
        finally:
            remove_tree(tmp)
        self.report_path = self.out / "REPORT.md"

    def commit(self, name: str, staged: Path) -> None:
        """Move study ``name``'s staged folder into place and rebuild REPORT.md from the files on disk.

        The report is rendered first (with the staged results in place of the old ones), then the
        folder and the report are swapped in back to back with SIGINT and SIGTERM held, so REPORT.md
        and every results.json agree before and after. Nothing runs between the two renames (the old
        folder is removed after both): a kill -9 can still fall between them, but only within microseconds.
        Once the folder is swapped in the study is committed, whatever happens to the report: a report
        that cannot be rendered or moved into place is recorded in ``report_error`` (:meth:`finish` tries again).

        Parameters
        ----------
        name : str
            The study.
        staged : Path
            Its complete staged folder beside ``out/name``.
        """
        tmp = None
        if self.report:
            new = read_results(staged / "results.json", name)
            try:
                tmp = self._render({name: new}, self.committed + [name])
            except OSError as exc:  # e.g. a full disk: the study is still committed, the old report stays
                self.report_error = one_line(exc)
        with sigint_deferred():
            old = swap_in(staged, self.out / name, keep_old=True)
            self.committed.append(name)
            self.failed.pop(name, None)
            try:
                self._publish(tmp)
            except OSError as exc:
                self.report_error = one_line(exc)
        if old is not None:
            remove_tree(old)

    def finish(self) -> None:
        """Rebuild REPORT.md from the files on disk once more (with every failure of the run).

        When it cannot be written, says so in one line on stderr, with whether the REPORT.md left in
        ``out`` is an earlier run's (which no longer describes the folder).
        """
        if not self.report:
            return
        try:
            tmp = self._render({}, self.committed)
            with sigint_deferred():
                self._publish(tmp)
        except OSError as exc:  # e.g. a full disk: the previous REPORT.md stays as it was
            self.report_error = one_line(exc)
            report = self.out / "REPORT.md"
            old = ("; the REPORT.md in --out is an earlier run's, which does not describe the studies of this run"
                   if self.committed and report.is_file() and not report.is_symlink() else "")
            sys.stderr.write(f"ctrl-analysis: error: REPORT.md not written: {self.report_error}{old}\n")
        else:
            self.report_error = None


def _left_out_lines(left_out: dict) -> list[str]:
    """REPORT.md's section on the studies of the folder whose results.json is unreadable (none: no lines)."""
    if not left_out:
        return []
    return ["## Left out of this report", "",
            ("These studies have a folder here whose `results.json` is not a results record that this report can "
             "read; they were not run by this run. Rerun them to bring them back."), "",
            *(f"- **{name}**: {why}" for name, why in left_out.items()), ""]
