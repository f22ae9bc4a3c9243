"""Tests of ctrl_analysis.runs.parallel (processes, Dask), batch chunking in the engine, and progress bars."""

import io

import numpy as np
import pytest

from ctrl_analysis.engine import Execution, Save
from ctrl_analysis.engine.blocks import ContinuousBlock
from ctrl_analysis.engine.integrators import rk4_step
from ctrl_analysis.engine.loop import Loop, place
from ctrl_analysis.engine.memory import check_result_memory, chunk_bounds
from ctrl_analysis.estimators.differential import DifferentialEstimator
from ctrl_analysis.noise import draw_noise, gaussian_noise, run_seeds, uniform_noise
from ctrl_analysis.runs import cluster, parallel, progress

N_STEPS = 200


class Damped(ContinuousBlock):
    """x'' + c x' + k x = f + w, output y = x + v (a small noisy plant)."""

    inputs, outputs, states = ("w", "v"), ("y",), ("p", "q")
    feedthrough = True

    def __init__(self, k=4.0, c=0.4):
        self.k, self.c = k, c

    def initial_state(self):
        return np.array([1.0, 0.0])

    def rhs(self, t, x, u, params=None):
        dx = np.empty_like(x)
        dx[:, 0] = x[:, 1]
        dx[:, 1] = -self.k * x[:, 0] - self.c * x[:, 1] + u[:, 0]
        return dx

    def output(self, t, x, u, params=None):
        return x[:, :1] + u[:, 1:2]


def mc_chunk(seeds):
    """One Monte Carlo chunk: noise from the seeds, the loop, per-run mean |y - x̂1| and final states."""
    noise = draw_noise(seeds, N_STEPS, gaussian_noise([0.3, 0.01]))
    loop = Loop([place(Damped(), "plant"), place(DifferentialEstimator(3, 4.0), "sigma")], dt=0.01)
    res = loop.simulate(N_STEPS, inputs={"w": noise[:, :, 0], "v": noise[:, :, 1]}, seeds=seeds)
    return {"err": np.mean(np.abs(res.states["plant"][:, :, 0] - res["xhat[0]"]), axis=0),
            "x_end": res.x[-1]}


def sweep_fn(points, seeds):
    """A sweep chunk: the plant's stiffness k per run (a per-run parameter through the input), RMS of y."""
    noise = draw_noise(seeds, N_STEPS, uniform_noise([-0.1, -0.01], [0.1, 0.01]))
    k = points["k"]
    x = np.zeros((len(seeds), 2))
    x[:, 0] = points["x0"]

    def rhs(t, xx, u, params=None):
        dx = np.empty_like(xx)
        dx[:, 0] = xx[:, 1]
        dx[:, 1] = -k * xx[:, 0] - 0.4 * xx[:, 1] + u[:, 0]
        return dx

    xs = [x]
    for n in range(N_STEPS):  # RK4 with the noise held over each sample
        xs.append(rk4_step(rhs, 0.01 * n, xs[-1], noise[n], 0.01))
    return np.sqrt(np.mean(np.stack(xs)[:, :, 0] ** 2, axis=0))


def test_monte_carlo_in_two_processes_equals_one_process_bit_for_bit():
    seeds = run_seeds(11, 12)
    one = parallel.monte_carlo(mc_chunk, seeds, jobs=1)
    two = parallel.monte_carlo(mc_chunk, seeds, jobs=2)
    small = parallel.monte_carlo(mc_chunk, seeds, jobs=2, chunk_size=5)
    for other in (two, small):
        assert np.array_equal(one["err"], other["err"]) and np.array_equal(one["x_end"], other["x_end"])
    assert one["err"].shape == (12,) and np.all(one["err"] > 0)


