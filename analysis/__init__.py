"""One module per study: the paper's plants, parameters, figures and tables.

Each study module defines ``INFO`` (a :class:`ctrl_analysis.report.StudyInfo`) and
``run(ctx) -> StudyResult``. The CLI finds them through :data:`STUDIES`.
"""

from __future__ import annotations

import importlib

__all__ = ["STUDIES", "load_study"]

#: CLI study name -> module that reproduces it.
STUDIES = {
    "ikf-mfac": "analysis.ikf_mfac",
    "ckf": "analysis.ckf",
    "differential-estimator": "analysis.differential_estimator",
    "meso": "analysis.meso",
    "pendulum": "analysis.pendulum",
}


def load_study(name: str):
    """Import the module of study ``name``."""
    if name not in STUDIES:
        raise ValueError(f"study must be one of {list(STUDIES)}, got {name!r}")
    return importlib.import_module(STUDIES[name])
