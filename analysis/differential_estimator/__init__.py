"""Study `differential-estimator`: Qi, Chen, Xue & Yuan 2004, a new differential state estimator and controller for nonlinear stochastic systems.

Built so far: the linear analysis of Σ (eq. 3-9, Fig. 1-2, a design table) and the controller
polynomial of Example 2 (:mod:`.linear`). Not built yet: the time-domain Examples 1 and 2.
"""

from __future__ import annotations

from ctrl_analysis.report import StudyContext, StudyInfo, StudyResult

from . import linear

__all__ = ["INFO", "MISSING", "run"]

INFO = StudyInfo(
    name='differential-estimator',
    seed_file='002_a1e12cd95cff3523.txt',
    paper='Qi, Chen, Xue & Yuan 2004, a new differential state estimator and controller for nonlinear stochastic systems',
    reproduces='eq. (9) check, Fig. 1 root locus, Fig. 2 Bode, Examples 1-2 (Fig. 3-5), robustness map',
)

MISSING = ["Example 1 (Fig. 3-4)", "Example 2 (Fig. 5) and robustness sweep"]


def run(ctx: StudyContext) -> StudyResult:
    """Reproduce what exists of the study; list what is not built yet."""
    result = StudyResult(INFO)
    linear.run_linear(ctx, result)
    result.missing = list(MISSING)
    ctx.progress("not built yet: " + "; ".join(MISSING))
    return result
