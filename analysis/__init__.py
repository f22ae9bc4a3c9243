"""One module per study: the paper's plants, parameters, figures and tables.

Each study module defines ``INFO`` (a :class:`ctrl_analysis.reporting.report.StudyInfo`) and
``run(ctx, params=None) -> StudyResult``: ``ctx`` the output folder, runs, seed and ``--quick`` from the
CLI (:class:`ctrl_analysis.reporting.report.StudyContext`), ``params`` an optional dict of overrides of the study's
settings, ``{prefix: parameter object or {field: value}}`` under the prefixes of its results.json names
(:func:`ctrl_analysis.reporting.study.study_params`; ``None``: the study's chosen values, what the CLI runs). The
CLI finds them through :data:`STUDIES`.
"""

from __future__ import annotations

import importlib

__all__ = ["MEMORY", "STUDIES", "load_study"]

#: CLI study name -> module that reproduces it.
STUDIES = {
    "ikf-mfac": "analysis.ikf_mfac",
    "ckf": "analysis.ckf",
    "differential-estimator": "analysis.differential_estimator",
    "meso": "analysis.meso",
    "pendulum": "analysis.pendulum",
}


#: Measured memory of each study, for the CLI's up-front ``--runs`` check: ``{"quick" | "full": (base bytes,
#: bytes per Monte Carlo run)}``. Measured with ``OPENBLAS_NUM_THREADS=1 python benchmarks/memory_per_run.py``
#: (2026-11-24, 2-core machine): the peak resident size (ru_maxrss) each study adds to its process, run in
#: one process at 10 and 210 runs (--quick) and 5 and 105 runs (full); per run = difference / runs added,
#: base = the rest. A study that keeps its runs' traces grows linearly in --runs. Check:
#: pendulum --quick --runs 1500 --jobs 1 was estimated at 1.79 GB (with the CLI's 223 MiB) and peaked at 1.82 GB
#: before it reduced its runs part by part; now it is estimated at 617 MB and peaks at 395 MB (20 000 runs: 402 MB).
#: A study that reduces its runs chunk by chunk is measured past its chunk (``POINTS_FOR`` of that script):
#: ikf-mfac (``analysis.ikf_mfac.quantities.TABLE_CHUNK`` = 2000 runs; 2026-11-28) added 270 and 296 MB at
#: --quick 2000 and 20000 runs, 291 and 294 MB at 2000 and 8000 full runs: its base is the chunk's peak, its
#: slope the per-run values it keeps (1.5 and 0.5 kB). meso (``analysis.meso.loops.ROWS_PER_PART`` = 64 rows, 3 a
#: run; 2026-11-28) measured at 100 and 1000 --quick runs, 30 and 300 full runs: 11 and 95 kB a run (was 1.6 and
#: 4.2 MB, its noise and signals held for every row at once). pendulum keeps every run's traces up to
#: ``analysis.pendulum.loops.RUNS_PER_PART`` = 256 runs and reduces parts of at most that many above: its base is the
#: peak at 256 runs (360 MB --quick, 699 MB full), its slope what it keeps per run past the part (15 and 0.7 kB,
#: measured at 300 and 3000 --quick runs, 300 and 900 full; was 0.97 and 2.4 MB a run at every run count).
#: differential-estimator, likewise above 128 runs (``example1/example2.RUNS_PER_PART``): base the 128-run peak (166 MB
#: --quick, 1.29 GB full), slope 23 kB a run (300 and 3000 --quick runs; the full runs' slope, 200 and 500, was below
#: the noise and the values kept per run do not depend on the horizon), was 0.58 and 4.3 MB. ckf keeps the traces of
#: ``analysis.ckf.RUNS_PER_PART`` = 128 runs and simulates the rest that many at a time keeping their window sums: base
#: the 128-run peak (458 MB --quick, 1.40 GB full), slope 1.1 and 0.8 kB a run (2000 --quick runs, 600 full), was 3.1
#: and 9.6 MB.
MEMORY = {
    "ikf-mfac": {"quick": (280087520, 1514), "full": (304087616, 524)},
    "ckf": {"quick": (457876191, 1050), "full": (1398118434, 815)},
    "differential-estimator": {"quick": (165793792, 23339), "full": (1291825152, 23339)},
    "meso": {"quick": (97652280, 11104), "full": (242845468, 95239)},
    "pendulum": {"quick": (359657472, 15067), "full": (698535936, 703)},
}


def load_study(name: str):
    """Import the module of study ``name``."""
    if name not in STUDIES:
        raise ValueError(f"study must be one of {list(STUDIES)}, got {name!r}")
    return importlib.import_module(STUDIES[name])