@pytest.mark.parametrize("bad, error, message", [
    ([1, -2], ValueError, "seeds must be >= 0, got -2"),
    ([1, np.nan], TypeError, "seeds must be an integer"),
    ([1.5], TypeError, "seeds must be an integer, got 1.5"),
    (["x"], TypeError, "seeds must be an integer, got 'x'"),
    ([1 + 1j], TypeError, "seeds must be an integer"),
    (np.ones((2, 1, 1)), TypeError, "seeds must be an integer"),
    ([], ValueError, "seeds must contain at least one seed"),
    ("12", TypeError, "seeds must be a sequence of non-negative integers"),
])
def test_monte_carlo_and_sweep_take_non_negative_integer_seeds(bad, error, message):
    with pytest.raises(error, match=message):
        parallel.monte_carlo(_seeds_as_floats, bad)
    with pytest.raises(error, match=message):
        parallel.sweep(_sweep_rows, {"a": [1.0]}, bad)


def test_seeds_of_any_integer_kind_and_size_give_the_same_batch():
    one = parallel.monte_carlo(_seeds_as_floats, [0, 7, 2**40])
    assert np.array_equal(one, parallel.monte_carlo(_seeds_as_floats, np.array([0.0, 7.0, 2.0**40])))
    assert np.array_equal(parallel.monte_carlo(_seeds_as_floats, np.array([3, 4], dtype=np.uint32)), [3.0, 4.0])
    assert parallel.sweep(_sweep_rows, {"b": [1.0, 2.0]}, np.array([5, 6])).shape == (2, 2)


def _seeds_as_floats(seeds):
    return np.array([float(s) for s in seeds])


def _sweep_rows(points, seeds):
    (values,) = points.values()
    return values * np.array([float(s) for s in seeds])


def test_map_chunks_keeps_order_and_validates():
    assert parallel.map_chunks(abs, [-3, 1, -2, 5], jobs=2) == [3, 1, 2, 5]
    with pytest.raises(ValueError, match="jobs must be"):
        parallel.map_chunks(abs, [1], jobs=0)
    with pytest.raises(ValueError, match="scheduler must be"):
        parallel.map_chunks(abs, [1], scheduler=3)


def test_chunk_slices_cover_the_range_once():
    for n, k, size in ((10, 3, None), (7, 10, None), (100, 1, 33)):
        s = parallel.chunk_slices(n, chunks=k, chunk_size=size)
        assert np.array_equal(np.concatenate([np.arange(n)[x] for x in s]), np.arange(n))
    assert chunk_bounds(7, 3) == [(0, 3), (3, 6), (6, 7)]


def test_sweep_on_a_two_worker_local_cluster_equals_the_local_sweep_bit_for_bit():
    from distributed import Client, LocalCluster

    grid = {"k": [1.0, 4.0, 9.0], "x0": [0.5, 1.0]}
    seeds = run_seeds(5, 4)
    local = parallel.sweep(sweep_fn, grid, seeds)
    assert local.shape == (3, 2, 4)
    pts = parallel.grid_points(grid)
    whole = sweep_fn({k: np.repeat(v, 4) for k, v in pts.items()}, seeds * 6).reshape(3, 2, 4)
    assert np.array_equal(local, whole)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        on_dask = parallel.sweep(sweep_fn, grid, seeds, scheduler=client, chunk_size=5)
    assert np.array_equal(local, on_dask)
    # larger stiffness, smaller excursion from the same start: the grid axes are where they say
    assert local[2, 1].mean() < local[0, 1].mean()


def _sum_with(task):
    table, (i, scale) = task
    return float(table[i::7].sum() * scale)


def test_what_every_chunk_shares_is_sent_to_the_cluster_once_with_the_same_results():
    """A 4 MB table shared by 6 chunks is scattered once (not embedded in every task), results bit for bit."""
    import warnings

    from distributed import Client, LocalCluster

    table = np.random.default_rng(3).standard_normal(500_000)
    tasks = [(table, (i, 0.5 * i)) for i in range(6)]
    local = parallel.map_chunks(_sum_with, tasks)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as lc, \
            Client(lc) as client:
        sent = []
        scatter = client.scatter
        client.scatter = lambda obj, **kw: sent.append(obj) or scatter(obj, **kw)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            on_dask = parallel.map_chunks(_sum_with, tasks, scheduler=client)
    assert on_dask == local
    assert len(sent) == 1 and sent[0] is table  # the table once; the small per-chunk members stay in their tasks
    assert not [w for w in caught if "large graph" in str(w.message)], [str(w.message) for w in caught]


