"""benchmarks/scaling.py's replay: a recorded run's studies scheduled on W workers (issue 30, item 5)."""

import importlib.util
import json
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


def _lane(phases, priority=0):
    lane = scaling.Lane(phases)
    lane.priority = priority
    return lane


def test_the_lanes_of_a_fan_go_on_independently_and_the_driver_waits_for_all():
    # lane x: one 3 s call; lane y: two 1 s calls one after the other. Side by side: 1 + 3 + 1 on 2 workers;
    # in lockstep y's second call would wait for x's call (1 + 3 + 1 + 1)
    fan = {"a": [("serial", 1.0), ("fan", [_lane([("map", [3.0])]), _lane([("map", [1.0]), ("map", [1.0])])]),
                 ("serial", 1.0)]}
    assert scaling.replay(fan, 2) == pytest.approx(5.0)
    assert scaling.replay(fan, 1) == pytest.approx(7.0)
    assert scaling.critical_path(fan) == pytest.approx(5.0)


def test_a_lane_with_a_lower_priority_is_served_first():
    # 2 workers; lane p (priority -1): a 1 s call, then a 4 s figure; lane q: four 1 s calls sent first
    def chains(prio):
        return {"a": [("fan", [_lane([("map", [1.0] * 4)]), _lane([("map", [1.0]), ("async", [4.0])], prio)])]}

    assert scaling.replay(chains(0), 2) == pytest.approx(7.0)  # FIFO: the figure starts at 3
    assert scaling.replay(chains(-1), 2) == pytest.approx(5.0)  # first: the figure starts at 1


def test_a_trace_with_a_fan_loads_as_lanes_with_their_own_cpu_clock(tmp_path):
    ev = [{"kind": "study", "study": "s", "start": 0.0, "end": 10.0, "cpu_start": 0.0, "cpu_end": 5.0},
          {"kind": "fan", "study": "s", "fan": "f", "submitted": 1.0, "returned": 9.0, "cpu_submitted": 1.0,
           "cpu_returned": 4.0},
          {"kind": "lane", "study": "s", "fan": "f", "lane": "x", "start": 1.0, "end": 8.0, "tcpu_start": 0.0,
           "tcpu_end": 0.5, "priority": -1},
          {"kind": "map", "study": "s", "fan": "f", "lane": "x", "submitted": 2.0, "returned": 5.0,
           "cpu_submitted": 1.5, "cpu_returned": 2.5, "tcpu_submitted": 0.2, "tcpu_returned": 0.3,
           "calls": [[2.0, 4.0, 1.5], [2.0, 5.0, 2.5]]},
          {"kind": "map", "study": "s", "fan": "f", "lane": "x", "async": True, "submitted": 5.5, "returned": 7.0,
           "cpu_submitted": 2.6, "cpu_returned": 2.6, "tcpu_submitted": 0.4, "tcpu_returned": 0.4,
           "calls": [[5.5, 7.0, 1.25]]}]
    (tmp_path / "1.jsonl").write_text("\n".join(json.dumps(e) for e in ev) + "\n")
    (study,) = scaling.load(str(tmp_path)).values()
    assert [p[0] for p in study] == ["serial", "fan", "serial"]
    assert study[0][1] == pytest.approx(1.0) and study[2][1] == pytest.approx(1.0)  # process CPU around the fan
    (lane,) = study[1][1]
    assert lane.priority == -1
    assert lane == [("serial", pytest.approx(0.2)), ("map", [1.5, 2.5]), ("serial", pytest.approx(0.1)),
                    ("async", [1.25]), ("serial", pytest.approx(0.1))]
