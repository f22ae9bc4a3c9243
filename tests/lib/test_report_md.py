"""REPORT.md as a reader meets it: overview counts, one score per paper cell, diverged quantities,
side-by-side paper tables, generated summaries, summarised evidence, captions and the glossary."""

import re

from ctrl_analysis.reporting.markdown import (
    paper_tables,
    study_summary,
    summarise,
    tally,
    write_report_md,
)
from ctrl_analysis.reporting.report import (
    StudyContext,
    StudyInfo,
    StudyResult,
    count_verdicts,
)

INFO = StudyInfo(name="demo", seed_file="x.txt", paper="A paper", reproduces="things")


def _result() -> StudyResult:
    r = StudyResult(INFO)
    # Table 2: rows ESO / MESO, columns est_x1 / est_x2; the ESO x1 cell has two readings, the primary differs
    r.quantity("t2.eso.x1.alt", "ESO x1, other reading", 1.0, paper=1.0, tolerance=0.1, unit="",
               cell="Table 2 / ESO / est_x1")
    r.quantity("t2.eso.x1", "ESO x1", 2.0, paper=1.0, std=0.1, runs=10, tolerance=0.1, unit="",
               cell="Table 2 / ESO / est_x1", primary=True)
    r.quantity("t2.eso.x2", "ESO x2", 0.5, paper=0.5, tolerance=0.1, unit="1/s", cell="Table 2 / ESO / est_x2",
               primary=True)
    r.quantity("t2.meso.x1", "MESO x1", None, paper=0.2, runs=4, runs_diverged=4, tolerance=0.1, unit="",
               cell="Table 2 / MESO / est_x1", primary=True)
    r.quantity("t2.meso.x2", "MESO x2", 0.3, paper=0.3, tolerance=0.1, unit="1/s", cell="Table 2 / MESO / est_x2",
               primary=True)
    r.quantity("text.step", "step in degrees", 5.7296, paper=5.7325, tolerance=1e-4, unit="deg",
               cell="§5 / 0.1 rad = 5.7325°", primary=True)
    r.quantity("sweep", "a sweep", list(range(20)), unit="")
    r.finding("first", "The first finding holds. A second sentence follows.",
              evidence={"curve": [float(i) for i in range(50)], "k": 3})
    r.finding("second", "Values [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12] in a text are summarised.")
    return r


def _report(tmp_path, results=None) -> str:
    r = _result()
    ctx = StudyContext(out_dir=tmp_path / "demo")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ctx.save_figure(r, plt.figure(), "fig3_demo.png", caption="Redraws Fig. 3: the demo signal.")
    ctx.save_figure(r, plt.figure(), "extra.png")
    data = r.to_dict()
    return write_report_md(results or [data], tmp_path).read_text(), data


def test_overview_counts_each_cell_once_and_diverged(tmp_path):
    text, data = _report(tmp_path)
    counts = count_verdicts(data)
    # 5 cells: ESO x1 scored by its primary (differs), not by the agreeing first reading; MESO x1 diverged;
    # the §5 step differs (5.7296 against the printed 5.7325 at 1e-4)
    assert counts == {"agrees": 2, "reachable": 0, "differs": 2, "diverged": 1, "new": 1}
    overview = text.split("## Overview")[1].split("###")[0]
    # claims hold / fail / depend / untestable / beyond the paper, cells agree / reachable / differ / diverged / lost,
    # checks and errata, new, findings, figures
    assert "| [demo](#demo) | A paper | yes | 0 | 0 | 0 | 0 | 0 | 2 | 0 | 2 | 1 | 0 | 0, 0 | 1 | 2 | 2 |" in overview
    assert text.index("## Overview") < text.index("## demo")
    assert tally(data) == {"agrees": 2, "reachable": 0, "differs": 2, "diverged": 1, "printed": 5, "lost": 0,
                           "new": 1, "new_diverged": 0, "checks": 0, "errata": 0, "findings": 2}
    # a new quantity whose runs all diverged is not a diverged paper cell
    r = _result()
    r.quantity("beyond", "beyond the paper, all runs diverged", None, runs=3, runs_diverged=3, unit="")
    r.quantity("lost", "a cell whose printed value was lost", 1.0, unit="", cell="Table 9 / a / b", primary=True)
    t = tally(r.to_dict())
    assert (t["diverged"], t["new"], t["new_diverged"], t["lost"]) == (1, 2, 1, 1)


