"""Study `pendulum`: Li, Ji & Feng 2008, sub-optimal filter in the fuzzy control of an inverted pendulum.

Not built yet: this module reproduces nothing so far and says what is missing.
"""

from __future__ import annotations

from ctrl_analysis.report import StudyContext, StudyInfo, StudyResult

INFO = StudyInfo(
    name='pendulum',
    seed_file='004_5e64e0f766ab04b2.txt',
    paper='Li, Ji & Feng 2008, sub-optimal filter in the fuzzy control of an inverted pendulum',
    reproduces='steady-state Kalman / alpha-beta gain verification, Riccati convergence, fuzzy closed loop (Fig. 3-4)',
)

MISSING = ['steady-state gain verification', 'fuzzy controller and closed-loop simulation (Fig. 3-4)']


def run(ctx: StudyContext) -> StudyResult:
    """Reproduce what exists of the study; list what is not built yet."""
    result = StudyResult(INFO)
    result.missing = list(MISSING)
    ctx.progress("not built yet: " + "; ".join(MISSING))
    return result
