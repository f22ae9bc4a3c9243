"""Plan past this machine: replay a recorded run's tasks on 1-64 workers (issue 30, item 5).

Record a real run, then replay its schedule::

    python benchmarks/scaling.py record --trace /tmp/trace -- reproduce all --out /tmp/out --jobs 2
    python benchmarks/scaling.py replay /tmp/trace --workers 1 2 4 8 16 32 64

``record`` runs ``ctrl-analysis`` with ``CTRL_ANALYSIS_TRACE`` set (:mod:`ctrl_analysis.runs.taskpool`): every process
appends each study's start and end and each ``map_chunks`` call with its calls' start and end. It prints the
run's wall time. ``replay`` rebuilds each study as a chain: a serial stretch of its driver (everything between
two maps: set-up, figures, linear analysis, sweeps evaluated one after another), then a map (its calls, any
order), then the next serial stretch, and so on. It schedules these on ``W`` workers as the command does now:
``min(W, studies)`` drivers side by side, longest study first, and one pool in which the drivers' serial
stretches and every study's calls wait in one queue, first ready first served (the shared pool of
``ctrl_analysis.runs.taskpool``). It prints the predicted wall time and speed-up per worker count, the critical
path (the longest study with unlimited workers: its serial stretches plus its longest call per map) and the
serial fraction (the drivers' serial time over all the work). A figure the driver sent to the pool to be
rendered (``StudyContext.save_figure``) is an async phase: its call waits in the same queue, the driver goes
on, and the study ends when its driver and its figures have.

What the model leaves out: a call's duration is taken as recorded (no contention for memory bandwidth, no
compile time that more processes would repeat or share), and the time to send a call and its result. Check it
against a real run on the machine that recorded it (``--check SECONDS``: the recorded wall time).
"""

from __future__ import annotations

import argparse
import heapq
import json
import os
import subprocess
import sys
import time
from pathlib import Path


def load(folder: str, clock: str = "cpu") -> dict:
    """The trace's studies: name -> list of phases, ``("serial", seconds)`` or ``("map", [seconds, ...])``.

    ``clock="cpu"`` takes each piece's CPU seconds (a trace recorded with more processes than cores),
    ``"wall"`` its wall-clock seconds.
    """
    events = []
    for f in sorted(Path(folder).glob("*.jsonl")):
        events += [json.loads(line) for line in f.open(encoding="utf-8") if line.strip()]
    studies = {e["study"]: (e["start"], e["end"]) for e in events if e["kind"] == "study"}
    maps: dict = {}
    for e in events:
        if e["kind"] == "map" and e["study"] in studies:
            maps.setdefault(e["study"], []).append(e)
    if not studies:  # a run without studies (the arena): its maps, from the first to the last
        ms = [e for e in events if e["kind"] == "map"]
        if not ms:
            raise SystemExit(f"no study and no map in the trace {folder}")
        studies = {"run": (min(e["submitted"] for e in ms), max(e["returned"] for e in ms))}
        maps = {"run": ms}
    cpu = {e["study"]: (e["cpu_start"], e["cpu_end"]) for e in events if e["kind"] == "study" and "cpu_start" in e}
    chains = {}
    for name, (start, end) in studies.items():
        phases, t, c = [], start, cpu.get(name, (None,))[0]
        for m in sorted(maps.get(name, []), key=lambda e: e["submitted"]):
            calls = [(x[2] if clock == "cpu" else x[1] - x[0]) for x in m["calls"]]
            if clock == "cpu" and c is not None:
                phases.append(("serial", max(0.0, m["cpu_submitted"] - c)))
                c = m["cpu_returned"]
            elif m["submitted"] >= t:
                phases.append(("serial", m["submitted"] - t))
            # a figure rendered in the pool: the driver goes on without waiting (StudyContext.save_figure)
            phases.append(("async" if m.get("async") else "map", calls))
            t = max(t, m["submitted"] if m.get("async") else m["returned"])
        if clock == "cpu" and c is not None:
            phases.append(("serial", max(0.0, cpu[name][1] - c)))
        else:
            phases.append(("serial", max(0.0, end - t)))
        chains[name] = phases
    return chains


