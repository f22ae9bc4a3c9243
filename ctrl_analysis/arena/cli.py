"""``ctrl-analysis arena``: the arena's subcommand (registered by :mod:`ctrl_analysis.cli`)."""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from .._validate import check_out_dir, check_path

__all__ = ["add_parser", "check_args", "main", "read_record"]


def add_parser(sub) -> argparse.ArgumentParser:
    """Register ``arena`` on the ``ctrl-analysis`` subparsers.

    Parameters
    ----------
    sub : argparse._SubParsersAction

    Returns
    -------
    argparse.ArgumentParser
    """
    p = sub.add_parser("arena", help="every estimator tuned fairly, scored against the bound",
                       description="Which derivative estimator for my signal? Without --signal: the benchmark (every "
                                   "family tuned on the arena's signal classes and noises, the papers' claims judged) "
                                   "into OUT/arena. With --signal F.csv: every family tuned on your record, ranked by "
                                   "worst-case error against the bound 2√(εL), written to OUT/arena (results.json, "
                                   "REPORT.md, estimate.csv, figures).")
    p.add_argument("--signal", default=None, metavar="F.csv",
                   help="tune on a recorded signal: CSV columns time, measurement[, true derivative]")
    p.add_argument("--noise-bound", type=float, default=None, metavar="E",
                   help="bound ε on |noise| of the record (with --signal)")
    p.add_argument("--accel-bound", type=float, default=None, metavar="L",
                   help="bound L on |f''| of the record (with --signal)")
    p.add_argument("--out", default=None,
                   help="output directory; the results go to OUT/arena (default: figures, or arena-out with --signal, "
                        "so a record run never replaces the committed benchmark)")
    p.add_argument("--runs", type=int, default=None, help="records per case (default 3; 1 with --quick)")
    p.add_argument("--seed", type=int, default=0, help="base seed (default: 0)")
    p.add_argument("--quick", action="store_true", help="2 signal classes, 1 noise class, short records")
    p.add_argument("--jobs", type=int, default=None, help="processes (default: all cores)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS", help="Dask scheduler ('local' or tcp://...)")
    return p


