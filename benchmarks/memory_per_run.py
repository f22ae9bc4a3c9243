"""Measure each study's memory per Monte Carlo run, for the CLI's up-front ``--runs`` check (``analysis.MEMORY``).

Each study runs in a fresh process at two run counts, quick and full, far enough apart that the
difference dominates the noise of the resident size; the peak resident size (``ru_maxrss``) minus
that of the process before the study ran gives a base and a slope per run:
``base + per_run * runs``. Prints the table to paste into ``analysis/__init__.py``. A study that reduces
its runs chunk by chunk (:data:`POINTS_FOR`) is measured past its chunk: its base is then the chunk's peak
and its slope what it keeps per run.

    OPENBLAS_NUM_THREADS=1 python benchmarks/memory_per_run.py [study ...]
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
POINTS = {"quick": (10, 210), "full": (5, 105)}
#: A study that reduces its runs chunk by chunk is measured past its chunk (ikf-mfac's TABLE_CHUNK, 2000 runs;
#: meso's ROWS_PER_PART, pendulum's, differential-estimator's and ckf's
#: RUNS_PER_PART), where only what it keeps per run still grows; below the chunk
#: its peak is at most the first point's.
POINTS_FOR = {"ikf-mfac": {"quick": (2000, 20000), "full": (2000, 8000)},
              # meso simulates at most analysis.meso.loops.ROWS_PER_PART rows (3 per run) at a time
              "meso": {"quick": (100, 1000), "full": (30, 300)},
              # pendulum reduces a case's runs analysis.pendulum.loops.RUNS_PER_PART at a time above that many
              "pendulum": {"quick": (256, 3000), "full": (256, 900)},
              # differential-estimator reduces parts of example1/example2.RUNS_PER_PART runs above that many
              "differential-estimator": {"quick": (300, 3000), "full": (200, 500)},
              # ckf keeps the traces of analysis.ckf.RUNS_PER_PART runs and simulates the rest that many at a time
              "ckf": {"quick": (128, 2000), "full": (128, 600)}}

CHILD = """
import json, resource, sys, tempfile, warnings
from pathlib import Path
from analysis import load_study
from ctrl_analysis.reporting.report import StudyContext
name, runs, quick = sys.argv[1], int(sys.argv[2]), sys.argv[3] == "quick"
study = load_study(name)
warnings.simplefilter("ignore")
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
study.run(StudyContext(out_dir=Path(tempfile.mkdtemp()), runs=runs, quick=quick))
print(json.dumps(1024 * (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before)))
"""


def peak(name: str, runs: int, mode: str) -> int:
    out = subprocess.run([sys.executable, "-c", CHILD, name, str(runs), mode], cwd=REPO, capture_output=True,
                         text=True, check=True)
    return int(json.loads(out.stdout.strip().splitlines()[-1]))


def main(names) -> None:
    from analysis import STUDIES

    for name in names or list(STUDIES):
        row = {}
        for mode, (r1, r2) in POINTS_FOR.get(name, POINTS).items():
            p1, p2 = peak(name, r1, mode), peak(name, r2, mode)
            per_run = max(0.0, (p2 - p1) / (r2 - r1))
            row[mode] = (int(p1 - per_run * r1), int(per_run))
        print(f'    "{name}": {json.dumps(row)},', flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
