"""The ``ctrl-analysis`` command: list studies, reproduce them into figures/ and results.json."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from pathlib import Path

from .runs import _threads  # noqa: F401 - before the imports that load numpy: one BLAS thread per process

# isort: split
from .arena.report_section import arena_links, arena_section
from .reporting.atomic import (
    LockedError,
    exclusive_lock,
    new_staging,
    recover_staging,
    remove_tree,
)
from .reporting.formatting import one_line
from .reporting.markdown import summary_table
from .reporting.report import StudyContext, write_results_json
from .reporting.run_folder import RunFolder

__all__ = ["main"]


class _Parser(argparse.ArgumentParser):
    """argparse that reports a usage error as one line on stderr and exit status 2."""

    def error(self, message):
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


#: What ``--help`` says about the command (plain text: it is printed on a terminal, not rendered).
DESCRIPTION = "List the reproduced papers, and reproduce them into figures, results.json and REPORT.md."
EPILOG = """exit status: 0 done; 1 a study failed (the others still ran, the failures are listed at the end),
REPORT.md could not be written, or the Dask cluster failed mid-run (its scheduler lost, or no worker
connected for 60 s: the run stops in one line); 2 the command cannot run, checked before any work (an
unknown study, a bad --out, --runs beyond this machine's memory, a --scheduler that is malformed,
unreachable or not a Dask scheduler (10 s to answer), another run writing into the same --out);
130 interrupted with Ctrl-C (the previous output is left intact)."""


def _build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="ctrl-analysis", description=DESCRIPTION, epilog=EPILOG,
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    sub.add_parser("list", help="studies and what each reproduces", description="List the studies and what each "
                   "reproduces.")
    rep = sub.add_parser("reproduce", help="figures + results.json (+ REPORT.md for all)", epilog=EPILOG,
                         formatter_class=argparse.RawDescriptionHelpFormatter,
                         description="Reproduce studies into --out: each study's figures and results.json; "
                                     "'all' also writes REPORT.md, which is rebuilt from the results.json files "
                                     "on disk after every study.")
    rep.add_argument("studies", nargs="+", metavar="STUDY", help="study names, or 'all'")
    rep.add_argument("--out", default="figures", help="output directory (default: figures)")
    rep.add_argument("--runs", type=_positive_int, default=None, help="Monte Carlo runs where noise is random")
    rep.add_argument("--seed", type=_seed, default=0, help="base seed (default: 0)")
    rep.add_argument("--quick", action="store_true", help="fewer runs / shorter horizons, for smoke tests")
    rep.add_argument("--jobs", type=_positive_int, default=None,
                     help="processes: studies run side by side, Monte Carlo chunks split (default: all cores)")
    rep.add_argument("--verbose", "-v", action="store_true",
                     help="print every study's progress messages and its table of quantities (default: one line "
                          "per study; the tables are in REPORT.md and results.json)")
    rep.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="run every Monte Carlo batch and sweep on a Dask cluster: 'local' starts one on this "
                          "machine, or the address of a running scheduler, tcp://host:8786 (same numbers as a "
                          "local run)")
    # the arena's subcommand lives in its package
    from .arena.cli import add_parser as add_arena

    add_arena(sub)
    return parser


def _progress(study: str, verbose: bool = True):
    from .runs.progress import write

    def emit(msg: str) -> None:
        write(f"[{study}] {msg}")  # through tqdm when bars are drawn, so they stay intact

    return emit if verbose else (lambda msg: None)


def _check_out(text: str) -> Path:
    """The --out directory, created if needed; a one-line usage error when it cannot hold results."""
    from ._validate import check_out_dir

    try:
        return check_out_dir("--out", text)
    except (TypeError, ValueError) as exc:
        raise _UsageError(str(exc)) from None


class _UsageError(Exception):
    """A bad command line detected after parsing: one line, exit status 2."""


def _run_study(task) -> dict:
    """Run one study (here or in a worker process) into a fresh staging directory beside ``out/name``.

    The staged directory is complete when this returns; the main process moves it into place
    (:func:`_commit`). Returns a record with the study's name, its summary text, the staged path
    and ``error`` (one line, or ``None``); never raises for a study failure, so one failing study
    does not stop the others.
    """
    from .runs.progress import set_context

    name, out, runs, seed, quick, jobs, scheduler, position, verbose = task
    from .runs.taskpool import driver

    set_context(name, position)  # the study's own bars (long simulations) carry its name, on their own line
    try:
        with driver():
            return _run_study_here(name, Path(out), runs, seed, quick, jobs, scheduler, verbose)
    finally:
        set_context()


def _run_study_here(name, out, runs, seed, quick, jobs, scheduler, verbose=True) -> dict:
    from analysis import load_study

    from .runs.parallel import ClusterError, active_cluster
    from .runs.taskpool import trace_event

    record = {"name": name, "error": None, "text": "", "staged": None, "cluster": None,
              "run": {"seed": seed, "runs": runs, "quick": bool(quick)}}
    cluster = active_cluster()
    if cluster is not None and cluster["failed"] is not None:  # every batch would fail: not started
        record["error"], record["cluster"] = f"not run: the Dask cluster had failed: {cluster['failed']}", "not run"
        return record
    staged = new_staging(out / name)
    ctx = None
    try:
        ctx = StudyContext(out_dir=staged, runs=runs, seed=seed, quick=quick, progress=_progress(name, verbose),
                           jobs=jobs, scheduler=scheduler)
        t0, started, cpu = time.perf_counter(), time.time(), time.process_time()
        result = load_study(name).run(ctx, params=None)  # the study's chosen values (analysis/__init__.py)
        ctx.wait_figures()  # figures rendered in the run's pool (StudyContext.save_figure)
        result.runtime_s = time.perf_counter() - t0
        trace_event({"kind": "study", "study": name, "start": started, "end": time.time(), "cpu_start": cpu,
                     "cpu_end": time.process_time(), "jobs": jobs})
        # what the command line asked for, beside the study's own settings
        result.settings["cli"] = dict(record["run"])
        write_results_json(result, staged)
        data = result.to_dict()
    except Exception as exc:  # noqa: BLE001 - any study failure is reported in one line, never a traceback
        _settle(ctx)
        remove_tree(staged)
        record["error"] = one_line(exc)
        if isinstance(exc, ClusterError):
            record["cluster"] = "failed"
        return record
    except BaseException:
        _settle(ctx)
        remove_tree(staged)
        raise
    record["staged"] = str(staged)
    record["text"] = _study_lines(name, out, data, result.runtime_s, verbose)
    return record


def _settle(ctx) -> None:
    """Let a failed study's figures still being rendered end before its staging folder is removed."""
    if ctx is not None:
        with contextlib.suppress(Exception):
            ctx.wait_figures()