def test_map_chunks_given_the_process_wide_clusters_scheduler_runs_there_not_on_a_second_cluster(monkeypatch):
    # a study hands its context's --scheduler to a sweep while the CLI's use_cluster is active
    from distributed import Client, LocalCluster

    made = []

    def client(scheduler, jobs, timeout=30.0):
        if isinstance(scheduler, Client):
            return scheduler, False
        made.append(scheduler)
        cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None)
        return Client(cluster), True

    monkeypatch.setattr(parallel, "_client", client)
    monkeypatch.setattr(cluster, "_client", client)  # use_cluster lives in ctrl_analysis.runs.cluster
    with parallel.use_cluster("local", 1):
        assert parallel.map_chunks(abs, [-1, -2, 3], scheduler="local") == [1, 2, 3]
        assert parallel.map_chunks(abs, [-4]) == [4]
        assert parallel.active_cluster()["chunks"] == 4
    assert made == ["local"]
    assert parallel.active_cluster() is None


def test_a_cluster_without_workers_fails_in_one_error_after_the_worker_timeout_and_at_once_after():
    # a scheduler with no worker keeps tasks waiting for ever (as after every worker is killed): the mapping
    # gives up after worker_timeout, and the process-wide cluster is marked failed so the next batch does not wait
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster, Client(cluster) as client, \
            parallel.use_cluster(client, worker_timeout=1.0):
        with pytest.raises(parallel.ClusterError, match=r"no Dask worker connected to the scheduler at \S+ for "
                                                         r"1 s: every worker was lost, or none joined \(3 of 3 chunks"):
            parallel.map_chunks(abs, [-1, -2, 3])
        failed = parallel.active_cluster()["failed"]
        assert failed is not None and "no Dask worker" in failed
        with pytest.raises(parallel.ClusterError) as again:
            parallel.map_chunks(abs, [-4])
        assert str(again.value) == failed
    assert parallel.active_cluster() is None


def test_an_address_that_is_a_dask_worker_not_its_scheduler_is_refused_in_one_line():
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, processes=False, protocol="tcp", host="127.0.0.1",
                      dashboard_address=None) as cluster:
        worker = next(iter(cluster.scheduler_info["workers"]))
        with pytest.raises(OSError, match=r"is a Dask Worker, not a scheduler: give the scheduler's address"), \
                parallel.use_cluster(worker, timeout=10.0):
            pass
        with parallel.use_cluster(cluster.scheduler_address, timeout=10.0):  # the scheduler's own address works
            assert parallel.map_chunks(abs, [-5]) == [5]


class UnpicklableDamped(Damped):
    """The small plant holding a lock: a loop of it cannot go to worker processes, even by cloudpickle."""

    def __init__(self):
        super().__init__()
        import threading

        self.hook = threading.Lock()


class LambdaDamped(Damped):
    """The small plant with a lambda inside, as a script writes it: it travels by cloudpickle."""

    def __init__(self):
        super().__init__()
        self.hook = lambda x: x


def test_an_unpicklable_loops_batches_warn_once_per_process(monkeypatch):
    import warnings

    monkeypatch.setattr(parallel, "_WARNED", set())
    loop = Loop([place(UnpicklableDamped(), "plant"), place(DifferentialEstimator(3, 4.0), "sigma")], dt=0.01)
    noise = draw_noise(run_seeds(1, 4), 20, gaussian_noise([0.3, 0.01]))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(3):  # a study's three batches of one loop: the same sentence once
            loop.simulate(20, inputs={"w": noise[:, :, 0], "v": noise[:, :, 1]}, execution=Execution(jobs=2))
    said = [w for w in caught if "needs a picklable loop" in str(w.message)]
    assert len(said) == 1 and said[0].category is RuntimeWarning

