"""results.json schema: unit and tolerance on every quantity, the diverged verdict, cell counting,
the validator (on synthetic dicts and on every committed figures/*/results.json), atomic writes."""

import copy
import json
from pathlib import Path

import pytest

from ctrl_analysis.reporting.markdown import write_report_md
from ctrl_analysis.reporting.report import (
    RESULTS_SCHEMA,
    Quantity,
    StudyInfo,
    StudyResult,
    count_verdicts,
    staged_directory,
    validate_results,
    write_results_json,
    write_text_atomic,
)

INFO = StudyInfo(name="demo", seed_file="x.txt", paper="A paper", reproduces="things")
REPO = Path(__file__).resolve().parents[2]


def _result() -> StudyResult:
    r = StudyResult(INFO)
    r.quantity("t2.x1.eso", "x1 ESO", 1.0, paper=1.05, cell="Table 2 / x1 ESO", unit="rad", tolerance=0.1)
    r.quantity("t2.x1.eso.literal", "x1 ESO literal", 3.0, paper=1.05, cell="Table 2 / x1 ESO", unit="rad")
    r.quantity("t2.x2.eso", "x2 ESO", 5.0, paper=1.0, cell="Table 2 / x2 ESO", unit="rad/s")
    r.quantity("t2.x2.eso.state", "x2 ESO state reading", 1.0, paper=1.0, cell="Table 2 / x2 ESO",
               primary=True, unit="rad/s")
    r.quantity("lit.meso", "literal MESO", None, paper=0.5, runs=4, runs_diverged=4, unit="")
    r.quantity("extra", "a new quantity", 2.0, unit="dB")
    return r


def test_every_quantity_has_unit_and_tolerance_and_validates():
    data = _result().to_dict()
    assert data["schema"] == RESULTS_SCHEMA
    validate_results(data)
    q = {d["id"]: d for d in data["quantities"]}
    assert all("unit" in d and "tolerance" in d for d in data["quantities"])
    assert q["t2.x1.eso"]["unit"] == "rad" and q["t2.x1.eso"]["tolerance"] == 0.1
    # default: half a unit of the last printed digit (1.05: 0.005), written because a paper value exists
    assert q["t2.x1.eso.literal"]["tolerance"] == pytest.approx(0.005 / 1.05)
    assert q["extra"]["tolerance"] is None and q["extra"]["verdict"] == "new"


def test_diverged_verdict_has_no_value():
    r = StudyResult(INFO)
    q = r.quantity("a", "all runs diverged", None, paper=1.0, diverged=True)
    assert q.verdict == "diverged" and q.to_dict()["value"] is None
    q2 = r.quantity("b", "runs all diverged", None, paper=1.0, runs=3, runs_diverged=3)
    assert q2.verdict == "diverged"
    q4 = r.quantity("f", "no healthy run contributed", None, paper=1.0, runs=0)
    assert q4.verdict == "diverged" and q4.to_dict()["verdict"] == "diverged"
    assert r.quantity("g", "no value, one healthy run", None, paper=1.0, runs=1).verdict == "differs"
    q3 = r.quantity("c", "some runs diverged", 1.0, paper=1.0, runs=3, runs_diverged=1, std=0.1)
    assert q3.verdict == "agrees" and q3.to_dict()["runs_diverged"] == 1
    with pytest.raises(ValueError, match="diverged quantity has no value"):
        Quantity("d", "d", 1.0, paper=1.0, diverged=True)
    with pytest.raises(ValueError, match="runs_diverged must be <= 3"):
        Quantity("e", "e", None, runs=3, runs_diverged=4)


def test_counts_score_each_paper_cell_once_with_its_primary():
    counts = count_verdicts(_result().to_dict())
    # cell x1: first quantity (agrees) counts; cell x2: the primary (agrees) counts, not the first (differs);
    # the diverged quantity and the new one count individually
    assert counts == {"agrees": 2, "reachable": 0, "differs": 0, "new": 1, "diverged": 1}


def test_two_primaries_in_one_cell_are_rejected():
    r = StudyResult(INFO)
    r.quantity("a", "a", 1.0, paper=1.0, cell="T1", primary=True)
    r.quantity("b", "b", 1.0, paper=1.0, cell="T1", primary=True)
    with pytest.raises(ValueError, match="two primary"):
        r.to_dict()


def test_one_run_records_no_std(tmp_path):
    q = Quantity("a", "a", 1.0, paper=1.0, std=0.0, runs=1).to_dict()
    assert q["std"] is None
    r = StudyResult(INFO)
    r.quantity("a", "a", 1.0, paper=1.0, std=0.0, runs=1)
    r.quantity("b", "b", 2.0, std=0.5, runs=3)
    table = write_report_md([r.to_dict()], tmp_path).read_text()
    assert "| 1 (1 run) |" in table and "± 0 " not in table and "| 2 ± 0.5 (3 runs) |" in table
    assert Quantity("a", "a", 1.0, std=0.2, runs=5).to_dict()["std"] == 0.2