def read_record(path) -> tuple:
    """Read a user's CSV record: ``(t, y, d1 or None)``.

    Parameters
    ----------
    path : str or Path
        CSV with a header row or none; columns time, measurement and optionally the true derivative.

    Returns
    -------
    tuple
        ``t``, ``y`` (N,), ``d1`` (N,) or ``None``.

    Raises
    ------
    TypeError
        If ``path`` is not a path.
    ValueError
        An empty path, an unreadable or non-UTF-8 file, fewer than two columns, fewer than 20 rows, a
        non-numeric or NaN value, time not strictly increasing or not uniformly sampled (within 1 %).
    """
    path = check_path("--signal path", path)
    where = f"--signal path {str(path)!r}"  # names the option and the argument
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ValueError(f"{where} cannot be read ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise ValueError(f"{where} is not a UTF-8 text (CSV) file") from None
    rows = [r for r in (line.strip() for line in text.splitlines()) if r]
    if rows and not _numeric(rows[0].split(",")[0]):
        rows = rows[1:]  # header
    try:
        data = [[float(v) for v in r.split(",")] for r in rows]
    except ValueError:
        raise ValueError(f"{where}: every value must be a number") from None
    widths = {len(r) for r in data}
    if not data or min(widths) < 2 or len(widths) != 1:
        raise ValueError(f"{where} must have the columns time, measurement[, derivative] on every row")
    a = np.array(data)
    if a.shape[0] < 20:
        raise ValueError(f"{where} must have at least 20 samples, got {a.shape[0]}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{where} contains NaN or infinite values")
    dt = np.diff(a[:, 0])
    if np.any(dt <= 0):
        raise ValueError(f"{where}: time must be strictly increasing (row {int(np.argmax(dt <= 0)) + 2})")
    if np.max(np.abs(dt - np.median(dt))) > 0.01 * np.median(dt):
        raise ValueError(f"{where}: time must be uniformly sampled (steps within 1 %)")
    return a[:, 0], a[:, 1], (a[:, 2] if a.shape[1] > 2 else None)


def _numeric(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def check_args(args) -> SimpleNamespace:
    """Every argument of ``ctrl-analysis arena`` checked before any heavy import; the resolved values.

    Parameters
    ----------
    args : argparse.Namespace

    Returns
    -------
    types.SimpleNamespace
        ``jobs``, ``out`` (created, writable), ``record`` (``(t, y, d1)`` of ``--signal`` or None).

    Raises
    ------
    ValueError
        Naming the argument and the rule.
    """
    from ..parallel import check_scheduler_address, default_jobs

    jobs = default_jobs() if args.jobs is None else int(args.jobs)
    if jobs < 1:
        raise ValueError(f"--jobs must be >= 1, got {jobs}")
    if args.runs is not None and args.runs < 1:
        raise ValueError(f"--runs must be >= 1, got {args.runs}")
    if args.seed < 0:
        raise ValueError(f"--seed must be >= 0, got {args.seed}")
    if args.scheduler is not None:
        check_scheduler_address(args.scheduler)
    bounds = (("--noise-bound", args.noise_bound), ("--accel-bound", args.accel_bound))
    if args.signal is None:
        given = [name for name, v in bounds if v is not None]
        if given:
            raise ValueError(f"{' and '.join(given)} describe a record: give them with --signal F.csv")
    else:
        for name, v in bounds:
            if v is None or not math.isfinite(v) or v <= 0:
                raise ValueError(f"{name} must be given, finite and > 0 with --signal, got {v}")
    record = read_record(args.signal) if args.signal is not None else None
    out = _check_out(args.out if args.out is not None else ("figures" if args.signal is None else "arena-out"))
    return SimpleNamespace(jobs=jobs, out=out, record=record)


def _check_out(text: str) -> Path:
    """The --out directory, created if needed; ValueError when it cannot hold results."""
    out = check_out_dir("--out", text)
    if (out / "arena").exists() and not (out / "arena").is_dir():
        raise ValueError(f"--out {text!r} holds a file named arena where the arena's folder goes")
    return out


def main(args, checked: SimpleNamespace | None = None) -> int:
    """Run ``ctrl-analysis arena`` with parsed ``args``; returns the exit status.

    Parameters
    ----------
    args : argparse.Namespace
    checked : types.SimpleNamespace, optional
        :func:`check_args`' result (checked here when not given).

    Returns
    -------
    int
        0 on success, 2 on bad input (one line on stderr).
    """
    try:
        checked = check_args(args) if checked is None else checked
        if checked.record is not None:
            return _user(args, checked)
        return _full(args, checked)
    except ValueError as exc:
        sys.stderr.write(f"ctrl-analysis: error: {' '.join(str(exc).split())}\n")
        return 2


def _user(args, checked) -> int:
    from ..progress import write
    from ..reporting.atomic import staged_directory, write_text_atomic
    from ..reporting.report import StudyContext, write_results_json
    from .record import report_lines, run_record

    t, y, d1 = checked.record
    out = checked.out
    t0 = time.perf_counter()
    with staged_directory(out / "arena") as staged:
        ctx = StudyContext(out_dir=staged, jobs=checked.jobs, progress=lambda m: write(f"[arena] {m}"))
        result, ranking = run_record(ctx, t, y, d1, args.noise_bound, args.accel_bound, source=str(args.signal))
        result.runtime_s = time.perf_counter() - t0
        write_results_json(result, staged)
        write_text_atomic(staged / "REPORT.md", "\n".join(report_lines(result.to_dict())) + "\n")
    s = result.settings
    print(f"bound 2√(εL) = {result.get('bound').value:.4g}; errors after a start-up window of "
          f"{s['startup_window_s']:.4g} s, scored on {s['scored_on']}")
    for i, r in enumerate(ranking, 1):
        params = ", ".join(f"{k} = {v:.4g}" for k, v in r["params"].items())
        print(f"{i}. {r['family']:10s} worst |f̂' - f'| = {r['worst']:.4g} ({r['ratio']:.2f}× bound)  {params}")
    w = ranking[0]
    print(f"recommendation: {w['label']} with {w['params']}: the smallest worst-case derivative error on this record.")
    print(f"arena: {out / 'arena'} (results.json, REPORT.md, estimate.csv, {len(result.figures)} figures; "
          f"{result.runtime_s:.1f} s)")
    return 0


def _full(args, checked) -> int:
    from dataclasses import replace

    from ..reporting.atomic import staged_directory
    from ..reporting.report import StudyContext, write_results_json
    from .recommend import QUICK, default_settings, run_arena

    settings = QUICK if args.quick else default_settings()
    if args.runs is not None:
        settings = replace(settings, records=args.runs)
    out = checked.out
    t0 = time.perf_counter()
    with staged_directory(out / "arena") as staged:
        from ..progress import write

        ctx = StudyContext(out_dir=staged, seed=args.seed, quick=args.quick, jobs=checked.jobs,
                           scheduler=args.scheduler, progress=lambda m: write(f"[arena] {m}"))
        result, raw = run_arena(ctx, settings)
        result.settings.update({"mode": "benchmark", "cli": {"seed": args.seed, "quick": bool(args.quick),
                                                              "runs": args.runs}})
        result.runtime_s = time.perf_counter() - t0
        write_results_json(result, staged)
    print(f"arena: {out / 'arena' / 'results.json'} ({raw['tunings']} tunings, {result.runtime_s:.1f} s)")
    for f in result.findings:
        print("- " + f["text"])
    return 0