def test_a_loop_with_a_lambda_runs_in_worker_processes_bit_for_bit(monkeypatch):
    """Chunks travel by cloudpickle (as on Dask): a lambda inside a block no longer keeps the batch in-process."""
    import warnings

    monkeypatch.setattr(parallel, "_WARNED", set())
    loop = Loop([place(LambdaDamped(), "plant"), place(DifferentialEstimator(3, 4.0), "sigma")], dt=0.01)
    noise = draw_noise(run_seeds(1, 4), 20, gaussian_noise([0.3, 0.01]))
    inputs = {"w": noise[:, :, 0], "v": noise[:, :, 1]}
    with warnings.catch_warnings():
        warnings.filterwarnings("error", message=".*needs a picklable loop")
        two = loop.simulate(20, inputs=inputs, execution=Execution(jobs=2))
    one = loop.simulate(20, inputs=inputs)
    np.testing.assert_array_equal(two.x, one.x)
    assert parallel.map_chunks(lambda a: a * 2, [1, 2, 3], jobs=2) == [2, 4, 6]


def test_loop_chunked_batch_equals_unchunked_bit_for_bit():
    seeds = run_seeds(2, 7)
    noise = draw_noise(seeds, N_STEPS, gaussian_noise([0.3, 0.01]))
    loop = Loop([place(Damped(), "plant"), place(DifferentialEstimator(3, 4.0), "sigma")], dt=0.01)
    inputs = {"w": noise[:, :, 0], "v": noise[:, :, 1]}
    whole = loop.simulate(N_STEPS, inputs=inputs)
    for kw in ({"execution": Execution(chunk_runs=3)}, {"execution": Execution(max_bytes=1.0)}):
        part = loop.simulate(N_STEPS, inputs=inputs, **kw)
        assert np.array_equal(whole.x, part.x)
        for s in whole.signals:
            assert np.array_equal(whole[s], part[s])
    kept = loop.simulate(N_STEPS, inputs=inputs, save=Save(keep=["y"], states=False), execution=Execution(chunk_runs=2))
    assert list(kept.signals) == ["y"] and kept.x is None and np.array_equal(kept["y"], whole["y"])
    with pytest.raises(ValueError, match="names unknown signal 'nope'"):
        loop.simulate(N_STEPS, inputs=inputs, save=Save(keep=["nope"]))


def test_result_too_large_raises_a_memory_error_that_says_what_to_do():
    with pytest.raises(MemoryError, match="states=False.*map_chunks"):
        check_result_memory(15 * 2**30, 4 * 2**30, "Loop.simulate")
    check_result_memory(1.0, 4 * 2**30, "Loop.simulate")


def test_progress_bar_is_silent_off_a_terminal(monkeypatch):
    monkeypatch.delenv("CTRL_ANALYSIS_PROGRESS", raising=False)
    stream = io.StringIO()
    assert not progress.enabled(stream)
    with progress.bar(10, desc="x", stream=stream) as pb:
        pb.update(3)
    assert stream.getvalue() == "" and isinstance(pb, progress.NullBar) and pb.n == 3
    monkeypatch.setenv("CTRL_ANALYSIS_PROGRESS", "1")
    with progress.bar(10, desc="runs", stream=stream) as pb:
        pb.update(10)
    assert "runs" in stream.getvalue()


def test_long_simulation_shows_its_own_labelled_bar_and_counts_every_run_sample(monkeypatch, capsys):
    from ctrl_analysis.engine.loop import AUTO_BAR_WORK
    from ctrl_analysis.estimators.lowpass import LowPassFilter

    # the loop of test_speed_kernels' low-pass test (one compiled structure for both tests)
    loop = Loop([place(LowPassFilter(5.0, order=2).digital(0.01, channels=3), "W")], dt=0.01)
    B, n = 1000, AUTO_BAR_WORK // 1000
    u = np.linspace(0.0, 1.0, B)[None, :] * np.ones((n, 1))
    ins = {"u[1]": 0.0, "u[2]": 1.0}
    for engine, m in (("numpy", 200), ("compiled", n)):
        counted = []
        ref = loop.simulate(m, inputs={"u[0]": u[:m], **ins}, save=Save(states=False),
                            execution=Execution(engine=engine, progress=False))
        got = loop.simulate(m, inputs={"u[0]": u[:m], **ins}, save=Save(states=False),
                            execution=Execution(engine=engine, progress=counted.append, chunk_runs=300))
        assert sum(counted) == B * m and len(counted) > 4, engine  # several updates, all the work
        assert np.array_equal(ref["w[0]"], got["w[0]"]), engine  # progress never changes the numbers
    monkeypatch.setenv("CTRL_ANALYSIS_PROGRESS", "1")
    progress.set_context("mystudy", None)
    try:
        capsys.readouterr()
        loop.simulate(n, inputs={"u[0]": u, **ins}, save=Save(states=False, keep=[]))  # progress=None: own bar
        err = capsys.readouterr().err
        assert f"mystudy: {B} runs x {n} samples" in err
        loop.simulate(n - 1, inputs={"u[0]": u[:-1, :10], **ins}, save=Save(states=False))  # short: no bar
        assert "runs x" not in capsys.readouterr().err
    finally:
        progress.set_context()


