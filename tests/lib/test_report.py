"""Report layer: computed verdicts, results.json contract, REPORT.md."""

import json
import math

import numpy as np
import pytest

from ctrl_analysis.reporting.markdown import write_report_md
from ctrl_analysis.reporting.report import (
    Quantity,
    StudyContext,
    StudyInfo,
    StudyResult,
    compute_verdict,
    read_runtime,
    relative_error,
    write_results_json,
)

INFO = StudyInfo(name="demo", seed_file="x.txt", paper="A paper", reproduces="things")


@pytest.mark.parametrize(
    "value,paper,tol,verdict",
    [
        (1.05, 1.0, 0.1, "agrees"),
        (1.2, 1.0, 0.1, "differs"),
        (3.0, None, None, "new"),
        ([1.0, 2.1], [1.0, 2.0], 0.1, "agrees"),
        ([1.0, 2.5], [1.0, 2.0], 0.1, "differs"),
        ([1.0], [1.0, 2.0], 0.5, "differs"),  # shape mismatch never agrees
        (float("nan"), 1.0, 10.0, "differs"),  # a diverged value never agrees
        (None, 1.0, 0.1, "differs"),
        (0.05, 0.0, 0.1, "agrees"),  # absolute error where the paper value is 0
    ],
)
def test_verdict_is_computed(value, paper, tol, verdict):
    assert compute_verdict(value, paper, tol) == verdict
    assert Quantity("q", "q", value, paper, tolerance=tol).verdict == verdict


def test_relative_error():
    assert relative_error(-9.0, -10.0) == pytest.approx(0.1)
    assert math.isinf(relative_error([1, 2], [1]))


def test_results_json_contract(tmp_path):
    r = StudyResult(INFO, settings={"h": np.float64(1e-3), "n": np.int64(5), "v": np.arange(3)})
    r.quantity("a.b", "a quantity", np.float64(1.29e-4), paper=1.3179e-4, std=2e-6, runs=20, tolerance=0.25)
    r.quantity("a.c", "a diverged one", float("nan"), paper=1.0)
    r.quantity("a.d", "new", [1.0, 2.0])
    r.reconstruction("h", 1e-3, "the paper does not print it")
    r.finding("eq9-typo", "text", evidence={"x": 1})
    with pytest.raises(ValueError, match="a.b"):
        r.quantity("a.b", "dup", 1.0)
    r.runtime_s = 1.25
    data = json.loads(write_results_json(r, tmp_path).read_text())
    assert set(data) >= {"study", "seed_file", "settings", "reconstructions", "quantities", "findings", "figures",
                         "versions"}
    # the wall time varies between identical runs: beside results.json (untracked), not in it
    assert "runtime_s" not in data and read_runtime(tmp_path) == 1.25
    assert read_runtime(tmp_path / "nowhere") is None
    q = {d["id"]: d for d in data["quantities"]}
    assert q["a.b"]["verdict"] == "agrees" and q["a.b"]["runs"] == 20 and q["a.b"]["tolerance"] == 0.25
    assert q["a.c"]["value"] is None and q["a.c"]["verdict"] == "differs" and "not finite" in q["a.c"]["note"]
    assert q["a.d"]["verdict"] == "new" and q["a.d"]["tolerance"] is None
    assert all(d["unit"] == "" for d in data["quantities"])  # the key is always present
    assert data["settings"] == {"h": 1e-3, "n": 5, "v": [0, 1, 2]}
    assert data["versions"]["control"]


def test_report_md_lists_tables_findings_figures(tmp_path):
    r = StudyResult(INFO)
    r.quantity("x", "x", 2.0, paper=1.0)
    r.finding("f1", "a finding")
    r.figures.append("fig1.png")
    r.missing.append("part B")
    text = write_report_md([r.to_dict()], tmp_path).read_text()
    assert "| `x` | x |  | 1 | 2 | — | 50 % | differs |" in text  # printed "1": half a unit is 50 %
    assert "- **a finding**" in text and text.count("\n| `x`") == 1
    assert "![fig1.png](demo/fig1.png)" in text and "part B" in text


