"""``ctrl-analysis arena``: the arena's subcommand (registered by :mod:`ctrl_analysis.cli`)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from .._validate import check_path

__all__ = ["add_parser", "main", "read_record"]


def add_parser(sub) -> argparse.ArgumentParser:
    """Register ``arena`` on the ``ctrl-analysis`` subparsers.

    Parameters
    ----------
    sub : argparse._SubParsersAction

    Returns
    -------
    argparse.ArgumentParser
    """
    p = sub.add_parser("arena", help="every estimator tuned fairly, scored against the bound")
    p.add_argument("--signal", default=None, metavar="F.csv",
                   help="tune on a recorded signal: CSV columns time, measurement[, true derivative]")
    p.add_argument("--noise-bound", type=float, default=None, metavar="E", help="noise bound ε of the record")
    p.add_argument("--accel-bound", type=float, default=None, metavar="L", help="bound L on |f''| of the record")
    p.add_argument("--out", default="figures", help="output directory (default: figures)")
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


def main(args) -> int:
    """Run ``ctrl-analysis arena`` with parsed ``args``; returns the exit status.

    Parameters
    ----------
    args : argparse.Namespace

    Returns
    -------
    int
        0 on success, 2 on bad input (one line on stderr).
    """
    from ..parallel import default_jobs

    try:
        jobs = default_jobs() if args.jobs is None else int(args.jobs)
        if jobs < 1:
            raise ValueError(f"--jobs must be >= 1, got {jobs}")
        if args.signal is not None:
            return _user(args, jobs)
        return _full(args, jobs)
    except ValueError as exc:
        sys.stderr.write(f"ctrl-analysis: error: {' '.join(str(exc).split())}\n")
        return 2


def _user(args, jobs) -> int:
    from .bound import lower_bound
    from .recommend import recommend_for_record

    for name, v in (("--noise-bound", args.noise_bound), ("--accel-bound", args.accel_bound)):
        if v is None or not np.isfinite(v) or v <= 0:
            raise ValueError(f"{name} must be given and > 0 with --signal, got {v}")
    t, y, d1 = read_record(args.signal)
    ranking = recommend_for_record(t, y, d1, args.noise_bound, args.accel_bound, jobs=jobs)
    b = lower_bound(args.noise_bound, args.accel_bound)
    print(f"bound 2√(εL) = {b:.4g}; " + ("scored on the given derivative" if d1 is not None else
                                         "no derivative given: scored on a zero-phase fit of the record plus uniform noise"))
    for i, r in enumerate(ranking, 1):
        params = ", ".join(f"{k} = {v:.4g}" for k, v in r["params"].items())
        print(f"{i}. {r['family']:10s} worst |f̂' - f'| = {r['worst']:.4g} ({r['ratio']:.2f}× bound)  {params}")
    w = ranking[0]
    print(f"recommendation: {w['label']} with {w['params']}: the smallest worst-case derivative error on this record.")
    return 0


def _full(args, jobs) -> int:
    from dataclasses import replace

    from ..reporting.atomic import staged_directory
    from ..reporting.report import StudyContext, write_results_json
    from .recommend import QUICK, default_settings, run_arena

    settings = QUICK if args.quick else default_settings()
    if args.runs is not None:
        if args.runs < 1:
            raise ValueError(f"--runs must be >= 1, got {args.runs}")
        settings = replace(settings, records=args.runs)
    if args.seed < 0:
        raise ValueError(f"--seed must be >= 0, got {args.seed}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    with staged_directory(out / "arena") as staged:
        from ..progress import write

        ctx = StudyContext(out_dir=staged, seed=args.seed, quick=args.quick, jobs=jobs, scheduler=args.scheduler,
                           progress=lambda m: write(f"[arena] {m}"))
        result, raw = run_arena(ctx, settings)
        result.runtime_s = time.perf_counter() - t0
        write_results_json(result, staged)
    print(f"arena: {out / 'arena' / 'results.json'} ({raw['tunings']} tunings, {result.runtime_s:.1f} s)")
    for f in result.findings:
        print("- " + f["text"])
    return 0
