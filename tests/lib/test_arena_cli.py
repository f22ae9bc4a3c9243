"""The arena's command line, the user-record path and the results.json contract on a tiny run."""

import json

import numpy as np
import pytest

from ctrl_analysis.arena.cli import read_record
from ctrl_analysis.arena.recommend import ArenaSettings, arena_report_lines, run_arena
from ctrl_analysis.arena.tuning import Setup
from ctrl_analysis.cli import main
from ctrl_analysis.reporting.report import (
    StudyContext,
    validate_results,
    write_results_json,
)


def _csv(path, rows, header="time,y"):
    path.write_text(header + "\n" + "\n".join(",".join(f"{v}" for v in r) for r in rows) + "\n")
    return path


@pytest.mark.parametrize("rows, header, message", [
    ([[0.01 * k] for k in range(50)], "time", "columns time, measurement"),
    ([[0.01 * k, np.nan] for k in range(50)], "time,y", "NaN"),
    ([[0.01 * (k % 30), 1.0] for k in range(50)], "time,y", "strictly increasing"),
    ([[0.01 * k, "abc"] for k in range(50)], "time,y", "number"),
])
def test_malformed_csv_is_one_line_and_exit_2(tmp_path, capsys, rows, header, message):
    f = _csv(tmp_path / "bad.csv", rows, header)
    code = main(["arena", "--signal", str(f), "--noise-bound", "0.01", "--accel-bound", "2"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and message in err and "--signal" in err


def test_missing_bounds_are_a_usage_error(tmp_path, capsys):
    f = _csv(tmp_path / "ok.csv", [[0.01 * k, np.sin(0.01 * k)] for k in range(100)])
    assert main(["arena", "--signal", str(f)]) == 2
    assert "--noise-bound" in capsys.readouterr().err


def test_read_record_with_derivative(tmp_path):
    t = 0.01 * np.arange(40)
    f = _csv(tmp_path / "d.csv", np.column_stack([t, t**2, 2 * t]), "t,y,dy")
    tt, _, d1 = read_record(f)
    assert np.allclose(tt, t) and np.allclose(d1, 2 * t)


def test_tiny_arena_writes_valid_results(tmp_path):
    s = ArenaSettings(signals=("sines",), noises=("uniform",), eps=(0.01,), L=2.0, records=1,
                      setup=Setup(dt=0.01, n=400, transient=1.0), rounds=0, families=("leso2", "algebraic"))
    ctx = StudyContext(out_dir=tmp_path, quick=True)
    result, raw = run_arena(ctx, s)
    write_results_json(result, tmp_path)
    data = validate_results(json.loads((tmp_path / "results.json").read_text()))
    ids = {q["id"] for q in data["quantities"]}
    assert "sines.uniform.0.01.leso2.adv_ratio" in ids and raw["tunings"] == 9 + 5 * 2  # grids: 9 bandwidths; 5 windows x 2 degrees
    assert all(q["unit"] is not None for q in data["quantities"])
    adv = [q["value"] for q in data["quantities"] if q["id"].endswith("adv_ratio")]
    assert min(adv) >= 1 - 1e-9
    assert sorted(data["figures"]) == ["arena_best_on_one_signal.png", "arena_pareto.png", "arena_ratio_heatmap.png"]
    assert any(f["id"] == "recommend-sines-uniform" for f in data["findings"])
    assert arena_report_lines(data)[0] == "## Estimator arena"


def _sine_csv(path, derivative=True, n=600):
    t = 0.01 * np.arange(n)
    y = np.sin(t) + 0.01 * np.random.default_rng(0).uniform(-1, 1, n)
    cols = [t, y, np.cos(t)] if derivative else [t, y]
    return _csv(path, np.column_stack(cols), "t,y,dy" if derivative else "t,y")


@pytest.mark.parametrize("derivative", [True, False], ids=["with-derivative", "surrogate"])
def test_a_record_run_writes_its_folder(tmp_path, capsys, derivative):
    f = _sine_csv(tmp_path / "rec.csv", derivative)
    out = tmp_path / "D"
    code = main(["arena", "--signal", str(f), "--noise-bound", "0.01", "--accel-bound", "1", "--out", str(out),
                 "--jobs", "1"])
    assert code == 0
    folder = out / "arena"
    data = validate_results(json.loads((folder / "results.json").read_text()))
    s = data["settings"]
    assert s["mode"] == "record" and s["samples"] == 600 and s["startup_window_s"] > 0
    assert ("own derivative" in s["scored_on"]) == derivative
    ratios = {q["id"]: q["value"] for q in data["quantities"] if q["id"].endswith(".ratio")}
    worst = {q["id"]: q["value"] for q in data["quantities"] if q["id"].endswith(".worst")}
    bound = next(q["value"] for q in data["quantities"] if q["id"] == "bound")
    assert bound == pytest.approx(2 * np.sqrt(0.01 * 1.0))
    # the ranking is best first and each ratio is its worst-case error over the bound
    assert list(worst.values()) == sorted(worst.values())
    assert all(ratios[k[:-6] + ".ratio"] == pytest.approx(v / bound) for k, v in worst.items())
    est = np.loadtxt(folder / "estimate.csv", delimiter=",", skiprows=1)
    assert est.shape == (600, 3)
    if derivative:  # after the start-up window the recommended estimate is within its own scored worst case
        t0 = s["startup_window_s"]
        after = est[:, 0] >= t0 + 1e-9
        assert np.max(np.abs(est[after, 2] - np.cos(est[after, 0]))) <= min(worst.values()) * 1.05
    assert sorted(data["figures"]) == ["ranking.png", "record_estimate.png"]
    assert all((folder / fig).stat().st_size > 5_000 for fig in data["figures"])
    report = (folder / "REPORT.md").read_text()
    assert "start-up window" in report and "| 1 |" in report and "estimate.csv" in report
    printed = capsys.readouterr().out
    assert "start-up window" in printed and str(folder) in printed


def test_bounds_without_a_record_and_a_file_as_out_are_usage_errors(tmp_path, capsys):
    assert main(["arena", "--noise-bound", "0.01"]) == 2
    assert "--noise-bound describe a record: give them with --signal" in capsys.readouterr().err
    f = _sine_csv(tmp_path / "rec.csv")
    (tmp_path / "file").write_text("x")
    assert main(["arena", "--signal", str(f), "--noise-bound", "0.01", "--accel-bound", "1", "--out",
                 str(tmp_path / "file")]) == 2
    assert "--out must be a directory" in capsys.readouterr().err


def test_bad_arguments_are_answered_before_the_heavy_imports(tmp_path):
    import subprocess
    import sys

    code = ("import sys; from ctrl_analysis.cli import main; "
            f"rc = main(['arena', '--signal', {str(tmp_path / 'none.csv')!r}, '--noise-bound', '1', '--accel-bound', "
            "'1']); print(rc, sorted(m for m in ('analysis', 'scipy.signal', 'matplotlib.pyplot', 'control') "
            "if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.stdout.strip() == "2 []" and "cannot be read" in proc.stderr


def test_list_shows_the_arena(capsys):
    assert main(["list"]) == 0
    assert "arena" in capsys.readouterr().out.splitlines()[-1]


def test_the_reports_arena_section_says_where_it_comes_from(tmp_path):
    from ctrl_analysis.arena.report_section import arena_section as _arena_section

    s = ArenaSettings(signals=("sines",), noises=("uniform",), eps=(0.01,), L=2.0, records=1,
                      setup=Setup(dt=0.01, n=400, transient=1.0), rounds=0, families=("leso2",))
    (tmp_path / "arena").mkdir()
    result, _ = run_arena(StudyContext(out_dir=tmp_path / "arena", quick=True), s)
    result.settings.update({"mode": "benchmark", "cli": {"seed": 3, "quick": True, "runs": None}})
    write_results_json(result, tmp_path / "arena")
    lines = _arena_section(tmp_path)
    assert lines[0] == "## Estimator arena" and "separate `ctrl-analysis arena` run (seed 3, --quick)" in lines[2]
    result.settings["mode"] = "record"
    result.settings["signal"] = "my.csv"
    write_results_json(result, tmp_path / "arena")
    assert "holds an arena run on a record (`my.csv`), not the benchmark" in _arena_section(tmp_path)[2]
