"""Study `meso`: Chen & Gao 2018, modified extended state observer: analysis and implementation.

Not built yet: this module reproduces nothing so far and says what is missing.
"""

from __future__ import annotations

from ctrl_analysis.report import StudyContext, StudyInfo, StudyResult

INFO = StudyInfo(
    name='meso',
    seed_file='003_69569f7e4aa9c67b.txt',
    paper='Chen & Gao 2018, modified extended state observer: analysis and implementation',
    reproduces='linear ESO analysis (omega_o, poles, Bode), Tables 2-3, Fig. 3-6',
)

MISSING = ['linear observer analysis', 'situations 1 and 2 (Tables 2-3, Fig. 3-6)']


def run(ctx: StudyContext) -> StudyResult:
    """Reproduce what exists of the study; list what is not built yet."""
    result = StudyResult(INFO)
    result.missing = list(MISSING)
    ctx.progress("not built yet: " + "; ".join(MISSING))
    return result