def test_side_by_side_table_is_laid_out_as_the_paper(tmp_path):
    text, data = _report(tmp_path)
    lines = paper_tables(data)
    head = next(line for line in lines if line.startswith("| |"))
    assert head == "| | est_x1 (paper) | est_x1 (here) | est_x2 (paper) | est_x2 (here) |"
    eso = next(line for line in lines if line.startswith("| ESO |"))
    assert eso.startswith("| ESO | 1 | 2 ± 0.1 (+100 %) ✗ | 0.5 | 0.5 ✓ |")
    meso = next(line for line in lines if line.startswith("| MESO |"))
    assert "diverged (4 runs, 4 diverged)" in meso
    # a tight tolerance shows enough digits to see the difference
    assert any(line.startswith("| §5 / 0.1 rad = 5.7325° | 5.7325 | 5.7296 (-0.051 %) ✗") for line in lines)
    # the long quantity list is in the appendix, after every study section
    section = text.split("## demo")[1].split("## Appendix")[0]
    assert "printed beside reproduced" in section and "| `t2.eso.x1` |" not in section
    assert "| `t2.eso.x1` |" in text.split("## Appendix: every quantity")[1]


def test_summary_is_generated_from_verdicts_and_findings(tmp_path):
    lines = study_summary(_result().to_dict())
    assert len(lines) == 3
    assert lines[0].startswith("- **Agrees:** 2 of 5 printed paper cells") and "Table 2: 2 of 4" in lines[0]
    assert "Table 2 / ESO / est_x1 (2 vs 1, +100 %)" in lines[1]
    assert "Table 2 / MESO / est_x1 (all runs diverged)" in lines[1]
    assert "The first finding holds." in lines[2] and "second sentence" not in lines[2]


def test_long_arrays_are_summarised_and_captions_shown(tmp_path):
    text, _ = _report(tmp_path)
    assert "[50 values: min 0 / median 24.5 / max 49]" in text
    assert "[12 values: min 1 / median 6.5 / max 12]" in text  # inside a finding's text
    assert "[20 values: min 0 / median 9.5 / max 19]" in text  # a quantity's value
    assert "*fig3_demo.png* — Redraws Fig. 3: the demo signal." in text
    assert "*extra.png* — (no caption recorded)" in text
    assert summarise({"a": [1, 2]}) == "{a: [1, 2]}"


def test_glossary_lists_only_terms_used(tmp_path):
    text, _ = _report(tmp_path)
    glossary = text.split("## Glossary")[1]
    assert "**diverged**" in glossary and "**agrees / differs**" in glossary
    assert "**Kalata index**" not in glossary  # not used in this report
    r = StudyResult(INFO)
    r.finding("k", "The Kalata index of the pair is 0.3.")
    text2 = write_report_md([r.to_dict()], tmp_path / "b").read_text()
    assert "**Kalata index**" in text2.split("## Glossary")[1]


def test_built_studies_come_first(tmp_path):
    empty = StudyResult(StudyInfo("empty", "y.txt", "B paper", "")).to_dict()
    empty["missing"] = ["everything"]
    built = _result().to_dict()
    text = write_report_md([empty, built], tmp_path).read_text()
    assert text.index("## demo") < text.index("## empty")
    assert re.search(r"\*\*Not reproduced \(1: 0 printed cells that differ or diverged, 1 part of the paper\):\*\*"
                     r"\n\n1\. everything", text)


def test_extra_sections_come_after_the_studies_and_before_the_appendix(tmp_path):
    text = write_report_md([_result().to_dict()], tmp_path, extra=["## Estimator arena", "", "ranked."]).read_text()
    assert text.index("## demo") < text.index("## Estimator arena") < text.index("## Appendix: every quantity")
    import pytest

    with pytest.raises(TypeError, match="extra"):
        write_report_md([_result().to_dict()], tmp_path, extra=[3])