def test_context_runs_and_save_figure(tmp_path):
    from ctrl_analysis.reporting.report import new_figure

    assert StudyContext(tmp_path).runs_or(100, 5) == 100
    assert StudyContext(tmp_path, quick=True).runs_or(100, 5) == 5
    assert StudyContext(tmp_path, runs=7, quick=True).runs_or(100, 5) == 7
    r = StudyResult(INFO)
    fig, ax = new_figure(title="t")
    ax.plot([0, 1], [0, 1])
    path = StudyContext(tmp_path).save_figure(r, fig, "f.png")
    assert path.exists() and path.stat().st_size > 1000 and r.figures == ["f.png"]


def test_table_cells_escape_pipes(tmp_path):
    r = StudyResult(INFO)
    r.quantity("e", "mean |x - x_hat|", 1.0, note="a | b")
    row = [line for line in write_report_md([r.to_dict()], tmp_path).read_text().splitlines()
           if line.startswith("| `e`")][0]
    assert row.count("|") - row.count("\\|") == 10  # nine cells, ten unescaped separators


def test_merging_parts_recorded_apart_equals_recording_them_in_order():
    """Issue 30: a study records independent parts in other processes and merges them in order: the same
    results.json as one process recording them one after the other; a part that repeats an id is refused."""
    info = StudyInfo("s", "f", "p", "r")

    def part_a(r):
        r.quantity("a.x", "x", 1.0, paper=1.0)
        r.reconstruction("a_h", 0.1, "not printed")
        r.figures.append("a.png")
        r.captions["a.png"] = "caption a"
        r.seeds["a"] = [1, 2]

    def part_b(r):
        r.quantity("b.y", "y", 2.0)
        r.finding("b-f", "found")
        r.figures.append("b.png")
        r.captions["b.png"] = "caption b"
        r.settings["b"] = {"T": 5}

    whole = StudyResult(info)
    part_a(whole)
    part_b(whole)
    merged, a, b = StudyResult(info), StudyResult(info), StudyResult(info)
    part_a(a)
    part_b(b)
    merged.merge(a)
    merged.merge(b)
    assert json.dumps(merged.to_dict(), sort_keys=False) == json.dumps(whole.to_dict(), sort_keys=False)
    with pytest.raises(ValueError, match=r"quantity ids already recorded here: \['a.x'\]"):
        merged.merge(a)
    with pytest.raises(ValueError, match="of study 's'"):
        merged.merge(StudyResult(StudyInfo("t", "f", "p", "r")))


def test_figures_saved_side_by_side_are_the_bytes_saved_one_by_one(tmp_path):
    """Issue 30: StudyContext.save_figures renders several figures over its processes: the same PNGs, captions and
    figure list as save_figure one by one; a figure holding a lambda is rendered in place."""
    import matplotlib.ticker as mticker

    from ctrl_analysis.reporting.report import new_figure

    def figs():
        out = []
        for i in range(3):
            fig, ax = new_figure(title=f"figure {i}")
            ax.plot(np.cos(np.linspace(0.0, 3.0 + i, 50)), label="cos")
            ax.legend()
            if i == 1:
                ax.yaxis.set_major_formatter(mticker.FuncFormatter(lambda v, _: f"{v:.2f}"))
            out.append((fig, f"f{i}.png", f"caption {i}", 60))
        return out

    one, many = StudyResult(INFO), StudyResult(INFO)
    for fig, name, caption, dpi in figs():
        StudyContext(out_dir=tmp_path / "one").save_figure(one, fig, name, dpi=dpi, caption=caption)
    paths = StudyContext(out_dir=tmp_path / "many", jobs=2).save_figures(many, figs())
    assert [p.name for p in paths] == many.figures == one.figures == ["f0.png", "f1.png", "f2.png"]
    assert many.captions == one.captions
    for name in one.figures:
        assert (tmp_path / "many" / name).read_bytes() == (tmp_path / "one" / name).read_bytes()
    with pytest.raises(TypeError, match="figures must be a sequence"):
        StudyContext(out_dir=tmp_path).save_figures(many, [("not", "a tuple of 3 or 4", 1, 2, 3)])
