"""Shared run() for a registered study whose parts are not built yet: it reports what is missing."""

from __future__ import annotations

from ctrl_analysis.report import StudyContext, StudyInfo, StudyResult


def run_unbuilt(ctx: StudyContext, info: StudyInfo, missing: list[str]) -> StudyResult:
    """An empty result whose ``missing`` lists the parts still to build."""
    result = StudyResult(info)
    result.missing = list(missing)
    ctx.progress("not built yet: " + "; ".join(missing))
    return result
