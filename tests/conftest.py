"""Suite-wide time limits and ordering.

Every test's time limit (pytest-timeout: the ``timeout`` in pyproject.toml, or a test's own
``@pytest.mark.timeout``) is a hang detector, scaled here with the measured load and speed of this machine
(:mod:`hang`), so a loaded CI machine cannot reach it without a real hang.

Ordering: the end-to-end ``reproduce all --quick`` test starts first, the long waiting tests next.

On a fresh clone numba compiles every loop structure once and caches it on disk. Started first, the
end-to-end run compiles the studies' structures (in its own processes) while the other pytest-xdist
worker runs the library tests; the study tests that come later load them from the cache instead of
compiling the same structures at the same time in another process.
"""

import pytest
from hang import limit


def _scale_time_limits(config, items) -> None:
    base = float(config.getini("timeout") or 0)
    for item in items:
        marker = item.get_closest_marker("timeout")
        seconds = float(marker.args[0]) if marker is not None and marker.args else base
        if seconds > 0:
            item.add_marker(pytest.mark.timeout(limit(seconds)), append=False)


#: Long tests that mostly wait (on subprocesses, a Dask cluster, stand-in studies that sleep) start right
#: after the end-to-end run, so the other worker's short tests fill the time instead of queueing behind them.
EARLY = ("test_reproduce_all_quick_writes_valid_results",
         "test_a_study_on_a_real_cluster_equals_the_run_in_one_process",
         "test_interrupts_and_kills_at_several_points_leave_report_and_results_in_agreement",
         "test_two_runs_into_one_folder_do_not_interleave")


def pytest_collection_modifyitems(config, items):
    _scale_time_limits(config, items)
    first = sorted((item for item in items if item.nodeid.endswith(EARLY)),
                   key=lambda item: [item.nodeid.endswith(name) for name in EARLY].index(True))
    items[:] = first + [item for item in items if item not in first]
