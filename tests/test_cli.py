"""The command line: one run, and bad input answered with one line and no traceback."""

import os
import subprocess
import sys

import pandas as pd
import pytest

from magexp.paths import ROOT


def magexp(*args, cwd):
    env = {**os.environ, "HYDRA_FULL_ERROR": "0"}
    return subprocess.run([sys.executable, "-m", "magexp", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=120, env=env)


def test_single_run_prints_metrics_and_writes_rows(tmp_path):
    out = tmp_path / "run"
    proc = magexp("scenario=ding2024_exp1", "estimator=ipso", "seed=3", "estimator.n_iterations=100",
                  f"hydra.run.dir={out}", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "fun" in proc.stdout and "noise_floor" in proc.stdout
    metrics = pd.read_csv(out / "metrics.csv")
    assert metrics.estimator[0] == "ipso" and metrics.seed[0] == 3
    assert len(pd.read_csv(out / "history.csv")) == 101


def test_multirun_sweeps_a_key(tmp_path):
    proc = magexp("-m", "estimator=ellipsoid,lm", "scenario.noise=0,5", f"hydra.sweep.dir={tmp_path / 'sweep'}",
                  cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert len(list((tmp_path / "sweep").glob("*/metrics.csv"))) == 4


@pytest.mark.parametrize("args, word", [
    (["estimator=foo"], "estimator='foo'"),
    (["scenario=nope"], "scenario='nope'"),
    (["scenario.noise=-1"], "scenario.noise=-1"),
    (["estimator.n_particles=0"], "estimator.n_particles=0"),
    (["scenario.n_readings=0"], "scenario.n_readings=0"),
    (["seed=-2"], "seed=-2"),
    (["scenario.nois=3"], "scenario.nois"),
    (["-m", "estimator=pso,bogus"], "estimator='bogus'"),
])
def test_bad_input_is_one_line(tmp_path, args, word):
    proc = magexp(*args, f"hydra.run.dir={tmp_path / 'r'}", cwd=tmp_path)
    assert proc.returncode != 0
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr
    assert word in lines[0] and "Traceback" not in proc.stderr
