"""Study `ikf-mfac`: Lu & Hou 2022, model-free adaptive control with disturbance rejection based on a modified Kalman filter (IKF-MFAC).

Not built yet: this module reproduces nothing so far and says what is missing.
"""

from __future__ import annotations

from ctrl_analysis.report import StudyContext, StudyInfo, StudyResult

from ._unbuilt import run_unbuilt

INFO = StudyInfo(
    name='ikf-mfac',
    seed_file='000_1281acf4834e65d1.txt',
    paper='Lu & Hou 2022, model-free adaptive control with disturbance rejection based on a modified Kalman filter (IKF-MFAC)',
    reproduces='Table 1 (RMSE/SNR of MFAC, TD-MFAC, D-MFAC, IKF-MFAC), Fig. 2-6, steady IKF gain',
)

MISSING = ['CFDL-MFAC, D-MFAC, TD-MFAC and IKF-MFAC controllers', 'Examples 1 and 2 with Monte Carlo Table 1', 'Fig. 2-6']


def run(ctx: StudyContext) -> StudyResult:
    """Reproduce what exists of the study; list what is not built yet."""
    return run_unbuilt(ctx, INFO, MISSING)
