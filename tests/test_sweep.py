"""``-m`` sweeps through magexp's launcher and :mod:`magexp.run.executor`: the same table and job folders
on local processes and on a Dask cluster, a killed sweep resumed from the run cache, jobs run in
parallel when asked, the sweep folder layout, and the launcher's settings checked before any run.

Subprocesses where the process boundary is what is tested (a whole command, a kill); the
launcher's :func:`magexp.run.sweep.launch` in-process otherwise.
"""

import csv
import io
import os
import signal
import subprocess
import sys
import time

import pytest
import yaml

from magexp.run import cache
from magexp.__main__ import main as magexp_main

IPSO = ["estimator=ipso", "estimator.n_particles=20", "estimator.n_iterations=100"]
SWEEP = ["-m", *IPSO, "scenario.noise=0,5", "seed=range(3)"]  # 6 jobs, a stochastic estimator
JOB_FILES = ("estimate.csv", "history.csv", "config.yaml", ".hydra/overrides.yaml")
VARYING = ("wall_time", "cached")  # the only columns that may differ between two computations of a run


def magexp(*args, cwd, cache, **kw):
    env = {**os.environ, "HYDRA_FULL_ERROR": "0", "MAGEXP_CACHE": str(cache)}
    return subprocess.run([sys.executable, "-m", "magexp", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300, env=env, **kw)


def read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def without(path, columns=VARYING) -> bytes:
    """The CSV file's bytes with ``columns`` dropped, everything else as written."""
    rows = list(csv.reader(io.StringIO(path.read_text())))
    keep = [i for i, name in enumerate(rows[0]) if name not in columns]
    out = io.StringIO()
    csv.writer(out).writerows([[row[i] for i in keep] for row in rows])
    return out.getvalue().encode()


def cached_runs(cache_dir):
    return {p.name: p.stat().st_mtime_ns for p in cache_dir.rglob(f"*{cache.SUFFIX}")}


def assert_same_sweeps(a, b):
    """Two sweep folders hold the same table and job folders, byte for byte but for :data:`VARYING`."""
    jobs = sorted(p.name for p in a.iterdir() if p.is_dir())
    assert jobs == sorted(p.name for p in b.iterdir() if p.is_dir()) and jobs
    assert without(a / "sweep.csv") == without(b / "sweep.csv")
    for job in jobs:
        assert without(a / job / "metrics.csv") == without(b / job / "metrics.csv"), job
        for name in JOB_FILES:
            assert (a / job / name).read_bytes() == (b / job / name).read_bytes(), (job, name)


@pytest.mark.full  # a sweep on a Dask cluster (make test-full); Dask's results in make test: test_executor.py's killed-worker test
def test_local_processes_and_a_dask_cluster_give_the_same_sweep(tmp_path, cli, monkeypatch):
    """The same sweep on 2 local processes (in this process's command) and on a Dask LocalCluster of 2
    workers (a real command: its output is checked for cluster chatter), each with its own empty
    cache (every run computed twice): the same table and job folders, byte for byte."""
    monkeypatch.setattr(cache, "CACHE", tmp_path / "cache_local")
    local = cli(*SWEEP, "hydra.launcher.jobs=2", f"hydra.sweep.dir={tmp_path / 'local'}", cwd=tmp_path)
    assert local.returncode == 0, local.stderr
    dask = magexp(*SWEEP, "hydra.launcher.executor=dask", "hydra.launcher.jobs=2",
                  f"hydra.sweep.dir={tmp_path / 'dask'}", cwd=tmp_path, cache=tmp_path / "cache_dask")
    assert dask.returncode == 0, dask.stderr
    assert "HYDRA" not in dask.stdout + dask.stderr  # no cluster chatter
    assert len(cached_runs(tmp_path / "cache_dask")) == 6
    assert_same_sweeps(tmp_path / "local", tmp_path / "dask")
    rows = read_csv(tmp_path / "dask" / "sweep.csv")
    assert [(r["scenario.noise"], r["seed"], r["job"]) for r in rows] == \
        [(n, s, str(j)) for j, (n, s) in enumerate((n, s) for n in "05" for s in "012")]
    assert {r["cached"] for r in rows} == {"False"}
    overrides = yaml.safe_load((tmp_path / "dask" / "4" / ".hydra" / "overrides.yaml").read_text())
    assert overrides == [*IPSO, "scenario.noise=5", "seed=1"]


# a real sweep process killed (SIGKILL to its process group, its workers too) at a fixed point:
# right after its second run reached the cache
KILLED = """
import os, signal, sys
from magexp.run import cache
from magexp.__main__ import main
store, stored = cache.store, []
def store_then_die(*args, **kw):
    kept = store(*args, **kw)
    stored.append(1)
    if len(stored) == 2:
        os.killpg(0, signal.SIGKILL)
    return kept
cache.store = store_then_die
main(sys.argv[1:])
"""


@pytest.mark.full  # a killed sweep (make test-full); resuming from the cache after a kill: test_resume.py
def test_killed_sweep_resumes_from_the_cache_with_the_same_table(tmp_path, cli, monkeypatch):
    cache_dir = tmp_path / "cache"
    first = subprocess.run([sys.executable, "-c", KILLED, *SWEEP, "hydra.launcher.jobs=1",
                            f"hydra.sweep.dir={tmp_path / 'a'}"], cwd=tmp_path,
                           env={**os.environ, "MAGEXP_CACHE": str(cache_dir)}, stdout=subprocess.DEVNULL,
                           stderr=subprocess.PIPE, start_new_session=True, timeout=300)
    assert first.returncode == -signal.SIGKILL, first.stderr
    finished = cached_runs(cache_dir)
    assert len(finished) == 2, "the kill must land midway"
    monkeypatch.setattr(cache, "CACHE", cache_dir)
    resumed = cli(*SWEEP, "hydra.launcher.jobs=2", f"hydra.sweep.dir={tmp_path / 'b'}", cwd=tmp_path)
    assert resumed.returncode == 0, resumed.stderr
    after = cached_runs(cache_dir)
    assert len(after) == 6
    assert {k: after[k] for k in finished} == finished  # finished runs were not redone
    rows = read_csv(tmp_path / "b" / "sweep.csv")  # the tidy table: swept keys first, one row per job
    assert list(rows[0])[:3] == ["scenario.noise", "seed", "job"]
    assert sum(r["cached"] == "True" for r in rows) == len(finished)
    monkeypatch.setattr(cache, "CACHE", tmp_path / "cache2")
    whole = cli(*SWEEP, f"hydra.sweep.dir={tmp_path / 'c'}", cwd=tmp_path)
    assert whole.returncode == 0, whole.stderr
    assert_same_sweeps(tmp_path / "b", tmp_path / "c")  # as an uninterrupted sweep


def _hydra_config(sweep_dir, *settings):
    from magexp.run.compose import hydra_compose

    return hydra_compose((f"hydra.sweep.dir={sweep_dir}", *settings), with_hydra=True)


def _settings(config):
    return {k: config.hydra.launcher[k] for k in ("executor", "jobs", "scheduler")}


def test_jobs_run_in_two_processes_at_once_when_asked(tmp_path, monkeypatch):
    """``hydra.launcher.jobs=2``: the runs execute in two worker processes, overlapping in time."""
    import magexp.run.executor
    from magexp.run.sweep import launch

    real, log = magexp.run.executor.run_batch, tmp_path / "tasks.log"

    def recorded(configs):  # inherited by the forked workers
        start = time.time()
        time.sleep(0.3)
        outs = list(real(configs))
        with log.open("a") as fh:
            fh.write(f"{os.getpid()} {start} {time.time()}\n")
        return iter(outs)

    monkeypatch.setattr(magexp.run.executor, "run_batch", recorded)
    config = _hydra_config(tmp_path / "sweep", "hydra.launcher.jobs=2")
    jobs = [["estimator=ellipsoid", f"seed={s}"] for s in range(6)]
    returns = launch(config, jobs, 0, _settings(config))
    tasks = [line.split() for line in log.read_text().splitlines()]
    pids = {int(t[0]) for t in tasks}
    assert len(pids) == 2 and os.getpid() not in pids
    spans = sorted((float(a), float(b)) for _, a, b in tasks)
    assert any(b0 > a1 for (_, b0), (a1, _) in zip(spans, spans[1:])), "no two tasks ran at the same time"
    assert [r.return_value["seed"] for r in returns] == list(range(6))
    assert [p.name for p in sorted((tmp_path / "sweep").iterdir(), key=lambda p: int(p.name))] == \
        [str(i) for i in range(6)]


def test_launch_numbers_jobs_from_the_batch_start_and_honours_a_subdir(tmp_path):
    """A second batch of Hydra's sweeper starts at ``initial_job_idx``; ``hydra.sweep.subdir`` names folders."""
    from magexp.run.sweep import launch

    config = _hydra_config(tmp_path / "s", "hydra.launcher.jobs=1")
    launch(config, [["estimator=ellipsoid", "seed=7"]], 4, _settings(config))
    assert read_csv(tmp_path / "s" / "4" / "metrics.csv")[0]["seed"] == "7"
    config = _hydra_config(tmp_path / "t", "hydra.launcher.jobs=1", "hydra.sweep.subdir=${hydra.job.override_dirname}")
    launch(config, [["estimator=ellipsoid", "seed=7"], ["estimator=lm", "seed=8"]], 0, _settings(config))
    assert sorted(p.name for p in (tmp_path / "t").iterdir()) == ["estimator=ellipsoid,seed=7", "estimator=lm,seed=8"]
    assert read_csv(tmp_path / "t" / "estimator=lm,seed=8" / "metrics.csv")[0]["estimator"] == "lm"


def test_sweep_runs_share_the_run_cache_with_reproduce(tmp_path):
    """A run computed by :func:`magexp.run.executor.run_many` (``make reproduce``'s layer) is a cached job of a
    sweep, with the same metrics."""
    from magexp.run.compose import compose_config, resolved
    from magexp.run.executor import run_many
    from magexp.run.sweep import launch

    done = run_many([resolved(compose_config(["estimator=ellipsoid", "seed=2"]))], jobs=1)
    config = _hydra_config(tmp_path / "s", "hydra.launcher.jobs=1")
    (ret,) = launch(config, [["estimator=ellipsoid", "seed=2"]], 0, _settings(config))
    assert ret.return_value["cached"] is True
    assert ret.return_value["fun"] == done.metrics(0)["fun"]


@pytest.mark.parametrize("args, words", [
    (["hydra.launcher.executor=nope"], ["hydra.launcher.executor='nope'", "local, dask"]),
    (["hydra.launcher.jobs=-1"], ["hydra.launcher.jobs=-1", ">= 0"]),
    (["hydra.launcher.scheduler=slurm"], ["hydra.launcher.scheduler='slurm'", "executor=dask"]),
    (["hydra/launcher=nope"], ["'nope'", "magexp"]),
])
def test_bad_launcher_settings_are_one_line_before_anything_is_written(tmp_path, monkeypatch, capsys, args, words):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as info:
        magexp_main(["-m", "estimator=ellipsoid", "seed=1,2", *args])
    assert info.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and all(w in lines[0] for w in words), lines
    assert list(tmp_path.iterdir()) == [tmp_path / "cache"] or not list(tmp_path.iterdir())


def test_a_sweep_composes_each_cell_once_and_each_job_reads_hydras_config(tmp_path, cli, monkeypatch):
    """``-m scenario=ding2024_exp1 estimator=ellipsoid,lm seed=0,1``: two cells of two seeds, each group choice
    composed by Hydra at most once in the process (its checks and its launch share it); every job's
    ``config.yaml`` is ``hydra.compose`` of that job's own overrides."""
    from omegaconf import OmegaConf

    from magexp.run import compose

    composed = []
    hydra_compose = compose.hydra_compose

    def counted(overrides=(), *args, with_hydra=False):
        if not with_hydra:  # a run config (not the hydra node that checks the launcher's settings)
            composed.append(overrides)
        return hydra_compose(overrides, *args, with_hydra=with_hydra)

    monkeypatch.setattr(compose, "hydra_compose", counted)
    proc = cli("-m", "scenario=ding2024_exp1", "estimator=ellipsoid,lm", "seed=0,1", f"hydra.sweep.dir={tmp_path / 's'}",
               cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    choices = {(), ("scenario=ding2024_exp1",), ("estimator=ellipsoid",), ("estimator=lm",)}  # the defaults, each choice
    assert len(set(composed)) == len(composed) and set(composed) <= choices  # none twice (once, unless before)
    for job in (["scenario=ding2024_exp1", f"estimator={e}", f"seed={s}"] for e in ("ellipsoid", "lm") for s in (0, 1)):
        folder = next(p.parent.parent for p in (tmp_path / "s").glob("*/.hydra/overrides.yaml")
                      if yaml.safe_load(p.read_text()) == job)
        expected = compose.resolved(hydra_compose(tuple(job)))
        assert yaml.safe_load((folder / "config.yaml").read_text()) == expected
        assert OmegaConf.to_yaml(expected) == (folder / "config.yaml").read_text()


def test_a_sweep_is_expanded_once_and_its_checked_jobs_are_launched_in_batches(tmp_path, cli, monkeypatch):
    """``magexp -m``: the sweep's jobs are listed once (the list every job was checked against), and magexp's
    sweeper launches that list, ``hydra.sweeper.max_batch_size`` jobs at a time, numbered across batches."""
    from magexp.run import preflight
    from magexp.run.preflight import sweep_jobs

    expansions = []

    def counted(overrides):
        expansions.append(list(overrides))
        return sweep_jobs(overrides)

    monkeypatch.setattr(preflight, "sweep_jobs", counted)
    proc = cli("-m", "estimator=ellipsoid,lm", "seed=0,1", "hydra.sweeper.max_batch_size=3",
               f"hydra.sweep.dir={tmp_path / 's'}", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert expansions == [["estimator=ellipsoid,lm", "seed=0,1"]]
    launched = {p.parent.parent.name: yaml.safe_load(p.read_text())
                for p in (tmp_path / "s").glob("*/.hydra/overrides.yaml")}
    assert launched == {str(n): job for n, job in enumerate(sweep_jobs(expansions[0]))}
    assert (tmp_path / "s" / "multirun.yaml").is_file() and len(read_csv(tmp_path / "s" / "sweep.csv")) == 4


def test_hydra_sweep_syntax_is_expanded_as_hydras_sweeper_does(tmp_path, cli):
    """``a,b``, ``range()`` and a group's ``glob()``: the jobs magexp checks are the jobs Hydra launches."""
    from magexp.run.preflight import expand_sweep

    jobs = expand_sweep(["estimator=glob(*pso,exclude=pso)", "scenario.noise=0,5", "seed=range(1,3)"])
    assert jobs == [[f"estimator={e}", f"scenario.noise={n}", f"seed={s}"]
                    for e in ("ipso", "rdpso") for n in (0, 5) for s in (1, 2)]
    proc = cli("-m", "estimator=glob(ellips*,exclude=*specific)", "seed=range(2)", f"hydra.sweep.dir={tmp_path / 's'}",
               cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert [(r["estimator"], r["seed"]) for r in read_csv(tmp_path / "s" / "sweep.csv")] == \
        [("ellipsoid", "0"), ("ellipsoid", "1")]


def test_sweep_table_has_the_swept_keys_first_and_the_union_of_metrics(tmp_path):
    from magexp.run.sweep import gather

    for num, (est, noise, metrics) in enumerate([("lm", "0", {"fun": "1.5", "nfev": "40"}),
                                                  ("ellipsoid", "5", {"fun": "2.5", "gram_error": "0.1"})]):
        job = tmp_path / str(num)
        (job / ".hydra").mkdir(parents=True)
        (job / ".hydra" / "overrides.yaml").write_text(f"- estimator={est}\n- scenario.noise={noise}\n- seed=3\n")
        with (job / "metrics.csv").open("w") as fh:
            fh.write(",".join(["estimator", *metrics]) + "\n" + ",".join([est, *metrics.values()]) + "\n")
    rows = read_csv(gather(tmp_path, ["estimator", "scenario.noise"]))
    assert list(rows[0]) == ["estimator", "scenario.noise", "job", "fun", "nfev", "gram_error"]
    assert rows == [{"estimator": "lm", "scenario.noise": "0", "job": "0", "fun": "1.5", "nfev": "40", "gram_error": ""},
                    {"estimator": "ellipsoid", "scenario.noise": "5", "job": "1", "fun": "2.5", "nfev": "",
                     "gram_error": "0.1"}]



def test_the_cached_column_is_true_only_for_runs_read_from_the_cache(tmp_path, cli):
    """A sweep's ``cached`` column says True for a run read from a valid cache entry, and False for one
    recomputed after its entry was damaged (issue 34: it said True for both)."""
    args = ["-m", "estimator=lm", "seed=0,1", "hydra.launcher.jobs=1"]
    assert cli(*args, f"hydra.sweep.dir={tmp_path / 'a'}", cwd=tmp_path).returncode == 0
    entries = sorted(cache.CACHE.rglob(f"*{cache.SUFFIX}"), key=lambda p: p.stat().st_mtime_ns)
    assert len(entries) == 2
    damaged = bytearray(entries[0].read_bytes())
    damaged[len(damaged) // 2] ^= 0xFF  # a flipped byte: the entry's digest no longer matches
    entries[0].write_bytes(bytes(damaged))
    again = cli(*args, f"hydra.sweep.dir={tmp_path / 'b'}", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert sorted(r["cached"] for r in read_csv(tmp_path / "b" / "sweep.csv")) == ["False", "True"]
