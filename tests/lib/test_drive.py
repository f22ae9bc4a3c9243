"""Chains of maps advanced side by side (chains.drive), one pool for a command (pool_here), and the pool's
priorities (issue 30: the arena's families no longer wait for one another round by round)."""

import json
import os
import threading
import time
from concurrent.futures import Future

import pytest

from ctrl_analysis.runs import chains, parallel, taskpool


def _square(x):
    return x * x


def _slow(x):
    time.sleep(x)
    return x


def _chain(rounds, width):
    """Yields ``rounds`` lists of ``width`` numbers; each round's numbers depend on the last round's squares."""
    seen, base = [], 1
    for _ in range(rounds):
        got = yield [base + i for i in range(width)]
        seen.append(got)
        base = sum(got) % 7 + 1
    return seen


def _failing(rounds):
    yield [1]
    raise ValueError("chain b broke")


def _by_hand(rounds, width):
    seen, base = [], 1
    for _ in range(rounds):
        seen.append([(base + i) ** 2 for i in range(width)])
        base = sum(seen[-1]) % 7 + 1
    return seen


def test_every_chain_is_sent_its_own_values_in_lockstep_and_in_a_pool():
    want = {"a": _by_hand(2, 1), "b": _by_hand(4, 2), "c": []}
    assert want["b"][:2] == [[1, 4], [36, 49]] and want["a"] == [[1], [4]]  # each round from the last
    serial = chains.drive(_square, {"a": _chain(2, 1), "b": _chain(4, 2), "c": _chain(0, 2)})
    assert serial == want and list(serial) == ["a", "b", "c"]
    with chains.pool_here(2) as opened:
        assert opened and taskpool.pool_available()
        pooled = chains.drive(_square, {"a": _chain(2, 1), "b": _chain(4, 2), "c": _chain(0, 2)}, jobs=2)
    assert pooled == want and not taskpool.pool_available()


def test_lockstep_joins_the_chains_lists_round_by_round():
    together = chains.lockstep({"a": _chain(1, 2), "b": _chain(2, 1)})
    assert next(together) == [1, 2, 1]  # a's two numbers, then b's one
    assert together.send([1, 4, 1]) == [2]  # a is done; b's second round starts at 1 % 7 + 1
    with pytest.raises(StopIteration) as done:
        together.send([4])
    assert done.value.value == {"a": [[1, 4]], "b": [[1], [4]]}


def test_in_a_pool_a_slow_chain_does_not_hold_back_a_quick_one(tmp_path, monkeypatch):
    monkeypatch.setenv("CTRL_ANALYSIS_TRACE", str(tmp_path))

    def slow():
        yield [1.0]

    def quick():
        for _ in range(3):
            yield [0.0]

    with chains.pool_here(2):
        chains.drive(_slow, {"slow": slow(), "quick": quick()}, jobs=2)
    events = [json.loads(line) for f in tmp_path.glob("*.jsonl") for line in f.open()]
    maps = {lane: sorted((e for e in events if e.get("lane") == lane and e["kind"] == "map"),
                         key=lambda e: e["submitted"]) for lane in ("slow", "quick")}
    assert len(maps["slow"]) == 1 and len(maps["quick"]) == 3
    # the quick chain's later rounds were sent while the slow chain's one call still ran (in lockstep they wait)
    assert maps["quick"][-1]["submitted"] < maps["slow"][0]["returned"]
    fans = [e for e in events if e["kind"] == "fan"]
    lanes = [e for e in events if e["kind"] == "lane"]
    assert len(fans) == 1 and {e["lane"] for e in lanes} == {"slow", "quick"}
    assert all(e["fan"] == fans[0]["fan"] for e in lanes + maps["slow"] + maps["quick"])


def test_a_failed_chain_raises_its_error_after_the_others_stop():
    for opened in (False, True):
        with chains.pool_here(2 if opened else 1):
            with pytest.raises(ValueError, match="chain b broke"):
                chains.drive(_square, {"a": _chain(3, 1), "b": _failing(1)}, jobs=2 if opened else 1)


def test_pool_here_opens_only_where_no_pool_or_cluster_serves_the_maps():
    with chains.pool_here(1) as opened:
        assert not opened and not taskpool.pool_available()
    with chains.pool_here(2, scheduler=False) as outer:
        with chains.pool_here(2) as inner:
            assert outer and not inner  # one pool; the inner block uses it
            assert parallel.map_chunks(_square, [1, 2, 3], jobs=2) == [1, 4, 9]
    with pytest.raises(ValueError, match="jobs"), chains.pool_here(0):
        pass
    assert os.environ.get(taskpool._ENV) is None


class _Executor:
    """Records what the feed hands it; each call finishes when the test says."""

    def __init__(self):
        self.order, self.futures = [], []

    def submit(self, fn, blob):
        fut = Future()
        self.order.append(blob)
        self.futures.append(fut)
        return fut


def _wait_for(cond):
    for _ in range(2000):
        if cond():
            return
        time.sleep(0.005)
    raise AssertionError("the feed did not hand the call on")


def test_the_pool_serves_lower_priority_first_then_first_come():
    ex = _Executor()
    feed = taskpool._Feed(ex, depth=1)
    got = []
    try:
        never = threading.Event()
        feed.submit(0, b"first", got.append, never)
        _wait_for(lambda: len(ex.order) == 1)  # the one slot is taken: the others wait
        feed.submit(0, b"late-0", got.append, never)
        feed.submit(0, b"later-0", got.append, never)
        feed.submit(-1, b"urgent", got.append, never)
        for i in range(3):
            ex.futures[i].set_result(i)
            _wait_for(lambda i=i: len(ex.order) == i + 2)
        assert ex.order == [b"first", b"urgent", b"late-0", b"later-0"]
        assert len(got) == 3  # done() called for each finished call
    finally:
        feed.close()


def test_a_dropped_call_is_never_handed_on():
    ex = _Executor()
    feed = taskpool._Feed(ex, depth=1)
    dropped = threading.Event()
    try:
        feed.submit(0, b"a", lambda f: None, threading.Event())
        _wait_for(lambda: len(ex.order) == 1)
        feed.submit(0, b"b", lambda f: None, dropped)
        feed.submit(0, b"c", lambda f: None, threading.Event())
        dropped.set()
        ex.futures[0].set_result(0)
        _wait_for(lambda: len(ex.order) == 2)
        assert ex.order == [b"a", b"c"]
    finally:
        feed.close()


def test_drive_refuses_what_is_not_a_dict_of_generators_and_bad_priorities():
    with pytest.raises(TypeError, match="chains"):
        chains.drive(_square, {"a": [1, 2]})
    with pytest.raises(TypeError, match="priority"):
        chains.drive(_square, {"a": _chain(1, 1)}, priority={"b": 1})
    with pytest.raises(TypeError, match="priority"):
        chains.drive(_square, {"a": _chain(1, 1)}, priority={"a": True})
