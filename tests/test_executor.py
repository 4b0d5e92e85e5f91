"""The executor layer: shared work per batch, deduplication, task plans, and the Dask backend."""

import os
import pickle
import signal
import threading
import time

import pytest
from omegaconf import OmegaConf

from magexp.run import cache, runkeys

from magexp.run import executor, executors

from magexp.run import runner
from magexp.run.compose import compose_config


def configs(*overrides, seeds=(0, 1)):
    cfg = compose_config(list(overrides))
    base = OmegaConf.to_container(cfg, resolve=True)
    return [{**base, "seed": s} for s in seeds]


DING = ("scenario=ding2024_exp1", "scenario.n_readings=60")


def same(a, b):
    """Two RunOutputs hold the same numbers (bit for bit), the fit's wall time aside."""
    ma = {k: v for k, v in a.metrics.items() if k != "wall_time"}
    mb = {k: v for k, v in b.metrics.items() if k != "wall_time"}
    a, b = vars(a).copy(), vars(b).copy()
    a["metrics"], b["metrics"] = ma, mb
    a.pop("fit_cpu"), b.pop("fit_cpu")  # CPU time varies
    return pickle.dumps(a) == pickle.dumps(b)


def test_batch_equals_single_runs_and_shares_the_bound(monkeypatch):
    batch = configs(*DING, "estimator=ellipsoid") + configs(*DING, "estimator=lm")
    alone = [runner.run(OmegaConf.create(c)) for c in batch]
    calls = []
    real = runner.problem_bound
    monkeypatch.setattr(runner, "problem_bound", lambda p: calls.append(1) or real(p))
    together = list(runner.run_batch(batch))
    assert all(same(a, b) for a, b in zip(alone, together))
    assert len(calls) == 2  # one bound per seed, shared by both estimators
    assert "rms_bound" in together[0].metrics


def test_identical_runs_run_once_also_when_forced():
    batch = configs(*DING, "estimator=ellipsoid")
    twice = batch + batch
    for use_cache in (True, False):
        counts = {}
        outputs = executor.run_many(twice, jobs=1, use_cache=use_cache, counts=counts)
        assert counts["requested"] == 4 and counts["distinct"] == 2
        assert counts["computed"] == (2 if not use_cache or counts["cached"] == 0 else 0)
        assert same(outputs[0], outputs[2]) and outputs.metrics(1) == outputs.metrics(3)
    counts = {}
    executor.run_many(twice, jobs=1, counts=counts)
    assert counts["cached"] == 2 and counts["computed"] == 0


def test_outputs_are_read_back_from_the_cache():
    batch = configs(*DING, "estimator=ellipsoid")
    outputs = executor.run_many(batch, jobs=1)
    keys = [runkeys.run_key(c) for c in batch]
    assert outputs.keys == keys and all(cache.exists(k) for k in keys)
    assert same(outputs[1], cache.load(keys[1]))


def test_task_plan_keeps_each_seed_of_a_scenario_together():
    batch = (configs(*DING, "estimator=ellipsoid", seeds=range(6)) + configs(*DING, "estimator=lm", seeds=range(6))
             + configs("scenario=ding2024_exp2", "estimator=ellipsoid", seeds=range(3)))
    tasks = executor.plan_tasks(batch, workers=2)
    assert sorted(i for t in tasks for i in t) == list(range(len(batch)))
    for task in tasks:  # one scenario (its data: the scenario node and the objective) per task
        assert len({repr((batch[i]["scenario"], batch[i].get("objective"))) for i in task}) == 1
    where = {i: k for k, t in enumerate(tasks) for i in t}
    for i in range(6):  # both estimators of a seed share a task (and so its dataset and bound)
        assert where[i] == where[6 + i]
    assert len(tasks) > 2  # the work is split for both workers


def test_local_processes_give_the_same_bytes_as_this_process(tmp_path, monkeypatch):
    batch = configs(*DING, "estimator=ellipsoid", seeds=range(4)) + configs(*DING, "estimator=lm", seeds=range(4))
    inline = executor.run_many(batch, jobs=1)
    monkeypatch.setattr(cache, "CACHE", tmp_path / "other")
    with executors.make_executor("local", jobs=2) as ex:
        assert isinstance(ex, executors.LocalExecutor)
        pooled = executor.run_many(batch, executor=ex)
    assert all(same(a, b) for a, b in zip(inline, pooled))


@pytest.mark.parametrize("kind, kwargs, words", [
    ("slurm", {}, "'slurm'"),
    ("local", {"jobs": -1}, "--jobs -1"),
    ("local", {"scheduler": "tcp://x:1"}, "needs --executor dask"),
])
def test_bad_executor_settings(kind, kwargs, words):
    from magexp.errors import MagexpError

    with pytest.raises(MagexpError, match=words):
        executors.make_executor(kind, **kwargs)