def _study_lines(name: str, out: Path, data: dict, runtime: float, verbose: bool) -> str:
    """What a finished study prints: one line of verdict counts (with --verbose also its quantities and gaps)."""
    from .reporting.claims import claim_counts
    from .reporting.markdown import not_reproduced, tally

    c, k = tally(data), claim_counts(data)
    line = (f"== {name}: {out / name / 'results.json'} ({len(data['figures'])} figures, {runtime:.1f} s): "
            f"claims {k['holds']} hold, {k['fails']} fail, {k['depends']} depend, {k['untestable']} untestable; "
            f"cells {c['agrees']} agree, {c['reachable']} reachable, {c['differs']} differ, {c['diverged']} diverged")
    gaps = not_reproduced(data)
    if not verbose:
        return line + (f"; not reproduced: {len(gaps)} (listed in REPORT.md)" if gaps else "")
    lines = ["", line]
    if data["quantities"]:
        lines.append(summary_table(data))
    if gaps:
        lines.append("not reproduced: " + "; ".join(gaps))
    return "\n".join(lines)


def _previous_runtime(study_dir: Path) -> float:
    """The wall time of the study already in ``study_dir`` (its timing.json; ``inf`` when unknown)."""
    from .reporting.report import read_runtime

    value = read_runtime(study_dir)
    return float("inf") if value is None else value


