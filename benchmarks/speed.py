"""Speed figures anyone can reproduce: cold and warm `reproduce all`, `--quick`, and the test suite.

    python benchmarks/speed.py                 # everything (a few minutes on 2 cores)
    python benchmarks/speed.py --skip-full     # --quick and the suite only
    python benchmarks/speed.py --skip-tests    # the reproduce runs only

"Cold" is the first run after installing: the compiled loops' caches (numba's and ctrl-analysis's
generated runners) start empty, in fresh folders given by ``NUMBA_CACHE_DIR`` and
``CTRL_ANALYSIS_CACHE``; "warm" is the same command again with those caches filled. Every command
runs in a fresh process from the repository, writes into a temporary folder and must exit 0. The
machine's cores and load are printed first: on a shared or loaded machine the times are longer.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - macOS / Windows
        return os.cpu_count() or 1


def timed(label: str, argv: list[str], env: dict) -> float:
    t0 = time.perf_counter()
    proc = subprocess.run(argv, cwd=REPO, env=env, capture_output=True, text=True, check=False)
    dt = time.perf_counter() - t0
    if proc.returncode != 0:
        sys.exit(f"{label}: exit {proc.returncode}\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")
    print(f"{label:44s} {dt:7.1f} s", flush=True)
    return dt


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description="Time reproduce all (cold, warm), --quick and the test suite.")
    parser.add_argument("--skip-full", action="store_true", help="skip the full reproduce all (cold and warm)")
    parser.add_argument("--skip-tests", action="store_true", help="skip the test suite")
    args = parser.parse_args(argv)
    n = cores()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"cores: {n} (os.cpu_count() = {os.cpu_count()}), load average at start: {load:.1f}, "
          f"python {sys.version.split()[0]}")
    with tempfile.TemporaryDirectory(prefix="ctrl-analysis-speed-") as tmp:
        tmp = Path(tmp)
        # output is captured (not a terminal), so no progress bars are drawn
        env = {**os.environ, "PYTHONPATH": str(REPO), "OPENBLAS_NUM_THREADS": "1",
               "NUMBA_CACHE_DIR": str(tmp / "numba"), "CTRL_ANALYSIS_CACHE": str(tmp / "runners")}
        env.pop("CTRL_ANALYSIS_PROGRESS", None)
        cli = [sys.executable, "-m", "ctrl_analysis.cli", "reproduce", "all"]
        if not args.skip_full:
            timed("reproduce all, cold (empty caches)", [*cli, "--out", str(tmp / "cold")], env)
            timed("reproduce all, warm", [*cli, "--out", str(tmp / "warm")], env)
            timed("reproduce all --quick, warm", [*cli, "--quick", "--out", str(tmp / "quick")], env)
        else:
            timed("reproduce all --quick, cold (empty caches)", [*cli, "--quick", "--out", str(tmp / "quick0")], env)
            timed("reproduce all --quick, warm", [*cli, "--quick", "--out", str(tmp / "quick")], env)
        if not args.skip_tests:
            timed(f"python -m pytest -q -n {n} (caches of the runs above)",
                  [sys.executable, "-m", "pytest", "-q", "-n", str(n),
                                                        "-p", "no:cacheprovider"], env)


if __name__ == "__main__":
    main()