def _kill_a_worker_once_busy(client, done: threading.Event):
    """Kill one worker process (SIGKILL) as soon as it is running a task."""
    deadline = time.time() + 120
    while time.time() < deadline and not done.is_set():
        busy = [addr for addr, w in client.scheduler_info()["workers"].items() if w.get("metrics", {}).get("executing")]
        processing = client.processing()
        busy = busy or [addr for addr, tasks in processing.items() if tasks]
        if busy:
            pid = client.run(os.getpid, workers=[busy[0]])[busy[0]]
            os.kill(pid, signal.SIGKILL)
            return pid
        time.sleep(0.02)
    return None


@pytest.mark.full  # make test's budget: a slow case (make test-full runs it)
@pytest.mark.slow
def test_dask_cluster_survives_a_killed_worker_with_identical_results(tmp_path, monkeypatch):
    """A LocalCluster of one worker runs a tiny reproduction; the worker is killed midway; the scheduler
    reruns its task on the worker that replaces it and every output file is byte-identical (a sweep on a Dask
    cluster: tests/test_sweep.py::test_local_processes_and_a_dask_cluster_give_the_same_sweep)."""
    from magexp.artifacts.plots import style
    from magexp.artifacts.reproduce import reproduce, select

    monkeypatch.setattr(style, "save", lambda fig, path: style.plt.close(fig) or [])  # the figure is not compared
    selected = select(["ding2024"], "ding2024_fig5")
    monkeypatch.setattr(cache, "CACHE", tmp_path / "cache_local")
    reproduce(selected, tmp_path / "local", seeds=2, jobs=1, tiny=True, log=lambda *_: None)

    monkeypatch.setattr(cache, "CACHE", tmp_path / "cache_dask")
    with executors.make_executor("dask", jobs=1) as ex:  # its nanny restarts it and the task runs again
        done = threading.Event()
        killer = threading.Thread(target=lambda: killed.append(_kill_a_worker_once_busy(ex.client, done)))
        killed: list = []
        killer.start()
        try:
            reproduce(selected, tmp_path / "dask", seeds=2, tiny=True, executor=ex, log=lambda *_: None)
        finally:
            done.set()
            killer.join()
    assert killed and killed[0] is not None, "no worker was killed midway"
    for name in ("ding2024/summary.csv", "ding2024/ding2024_fig5.csv", "ding2024/ding2024_fig5_runs.csv"):
        assert (tmp_path / "local" / name).read_bytes() == (tmp_path / "dask" / name).read_bytes(), name


def test_jobqueue_submits_single_threaded_one_worker_jobs():
    pytest.importorskip("dask_jobqueue")
    import dask

    with dask.config.set({"jobqueue.slurm.memory": "2GB", "jobqueue.slurm.queue": "normal"}):
        cluster = executors.jobqueue_cluster("slurm")
        try:
            script = cluster.job_script()
        finally:
            cluster.close()
    assert "#SBATCH -p normal" in script and "--nthreads 1" in script and "#SBATCH --cpus-per-task=1" in script


def test_jobqueue_missing_names_the_install(monkeypatch):
    import sys

    from magexp.errors import MagexpError

    monkeypatch.setitem(sys.modules, "dask_jobqueue", None)
    with pytest.raises(MagexpError, match=r"pip install 'magexp\[cluster\]'"):
        executors.jobqueue_cluster("pbs")


class _RemoteLike(executors.InlineExecutor):
    """An executor whose workers do not see the parent's files (a remote Dask scheduler)."""

    shares_files = False


class _Recording(executors.InlineExecutor):
    """The in-process executor, keeping what each task sends back to the parent and which runs the
    cache held when the task was done."""

    def __init__(self, stored):
        super().__init__()
        self.stored, self.sent = stored, []

    def as_completed(self, futures):
        for future in super().as_completed(futures):
            value = future.result()  # the task runs here (in this process, when asked)
            self.sent.append((value, list(self.stored)))
            future.result = lambda value=value: value  # run once: the parent reads the same value
            yield future


def test_workers_store_their_runs_and_the_counts_split_the_cpu(tmp_path, monkeypatch):
    from magexp.artifacts.reproduce import cpu_line

    batch = configs(*DING, "estimator=ellipsoid", seeds=range(3)) + configs(*DING, "estimator=pso", seeds=range(3))
    keys = runkeys.run_keys(batch)
    monkeypatch.setattr(cache, "CACHE", tmp_path / "shared")
    stored = []
    real_store = cache.store
    monkeypatch.setattr(cache, "store", lambda *a, **k: stored.append(a[0]) or real_store(*a, **k))
    counts = {}
    recording = _Recording(stored)
    here = executor.run_many(batch, executor=recording, counts=counts)
    assert recording.sent
    returned = 0
    for (results, *_), stored_by_then in recording.sent:  # each run stored inside its task; only rows sent back
        assert all(isinstance(row, dict) and isinstance(fit, float) for row, fit in results)
        returned += len(results)
        assert len(stored_by_then) == returned
    assert returned == len(batch)
    assert sorted(stored) == sorted(keys) and all(cache.exists(k) for k in keys)
    assert pickle.dumps(here.metrics(3)) == pickle.dumps(executor.run_row(here[3]))  # the stored run's row
    assert counts["task_cpu"] >= counts["fit_cpu"] > 0
    line = cpu_line(counts["task_cpu"] + 0.5, counts)
    per_run = (counts["task_cpu"] - counts["fit_cpu"]) / len(batch) * 1e3
    assert f"worker: {per_run:.1f} ms per run outside fits; parent: 0.5 s" in line

    monkeypatch.setattr(cache, "CACHE", tmp_path / "remote")
    counts = {}
    there = executor.run_many(batch, executor=_RemoteLike(), counts=counts)  # outputs come back, the parent stores
    assert all(cache.exists(k) for k in keys) and counts["task_cpu"] >= counts["fit_cpu"] > 0
    assert all(same(a, b) for a, b in zip(here, there))
    for i in range(len(batch)):
        mine, theirs = ({k: v for k, v in m.items() if k != "wall_time"} for m in (here.metrics(i), there.metrics(i)))
        assert pickle.dumps(mine) == pickle.dumps(theirs)


