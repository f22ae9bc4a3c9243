"""One module per study: the paper's plants, parameters, figures and tables.

Each study module defines ``INFO`` (a :class:`ctrl_analysis.report.StudyInfo`) and
``run(ctx) -> StudyResult``. The CLI finds them through :data:`STUDIES`.
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
#: (2026-11, 2-core machine): the peak resident size (ru_maxrss) each study adds to its process, run in one
#: process at 10 and 210 runs (--quick) and 5 and 105 runs (full); per run = difference / runs added, base
#: = the rest. The whole batch's statistics are kept per run, so the footprint is linear in --runs.
MEMORY = {
    "ikf-mfac": {"quick": (116544307, 1220526), "full": (123884953, 2138644)},
    "ckf": {"quick": (73534259, 1612308), "full": (173454540, 5499863)},
    "differential-estimator": {"quick": (81150566, 768348), "full": (365347430, 4434206)},
    "meso": {"quick": (84377190, 1534812), "full": (250838630, 2483896)},
    "pendulum": {"quick": (80921190, 280514), "full": (106315161, 417095)},
}


def load_study(name: str):
    """Import the module of study ``name``."""
    if name not in STUDIES:
        raise ValueError(f"study must be one of {list(STUDIES)}, got {name!r}")
    return importlib.import_module(STUDIES[name])