def test_cli_rejects_jobs_below_one():
    from ctrl_analysis.cli import main

    # the side-by-side run itself is exercised by tests/studies/test_reproduce_all.py (default --jobs)
    with pytest.raises(SystemExit) as exc:
        main(["reproduce", "ckf", "--jobs", "0"])
    assert exc.value.code == 2


def test_loop_simulate_with_jobs_equals_one_process_bit_for_bit():
    seeds = run_seeds(8, 9)
    noise = draw_noise(seeds, N_STEPS, gaussian_noise([0.3, 0.01]))
    loop = Loop([place(Damped(), "plant"), place(DifferentialEstimator(3, 4.0), "sigma")], dt=0.01)
    kw = {"inputs": {"w": noise[:, :, 0], "v": noise[:, :, 1]}, "seeds": seeds,
          "x0": {"plant": np.column_stack([np.linspace(0, 1, 9), np.zeros(9)])}}
    one = loop.simulate(N_STEPS, **kw)
    two = loop.simulate(N_STEPS, execution=Execution(jobs=2), **kw)
    assert np.array_equal(one.x, two.x) and two.seeds == seeds and two.runs == 9
    for s in one.signals:
        assert np.array_equal(one[s], two[s])
    assert np.array_equal(one.to_timeresponse(4).outputs, two.to_timeresponse(4).outputs)


def test_a_numpy_loops_batch_goes_to_the_process_wide_cluster_with_the_same_numbers(monkeypatch):
    """Issue 30: inside use_cluster, a loop with a plain Python block (numpy engine) stayed in the command's process
    without a word; its batch is now split over the cluster's workers like a compiled loop's, from
    CLUSTER_MIN_WORK / 100 run-samples (4 runs x 20 samples here: the threshold set to just that, then one above)."""
    import warnings

    from distributed import Client, LocalCluster

    from ctrl_analysis.engine import engines

    loop = Loop([place(Damped(), "plant"), place(DifferentialEstimator(3, 4.0), "sigma")], dt=0.01)
    noise = draw_noise(run_seeds(3, 4), 20, gaussian_noise([0.3, 0.01]))
    inputs = {"w": noise[:, :, 0], "v": noise[:, :, 1]}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the numpy path is said once per loop: not the point here
        here = loop.simulate(20, inputs=inputs, params={"sigma": {"a": [3.0, 4.0, 5.0, 6.0]}})
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster, \
                Client(cluster) as client, parallel.use_cluster(client):
            monkeypatch.setattr(engines, "CLUSTER_MIN_WORK", 4 * 20 * 100)
            there = loop.simulate(20, inputs=inputs, params={"sigma": {"a": [3.0, 4.0, 5.0, 6.0]}})
            chunks = parallel.active_cluster()["chunks"]
            monkeypatch.setattr(engines, "CLUSTER_MIN_WORK", 4 * 20 * 100 + 1)
            small = loop.simulate(20, inputs=inputs, params={"sigma": {"a": [3.0, 4.0, 5.0, 6.0]}})
            assert parallel.active_cluster()["chunks"] == chunks  # too little work to ship: it ran here
    assert chunks >= 2  # it ran on the cluster's workers
    np.testing.assert_array_equal(there.x, here.x)
    np.testing.assert_array_equal(small.x, here.x)
