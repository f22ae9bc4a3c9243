"""Study `ckf`: Gong & Wu 2010, characteristic-model-based Kalman filter with golden-section adaptive control.

Not built yet: this module reproduces nothing so far and says what is missing.
"""

from __future__ import annotations

from ctrl_analysis.report import StudyContext, StudyInfo, StudyResult

from ._unbuilt import run_unbuilt

INFO = StudyInfo(
    name='ckf',
    seed_file='001_98762e3e5a8851d8.txt',
    paper='Gong & Wu 2010, characteristic-model-based Kalman filter with golden-section adaptive control',
    reproduces='Fig. 2-9 and Table 1: no filter vs LPF vs CKF under golden-section control',
)

MISSING = ['characteristic-model RLS identification and CKF', 'golden-section + maintaining-tracking + logic-integral control', 'Fig. 2-9, Table 1']


def run(ctx: StudyContext) -> StudyResult:
    """Reproduce what exists of the study; list what is not built yet."""
    return run_unbuilt(ctx, INFO, MISSING)
