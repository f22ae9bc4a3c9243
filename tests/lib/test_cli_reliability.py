"""CLI reliability: --out checked before any work, Ctrl-C leaves old output intact (exit 130), a failing
study neither stops the others nor prints a traceback, stale studies are marked in REPORT.md."""

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from hang import limit

import analysis
from ctrl_analysis.cli import main
from ctrl_analysis.reporting.report import StudyInfo, StudyResult

REPO = Path(__file__).resolve().parents[2]


def _cli(*argv, **kw):
    return subprocess.run([sys.executable, "-m", "ctrl_analysis.cli", *argv], capture_output=True, text=True,
                          cwd=REPO, timeout=limit(300), **kw)


@pytest.mark.parametrize("kind", ["file", "empty", "unwritable"])
def test_bad_out_is_one_line_exit_2_before_any_work(tmp_path, kind):
    out = {"file": str(tmp_path / "a_file"), "empty": "", "unwritable": "/proc/ctrl-analysis-out"}[kind]
    (tmp_path / "a_file").write_text("not a directory")
    proc = _cli("reproduce", "meso", "--quick", "--out", out)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "--out" in lines[0] and "Traceback" not in proc.stderr
    assert "[meso]" not in proc.stderr and proc.stdout == ""  # no study started
    assert (tmp_path / "a_file").read_text() == "not a directory"


def test_sigint_leaves_previous_output_intact(tmp_path):
    old = tmp_path / "meso"
    old.mkdir()
    files = {"results.json": b'{"study": "meso", "complete": true}\n', "fig3_situation1.png": b"\x89PNG old"}
    for name, data in files.items():
        (old / name).write_bytes(data)
    proc = subprocess.Popen([sys.executable, "-m", "ctrl_analysis.cli", "reproduce", "meso", "--quick", "--verbose",
                             "--out", str(tmp_path)], cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # Ctrl-C live in the
    # child even when the suite was started in the background by a shell without job control (SIGINT ignored)
    first = proc.stderr.readline()  # the study has started once it reports progress
    assert first.startswith("[meso]")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=limit(300))
    assert proc.returncode == 130
    assert "Traceback" not in err and err.strip().splitlines()[-1].startswith("ctrl-analysis: interrupted")
    assert sorted(p.name for p in old.iterdir()) == sorted(files)
    for name, data in files.items():
        assert (old / name).read_bytes() == data
    assert [p.name for p in tmp_path.iterdir()] == ["meso"]  # no staging directory left behind


def _fake_study(name, fail=None):
    class Fake:
        INFO = StudyInfo(name=name, seed_file="s.txt", paper="P", reproduces="r")

        @staticmethod
        def run(ctx, params=None):
            if fail is not None:
                raise fail
            result = StudyResult(Fake.INFO)
            result.quantity("q", "q", float(ctx.seed), runs=ctx.runs)
            result.seeds = {"noise": [ctx.seed]}
            (ctx.out_dir / "marker.txt").write_text("written into the staged directory")
            return result

    return Fake


def test_failing_study_does_not_stop_others_and_is_marked_stale(tmp_path, monkeypatch, capsys):
    names = list(analysis.STUDIES)
    broken, crashing = names[0], names[1]
    # an earlier complete run of the study that will now fail
    old = StudyResult(_fake_study(broken).INFO)
    old.quantity("q", "q", 1.0)
    (tmp_path / broken).mkdir()
    (tmp_path / broken / "results.json").write_text(json.dumps(old.to_dict()))
    fakes = {n: _fake_study(n) for n in names}
    fakes[broken] = _fake_study(broken, ValueError("n0 must be >= 2, got 1"))
    fakes[crashing] = _fake_study(crashing, ZeroDivisionError("division by zero"))
    monkeypatch.setattr(analysis, "load_study", lambda n: fakes[n])

    status = main(["reproduce", "all", "--out", str(tmp_path), "--seed", "7", "--runs", "3"])
    err = capsys.readouterr().err
    assert status == 1
    assert f"study {broken!r} failed: ValueError: n0 must be >= 2, got 1" in err
    assert f"study {crashing!r} failed: ZeroDivisionError: division by zero" in err
    assert err.strip().splitlines()[-1] == f"ctrl-analysis: 2 of {len(names)} studies failed: {broken}, {crashing}"
    assert "Traceback" not in err
    for n in names[2:]:  # the studies after the failures still ran
        data = json.loads((tmp_path / n / "results.json").read_text())
        assert data["settings"]["cli"] == {"seed": 7, "runs": 3, "quick": False}
        assert (tmp_path / n / "marker.txt").exists()
    assert not (tmp_path / crashing).exists()
    report = (tmp_path / "REPORT.md").read_text()
    assert f"| {broken} | **no — stale**" in report
    assert "**Stale:**" in report.split(f"## {broken}")[1].split("## ")[0]
    for n in names[2:]:
        assert f"| {n} | yes | 7 | 3 |" in report