def test_a_batch_gives_each_estimator_the_generator_run_generators_gives():
    import numpy as np

    from magexp.core.seeding import run_generators, run_sequences

    stream = {"name": "ding2024_exp1", "noise": 2}
    data, est = run_generators(7, stream=stream)
    data_seq, est_seq = run_sequences(7, stream=stream)
    first, second = np.random.default_rng(est_seq), np.random.default_rng(est_seq)  # twice from one sequence
    draws = est.random(5)
    assert np.array_equal(first.random(5), draws) and np.array_equal(second.random(5), draws)
    assert np.array_equal(np.random.default_rng(data_seq).normal(size=4), data.normal(size=4))


@pytest.mark.parametrize("scenario, estimators", [("ding2024_exp1", ("ellipsoid", "lm")),
                                                  ("yuan2018_mode1", ("lm", "ekf"))])
def test_truth_cost_is_computed_once_per_problem_and_equals_the_direct_cost(scenario, estimators, monkeypatch):
    import numpy as np

    from magexp.core import metrics

    batch = [c for e in estimators for c in configs(f"scenario={scenario}", f"estimator={e}", seeds=(0,))]
    alone = [runner.run(OmegaConf.create(c)) for c in batch]
    made, at_truth = [], []
    real_make = runner.make_problem

    def make(*args, **kwargs):  # count the problem's direct costs at its truth
        problem = real_make(*args, **kwargs)
        real_cost = problem.cost_direct
        problem.cost_direct = lambda x: at_truth.append(np.array_equal(x, problem.truth_theta())) or real_cost(x)
        made.append(problem)
        return problem

    monkeypatch.setattr(runner, "make_problem", make)
    together = list(runner.run_batch(batch))
    assert all(same(a, b) for a, b in zip(alone, together))
    assert len(made) == 1 and sum(at_truth) == 1  # one dataset, its truth's cost once for both estimators
    direct = made[0].cost_direct(made[0].truth_theta())
    assert together[0].metrics["truth_fun"] == together[1].metrics["truth_fun"] == direct
    assert metrics.truth_cost(made[0]) == direct and sum(at_truth) == 2  # kept: only the direct call above


@pytest.mark.parametrize("scenario, offset", [("ding2024_exp1", "scenario.errors.hard_iron"),
                                              ("yuan2018_mode1", "scenario.b"), ("yan2022_sim", "scenario.Bp")])
def test_the_invariants_jacobian_is_shared_across_seeds_and_the_bound_is_unchanged(scenario, offset, monkeypatch):
    import numpy as np

    from magexp.core import bounds
    from magexp.core.seeding import run_generators, scenario_stream
    from magexp.problems import make_problem

    # a truth of its own (an offset no other test uses): nothing kept from earlier work in this process
    unique = [round(v, 9) for v in np.random.default_rng().uniform(1, 2, 3)]
    problems = []
    for cfg in configs(f"scenario={scenario}", f"{offset}=[{unique[0]},{unique[1]},{unique[2]}]", seeds=(0, 1)):
        sc = runner.build(cfg["scenario"], "scenario")
        data = sc.generate(rng=run_generators(cfg["seed"], stream=scenario_stream(cfg["scenario"]))[0])
        problems.append(make_problem(cfg.get("objective") or sc.objective, data, sc.search,
                                     **getattr(sc, "problem_options", {})))
    assert np.array_equal(problems[0].truth_theta(), problems[1].truth_theta())
    calls = []
    real = bounds.central_differences
    monkeypatch.setattr(bounds, "central_differences", lambda fun, *a: calls.append(fun) or real(fun, *a))
    kept = [bounds.cramer_rao(problem) for problem in problems]
    assert sum(getattr(f, "__name__", "") == "invariants" for f in calls) == 1  # one truth: H once for both seeds
    monkeypatch.setattr(bounds, "central_differences", real)
    # from scratch: H = ∂h/∂θ by central differences for every problem, nothing kept
    monkeypatch.setattr(bounds, "invariant_jacobian", lambda problem, theta, steps, keep=0:
                        real(problem.invariants, theta, steps))
    fresh = [bounds.cramer_rao(problem) for problem in problems]
    assert pickle.dumps(kept) == pickle.dumps(fresh)  # the same bits
