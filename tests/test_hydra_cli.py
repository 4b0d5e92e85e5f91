"""Hydra's switches and hydra.* keys that magexp takes do what Hydra documents (issue 41, items 2 and 3); their
refusals are rows of tests/test_bad_input.py."""

from __future__ import annotations

import csv
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


#: a switch whose run takes a second or more (it composes every config or lists every group) in make test-full;
#: make test passes the same switch, or the same kind of switch, in a cheaper case
FULL = pytest.mark.full


@pytest.mark.parametrize("args, printed", [
    (["--cfg", "job", "--package", "scenario.field"], "# @package scenario.field"),
    (["--cfg", "hydra", "--package", "hydra.launcher"], "MagexpLauncher"),
    (["--cfg", "all", "-p", "estimator"], "# @package estimator"),
    (["--cfg=job", "--resolve"], "seed: 0"),
    (["--info", "plugins"], "MagexpLauncher"),
    pytest.param(["-i", "config", "estimator=lm"], "LevenbergMarquardt", marks=FULL),  # make test: --info plugins
    pytest.param(["--hydra-help"], "--shell-completion", marks=FULL),  # make test: the other switches Hydra parses
    (["-sc", "install=bash"], "hydra_bash_completion"),
    (["--shell-completion", "uninstall=fish"], "complete"),
], ids=lambda a: " ".join(a) if isinstance(a, list) else "")
def test_hydra_switches_do_what_hydra_documents(tmp_path, cli, args, printed):
    proc = cli(*args, cwd=tmp_path)
    assert proc.returncode == 0 and printed in proc.stdout, proc.stderr
    assert not any(tmp_path.iterdir())  # printed, nothing run


def test_sweeper_params_are_the_sweep_that_runs(tmp_path, cli):
    """hydra.sweeper.params sweeps its keys, a command-line override of the same key replaces it (as Hydra's
    sweeper does), the sweep is run in batches of max_batch_size, and the swept keys are sweep.csv's columns."""
    proc = cli("-m", "estimator=ellipsoid", 'hydra.sweeper.params={seed: "1,2", scenario.noise: "1,2"}',
               "scenario.noise=3", "hydra.sweeper.max_batch_size=1", "hydra.sweep.dir=s", "hydra.launcher.jobs=1",
               cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    with (tmp_path / "s" / "sweep.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [(r["seed"], r["job"]) for r in rows] == [("1", "0"), ("2", "1")]
    assert all("noise: 3" in (tmp_path / "s" / r["job"] / "config.yaml").read_text() for r in rows)


def test_every_hydra_key_magexp_takes_runs_with_a_good_value(tmp_path, cli):
    """The hydra.* keys a sweep takes, each with a good value, in one sweep of Hydra's basic sweeper and launcher."""
    proc = cli("-m", "estimator=ellipsoid", "seed=1,2", "hydra/sweeper=basic", "hydra/launcher=basic",
               "hydra/job_logging=disabled", "hydra/hydra_logging=disabled", "hydra.sweeper.max_batch_size=1",
               "hydra.sweep.dir=s", "hydra.sweep.subdir=${hydra.job.name}_${hydra.job.override_dirname}",
               "hydra.job.name=mine", "hydra.job.chdir=false", "hydra.verbose=false",
               "hydra.job.config.override_dirname.kv_sep=-", "hydra.job.config.override_dirname.exclude_keys=[estimator]",
               "hydra.run.dir=unused_by_a_sweep", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.parent.name for p in (tmp_path / "s").glob("*/metrics.csv")) == ["mine_seed-1", "mine_seed-2"]


@pytest.mark.full  # loky's worker processes: 3 s
def test_joblibs_launcher_runs(tmp_path, cli):
    """joblib's launcher, offered in LAUNCHER_EXTRAS, runs a sweep (its worker unpickles the derived schemas)."""
    proc = cli("-m", "estimator=ellipsoid", "seed=1,2", "hydra/launcher=joblib", "hydra.launcher.n_jobs=1",
               "hydra.sweep.dir=j", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.parent.name for p in (tmp_path / "j").glob("*/metrics.csv")) == ["0", "1"]


@pytest.mark.full
@pytest.mark.parametrize("args", [
    ["-m", 'hydra.sweeper.params={seed: "range(1000000000)"}'],
    ["-m", "seed=range(0,1,1e-9)"],
], ids=lambda a: " ".join(a))
def test_a_sweep_of_a_billion_jobs_is_refused_at_once(tmp_path, args):
    """Counted before it expands: one line in seconds, as a real process (before issue 41 the params sweep
    grew to 4.3 GB)."""
    start = time.monotonic()
    proc = subprocess.run([sys.executable, "-m", "magexp", *args], cwd=tmp_path, capture_output=True, text=True,
                          timeout=60, env={**os.environ, "PYTHONPATH": str(ROOT), "MAGEXP_CACHE": str(tmp_path / "c")})
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "MAGEXP_MAX_RUNS" in proc.stderr, proc.stderr
    assert time.monotonic() - start < 20 and not (tmp_path / "multirun").exists()
