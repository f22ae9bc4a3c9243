"""The arena's command line, the user-record path and the results.json contract on a tiny run."""

import json

import numpy as np
import pytest

from ctrl_analysis.arena.cli import read_record
from ctrl_analysis.arena.interface import FAMILIES, family
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


def test_bounds_a_noise_free_record_cannot_show_are_asked_for(tmp_path, capsys):
    f = _csv(tmp_path / "ok.csv", [[0.01 * k, np.sin(0.01 * k)] for k in range(100)])
    assert main(["arena", "--signal", str(f)]) == 2
    err = capsys.readouterr().err
    assert "no noise beyond its signal's own third differences" in err and "--noise-bound" in err


def test_without_bounds_they_are_estimated_from_the_record_and_said_so(tmp_path, capsys):
    t = 0.01 * np.arange(1500)
    y = np.sin(t) + 0.01 * np.random.default_rng(3).uniform(-1, 1, t.size)
    f = _csv(tmp_path / "noisy.csv", np.column_stack([t, y]))
    assert main(["arena", "--signal", str(f), "--out", str(tmp_path / "o"), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "estimated from the record" in out and "override them" in out
    r = json.loads((tmp_path / "o" / "arena" / "results.json").read_text())
    assert r["settings"]["bounds_source"] == {"noise_bound": "estimated from the record",
                                              "accel_bound": "estimated from the record"}
    # ε̂ from the third differences of uniform noise of bound 0.01; L̂ a lower estimate of max |sin''| = 1
    assert 0.5 < r["settings"]["noise_bound"] / 0.01 < 2 and 0.2 < r["settings"]["accel_bound"] <= 1.0
    assert "estimated from the record" in next(x["text"] for x in r["findings"] if x["id"] == "recommendation")


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
    # grids: 9 bandwidths; 5 windows x 2 degrees
    assert "sines.uniform.0.01.leso2.adv_ratio" in ids and raw["tunings"] == 9 + 5 * 2
    assert all(q["unit"] is not None for q in data["quantities"])
    adv = [q["value"] for q in data["quantities"] if q["id"].endswith("adv_ratio")]
    assert min(adv) >= 1 - 1e-9
    assert sorted(data["figures"]) == ["arena_best_on_one_signal.png", "arena_pareto.png", "arena_ratio_heatmap.png",
                                       "arena_startup.png"]
    assert any(f["id"] == "recommend-sines-uniform" for f in data["findings"])
    assert arena_report_lines(data)[0] == "## Estimator arena"
    # the start-up window scored apart, beside the same tunings started from the zero state (sines: y0 far from 0)
    start = next(f for f in data["findings"] if f["id"] == "start-up")
    assert "sines.uniform.0.01.leso2.startup" in ids
    assert start["evidence"]["first_max"] < start["evidence"]["zero_max"]


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
    causal = {f.name for f in FAMILIES}  # the offline smoothers are ranked apart (test_arena_offline.py)
    ratios = {q["id"]: q["value"] for q in data["quantities"] if q["id"].endswith(".ratio")}
    worst = {q["id"]: q["value"] for q in data["quantities"]
             if q["id"].endswith(".worst") and q["id"][:-6] in causal}
    bound = next(q["value"] for q in data["quantities"] if q["id"] == "bound")
    assert bound == pytest.approx(2 * np.sqrt(0.01 * 1.0))
    # the ranking is best first and each ratio is its worst-case error over the bound
    assert list(worst.values()) == sorted(worst.values())
    assert all(ratios[k[:-6] + ".ratio"] == pytest.approx(v / bound) for k, v in worst.items())
    est = np.loadtxt(folder / "estimate.csv", delimiter=",", skiprows=1)
    assert est.shape[0] == 600 and est.shape[1] in (4, 5, 6)  # + the best offline smoother's f̂' (and f̂'')
    header = (folder / "estimate.csv").read_text().splitlines()[0].split(",")
    win = min(worst, key=worst.get)[:-6]
    # the causal winner's f̂'' is the last column exactly when its family estimates f''
    assert (header[-1] == f"second derivative estimate (causal: {win})") == family(win).second
    assert len(header) == est.shape[1]
    if derivative:  # after the start-up window the recommended estimate is within its own scored worst case
        t0 = s["startup_window_s"]
        after = est[:, 0] >= t0 + 1e-9
        assert np.max(np.abs(est[after, 2] - np.cos(est[after, 0]))) <= min(worst.values()) * 1.05
        # the start-up window scored apart: the winner's start-up error / max |f'| (= 1 here), as the CSV shows it
        win = min(worst, key=worst.get)[:-6]
        start = next(q["value"] for q in data["quantities"] if q["id"] == win + ".startup")
        before = ~after
        assert start == pytest.approx(np.max(np.abs(est[before, 2] - np.cos(est[before, 0]))), rel=1e-6)
        assert est[0, 2] == pytest.approx(0.0, abs=1e-9)  # started at rest on the first sample: f̂'(0) = 0
    # a Pareto front needs a noise-free signal: the surrogate's fit has one, a record with its derivative has none
    assert sorted(data["figures"]) == ["ranking.png", "record_estimate.png"] + ([] if derivative else
                                                                               ["record_pareto.png"])
    assert all((folder / fig).stat().st_size > 5_000 for fig in data["figures"])
    report = (folder / "REPORT.md").read_text()
    assert "start-up window" in report and "| 1 |" in report and "estimate.csv" in report
    printed = capsys.readouterr().out
    assert "start-up window" in printed and str(folder) in printed


def test_bounds_without_a_record_and_a_file_as_out_are_usage_errors(tmp_path, capsys):
    assert main(["arena", "--noise-bound", "0.01"]) == 2
    assert "--noise-bound describes a record: give it with --signal" in capsys.readouterr().err
    assert main(["arena", "--noise-bound", "0.01", "--accel-bound", "1"]) == 2
    assert "--noise-bound and --accel-bound describe a record: give them with --signal" in capsys.readouterr().err
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


# --------------------------------------------------------------------- the record checked before any work (#28)
def _arena(args, capsys):
    code = main(["arena", *args])
    cap = capsys.readouterr()
    return code, cap.out, cap.err


@pytest.mark.parametrize("values, eps, L, message", [
    (1.0, "0.01", "1e-6", "--accel-bound 1e-06 is far below what the record's y shows: beyond its noise, its smoothed "
                          "second differences reach |f''| ≈ 0.8"),
    (1.0, "1e-8", "1", "--noise-bound 1e-08 is far below the record's own noise: the spread of its third differences "
                       "gives ε ≈ 0.011"),
    (1.0, "1e4", "1", "the bounds' time scale √(ε/L) = 100 s is longer than the record (5.99 s)"),
    (1.0, "0.01", "1e-300", "--accel-bound is 1e-300, outside the magnitudes 1e-50 to 1e+50"),
    (1e200, "0.01", "1", "the largest |measurement| (y) is 1.01e+200, outside the magnitudes 1e-50 to 1e+50"),
], ids=["accel-1e6-too-small", "noise-1e6-too-small", "noise-1e6-too-large", "bound-1e-300", "values-1e200"])
def test_bounds_the_record_contradicts_are_one_line_and_nothing_written(tmp_path, capsys, values, eps, L, message):
    t = 0.01 * np.arange(600)
    y = values * (np.sin(t) + 0.01 * np.random.default_rng(0).uniform(-1, 1, t.size))
    f = _csv(tmp_path / "rec.csv", np.column_stack([t, y]))
    out = tmp_path / "D"
    code, printed, err = _arena(["--signal", str(f), "--noise-bound", eps, "--accel-bound", L, "--out", str(out)],
                                capsys)
    assert code == 2 and printed == "" and err.count("\n") == 1 and message in err, err
    assert err.startswith(f"ctrl-analysis: error: --signal path {str(f)!r}") or "--accel-bound is" in err
    assert not out.exists()


def test_a_bound_looser_than_the_record_is_a_warning_recorded_beside_the_records_estimates(tmp_path, capsys):
    """--accel-bound 1e6 x too large: before, 'alpha, beta must give a stable filter' (exit 2); now the run, with
    one warning line, no numpy warning, and both the stated bounds and the record's estimates in the outputs."""
    import warnings

    f = _sine_csv(tmp_path / "rec.csv", derivative=False)
    out = tmp_path / "D"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning (overflow, invalid value) anywhere in the run
        code, printed, err = _arena(["--signal", str(f), "--noise-bound", "0.01", "--accel-bound", "1e6", "--out",
                                     str(out), "--jobs", "1"], capsys)
    assert code == 0
    assert [line for line in err.splitlines() if not line.startswith("[arena]")] == [
        "ctrl-analysis: warning: --accel-bound 1e+06 is 1.07e+06× above what the record shows (|f''| ≈ 0.938 beyond "
        "its noise): the ranking is tuned for the stated bound, and errors below the bound 2√(εL) are to be expected "
        "on this record"]
    assert "stated ε = 0.01, L = 1e+06; the record's own estimates: ε ≈ 0.01141, |f''| ≈ 0.9379" in printed
    data = validate_results(json.loads((out / "arena" / "results.json").read_text()))
    rc = data["settings"]["record_check"]
    assert rc["stated"] == {"noise_bound": 0.01, "accel_bound": 1e6} and len(rc["warnings"]) == 1
    assert rc["estimates"]["noise_bound"] == pytest.approx(0.01141, rel=1e-3)
    q = {x["id"]: x["value"] for x in data["quantities"]}
    assert q["record.accel_estimate"] == pytest.approx(0.9379, rel=1e-3)
    assert all(np.isfinite(v) for k, v in q.items() if k.endswith((".worst", ".ratio")))
    report = (out / "arena" / "REPORT.md").read_text()
    assert "noise ε = 0.01 (record: ε̂ ≈ 0.01141" in report and "|f''| ≤ L = 1e+06 (record: ≈ 0.9379" in report
    assert "**Warning:** --accel-bound 1e+06 is 1.07e+06× above" in report


def test_a_byte_order_mark_keeps_the_first_row(tmp_path):
    t = 0.01 * np.arange(40)
    body = "\n".join(f"{a!r},{b!r}" for a, b in zip(t.tolist(), np.sin(t).tolist(), strict=True)) + "\n"
    for name, text in (("bom.csv", body), ("bom_header.csv", "time,y\n" + body)):
        (tmp_path / name).write_text("\ufeff" + text, encoding="utf-8")
        tt, y, _ = read_record(tmp_path / name)
        assert tt.size == 40 and tt[0] == 0.0 and y[1] == np.sin(0.01), name


@pytest.mark.parametrize("kind", ["dev-zero", "folder", "fifo", "200 MB", "2 GiB"])
def test_what_is_not_a_small_regular_file_is_refused_before_it_is_read(tmp_path, capsys, kind):
    import os

    path = {"dev-zero": "/dev/zero", "folder": str(tmp_path)}.get(kind, str(tmp_path / "f.csv"))
    if kind == "dev-zero" and not os.path.exists(path):
        pytest.skip("no /dev/zero here")
    if kind == "fifo":
        os.mkfifo(path)  # opening it would wait for a writer forever
    if kind in ("200 MB", "2 GiB"):
        with open(path, "wb") as fh:  # sparse: no disk or memory is used
            fh.truncate(200 * 10**6 if kind == "200 MB" else 2 * 2**30)
    code, _, err = _arena(["--signal", path, "--noise-bound", "0.01", "--accel-bound", "1",
                           "--out", str(tmp_path / "D")], capsys)
    assert code == 2 and err.count("\n") == 1
    if kind.endswith("B"):
        assert "MiB, over the limit of 128 MiB (and at most 1000000 rows): decimate the record" in err
    else:
        assert "is not a regular file (a CSV file is needed, not a device, pipe or folder)" in err
    assert not (tmp_path / "D").exists()


def test_more_rows_than_the_limit_are_refused(tmp_path, monkeypatch):
    from ctrl_analysis.arena import recordcheck

    monkeypatch.setattr(recordcheck, "MAX_ROWS", 50)
    f = _sine_csv(tmp_path / "rec.csv", derivative=False, n=100)
    with pytest.raises(ValueError, match="has 100 rows, over the limit of 50: decimate the record"):
        read_record(f)
    f.write_text(f.read_text().split("\n", 1)[1])  # no header, no trailing newline: counted after parsing
    f.write_text(f.read_text().rstrip("\n"))
    monkeypatch.setattr(recordcheck, "MAX_ROWS", 99)
    with pytest.raises(ValueError, match="has 100 rows, over the limit of 99"):
        read_record(f)


def test_quick_with_a_file_as_out_and_a_bad_scheduler_are_refused_before_any_work(tmp_path, capsys, monkeypatch):
    from ctrl_analysis.arena import recommend

    def no_work(*args, **kwargs):
        raise AssertionError("the arena started tuning")

    monkeypatch.setattr(recommend, "run_arena", no_work)
    (tmp_path / "FILE").write_text("x")
    code, _, err = _arena(["--quick", "--out", str(tmp_path / "FILE")], capsys)
    assert code == 2
    assert err == f"ctrl-analysis: error: --out must be a directory, got the file {str(tmp_path / 'FILE')!r}\n"
    code, _, err = _arena(["--quick", "--scheduler", "nonsense", "--out", str(tmp_path / "D")], capsys)
    assert code == 2 and err.count("\n") == 1 and "got 'nonsense'" in err and "Traceback" not in err
    assert not (tmp_path / "D").exists()
    code, _, err = _arena(["--quick", "--runs", "1001", "--out", str(tmp_path / "D")], capsys)
    assert code == 2 and err == "ctrl-analysis: error: --runs must be in 1..1000 (records per case), got 1001\n"
    assert not (tmp_path / "D").exists()


def test_the_library_entry_checks_the_record_and_refuses_non_finite_errors(monkeypatch):
    from ctrl_analysis.arena import recommend

    t = 0.01 * np.arange(600)
    y = np.sin(t) + 0.01 * np.random.default_rng(0).uniform(-1, 1, t.size)
    with pytest.raises(ValueError, match="^the record: L 1e-06 is far below"):
        recommend.recommend_for_record(t, y, None, 0.01, 1e-6)
    with pytest.raises(ValueError, match="^eps must be"):
        recommend.recommend_for_record(t, y, None, -0.01, 1.0)

    def diverged(names, cases, setup, **kwargs):
        return {name: {"best": [{"worst": (np.array([1.0] * len(family(name).params)), np.array([np.inf] * 4))}]}
                for name in names}

    from ctrl_analysis.arena.interface import family

    monkeypatch.setattr(recommend, "tune_families", diverged)
    with pytest.raises(ValueError, match="every tuning of the sigma family gave a non-finite derivative error"):
        recommend.recommend_for_record(t, y, None, 0.01, 1.0)


def test_a_record_at_the_edge_of_the_scale_ranks_as_the_original_without_overflow():
    import warnings

    from ctrl_analysis.arena.recommend import recommend_for_record

    t = 0.01 * np.arange(300)
    y = np.sin(t) + 0.01 * np.random.default_rng(0).uniform(-1, 1, t.size)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        a = recommend_for_record(t, y, None, 0.01, 1.0, rounds=0)
        b = recommend_for_record(t, 2.0**150 * y, None, 2.0**150 * 0.01, 2.0**150, rounds=0)  # ~1.4e45
    assert [r["family"] for r in a] == [r["family"] for r in b]
    assert [r["ratio"] for r in a] == pytest.approx([r["ratio"] for r in b], rel=1e-9)


def test_several_channels_each_ranked_in_their_own_folder(tmp_path, capsys):
    from ctrl_analysis.arena.cli import read_channels

    t = 0.002 * np.arange(1500)
    rng = np.random.default_rng(4)
    cols = [t, np.sin(2 * t) + 0.01 * rng.uniform(-1, 1, t.size), 3 * np.cos(t) + 0.02 * rng.uniform(-1, 1, t.size)]
    f = _csv(tmp_path / "ch.csv", np.column_stack(cols), "time,left arm,left arm")
    assert read_channels(f)[1] == ["left_arm", "left_arm_2"]
    # without --channels a third column is the derivative, a fourth is refused naming the option
    g = _csv(tmp_path / "four.csv", np.column_stack(cols + [t]), "t,a,b,c")
    assert main(["arena", "--signal", str(g)]) == 2
    assert "4 columns" in capsys.readouterr().err
    assert main(["arena", "--channels"]) == 2
    assert "--channels describes a record's columns" in capsys.readouterr().err
    assert main(["arena", "--signal", str(f), "--channels", "--out", str(tmp_path / "o"), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "== channel left_arm" in out and "== channel left_arm_2" in out
    noise = {}
    for name in ("left_arm", "left_arm_2"):
        r = json.loads((tmp_path / "o" / "arena" / name / "results.json").read_text())
        noise[name] = r["settings"]["noise_bound"]  # each channel's bounds estimated from its own samples
    assert 0.5 < noise["left_arm"] / 0.01 < 2 and 0.5 < noise["left_arm_2"] / 0.02 < 2