def replay(chains: dict, workers: int) -> float:
    """Predicted wall time of the chains on ``workers`` workers (see the module docstring)."""
    order = sorted(chains, key=lambda n: -sum(_work(p) for p in chains[n]))
    waiting = list(order)
    drivers = min(workers, len(order))
    ready: list = []  # (ready time, sequence, study, phase index, duration)
    running: list = []  # (end time, sequence, study, phase index)
    left: dict = {}  # (study, phase) -> calls of a map not yet done
    rendering = dict.fromkeys(chains, 0)  # study -> its async calls (figures) not yet done
    ended: set = set()  # studies whose driver has run its last phase
    seq = 0
    t = 0.0

    def finish(name, at):
        if name in ended and not rendering[name] and waiting:  # this driver takes the next study
            ended.discard(name)
            push(waiting.pop(0), 0, at)

    def push(name, k, at):
        nonlocal seq
        if k >= len(chains[name]):
            ended.add(name)
            finish(name, at)  # the driver waits for its study's figures, then takes the next study
            return
        kind, what = chains[name][k]
        if kind == "serial":
            heapq.heappush(ready, (at, seq, name, k, what))
            seq += 1
        elif kind == "async":
            rendering[name] += len(what)
            for d in what:
                heapq.heappush(ready, (at, seq, name, k, d))
                seq += 1
            push(name, k + 1, at)
        elif not what:
            push(name, k + 1, at)
        else:
            left[(name, k)] = len(what)
            for d in what:
                heapq.heappush(ready, (at, seq, name, k, d))
                seq += 1

    for _ in range(drivers):
        push(waiting.pop(0), 0, 0.0)
    free = workers
    while ready or running:
        while free and ready:
            _, s, name, k, d = heapq.heappop(ready)
            heapq.heappush(running, (t + d, s, name, k))
            free -= 1
        t, _, name, k = heapq.heappop(running)
        free += 1
        if chains[name][k][0] == "serial":
            push(name, k + 1, t)
        elif chains[name][k][0] == "async":
            rendering[name] -= 1
            finish(name, t)
        else:
            left[(name, k)] -= 1
            if not left[(name, k)]:
                push(name, k + 1, t)
    return t


def _work(phase) -> float:
    return phase[1] if phase[0] == "serial" else sum(phase[1])


def critical_path(chains: dict) -> float:
    """The longest study with unlimited workers: its serial stretches and its longest call per map.

    An async call (a figure rendered in the pool) starts where the driver sent it and may end after it.
    """
    def length(phases):
        t = end = 0.0
        for kind, what in phases:
            if kind == "async":
                end = max(end, t + max(what, default=0.0))
            else:
                t += what if kind == "serial" else max(what, default=0.0)
        return max(t, end)

    return max(length(ph) for ph in chains.values())


def summary(chains: dict, workers: list[int], check: float | None = None) -> str:
    """The table ``replay`` prints."""
    total = sum(_work(p) for ph in chains.values() for p in ph)
    serial = sum(p[1] for ph in chains.values() for p in ph if p[0] == "serial")
    calls = sum(len(p[1]) for ph in chains.values() for p in ph if p[0] != "serial")
    times = {w: replay(chains, w) for w in workers}
    base = times[min(workers)]
    lines = [f"{len(chains)} studies, {calls} calls, work {total:.1f} s (of it the drivers' serial stretches "
             f"{serial:.1f} s, {serial / total:.0%}); critical path {critical_path(chains):.1f} s",
             "", f"| workers | predicted s | speed-up vs {min(workers)} |", "| ---: | ---: | ---: |"]
    lines += [f"| {w} | {times[w]:.1f} | {base / times[w]:.2f}x |" for w in workers]
    if check is not None:
        w = min(workers)
        lines.append(f"\nrecorded wall time {check:.1f} s; predicted at {w} workers {times[w]:.1f} s "
                     f"({times[w] / check:.2f}x of it)")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="verb", required=True)
    rec = sub.add_parser("record", help="run ctrl-analysis with the trace on")
    rec.add_argument("--trace", required=True, help="folder for the trace (emptied first)")
    rec.add_argument("command", nargs=argparse.REMAINDER, help="-- then ctrl-analysis's arguments")
    rep = sub.add_parser("replay", help="replay a trace on other worker counts")
    rep.add_argument("trace")
    rep.add_argument("--workers", type=int, nargs="+", default=[1, 2, 4, 8, 16, 32, 64])
    rep.add_argument("--check", type=float, default=None, help="a real run's wall time at the fewest workers, s")
    rep.add_argument("--clock", choices=("cpu", "wall"), default="cpu",
                     help="cost each piece by its CPU seconds (default) or its wall-clock seconds")
    args = p.parse_args(argv)
    if args.verb == "record":
        folder = Path(args.trace)
        folder.mkdir(parents=True, exist_ok=True)
        for f in folder.glob("*.jsonl"):
            f.unlink()
        cmd = [a for a in args.command if a != "--"]
        env = dict(os.environ, CTRL_ANALYSIS_TRACE=str(folder), OPENBLAS_NUM_THREADS="1")
        t0 = time.perf_counter()
        rc = subprocess.run([sys.executable, "-m", "ctrl_analysis.cli", *cmd], env=env).returncode
        print(f"wall {time.perf_counter() - t0:.1f} s, exit {rc}; trace in {folder}")
        return rc
    print(summary(load(args.trace, args.clock), sorted(set(args.workers)), args.check))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
