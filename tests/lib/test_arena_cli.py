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
