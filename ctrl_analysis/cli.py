"""The ``ctrl-analysis`` command: list studies, reproduce them into figures/ and results.json."""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from .report import StudyContext, staged_directory, summary_table, write_report_md, write_results_json

__all__ = ["main"]


class _Parser(argparse.ArgumentParser):
    """argparse that reports a usage error as one line on stderr and exit status 2."""

    def error(self, message):  # noqa: D102
        sys.stderr.write(f"ctrl-analysis: error: {message}\n")
        raise SystemExit(2)


def _int_at_least(minimum: int, what: str):
    """argparse type: an integer >= ``minimum``; the error says the rule and the value."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or value < minimum:
            raise argparse.ArgumentTypeError(f"must be a {what} integer, got {text!r}")
        return value

    return parse


_positive_int = _int_at_least(1, "positive")
_seed = _int_at_least(0, "non-negative")


def _build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="ctrl-analysis", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    sub.add_parser("list", help="studies and what each reproduces")
    rep = sub.add_parser("reproduce", help="figures + results.json (+ REPORT.md for all)")
    rep.add_argument("studies", nargs="+", metavar="STUDY", help="study names, or 'all'")
    rep.add_argument("--out", default="figures", help="output directory (default: figures)")
    rep.add_argument("--runs", type=_positive_int, default=None, help="Monte Carlo runs where noise is random")
    rep.add_argument("--seed", type=_seed, default=0, help="base seed (default: 0)")
    rep.add_argument("--quick", action="store_true", help="fewer runs / shorter horizons, for smoke tests")
    rep.add_argument("--jobs", type=_positive_int, default=None,
                     help="processes: studies run side by side, Monte Carlo chunks split (default: all cores)")
    rep.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="Dask scheduler for sweeps and large Monte Carlo ('local', or tcp://host:8786)")
    from .arena.cli import add_parser as add_arena  # the arena's subcommand lives in its package

    add_arena(sub)
    return parser


def _progress(study: str):
    from .progress import write

    def emit(msg: str) -> None:
        write(f"[{study}] {msg}")  # through tqdm when bars are drawn, so they stay intact

    return emit


def _check_out(text: str) -> Path:
    """The --out directory, created if needed; a one-line usage error when it cannot hold results."""
    if not text or not text.strip():
        raise _UsageError("--out must name a directory, got an empty string")
    out = Path(text)
    if out.exists() and not out.is_dir():
        raise _UsageError(f"--out must be a directory, got the file {text!r}")
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as exc:
        raise _UsageError(f"--out {text!r} is not a writable directory ({exc.strerror or exc})") from None
    return out


class _UsageError(Exception):
    """A bad command line detected after parsing: one line, exit status 2."""


def _one_line(exc: BaseException, limit: int = 400) -> str:
    text = " ".join(str(exc).split())
    if len(text) > limit:
        text = text[: limit - 1] + "…"
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _run_study(task) -> dict:
    """Run one study (here or in a worker process) into a staged directory beside ``out/name``.

    The directory is moved into place only when the study completed. Returns a record with the
    study's name, its summary text and ``error`` (one line, or ``None``); never raises for a study
    failure, so one failing study does not stop the others.
    """
    from .progress import set_context

    name, out, runs, seed, quick, jobs, scheduler, position = task
    set_context(name, position)  # the study's own bars (long simulations) carry its name, on their own line
    try:
        return _run_study_here(name, Path(out), runs, seed, quick, jobs, scheduler)
    finally:
        set_context()


def _run_study_here(name, out, runs, seed, quick, jobs, scheduler) -> dict:
    from analysis import load_study

    record = {"name": name, "error": None, "text": "", "run": {"seed": seed, "runs": runs, "quick": bool(quick)}}
    try:
        with staged_directory(out / name) as staged:
            ctx = StudyContext(out_dir=staged, runs=runs, seed=seed, quick=quick, progress=_progress(name),
                               jobs=jobs, scheduler=scheduler)
            t0 = time.perf_counter()
            result = load_study(name).run(ctx)
            result.runtime_s = time.perf_counter() - t0
            # what the command line asked for, beside the study's own settings
            result.settings["cli"] = dict(record["run"])
            write_results_json(result, staged)
            data = result.to_dict()
    except Exception as exc:  # noqa: BLE001 - any study failure is reported in one line, never a traceback
        record["error"] = _one_line(exc)
        return record
    lines = [f"\n== {name}: {out / name / 'results.json'} ({len(result.figures)} figures, {result.runtime_s:.1f} s)"]
    if data["quantities"]:
        lines.append(summary_table(data))
    if result.missing:
        lines.append("not reproduced: " + "; ".join(result.missing))
    record["text"] = "\n".join(lines)
    return record


def _previous_runtime(study_dir: Path) -> float:
    """``runtime_s`` of the results.json already in ``study_dir`` (``inf`` when there is none)."""
    try:
        return float(json.loads((study_dir / "results.json").read_text(encoding="utf-8"))["runtime_s"])
    except (OSError, ValueError, KeyError, TypeError):
        return float("inf")


def _reproduce(args) -> int:
    from analysis import STUDIES, load_study

    names = list(STUDIES) if "all" in args.studies else args.studies
    unknown = [n for n in names if n not in STUDIES]
    if unknown:
        raise _UsageError(f"unknown study {unknown[0]!r}; choose from {', '.join(STUDIES)} or all")
    out = _check_out(args.out)

    from .parallel import default_jobs, map_chunks

    todo = list(dict.fromkeys(names))
    jobs = default_jobs() if args.jobs is None else args.jobs
    # studies side by side in processes (each with its share of the cores), or one by one on a scheduler
    side_by_side = 1 if args.scheduler is not None else min(jobs, len(todo))
    # longest first (by the runtime of the previous output, unknown first): side by side, the run
    # then ends with the longest study instead of starting it last; summaries print in the asked order
    start = sorted(todo, key=lambda name: -_previous_runtime(out / name))
    tasks = [(name, str(out), args.runs, args.seed, args.quick, max(1, jobs // side_by_side), args.scheduler,
              1 + i % side_by_side if side_by_side > 1 else None) for i, name in enumerate(start)]
    if side_by_side > 1:  # import the studies (numpy, scipy, control, matplotlib) once, before the workers fork
        for name in todo:
            load_study(name)
    records = {r["name"]: r for r in map_chunks(_run_study, tasks, jobs=side_by_side, desc="studies", unit="study")}
    this_run: dict = {}
    failed: dict = {}
    for record in (records[name] for name in todo):
        name = record["name"]
        if record["error"] is not None:
            failed[name] = record["error"]
            sys.stderr.write(f"ctrl-analysis: error: study {name!r} failed: {failed[name]}\n")
            continue
        this_run[name] = record["run"]
        print(record["text"])
    # `all` writes REPORT.md; a partial run refreshes an existing one, so it never shows a study's old
    # numbers beside its new files (the studies not run now are marked stale there)
    if "all" in args.studies or (out / "REPORT.md").exists():
        results = []
        for name in STUDIES:
            p = out / name / "results.json"
            if p.exists():
                try:
                    results.append(json.loads(p.read_text(encoding="utf-8")))
                except (OSError, ValueError) as exc:
                    failed.setdefault(name, f"unreadable results.json: {_one_line(exc)}")
        try:
            print(f"\nreport: {write_report_md(results, out, this_run=this_run, failed=failed)}")
        except OSError as exc:  # e.g. a full disk: the previous REPORT.md stays as it was
            failed["REPORT.md"] = _one_line(exc)
            sys.stderr.write(f"ctrl-analysis: error: REPORT.md not written: {failed['REPORT.md']}\n")
    if failed:
        n_studies = sum(name != "REPORT.md" for name in failed)
        sys.stderr.write(f"ctrl-analysis: {n_studies} of {len(dict.fromkeys(names))} studies failed: "
                         f"{', '.join(failed)}\n")
        return 1
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit status.

    0 on success, 1 when a study failed (the others still ran; failures listed at the end), 2 on a
    bad command line (checked before any work), 130 on Ctrl-C (previous output left intact).
    ``reproduce all`` writes REPORT.md; reproducing some studies refreshes an existing REPORT.md,
    marking the studies not run now as stale.

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        The exit status.
    """
    try:
        args = _build_parser().parse_args(argv)
        if args.command == "list":
            from analysis import STUDIES, load_study

            for name in STUDIES:
                info = load_study(name).INFO
                print(f"{name:24s} {info.reproduces}")
            return 0
        if args.command == "arena":
            from .arena.cli import main as arena_main

            return arena_main(args)
        return _reproduce(args)
    except _UsageError as exc:
        sys.stderr.write(f"ctrl-analysis: error: {exc}\n")
        return 2
    except KeyboardInterrupt:
        sys.stderr.write("ctrl-analysis: interrupted; previous output left intact\n")
        return 130


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
