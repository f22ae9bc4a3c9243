"""The ``ctrl-analysis`` command: list studies, reproduce them into figures/ and results.json."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from .report import StudyContext, summary_table, write_report_md, write_results_json

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
    return parser


def _progress(study: str):
    def emit(msg: str) -> None:
        sys.stderr.write(f"[{study}] {msg}\n")
        sys.stderr.flush()

    return emit


def _run_study(task) -> tuple[int, str]:
    """Run one study (in this process or a worker) and write its results.json; (status, summary text)."""
    from analysis import load_study

    name, study_dir, runs, seed, quick, jobs, scheduler = task
    study_dir = Path(study_dir)
    ctx = StudyContext(out_dir=study_dir, runs=runs, seed=seed, quick=quick, progress=_progress(name),
                       jobs=jobs, scheduler=scheduler)
    t0 = time.perf_counter()
    try:
        result = load_study(name).run(ctx)
    except (ValueError, TypeError, RuntimeError, ArithmeticError, MemoryError) as exc:
        sys.stderr.write(f"ctrl-analysis: error: study {name!r} failed: {exc}\n")
        return 1, ""
    result.runtime_s = time.perf_counter() - t0
    path = write_results_json(result, study_dir)
    data = result.to_dict()
    lines = [f"\n== {name}: {path} ({len(result.figures)} figures, {result.runtime_s:.1f} s)"]
    if data["quantities"]:
        lines.append(summary_table(data))
    if result.missing:
        lines.append("not built yet: " + "; ".join(result.missing))
    return 0, "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit status."""
    from analysis import STUDIES, load_study

    args = _build_parser().parse_args(argv)
    if args.command == "list":
        for name in STUDIES:
            info = load_study(name).INFO
            print(f"{name:24s} {info.reproduces}")
        return 0

    names = list(STUDIES) if "all" in args.studies else args.studies
    unknown = [n for n in names if n not in STUDIES]
    if unknown:
        sys.stderr.write(
            f"ctrl-analysis: error: unknown study {unknown[0]!r}; choose from {', '.join(STUDIES)} or all\n"
        )
        return 2

    from .parallel import default_jobs, map_chunks

    out = Path(args.out)
    todo = list(dict.fromkeys(names))
    jobs = default_jobs() if args.jobs is None else args.jobs
    # studies side by side in processes (each with its share of the cores), or one by one on a scheduler
    side_by_side = 1 if args.scheduler is not None else min(jobs, len(todo))
    tasks = [(name, str(out / name), args.runs, args.seed, args.quick, max(1, jobs // side_by_side),
              args.scheduler) for name in todo]
    status = 0
    for study_status, text in map_chunks(_run_study, tasks, jobs=side_by_side, desc="studies"):
        status = max(status, study_status)
        if text:
            print(text)
    if "all" in args.studies:
        results = []
        for name in STUDIES:
            p = out / name / "results.json"
            if p.exists():
                results.append(json.loads(p.read_text(encoding="utf-8")))
        print(f"\nreport: {write_report_md(results, out)}")
    return status


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