NAN_TOLERANCE_CALLS = [
    "simulate_ivp(lambda t, x, u, p: -x, [1.0], [0.0, 1.0], rtol=nan)",
    "simulate_ivp(lambda t, x, u, p: -x, [1.0], [0.0, 1.0], atol=nan)",
    "riccati_trajectory([[0.0]], [[1.0]], [[1.0]], 1.0, 1.0, [[1.0]], [0.0, 1.0], rtol=nan)",
    "discrete_steady_state_batch([[[1.0]]], [[1.0]], [[1.0]], 1.0, tol=nan)",
]


def test_nan_tolerance_does_not_hang():
    # one subprocess with a timeout: before the fix the first and third calls never returned
    lines = ["from math import nan",
             "from ctrl_analysis.engine.ivp import simulate_ivp",
             "from ctrl_analysis.estimators.kalman import riccati_trajectory, discrete_steady_state_batch"]
    for call in NAN_TOLERANCE_CALLS:
        lines += ["try:", f"    {call}", "    print('returned')", "except ValueError as exc:", "    print(exc)"]
    proc = subprocess.run([sys.executable, "-c", "\n".join(lines)], capture_output=True, text=True, cwd=REPO,
                          timeout=limit(90), env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    out = proc.stdout.strip().splitlines()
    assert len(out) == len(NAN_TOLERANCE_CALLS), proc.stderr
    assert all("tol must be finite" in line for line in out), out


def test_report_that_cannot_be_written_is_one_line_and_keeps_the_old_one(tmp_path, monkeypatch, capsys):
    names = list(analysis.STUDIES)
    monkeypatch.setattr(analysis, "load_study", lambda n: _fake_study(n))
    (tmp_path / "REPORT.md").write_text("old report")

    def full_disk(*args, **kw):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("ctrl_analysis.reporting.run_folder.write_report_md", full_disk)
    assert main(["reproduce", "all", "--out", str(tmp_path)]) == 1  # an output asked for is missing
    captured = capsys.readouterr()
    err = captured.err
    assert "Traceback" not in err
    # the studies succeeded; REPORT.md is the one thing not written, and the old one is said to be stale
    assert err.strip().splitlines()[-1] == ("ctrl-analysis: error: REPORT.md not written: OSError: [Errno 28] No "
                                            "space left on device; the REPORT.md in --out is an earlier run's, "
                                            "which does not describe the studies of this run")
    assert f"{len(names)} of {len(names)} studies OK, 0 failed" in captured.out
    assert (tmp_path / "REPORT.md").read_text() == "old report"


def test_partial_run_refreshes_an_existing_report_and_marks_the_rest_stale(tmp_path, monkeypatch):
    names = list(analysis.STUDIES)
    monkeypatch.setattr(analysis, "load_study", lambda n: _fake_study(n))
    assert main(["reproduce", "all", "--out", str(tmp_path), "--seed", "1"]) == 0
    assert main(["reproduce", names[0], "--out", str(tmp_path), "--seed", "2"]) == 0
    report = (tmp_path / "REPORT.md").read_text()
    assert f"| {names[0]} | yes | 2 |" in report
    for n in names[1:]:
        assert f"| {n} | **no — stale**" in report
    assert main(["reproduce", names[0], "--out", str(tmp_path / "fresh")]) == 0
    assert not (tmp_path / "fresh" / "REPORT.md").exists()  # no report where there was none
