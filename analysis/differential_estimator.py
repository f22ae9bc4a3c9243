"""Study `differential-estimator`: Qi, Chen, Xue & Yuan 2004, a new differential state estimator and controller for nonlinear stochastic systems.

Not built yet: this module reproduces nothing so far and says what is missing.
"""

from __future__ import annotations

from ctrl_analysis.report import StudyContext, StudyInfo, StudyResult

INFO = StudyInfo(
    name='differential-estimator',
    seed_file='002_a1e12cd95cff3523.txt',
    paper='Qi, Chen, Xue & Yuan 2004, a new differential state estimator and controller for nonlinear stochastic systems',
    reproduces='eq. (9) check, Fig. 1 root locus, Fig. 2 Bode, Examples 1-2 (Fig. 3-5), robustness map',
)

MISSING = ['linear analysis of the estimator (eq. 3-9, Fig. 1-2)', 'Example 1 (Fig. 3-4)', 'Example 2 (Fig. 5) and robustness sweep']


def run(ctx: StudyContext) -> StudyResult:
    """Reproduce what exists of the study; list what is not built yet."""
    result = StudyResult(INFO)
    result.missing = list(MISSING)
    ctx.progress("not built yet: " + "; ".join(MISSING))
    return result
