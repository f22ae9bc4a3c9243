"""``ctrl-analysis arena``: the arena's subcommand (registered by :mod:`ctrl_analysis.cli`)."""

from __future__ import annotations

import argparse
import io
import math
import re
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
                   help="bound ε on |noise| of the record (with --signal; default: estimated from the record, "
                        "√3 times the spread of its third differences)")
    p.add_argument("--accel-bound", type=float, default=None, metavar="L",
                   help="bound L on |f''| of the record (with --signal; default: estimated from the record, the "
                        "curvature its smoothed second differences show beyond its noise)")
    p.add_argument("--channels", action="store_true",
                   help="with --signal: every column after time is a measurement channel (no derivative column), "
                        "each ranked on its own into OUT/arena/<column name>")
    p.add_argument("--out", default=None,
                   help="output directory; the results go to OUT/arena (default: figures, or arena-out with --signal, "
                        "so a record run never replaces the committed benchmark)")
    p.add_argument("--runs", type=int, default=None, help="records per case, 1 to 1000 (default 3; 1 with --quick)")
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
        An empty path, not a regular file (``/dev/zero``, a FIFO, a folder), a file over
        :data:`~.recordcheck.MAX_FILE_BYTES` or with over :data:`~.recordcheck.MAX_ROWS` rows, an unreadable
        or non-UTF-8 file, fewer than two columns, fewer than 20 rows, a non-numeric or NaN value, time not
        strictly increasing or not uniformly sampled (within 1 %).

    Notes
    -----
    A UTF-8 byte-order mark at the start of the file is skipped (it would otherwise make the first row look
    like a header and drop it).
    """
    header, a, where = _read_table(path)
    if a.shape[1] > 3:
        raise ValueError(f"{where} has {a.shape[1]} columns: a record is time, measurement[, derivative]; for several "
                         "measurement channels, each ranked on its own, add --channels")
    return a[:, 0], a[:, 1], (a[:, 2] if a.shape[1] > 2 else None)


def read_channels(path) -> tuple:
    """Read a CSV of several measurement channels: ``(t, names, Y)``, every column after time a channel.

    Parameters
    ----------
    path : str or Path
        CSV with a header row (the channels' names) or none (``channel1``, ``channel2``, ...).

    Returns
    -------
    tuple
        ``t`` (N,), ``names`` (list of str, usable as folder names, distinct), ``Y`` (N, C).

    Raises
    ------
    TypeError, ValueError
        As :func:`read_record`.
    """
    header, a, where = _read_table(path)
    names = []
    for i in range(1, a.shape[1]):
        raw = header[i].strip() if header is not None and i < len(header) else ""
        name = re.sub(r"[^A-Za-z0-9_.-]+", "_", raw).strip("._") or f"channel{i}"
        while name in names:
            name += f"_{i}"
        names.append(name)
    return a[:, 0], names, a[:, 1:]


def _read_table(path) -> tuple:
    """``(header fields or None, rows (N, columns), where)`` of a record CSV, every check of :func:`read_record` but
    the number of columns (at least two)."""
    from .recordcheck import MAX_ROWS, check_file

    path = check_path("--signal path", path)
    where = f"--signal path {str(path)!r}"  # names the option and the argument
    check_file(path, where)
    try:
        text = path.read_text(encoding="utf-8-sig")  # -sig: a byte-order mark is not part of the first row
    except OSError as exc:
        raise ValueError(f"{where} cannot be read ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise ValueError(f"{where} is not a UTF-8 text (CSV) file") from None
    if text.count("\n") > MAX_ROWS:  # counted before the rows are split into lists
        n = sum(1 for line in io.StringIO(text) if line.strip())
        n -= 0 if _numeric(text.lstrip().split("\n", 1)[0].split(",")[0]) else 1  # a header
        if n > MAX_ROWS:
            raise ValueError(f"{where} has {n} rows, over the limit of {MAX_ROWS}: decimate the record (keep every "
                             "k-th row) or cut it")
    rows = [r for r in (line.strip() for line in text.splitlines()) if r]
    header = None
    if rows and not _numeric(rows[0].split(",")[0]):
        header, rows = rows[0].split(","), rows[1:]
    try:
        data = [[float(v) for v in r.split(",")] for r in rows]
    except ValueError:
        raise ValueError(f"{where}: every value must be a number") from None
    widths = {len(r) for r in data}
    if not data or min(widths) < 2 or len(widths) != 1:
        raise ValueError(f"{where} must have the columns time, measurement[, derivative] on every row")
    a = np.array(data)
    if a.shape[0] > MAX_ROWS:
        raise ValueError(f"{where} has {a.shape[0]} rows, over the limit of {MAX_ROWS}: decimate the record (keep "
                         "every k-th row) or cut it")
    if a.shape[0] < 20:
        raise ValueError(f"{where} must have at least 20 samples, got {a.shape[0]}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{where} contains NaN or infinite values")
    dt = np.diff(a[:, 0])
    if np.any(dt <= 0):
        raise ValueError(f"{where}: time must be strictly increasing (row {int(np.argmax(dt <= 0)) + 2})")
    if np.max(np.abs(dt - np.median(dt))) > 0.01 * np.median(dt):
        raise ValueError(f"{where}: time must be uniformly sampled (steps within 1 %)")
    return header, a, where


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
        ``jobs``, ``out`` (created, writable), ``record`` (``(t, y, d1)`` of ``--signal`` or None),
        ``record_check`` (:func:`~.recordcheck.check_record`'s result, or None), ``eps`` and ``L`` (the bounds:
        stated, or estimated from the record where not given, :func:`~.recordcheck.estimated_bounds`) and
        ``bounds_source`` (``{"noise_bound": "stated" | "estimated from the record", "accel_bound": ...}``);
        with ``--channels``, ``channels``: one namespace per channel (``name``, ``record``, ``record_check``, ``eps``,
        ``L``, ``bounds_source``), each checked on its own, and ``record`` None.

    Raises
    ------
    ValueError
        Naming the argument and the rule: with ``--signal`` also a record whose bounds it contradicts, whose
        arithmetic would not stay finite, or whose tuning would cost more work or memory than the limits
        (:mod:`.recordcheck`).
    """
    from ..runs.parallel import check_scheduler_address, default_jobs
    from .recordcheck import MAX_RECORDS

    jobs = default_jobs() if args.jobs is None else int(args.jobs)
    if jobs < 1:
        raise ValueError(f"--jobs must be >= 1, got {jobs}")
    if args.runs is not None and not 1 <= args.runs <= MAX_RECORDS:
        raise ValueError(f"--runs must be in 1..{MAX_RECORDS} (records per case), got {args.runs}")
    if args.seed < 0:
        raise ValueError(f"--seed must be >= 0, got {args.seed}")
    if args.scheduler is not None:
        check_scheduler_address(args.scheduler)
    bounds = (("--noise-bound", args.noise_bound), ("--accel-bound", args.accel_bound))
    if args.signal is None:
        given = [name for name, v in bounds if v is not None]
        if given:
            raise ValueError(f"{' and '.join(given)} " + ("describe a record: give them" if len(given) > 1 else
                                                         "describes a record: give it") + " with --signal F.csv")
    else:
        for name, v in bounds:
            if v is not None and (not math.isfinite(v) or v <= 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
    channels = bool(getattr(args, "channels", False))
    if channels and args.signal is None:
        raise ValueError("--channels describes a record's columns: give it with --signal F.csv")
    none = {"record": None, "record_check": None, "eps": None, "L": None, "bounds_source": {}}
    where = f"--signal path {str(args.signal)!r}"
    if args.signal is None:
        found = SimpleNamespace(channels=[], **none)
    elif not channels:
        found = SimpleNamespace(channels=[], **vars(_checked_record(read_record(args.signal), args, where)))
    else:
        t, names, Y = read_channels(args.signal)
        found = SimpleNamespace(channels=[SimpleNamespace(name=n, **vars(_checked_record((t, Y[:, i], None), args,
                                                                                          f"{where}, channel {n!r}")))
                                          for i, n in enumerate(names)], **none)
    # the output folder is made only once everything else is accepted
    found.out = _check_out(args.out if args.out is not None else ("figures" if args.signal is None else "arena-out"))
    found.jobs = jobs
    return found


def _checked_record(record, args, where) -> SimpleNamespace:
    """One record's bounds (stated, or estimated where not given) and its :func:`~.recordcheck.check_record`."""
    from .recordcheck import check_record, estimated_bounds

    eps, L = args.noise_bound, args.accel_bound
    if eps is None or L is None:
        try:
            est = estimated_bounds(*record)
        except ValueError as exc:
            raise ValueError(f"{where}: {exc} (--noise-bound / --accel-bound)") from None
        eps = est["noise_bound"] if eps is None else eps
        L = est["accel_bound"] if L is None else L
    source = {"noise_bound": "stated" if args.noise_bound is not None else "estimated from the record",
              "accel_bound": "stated" if args.accel_bound is not None else "estimated from the record"}
    check = check_record(*record, eps, L, where=where, names=("--noise-bound", "--accel-bound"))
    return SimpleNamespace(record=record, record_check=check, eps=eps, L=L, bounds_source=source)


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
        if getattr(checked, "channels", None):
            for ch in checked.channels:  # each channel ranked on its own, in its own folder
                print(f"== channel {ch.name}")
                _user(args, SimpleNamespace(jobs=checked.jobs, out=checked.out, **vars(ch)), f"arena/{ch.name}")
            return 0
        if checked.record is not None:
            return _user(args, checked)
        return _full(args, checked)
    except ValueError as exc:
        sys.stderr.write(f"ctrl-analysis: error: {' '.join(str(exc).split())}\n")
        return 2


def _user(args, checked, folder: str = "arena") -> int:
    from ..reporting.atomic import staged_directory, write_text_atomic
    from ..reporting.report import StudyContext, write_results_json
    from ..runs.progress import write
    from .record import report_lines, run_record

    t, y, d1 = checked.record
    out = checked.out
    check = getattr(checked, "record_check", None)
    for w in (check or {}).get("warnings", []):
        sys.stderr.write(f"ctrl-analysis: warning: {w}\n")
    t0 = time.perf_counter()
    with staged_directory(out / folder) as staged:
        ctx = StudyContext(out_dir=staged, jobs=checked.jobs, progress=lambda m: write(f"[arena] {m}"))
        result, ranking = run_record(ctx, t, y, d1, checked.eps, checked.L, source=str(args.signal),
                                     check=check, bounds_source=checked.bounds_source)
        result.runtime_s = time.perf_counter() - t0
        write_results_json(result, staged)
        write_text_atomic(staged / "REPORT.md", "\n".join(report_lines(result.to_dict())) + "\n")
    s = result.settings
    print(f"bound 2√(εL) = {result.get('bound').value:.4g}; errors after a start-up window of "
          f"{s['startup_window_s']:.4g} s, scored on {s['scored_on']}")
    e = s["record_check"]["estimates"]
    src = checked.bounds_source
    if "estimated" in src["noise_bound"] or "estimated" in src["accel_bound"]:
        print(f"ε = {checked.eps:.4g} ({src['noise_bound']}: √3 × the spread of its third differences; for "
              f"Gaussian noise that is √3 σ, not a bound), L = {checked.L:.4g} ({src['accel_bound']}: a lower "
              "estimate of max |f''|); --noise-bound / --accel-bound override them. The bound 2√(εL) and the ratios "
              "to it rest on these estimates.")
    else:
        print(f"stated ε = {checked.eps:.4g}, L = {checked.L:.4g}; the record's own estimates: ε ≈ "
              f"{e['noise_bound']:.4g}, |f''| ≈ {e['accel']:.4g}"
              + ("" if e["accel"] > 0 else " (none beyond its noise)"))
    for i, r in enumerate(ranking, 1):
        params = ", ".join(f"{k} = {v:.4g}" for k, v in r["params"].items())
        print(f"{i}. {r['family']:10s} worst |f̂' - f'| = {r['worst']:.4g} ({r['ratio']:.2f}× bound)  {params}")
    off = result.settings.get("offline_families") or []
    if off:
        print("offline smoothers (the whole record, not a filter):")
        for i, name in enumerate(sorted(off, key=lambda n: result.get(f"{n}.worst").value), 1):
            print(f"{i}. {name:10s} worst |f̂' - f'| = {result.get(f'{name}.worst').value:.4g} "
                  f"({result.get(f'{name}.ratio').value:.2f}× bound)  {result.get(f'{name}.worst').note}")
        print(f"price of causality on this record: {result.get('price_of_causality.worst').value:.3g}× (worst case), "
              f"{result.get('price_of_causality.rms').value:.3g}× (RMS)")
    if any(x.id == "reference.difference_quotient.worst" for x in result.quantities):
        dq = result.get("reference.difference_quotient.worst")
        print(f"reference (not tuned): {dq.label.split(': ', 1)[1]} = {dq.value:.4g} ({dq.note})")
    w = ranking[0]
    print(f"recommendation: {w['label']} with {w['params']}: the smallest worst-case derivative error on this record "
          "among the causal filters (for the derivative of the recorded signal itself, the offline smoothers above).")
    print(f"arena: {out / folder} (results.json, REPORT.md, estimate.csv, {len(result.figures)} figures; "
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
    t0, started, cpu = time.perf_counter(), time.time(), time.process_time()
    with staged_directory(out / "arena") as staged:
        from ..runs.progress import _CONTEXT, write
        from ..runs.taskpool import trace_event

        ctx = StudyContext(out_dir=staged, seed=args.seed, quick=args.quick, jobs=checked.jobs,
                           scheduler=args.scheduler, progress=lambda m: write(f"[arena] {m}"))
        result, raw = run_arena(ctx, settings)
        result.settings.update({"mode": "benchmark", "cli": {"seed": args.seed, "quick": bool(args.quick),
                                                              "runs": args.runs}})
        result.runtime_s = time.perf_counter() - t0
        write_results_json(result, staged)
        # the whole command as one traced study (benchmarks/scaling.py): its maps carry this process's bar label
        trace_event({"kind": "study", "study": _CONTEXT["label"], "start": started, "end": time.time(),
                     "cpu_start": cpu, "cpu_end": time.process_time(), "jobs": checked.jobs})
    print(f"arena: {out / 'arena' / 'results.json'} ({raw['tunings']} tunings, {result.runtime_s:.1f} s)")
    for f in result.findings:
        print("- " + f["text"])
    return 0
