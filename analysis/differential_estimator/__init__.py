"""Study `differential-estimator`: Qi, Chen, Xue & Yuan 2004, a new differential state estimator and controller for nonlinear stochastic systems.

The linear analysis of Σ (eq. 3-9, Fig. 1-2, a design table) and the controller polynomial of
Example 2 are in :mod:`.linear`; the time-domain Examples 1 and 2 (Fig. 3-5, the literal and
stable presets, the robustness sweep) are in :mod:`.examples`.
"""

from __future__ import annotations

from ctrl_analysis.report import StudyContext, StudyInfo, StudyResult

from . import examples, linear

__all__ = ["INFO", "run"]

INFO = StudyInfo(
    name='differential-estimator',
    seed_file='002_a1e12cd95cff3523.txt',
    paper='Qi, Chen, Xue & Yuan 2004, a new differential state estimator and controller for nonlinear stochastic systems',
    reproduces='eq. (9) check, Fig. 1 root locus, Fig. 2 Bode, Examples 1-2 (Fig. 3-5), robustness map',
)


def run(ctx: StudyContext) -> StudyResult:
    """Reproduce the whole study: linear analysis, then Examples 1 and 2."""
    result = StudyResult(INFO)
    linear.run_linear(ctx, result)
    examples.run_examples(ctx, result)
    return result
