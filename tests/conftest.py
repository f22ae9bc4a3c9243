"""Suite-wide ordering: the end-to-end ``reproduce all --quick`` test starts first.

On a fresh clone numba compiles every loop structure once and caches it on disk. Started first, the
end-to-end run compiles the studies' structures (in its own processes) while the other pytest-xdist
worker runs the library tests; the study tests that come later load them from the cache instead of
compiling the same structures at the same time in another process.
"""


def pytest_collection_modifyitems(config, items):
    first = [item for item in items if item.nodeid.endswith("test_reproduce_all_quick_writes_valid_results")]
    items[:] = first + [item for item in items if item not in first]
