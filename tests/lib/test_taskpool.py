"""One pool for a whole run: drivers' chunks run on the shared workers, in order, with the same values."""

import json
import os

import numpy as np
import pytest

from ctrl_analysis.runs import parallel, taskpool


def _square(x):
    return x * x, os.getpid()


def _driver(n):
    """A study's driver: maps its chunks (jobs > 1) and says where they ran."""
    with taskpool.driver():
        out = parallel.map_chunks(_square, list(range(n)), jobs=4)
    return [v for v, _ in out], {pid for _, pid in out}, os.getpid(), taskpool.pool_available()


def _nested(x):
    """A chunk that maps again: in a pool worker it runs its calls in place (no call waits on the pool)."""
    return sum(v for v, _ in parallel.map_chunks(_square, [x, x + 1], jobs=2))


def _nested_driver(_):
    return parallel.map_chunks(_nested, [1, 2, 3], jobs=2)


def _fails(x):
    if x == 2:
        raise ValueError("chunk 2 is bad")
    return x


def _failing_driver(_):
    try:
        parallel.map_chunks(_fails, [0, 1, 2, 3], jobs=2)
    except ValueError as exc:
        return str(exc)
    return "no error"


def test_drivers_send_their_chunks_to_the_one_pool_in_order_and_traced(tmp_path, monkeypatch):
    monkeypatch.setenv("CTRL_ANALYSIS_TRACE", str(tmp_path / "trace"))
    with taskpool.shared_pool(2):
        assert not taskpool.pool_available()  # the owner maps as before (its drivers are its own processes)
        results = parallel.map_chunks(_driver, [5, 7], jobs=2, scheduler=False)
    for (values, pids, driver, available), n in zip(results, [5, 7], strict=True):
        assert values == [i * i for i in range(n)]
        assert available and driver not in pids  # the chunks ran on the pool's workers, not in the driver
    events = [json.loads(line) for f in sorted((tmp_path / "trace").glob("*.jsonl")) for line in f.open()]
    # the owner's map of the two drivers ("processes") and each driver's map on the pool; no worker writes
    assert sorted((e["where"], len(e["calls"])) for e in events) == [("pool", 5), ("pool", 7), ("processes", 2)]
    for e in events:
        assert all(e["submitted"] <= s + 1e-3 and s <= t <= e["returned"] + 1e-3 and 0 <= c <= t - s + 1e-2
                   for s, t, c in e["calls"])
        assert e["cpu_submitted"] <= e["cpu_returned"]
    assert not taskpool.pool_available() and taskpool._ENV not in os.environ


def test_calls_inside_a_call_are_part_of_it_in_the_trace(tmp_path, monkeypatch):
    monkeypatch.setenv("CTRL_ANALYSIS_TRACE", str(tmp_path / "t"))
    assert parallel.map_chunks(_nested, [1, 2]) == [1 + 4, 4 + 9]
    (f,) = (tmp_path / "t").glob("*.jsonl")
    (event,) = [json.loads(line) for line in f.open()]  # one map of two calls; their inner maps are inside them
    assert event["where"] == "here" and len(event["calls"]) == 2


def test_a_chunk_that_maps_again_runs_in_place_and_errors_reach_the_driver():
    with taskpool.shared_pool(2):
        nested = parallel.map_chunks(_nested_driver, [0, 0], jobs=2, scheduler=False)
        failed = parallel.map_chunks(_failing_driver, [0, 0], jobs=2, scheduler=False)
    assert nested == [[1 + 4, 4 + 9, 9 + 16]] * 2
    assert failed == ["chunk 2 is bad"] * 2


def test_shared_pool_refuses_a_bad_job_count():
    with pytest.raises(ValueError, match="jobs"), taskpool.shared_pool(0):
        pass


def test_values_through_the_pool_are_bit_identical():
    with taskpool.shared_pool(2):
        a = parallel.map_chunks(_driver_arrays, [3], jobs=2, scheduler=False)[0]
    b = [np.random.default_rng(s).standard_normal(1000).cumsum() for s in range(3)]
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)


def _rng_chunk(seed):
    return np.random.default_rng(seed).standard_normal(1000).cumsum()


def _driver_arrays(n):
    return parallel.map_chunks(_rng_chunk, list(range(n)), jobs=2)


def _figure_driver(folder):
    """A study's driver saving two figures: one that pickles (rendered by the pool), one holding a lambda (here)."""
    import matplotlib.ticker as mticker

    from ctrl_analysis.reporting.report import StudyContext, StudyInfo, StudyResult, new_figure

    with taskpool.driver():
        ctx = StudyContext(out_dir=folder)
        result = StudyResult(StudyInfo(name="toy", seed_file="toy.txt", paper="toy", reproduces="toy"))
        for name, formatter in (("pool.png", None), ("here.png", mticker.FuncFormatter(lambda v, _: f"{v:.1f}"))):
            fig, ax = new_figure(title=name)
            ax.plot(np.sin(np.linspace(0.0, 6.0, 200)), label="sin")
            ax.legend()
            if formatter is not None:
                ax.yaxis.set_major_formatter(formatter)
            ctx.save_figure(result, fig, name, dpi=60)
        sent = [name for _, _, name in ctx._pending]
        ctx.wait_figures()
    return sent, result.figures


def test_figures_render_in_the_pool_with_the_same_bytes(tmp_path, monkeypatch):
    """Issue 30: in a run's shared pool a study's figures are rendered by the pool's workers while the study goes on;
    the PNG equals the one rendered in place, and a figure that does not pickle is rendered in place."""
    monkeypatch.setenv("CTRL_ANALYSIS_TRACE", str(tmp_path / "trace"))
    with taskpool.shared_pool(2):
        out = parallel.map_chunks(_figure_driver, [tmp_path / "pool", tmp_path / "pool2"], jobs=2, scheduler=False)
    assert all(sent == ["pool.png"] and figures == ["pool.png", "here.png"] for sent, figures in out)
    figures = out[0][1]
    monkeypatch.delenv("CTRL_ANALYSIS_TRACE")
    _figure_driver(tmp_path / "here")  # no pool: both in place
    for name in figures:
        assert (tmp_path / "pool" / name).read_bytes() == (tmp_path / "here" / name).read_bytes()
    events = [json.loads(line) for f in sorted((tmp_path / "trace").glob("*.jsonl")) for line in f.open()]
    renders = [e for e in events if e.get("async")]
    assert len(renders) == 2  # one per driver
    assert all(e["cpu_submitted"] == e["cpu_returned"] and len(e["calls"]) == 1 for e in renders)


def test_a_figure_the_pool_could_not_render_is_named_when_the_study_waits(tmp_path):
    import threading

    from ctrl_analysis.reporting.report import StudyContext

    ctx = StudyContext(out_dir=tmp_path)
    done = threading.Thread(target=lambda: None)
    done.start()
    ctx._pending.append((done, [OSError("disk full")], "a.png"))
    with pytest.raises(RuntimeError, match="figure a.png could not be rendered: OSError: disk full"):
        ctx.wait_figures()
    ctx.wait_figures()  # nothing left
