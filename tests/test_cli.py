"""The command line: one run, its folder and outputs (sweeps: tests/test_sweep.py).

In-process through :func:`magexp.__main__.main` where the process boundary is not what is
tested; subprocesses for the exit codes, two processes at once, and killing a sweep.
"""

import csv
import os
import subprocess
import sys
import time

import pytest
import yaml

from magexp.__main__ import main as magexp_main


def magexp(*args, cwd, env=None, **kw):
    env = {**os.environ, "HYDRA_FULL_ERROR": "0", **(env or {})}
    return subprocess.run([sys.executable, "-m", "magexp", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300, env=env, **kw)


def read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_single_run_prints_metrics_and_writes_rows_with_provenance(tmp_path, capsys):
    out = tmp_path / "run"
    magexp_main(["scenario=ding2024_exp1", "estimator=ipso", "seed=3", "estimator.n_iterations=100",
                 f"hydra.run.dir={out}"])
    printed = capsys.readouterr().out
    assert "fun" in printed and "noise_floor" in printed and str(out) in printed
    (metrics,) = read_csv(out / "metrics.csv")
    assert metrics["estimator"] == "ipso" and metrics["seed"] == "3" and metrics["cached"] == "False"
    from magexp import __version__
    from magexp.run.provenance import config_hash

    config = yaml.safe_load((out / "config.yaml").read_text())
    assert config["estimator"]["n_iterations"] == 100 and config["seed"] == 3
    assert metrics["magexp_version"] == __version__ and metrics["config_hash"] == config_hash(config)
    assert metrics["numpy"] and metrics["magexp_commit"]
    assert len(read_csv(out / "history.csv")) == 101
    assert len(read_csv(out / "estimate.csv")) == 12  # vec(W) and the offset


def test_second_identical_run_comes_from_the_cache_with_the_same_numbers(tmp_path):
    args = ["estimator=lm", "seed=2"]
    magexp_main([*args, f"hydra.run.dir={tmp_path / 'a'}"])
    magexp_main([*args, f"hydra.run.dir={tmp_path / 'b'}"])
    (a,), (b,) = read_csv(tmp_path / "a" / "metrics.csv"), read_csv(tmp_path / "b" / "metrics.csv")
    assert a.pop("cached") == "False" and b.pop("cached") == "True"
    assert a == b


def test_runs_in_the_same_second_get_their_own_folders(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(time, "strftime", lambda fmt, *a: fmt.replace("%Y-%m-%d", "day").replace("%H-%M-%S", "now"))
    for seed in (1, 2, 3):
        magexp_main(["estimator=ellipsoid", f"seed={seed}"])
    folders = sorted(p.name for p in (tmp_path / "outputs" / "day").iterdir())
    assert folders == ["now", "now-2", "now-3"]
    seeds = [read_csv(tmp_path / "outputs" / "day" / f / "metrics.csv")[0]["seed"] for f in folders]
    assert seeds == ["1", "2", "3"]


@pytest.mark.full  # two interpreters (make test-full); make test: test_runs_in_the_same_second_get_their_own_folders
def test_two_processes_started_together_keep_separate_folders(tmp_path):
    env = {**os.environ, "MAGEXP_CACHE": str(tmp_path / "cache")}
    procs = [subprocess.Popen([sys.executable, "-m", "magexp", "estimator=ellipsoid", f"seed={s}"], cwd=tmp_path,
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for s in (1, 2)]
    for p in procs:
        assert p.wait(timeout=300) == 0, p.stderr.read()
    runs = sorted((tmp_path / "outputs").glob("*/*/metrics.csv"))
    assert len(runs) == 2 and len({r.parent for r in runs}) == 2
    assert sorted(read_csv(r)[0]["seed"] for r in runs) == ["1", "2"]


def test_cfg_job_prints_the_composed_config_and_runs_nothing(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    magexp_main(["--cfg", "job", "estimator=lm", "scenario.noise=5"])
    cfg = yaml.safe_load(capsys.readouterr().out)
    assert cfg["estimator"]["name"] == "lm" and cfg["scenario"]["noise"] == 5 and "hydra" not in cfg
    assert not any(tmp_path.iterdir())


def test_help_lists_the_groups_and_version_names_the_commit(capsys):
    magexp_main(["--help"])
    text = capsys.readouterr().out
    assert "ding2024_exp1" in text and "ellipsoid" in text and "-m" in text and "calibrate" in text
    magexp_main(["--version"])
    from magexp import __version__
    from magexp.run.provenance import commit

    assert capsys.readouterr().out.startswith(f"magexp {__version__} (commit {commit()}")


def test_exit_codes_across_the_process_boundary(tmp_path):
    ok = magexp("estimator=ellipsoid", f"hydra.run.dir={tmp_path / 'r'}", cwd=tmp_path,
                env={"MAGEXP_CACHE": str(tmp_path / "cache")})
    assert ok.returncode == 0, ok.stderr
    assert (tmp_path / "r" / "metrics.csv").exists()
    bad = magexp("scenario.nosie=2", cwd=tmp_path)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "nosie" in bad.stderr
    assert {p.name for p in tmp_path.iterdir()} == {"cache", "r"}  # the run cache and the run only


def test_each_subcommand_goes_through_the_one_error_path(cli, tmp_path):
    """``magexp calibrate`` and ``magexp reproduce`` are subcommands of the one entry point: their bad
    input is one line and exit 2, as a run's is; their ``--help`` exits 0."""
    bad = cli("calibrate", f"data.path={tmp_path / 'missing.csv'}", cwd=tmp_path)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "missing.csv" in bad.stderr
    bad = cli("reproduce", "nopaper", cwd=tmp_path)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "nopaper" in bad.stderr and "ding2024" in bad.stderr
    ok = cli("reproduce", "--help", cwd=tmp_path)
    assert ok.returncode == 0 and "--redraw" in ok.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_calibrate_is_its_own_command(tmp_path, cli):
    """``magexp calibrate ARGS`` hands ARGS to the calibrate command before any run config is composed
    (the end to end calibration: tests/test_calibrate.py::test_cli_end_to_end)."""
    calibrate = cli("calibrate", "data.path=x.csv", "estimator=lm", cwd=tmp_path)
    assert calibrate.returncode == 2 and calibrate.stderr.count("\n") == 1, calibrate.stderr
    assert "x.csv" in calibrate.stderr and "magexp calibrate" not in calibrate.stderr  # the recording is looked for
    run = cli("data.path=x.csv", "estimator=lm", cwd=tmp_path)  # the same keys to a run: pointed to calibrate
    assert run.returncode == 2 and run.stderr.count("\n") == 1 and "magexp calibrate" in run.stderr, run.stderr
    assert not list(tmp_path.iterdir())


def test_a_closed_form_run_imports_no_pandas_matplotlib_or_scipy(tmp_path):
    """Fast start: a one-run command loads only what the run needs (a fresh interpreter)."""
    code = ("import sys; from magexp.__main__ import main; main(['estimator=ellipsoid', 'hydra.run.dir=r']); "
            "print('heavy:', sorted(m for m in ('pandas', 'matplotlib', 'scipy', 'joblib') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "MAGEXP_CACHE": str(tmp_path / "cache")})
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] == "heavy: []"


def test_provenance_names_the_commit_and_hashes_the_resolved_config():
    from magexp.paths import ROOT
    from magexp.run.provenance import commit, config_hash, provenance

    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True)
    if head.returncode == 0:
        assert head.stdout.strip().startswith(commit())
    a = {"seed": 1, "scenario": {"noise": 2.0, "name": "x"}}
    assert config_hash(a) == config_hash({"scenario": {"name": "x", "noise": 2.0}, "seed": 1})  # key order
    assert config_hash(a) != config_hash({**a, "seed": 2}) and len(config_hash(a)) == 16
    fields = provenance(a)
    assert set(fields) == {"magexp_version", "magexp_commit", "python", "numpy", "scipy", "hydra", "omegaconf",
                           "config_hash"}
    import numpy

    assert fields["numpy"] == numpy.__version__ and fields["config_hash"] == config_hash(a)
