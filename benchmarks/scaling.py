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
on, and the study ends when its driver and its figures have. Chains a driver advances side by side
(``ctrl_analysis.runs.chains.drive``, e.g. the arena's families) are a fan: each lane's maps and its own
serial stretches (its thread's CPU) follow one another, the lanes independently, and the driver goes on when
every lane has ended; a lane's calls wait with its priority (lower first, as the pool serves them).

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


class Lane(list):
    """One chain of a fan: its phases, and its calls' priority in the pool (lower first)."""

    priority = 0


def _lane(maps: list, lane: dict, clock: str) -> list:
    """One chain of a fan (``drive``'s thread): its own serial stretches (its thread's CPU) and its maps."""
    phases = Lane()
    phases.priority = lane.get("priority", 0)
    c = lane["tcpu_start"] if clock == "cpu" else lane["start"]
    for m in sorted(maps, key=lambda e: e["submitted"]):
        phases.append(("serial", max(0.0, (m["tcpu_submitted"] if clock == "cpu" else m["submitted"]) - c)))
        phases.append(("async" if m.get("async") else "map", [(x[2] if clock == "cpu" else x[1] - x[0])
                                                              for x in m["calls"]]))
        c = m["tcpu_returned"] if clock == "cpu" else (m["submitted"] if m.get("async") else m["returned"])
    phases.append(("serial", max(0.0, (lane["tcpu_end"] if clock == "cpu" else lane["end"]) - c)))
    return phases


def load(folder: str, clock: str = "cpu") -> dict:
    """The trace's studies: name -> list of phases.

    A phase is ``("serial", seconds)``, ``("map", [seconds, ...])``, ``("async", [seconds, ...])`` (calls the
    driver does not wait for) or ``("fan", [phases, ...])`` (chains advanced side by side by
    ``ctrl_analysis.runs.chains.drive``, each a list of phases; the driver goes on when all have ended).
    ``clock="cpu"`` takes each piece's CPU seconds (a trace recorded with more processes than cores),
    ``"wall"`` its wall-clock seconds.
    """
    events = []
    for f in sorted(Path(folder).glob("*.jsonl")):
        events += [json.loads(line) for line in f.open(encoding="utf-8") if line.strip()]
    studies = {e["study"]: (e["start"], e["end"]) for e in events if e["kind"] == "study"}
    fans: dict = {}  # fan id -> {lane: (lane event, [maps])}
    for e in events:
        if e["kind"] == "lane":
            fans.setdefault(e["fan"], {}).setdefault(e["lane"], [None, []])[0] = e
    for e in events:
        if e["kind"] == "map" and "fan" in e:
            fans.setdefault(e["fan"], {}).setdefault(e["lane"], [None, []])[1].append(e)
    items: dict = {}  # study -> its maps and fans, in the order the driver sent them
    for e in events:
        if (e["kind"] == "map" and "fan" not in e) or e["kind"] == "fan":
            items.setdefault(e["study"], []).append(e)
    if not studies:  # a run without studies: its maps, from the first to the last
        ms = [e for st in items.values() for e in st]
        if not ms:
            raise SystemExit(f"no study and no map in the trace {folder}")
        studies = {"run": (min(e["submitted"] for e in ms), max(e["returned"] for e in ms))}
        items = {"run": ms}
    cpu = {e["study"]: (e["cpu_start"], e["cpu_end"]) for e in events if e["kind"] == "study" and "cpu_start" in e}
    chains = {}
    for name, (start, end) in studies.items():
        phases, t, c = [], start, cpu.get(name, (None,))[0]
        for m in sorted(items.get(name, []), key=lambda e: e["submitted"]):
            if clock == "cpu" and c is not None:
                phases.append(("serial", max(0.0, m["cpu_submitted"] - c)))
                c = m["cpu_returned"]
            elif m["submitted"] >= t:
                phases.append(("serial", m["submitted"] - t))
            if m["kind"] == "fan":
                phases.append(("fan", [_lane(maps, lane, clock) for lane, maps in fans[m["fan"]].values()]))
            else:  # a figure rendered in the pool is async: the driver goes on (StudyContext.save_figure)
                phases.append(("async" if m.get("async") else "map",
                               [(x[2] if clock == "cpu" else x[1] - x[0]) for x in m["calls"]]))
            t = max(t, m["submitted"] if m.get("async") else m["returned"])
        if clock == "cpu" and c is not None:
            phases.append(("serial", max(0.0, cpu[name][1] - c)))
        else:
            phases.append(("serial", max(0.0, end - t)))
        chains[name] = phases
    return chains


def _phases(chains: dict, name: str, path: tuple) -> list:
    """The list of phases that ``path`` (its last index dropped) points into: a study's, or a fan's lane's."""
    phases = chains[name]
    for k, i in zip(path[:-1:2], path[1:-1:2], strict=True):
        phases = phases[k][1][i]
    return phases


def replay(chains: dict, workers: int) -> float:
    """Predicted wall time of the chains on ``workers`` workers (see the module docstring)."""
    order = sorted(chains, key=lambda n: -sum(_work(p) for p in chains[n]))
    waiting = list(order)
    drivers = min(workers, len(order))
    ready: list = []  # (priority, ready time, sequence, study, path, duration): all ready now, lowest first
    running: list = []  # (end time, sequence, study, path)
    left: dict = {}  # (study, path) -> calls of a map, or lanes of a fan, not yet done
    rendering = dict.fromkeys(chains, 0)  # study -> its async calls (figures) not yet done
    ended: set = set()  # studies whose driver has run its last phase
    seq = 0
    t = 0.0

    def finish(name, at):
        if name in ended and not rendering[name] and waiting:  # this driver takes the next study
            ended.discard(name)
            push(waiting.pop(0), (0,), at)

    def after(name, path, at):
        push(name, path[:-1] + (path[-1] + 1,), at)

    def push(name, path, at):
        nonlocal seq
        phases = _phases(chains, name, path)
        if path[-1] >= len(phases):
            if len(path) == 1:
                ended.add(name)
                finish(name, at)  # the driver waits for its study's figures, then takes the next study
                return
            fan = path[:-2]  # a lane has ended: its fan goes on when all its lanes have
            left[(name, fan)] -= 1
            if not left[(name, fan)]:
                after(name, fan, at)
            return
        kind, what = phases[path[-1]]
        prio = getattr(phases, "priority", 0)
        if kind == "serial":
            heapq.heappush(ready, (prio, at, seq, name, path, what))
            seq += 1
        elif kind == "async":
            rendering[name] += len(what)
            for d in what:
                heapq.heappush(ready, (prio, at, seq, name, path, d))
                seq += 1
            after(name, path, at)
        elif not what:
            after(name, path, at)
        elif kind == "fan":
            left[(name, path)] = len(what)
            for i in range(len(what)):
                push(name, path + (i, 0), at)
        else:
            left[(name, path)] = len(what)
            for d in what:
                heapq.heappush(ready, (prio, at, seq, name, path, d))
                seq += 1

    for _ in range(drivers):
        push(waiting.pop(0), (0,), 0.0)
    free = workers
    while ready or running:
        while free and ready:
            _, _, s, name, path, d = heapq.heappop(ready)
            heapq.heappush(running, (t + d, s, name, path))
            free -= 1
        t, _, name, path = heapq.heappop(running)
        free += 1
        kind = _phases(chains, name, path)[path[-1]][0]
        if kind == "serial":
            after(name, path, t)
        elif kind == "async":
            rendering[name] -= 1
            finish(name, t)
        else:
            left[(name, path)] -= 1
            if not left[(name, path)]:
                after(name, path, t)
    return t


def _work(phase) -> float:
    if phase[0] == "fan":
        return sum(_work(p) for lane in phase[1] for p in lane)
    return phase[1] if phase[0] == "serial" else sum(phase[1])


def critical_path(chains: dict) -> float:
    """The longest study with unlimited workers: its serial stretches and its longest call per map.

    An async call (a figure rendered in the pool) starts where the driver sent it and may end after it; a
    fan lasts as long as its longest lane.
    """
    def length(phases):
        t = end = 0.0
        for kind, what in phases:
            if kind == "async":
                end = max(end, t + max(what, default=0.0))
            elif kind == "fan":
                t += max((length(lane) for lane in what), default=0.0)
            else:
                t += what if kind == "serial" else max(what, default=0.0)
        return max(t, end)

    return max(length(ph) for ph in chains.values())


def _leaves(phases: list) -> list:
    """Every serial, map and async phase, a fan's lanes opened."""
    return [q for p in phases for q in (_leaves([r for lane in p[1] for r in lane]) if p[0] == "fan" else [p])]


def summary(chains: dict, workers: list[int], check: float | None = None) -> str:
    """The table ``replay`` prints."""
    leaves = [p for ph in chains.values() for p in _leaves(ph)]
    total = sum(_work(p) for p in leaves)
    serial = sum(p[1] for p in leaves if p[0] == "serial")
    calls = sum(len(p[1]) for p in leaves if p[0] != "serial")
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