def _resolve_names(studies: list[str], registry) -> list[str]:
    """The studies asked for, in order, without repeats; ``all`` is every registered one."""
    unknown = [n for n in studies if n != "all" and n not in registry]
    if unknown:
        import difflib

        close = difflib.get_close_matches(unknown[0].lower().replace("_", "-"), [*registry, "all"], n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise _UsageError(f"unknown study {unknown[0]!r}; {hint}choose from {', '.join(registry)} or all")
    return list(registry) if "all" in studies else list(dict.fromkeys(studies))


def _check_targets(out: Path, names: list[str]) -> None:
    """Refuse (one line) to replace anything in ``out`` that ctrl-analysis did not write.

    A REPORT.md that is a folder or a link is refused too: the run would write every study and then
    fail to put its report in place.
    """
    report = out / "REPORT.md"
    if report.is_symlink() or (report.exists() and not report.is_file()):
        raise _UsageError(f"--out {str(out)!r} holds REPORT.md, which is not a file ctrl-analysis wrote (a "
                          f"{'link' if report.is_symlink() else 'folder'}); it is not replaced: move it away or "
                          f"choose another --out")
    for name in names:
        target = out / name
        if target.is_symlink() or (target.exists() and not target.is_dir()):
            raise _UsageError(f"--out {str(out)!r} holds {name!r}, which is not a folder ctrl-analysis wrote; "
                              f"it is not replaced: move it away or choose another --out")
        if target.is_dir() and not (target / "results.json").exists() and any(target.iterdir()):
            raise _UsageError(f"--out {str(out)!r} holds a folder {name!r} with files but no results.json, so "
                              f"ctrl-analysis did not write it; it is not replaced: move it away or choose another "
                              f"--out")


#: Resident memory of a process that has imported every study (numpy, scipy, control, matplotlib, numba):
#: 223 MiB, measured with ru_maxrss after ``load_study`` of the five studies.
_PROCESS_BYTES = 223 * 2**20


def _check_memory(names: list[str], runs: int | None, quick: bool, side_by_side: int) -> None:
    """Refuse (one line) a ``--runs`` whose Monte Carlo statistics would not fit in this machine's memory.

    The estimate is the registry's measured footprint (``analysis.MEMORY[study]["quick" | "full"]``:
    base bytes and bytes per run, from ``benchmarks/memory_per_run.py``) plus the process itself; the
    studies running side by side add up.
    """
    import analysis

    table = getattr(analysis, "MEMORY", {})
    if runs is None:
        return
    mode = "quick" if quick else "full"
    cost = {n: table[n][mode] for n in names if n in table and mode in table[n]}
    if not cost:
        return
    need = {n: _PROCESS_BYTES + base + per_run * runs for n, (base, per_run) in cost.items()}
    worst = sorted(need, key=need.get, reverse=True)[:side_by_side]
    total = sum(need[n] for n in worst)
    avail = _available_memory()
    if avail is not None and total > avail:
        per_run = max(cost[n][1] for n in worst)
        fixed = sum(_PROCESS_BYTES + cost[n][0] for n in worst)
        fits = max(0, int((avail - fixed) / max(1, sum(cost[n][1] for n in worst))))
        who = worst[0] if len(worst) == 1 else " + ".join(worst) + " side by side"
        raise _UsageError(f"--runs {runs} would need about {total / 2**30:.1f} GiB of memory ({who}; up to "
                          f"{per_run / 1e3:.0f} kB per run, measured), more than the {avail / 2**30:.1f} GiB "
                          f"available; use --runs {fits} or fewer" + (" or --jobs 1" if side_by_side > 1 else ""))


def _available_memory() -> float | None:
    """Bytes of memory available to new work (MemAvailable on Linux, else physical memory), or None."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return None


def _clean_report_temporaries(out: Path) -> None:
    """Remove ``.REPORT.md.*.tmp`` files a killed write left (only while the lock is held)."""
    for p in out.glob(".REPORT.md.*.tmp"):
        if p.is_file() and not p.is_symlink():
            with contextlib.suppress(OSError):
                p.unlink()


def _env_seconds(name: str, default: float) -> float:
    try:
        value = float(os.environ.get(name, default))
    except ValueError:
        value = default
    return value if value > 0 and value != float("inf") else default


def _scheduler_timeout() -> float:
    """Seconds --scheduler's address has to answer as a Dask scheduler (CTRL_ANALYSIS_SCHEDULER_TIMEOUT, 10)."""
    return _env_seconds("CTRL_ANALYSIS_SCHEDULER_TIMEOUT", 10.0)


def _worker_timeout() -> float:
    """Seconds a run waits while no Dask worker is connected (CTRL_ANALYSIS_WORKER_TIMEOUT, parallel.WORKER_TIMEOUT)."""
    from .runs.parallel import WORKER_TIMEOUT

    return _env_seconds("CTRL_ANALYSIS_WORKER_TIMEOUT", WORKER_TIMEOUT)


def _reproduce(args) -> int:
    from analysis import STUDIES, load_study

    t_start = time.perf_counter()
    todo = _resolve_names(args.studies, STUDIES)

    from .runs.parallel import check_scheduler_address, default_jobs, map_chunks, use_cluster

    if args.scheduler is not None:
        try:
            check_scheduler_address(args.scheduler)
        except ValueError as exc:
            raise _UsageError(f"--{exc}") from None
    jobs = default_jobs() if args.jobs is None else args.jobs
    # studies side by side in processes (each with its share of the cores), or one by one on a scheduler
    side_by_side = 1 if args.scheduler is not None else min(jobs, len(todo))
    _check_memory(todo, args.runs, args.quick, side_by_side)
    created = _missing_dirs(Path(args.out))
    try:
        return _reproduce_into(args, todo, jobs, side_by_side, t_start, STUDIES, load_study, map_chunks, use_cluster)
    finally:  # a run that wrote nothing (a refused --scheduler, say) leaves no folder it made behind
        _remove_if_empty(created)


def _reproduce_into(args, todo, jobs, side_by_side, t_start, STUDIES, load_study, map_chunks, use_cluster) -> int:
    out = _check_out(args.out)  # created here, after every check that needs no folder
    try:
        lock = exclusive_lock(out / ".ctrl-analysis.lock", what=f"--out {str(out)!r}")
        lock.__enter__()
    except LockedError as exc:
        raise _UsageError(str(exc)) from None
    run = RunFolder(out, report="all" in args.studies or (out / "REPORT.md").exists(), studies=list(STUDIES),
                    extra=arena_section, links=arena_links)
    lost = {}  # the studies the Dask cluster's failure stopped: name -> "failed" or "not run"
    try:
        recover_staging(out, list(STUDIES) + ["REPORT.md"])  # what a killed run left; nobody else writes here
        _clean_report_temporaries(out)
        _check_targets(out, todo)
        cluster = contextlib.nullcontext()
        if args.scheduler is not None:
            from .runs.parallel import silence_dask_logs

            silence_dask_logs()  # for good: a lost scheduler's client may still log after the cluster's block
            cluster = use_cluster(args.scheduler, jobs, timeout=_scheduler_timeout(),
                                  worker_timeout=_worker_timeout())
            try:
                cluster.__enter__()
            except (OSError, ValueError) as exc:
                raise _UsageError(f"--scheduler: {exc}") from None
        try:
            records = _run_studies(args, todo, out, jobs, side_by_side, run, load_study, map_chunks)
            dask, cluster_failed = _cluster_line()
        finally:
            cluster.__exit__(None, None, None)
        for record in records:
            name = record["name"]
            if record.get("cluster"):
                lost[name] = record["cluster"]
            elif record["error"] is not None:
                sys.stderr.write(f"ctrl-analysis: error: study {name!r} failed: {run.failed[name]}\n")
            else:
                print(record["text"])
        run.finish()
        for name, why in run.left_out.items():  # another study's results.json, not this run's: not a failure
            sys.stderr.write(f"ctrl-analysis: warning: REPORT.md leaves out {name}, not run now: {why}\n")
        if run.report_path is not None and run.report_error is None and args.verbose:
            print(f"\nreport: {run.report_path}")
        if lost:
            stopped = ", ".join(f"{name} {how}" for name, how in lost.items())
            sys.stderr.write(f"ctrl-analysis: error: the Dask cluster failed: {cluster_failed}; the run stopped: "
                             f"{stopped}\n")
        elif dask:
            print(dask)
    finally:
        recover_staging(out, list(STUDIES) + ["REPORT.md"])  # this run's staging, after an interrupt or crash
        lock.__exit__(None, None, None)
    failed = [name for name in todo if name in run.failed]
    if run.report_error is not None:
        where = "REPORT.md not written"
    elif run.report_path is not None:
        where = f"report: {run.report_path}"
    else:
        where = "no REPORT.md (written by reproduce all)"
    print(f"ctrl-analysis: {len(todo) - len(failed)} of {len(todo)} studies OK, {len(failed)} failed, "
          f"{time.perf_counter() - t_start:.1f} s; {where}")
    if any(name not in lost for name in failed):  # the cluster's line already names the studies it stopped
        sys.stderr.write(f"ctrl-analysis: {len(failed)} of {len(todo)} studies failed: {', '.join(failed)}\n")
    return 1 if failed or run.report_error is not None else 0


def _missing_dirs(path: Path) -> list[Path]:
    """``path`` and those of its parents that do not exist yet, deepest first (what creating it will make)."""
    missing = []
    path = path.absolute()
    while not path.exists() and not path.is_symlink() and path != path.parent:
        missing.append(path)
        path = path.parent
    return missing


def _remove_if_empty(dirs: list[Path]) -> None:
    """Remove the folders this run created, deepest first, each only if it is empty (``rmdir``)."""
    for d in dirs:
        try:
            d.rmdir()
        except OSError:
            return


def _run_studies(args, todo, out, jobs, side_by_side, run, load_study, map_chunks) -> list[dict]:
    """Run the studies (side by side in processes, or one by one here); each is committed as it finishes."""
    # longest first (by the runtime of the previous output, unknown first): side by side, the run
    # then ends with the longest study instead of starting it last; summaries print in the asked order
    start = sorted(todo, key=lambda name: -_previous_runtime(out / name))
    # with more cores than studies side by side, every study may use all of them: their chunks share one pool
    # (ctrl_analysis.runs.taskpool); with as many or fewer, each driver has its core and runs its chunks in place
    shared = side_by_side > 1 and jobs > side_by_side
    tasks = [(name, str(out), args.runs, args.seed, args.quick, jobs if shared else max(1, jobs // side_by_side),
              args.scheduler,
              1 + i % side_by_side if side_by_side > 1 else None, args.verbose) for i, name in enumerate(start)]
    pool = contextlib.nullcontext()
    if side_by_side > 1:  # import the studies (numpy, scipy, control, matplotlib) once, before the workers fork
        for name in todo:
            load_study(name)
    if shared:
        from .runs.taskpool import shared_pool

        pool = shared_pool(jobs)

    def commit(i, record):
        name = record["name"]
        if record["error"] is not None:
            run.failed[name] = record["error"]
            return
        try:
            run.commit(name, Path(record["staged"]))
        except (OSError, ValueError) as exc:
            record["error"] = run.failed[name] = one_line(exc)

    with pool:
        records = map_chunks(_run_study, tasks, jobs=side_by_side, scheduler=False, desc="studies", unit="study",
                             on_result=commit)
    by_name = {r["name"]: r for r in records}
    return [by_name[name] for name in todo]


def _cluster_line() -> tuple[str, str | None]:
    """The run's line on the Dask cluster (empty without one), and why the cluster failed (None if it did not)."""
    from .runs.parallel import active_cluster

    c = active_cluster()
    if c is None:
        return "", None
    return f"dask: {c['chunks']} chunks of Monte Carlo batches and sweeps ran on {c['address']}", c["failed"]


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit status.

    0 on success, 1 when a study failed (the others still ran; failures listed at the end), REPORT.md
    could not be written or the Dask cluster failed mid-run, 2 on a bad command line (checked before any
    work), 130 on Ctrl-C (previous output left intact).
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
            print(f"\n{'arena':24s} (ctrl-analysis arena [--signal F.csv]) which derivative estimator for a signal: "
                  "every family tuned fairly and ranked against the proven bound 2√(εL)")
            return 0
        if args.command == "arena":
            from .arena.cli import check_args
            from .arena.cli import main as arena_main

            try:
                checked = check_args(args)  # every argument, before the studies' heavy imports
            except ValueError as exc:
                raise _UsageError(" ".join(str(exc).split())) from None
            from analysis import arena_hooks

            arena_hooks.register()  # the studies' plant signals and the paper claims the arena judges
            return arena_main(args, checked)
        return _reproduce(args)
    except _UsageError as exc:
        sys.stderr.write(f"ctrl-analysis: error: {exc}\n")
        return 2
    except KeyboardInterrupt:
        sys.stderr.write("ctrl-analysis: interrupted; previous output left intact\n")
        return 130


def _exit(status: int) -> None:
    """Leave the process with ``status``; an interrupted run leaves with 130, never killed by SIGINT.

    Under ``python -m``, a KeyboardInterrupt that passed through an ``exec()`` of a string (dataclass
    and namedtuple creation, numba's compiler) sets CPython's "unhandled KeyboardInterrupt" flag even
    when :func:`main` caught it, and the interpreter then kills itself with SIGINT at exit (status -2,
    about 1 interrupt in 15). So after an interrupt the exit handlers are run here and the process
    leaves with 130 directly.
    """
    if status != 130:
        raise SystemExit(status)
    import atexit
    import os

    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(130)


if __name__ == "__main__":  # pragma: no cover
    _exit(main())
