"""benchmarks/scaling.py's replay: a recorded run's studies scheduled on W workers (issue 30, item 5)."""

import importlib.util
from pathlib import Path

import pytest

_SPEC = importlib.util.spec_from_file_location("scaling", Path(__file__).parents[2] / "benchmarks" / "scaling.py")
scaling = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(scaling)


def test_a_map_waits_and_a_figure_rendered_in_the_pool_does_not():
    # driver 1 s, a map of two 2 s calls, driver 1 s; then the same with the map's calls sent as figures (async)
    blocking = {"a": [("serial", 1.0), ("map", [2.0, 2.0]), ("serial", 1.0)]}
    rendered = {"a": [("serial", 1.0), ("async", [2.0, 2.0]), ("serial", 1.0)]}
    assert scaling.replay(blocking, 3) == pytest.approx(4.0)  # 1 + 2 + 1
    assert scaling.replay(rendered, 3) == pytest.approx(3.0)  # the figures end at 3, after the driver's 2
    assert scaling.replay(rendered, 1) == pytest.approx(6.0)  # one worker: all the work, one piece at a time
    assert scaling.critical_path(blocking) == pytest.approx(4.0)
    assert scaling.critical_path(rendered) == pytest.approx(3.0)


def test_a_driver_takes_the_next_study_only_when_its_figures_are_done():
    chains = {"a": [("serial", 1.0), ("async", [5.0])], "b": [("serial", 2.0)]}
    # 2 workers, 1 driver slot each: a (longest) and b start together; b ends at 2, a's figure at 6
    assert scaling.replay(chains, 2) == pytest.approx(6.0)
    # with 3 studies and 2 drivers, the third waits for a driver, not for a's figure's worker
    chains["c"] = [("serial", 1.0)]
    assert scaling.replay(chains, 2) == pytest.approx(6.0)