def _breaks(data, mutate):
    bad = copy.deepcopy(data)
    mutate(bad)
    return bad


@pytest.mark.parametrize(
    "mutate,fragment",
    [
        (lambda d: d.pop("quantities"), "lack keys"),
        (lambda d: d["quantities"][0].pop("unit"), "lacks keys \\['unit'\\]"),
        (lambda d: d["quantities"][0].pop("tolerance"), "lacks keys \\['tolerance'\\]"),
        (lambda d: d["quantities"][0].update(tolerance=None), "tolerance must be a number"),
        (lambda d: d["quantities"][0].update(tolerance=-0.1), "tolerance must be a number"),
        (lambda d: d["quantities"][0].update(unit=None), "unit must be a string"),
        (lambda d: d["quantities"][0].update(verdict="maybe"), "verdict must be one of"),
        (lambda d: d["quantities"][0].update(verdict="differs"), "does not follow"),
        (lambda d: d["quantities"][5].update(paper=2.0, tolerance=0.1), "needs paper None"),
        (lambda d: d["quantities"][4].update(value=1.0), "needs value None"),
        (lambda d: d["quantities"].append(dict(d["quantities"][0])), "recorded twice"),
        (lambda d: d["quantities"][2].update(primary=True), "already has primary"),
    ],
)
def test_validator_rejects_bad_results(mutate, fragment):
    data = _result().to_dict()
    validate_results(data)
    with pytest.raises(ValueError, match=fragment):
        validate_results(_breaks(data, mutate))


def _committed_results():
    return sorted((REPO / "figures").glob("*/results.json"))


@pytest.mark.parametrize("path", _committed_results(), ids=lambda p: p.parent.name)
def test_committed_results_json_validates(path):
    data = json.loads(path.read_text(encoding="utf-8"))
    if data.get("schema", 1) < RESULTS_SCHEMA:
        pytest.skip(f"{path.parent.name}/results.json predates schema {RESULTS_SCHEMA}; regenerate with "
                    "`ctrl-analysis reproduce all`")
    validate_results(data)
    # every figure has its caption, and every printed value names the paper cell it scores
    assert set(data.get("captions", {})) == set(data["figures"]), "figures without a caption"
    assert not [q["id"] for q in data["quantities"] if q["paper"] is not None and not q.get("cell")]


def test_report_shows_unit_tolerance_counts_and_marks_stale(tmp_path):
    fresh = _result().to_dict()
    old = dict(_result().to_dict(), study="old-study")
    text = write_report_md([fresh, old], tmp_path, this_run={"demo": {"seed": 7, "runs": 4, "quick": False}},
                           failed={"old-study": "ValueError: boom", "never-ran": "KeyError: x"}).read_text()
    assert "| never-ran | **no — failed**, and no earlier results |" in text
    assert "| `t2.x1.eso` | x1 ESO | Table 2 / x1 ESO | 1.05 | 1 | rad | 10 % | agrees |" in text
    assert "Paper cells: 2 agree, 0 reachable inside the plausible box, 0 differ, 1 diverged; 1 new quantities." in text
    assert "| demo | yes | 7 | 4 |" in text
    assert "| old-study | **no — stale**" in text
    stale_section = text.split("## old-study")[1]
    assert "**Stale:**" in stale_section and "ValueError: boom" in stale_section
    assert "**Stale:**" not in text.split("## demo")[1].split("## old-study")[0]


def test_staged_directory_is_complete_or_untouched(tmp_path):
    target = tmp_path / "study"
    target.mkdir()
    (target / "results.json").write_text("old")
    with pytest.raises(RuntimeError):
        with staged_directory(target) as staged:
            (staged / "fig.png").write_text("new")
            raise RuntimeError("study failed half-way")
    assert [p.name for p in target.iterdir()] == ["results.json"] and (target / "results.json").read_text() == "old"
    with staged_directory(target) as staged:
        (staged / "results.json").write_text("new")
    assert (target / "results.json").read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["study"]  # no staging leftovers


def test_failed_write_keeps_old_results(tmp_path, monkeypatch):
    path = write_text_atomic(tmp_path / "results.json", "complete old text")

    def broken_fsync(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("os.fsync", broken_fsync)
    with pytest.raises(OSError, match="No space"):
        write_results_json(_result(), tmp_path)
    assert path.read_text() == "complete old text" and [p.name for p in tmp_path.iterdir()] == ["results.json"]
