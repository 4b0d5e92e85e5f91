"""Bad input, table-driven: one line naming the value, a non-zero exit, no traceback, nothing written.

Every case runs the command line in-process (:func:`magexp.__main__.main`, the same code as
``magexp ...``) from an empty working folder; after it, the folder holds only the input files
(no Hydra folder, no partial output) and ``results/`` is untouched. The process boundary itself
(``python -m magexp`` exits with the code) is tested in ``test_cli.py``.
"""

import os

import pytest

from magexp.__main__ import main as magexp_main
from magexp.paths import RESULTS

MOCKUP_HEADER = "# magexp-recording v1\n# unit: nT\n# angles: rad\n# field: 34425, 1961, 35898\nbx,by,bz,heading,roll,trim\n"
ROWS = "".join(f"{1000 + 37 * i},{-500 + 11 * i * i % 700},{200 + 53 * i % 900},{0.1 * i},0.01,-0.02\n"
               for i in range(12))

FILES = {  # recordings read by scenario=yan2022_mockup scenario.path=<file>
    "missing_column.csv": "# magexp-recording v1\n# unit: nT\nbx,by\n1,2\n",
    "text.csv": MOCKUP_HEADER + ROWS + "1,abc,3,0,0,0\n",
    "nan.csv": MOCKUP_HEADER + ROWS + "1,nan,3,0,0,0\n",
    "huge.csv": MOCKUP_HEADER + ROWS + "1e308,2,3,0,0,0\n",
    "unit.csv": MOCKUP_HEADER.replace("unit: nT", "unit: furlong") + ROWS,
    "row_length.csv": MOCKUP_HEADER + ROWS + "1,2\n",
    "no_angles.csv": "# magexp-recording v1\n# unit: nT\nbx,by,bz\n" + "".join(
        ",".join(row.split(",")[:3]) + "\n" for row in ROWS.splitlines()),
}
CALIB_HEADER = "# magexp-recording v1\n# unit: nT\nbx,by,bz\n"
FILES.update({  # recordings read by magexp calibrate data.path=<file>
    "short.csv": CALIB_HEADER + "1,2,3\n4,5,6\n7,8,10\n",
    "good.csv": CALIB_HEADER + "".join(f"{1000 + 37 * i},{-500 + 11 * i * i % 700},{200 + 53 * i % 900}\n"
                                       for i in range(30)),
})
BINARY = bytes(range(256)) * 4  # not UTF-8 text

MOCKUP = ["scenario=yan2022_mockup", "estimator=ls"]

CASES = [  # (arguments, words the one line must contain)
    # config groups and keys
    (["estimator=foo"], ["'foo'", "ipso"]),
    (["scenario=nope"], ["'nope'", "ding2024_exp1"]),
    (["scenario.nosie=2"], ["scenario.nosie", "'nosie'", "noise", "n_readings"]),  # a typo names the keys
    (["scenario.search.offsett=[0,1]"], ["offsett", "offdiag"]),
    (["estimator.n_particle=3"], ["n_particle", "n_particles"]),
    (["sed=3"], ["sed", "seed"]),
    (["objective=bogus"], ["'bogus'", "scalar"]),
    # the simulation command has no calibration keys (the silently-wrong-job cases)
    (["task=calibrate"], ["task=calibrate", "magexp calibrate"]),
    (["task=bogus"], ["task=bogus", "magexp calibrate"]),
    (["data.path=mine.txt", "data.unit=uT", "estimator=lm"], ["data.path", "magexp calibrate"]),
    (["out=scratch/"], ["out=scratch/", "magexp calibrate"]),
    # values
    (["scenario.noise=-1"], ["-1", ">= 0"]),
    (["scenario.noise=nan"], ["nan"]),
    (["scenario.noise=inf"], ["inf"]),
    (["scenario.noise=abc"], ["scenario.noise=abc"]),
    (["scenario.noise=1e300"], ["1e+300", "1e+15"]),
    (["scenario.search.offset=[-1e300,1e300]"], ["search.offset", "1e+15"]),
    (["scenario.search.diag=[2,1]"], ["search.diag", "low < high"]),
    (["scenario.search.offset=[0,inf]"], ["search.offset"]),
    (["estimator.n_particles=0"], ["n_particles=0", ">= 1"]),
    (["estimator.n_particles=-3"], ["n_particles=-3"]),
    (["estimator.n_iterations=0"], ["n_iterations=0"]),
    (["estimator.n_particles=2.5"], ["2.5"]),
    (["estimator.velocity_clamp=-0.1"], ["velocity_clamp=-0.1"]),
    (["estimator.init.form=weird"], ["'weird'", "printed"]),
    (["scenario.n_readings=0"], ["n_readings=0"]),
    (["scenario.n_readings=100000000"], ["n_readings=100000000", "GiB"]),  # refused up front: memory
    (["scenario.n_readings=1e8"], ["n_readings=100000000", "GiB"]),
    (["scenario.n_readings=1.5"], ["n_readings=1.5", "an integer"]),
    (["estimator=lm", "scenario.n_readings=5"], ["n_readings=5", "12 parameters"]),  # fewer readings than parameters
    (["estimator=ellipsoid", "scenario.n_readings=11"], ["n_readings=11"]),
    (["scenario=yuan2018_mode1", "estimator=lm", "scenario.n_readings=3"], ["n_readings=3"]),
    (["scenario=yan2022_sim", "estimator=kf", "estimator.sigma2=0"], ["sigma2=0", "> 0"]),
    (["scenario=yan2022_sim", "estimator=kf", "estimator.sigma2=-5"], ["sigma2=-5"]),
    (["seed=-1"], ["seed=-1"]),
    (["seed=abc"], ["abc"]),
    (["seed=1.5"], ["seed=1.5"]),
    # recordings read by a scenario
    ([*MOCKUP, "scenario.path=missing.csv"], ["missing.csv", "does not exist"]),
    ([*MOCKUP, "scenario.path=a_folder"], ["a_folder", "is a directory"]),
    ([*MOCKUP, "scenario.path=binary.csv"], ["binary.csv", "not UTF-8"]),
    ([*MOCKUP, "scenario.path=huge.csv"], ["1e308", "1e+15"]),
    ([*MOCKUP, "scenario.path=missing_column.csv"], ["bz"]),
    ([*MOCKUP, "scenario.path=text.csv"], ["abc"]),
    ([*MOCKUP, "scenario.path=nan.csv"], ["nan"]),
    ([*MOCKUP, "scenario.path=unit.csv"], ["furlong"]),
    ([*MOCKUP, "scenario.path=row_length.csv"], ["row_length.csv"]),
    ([*MOCKUP, "scenario.path=no_angles.csv"], ["heading"]),
    # output folders, checked before any computation
    (["hydra.run.dir=a_file"], ["a_file", "is a file"]),
    (["hydra.run.dir=a_file/run"], ["a_file", "is a file"]),
    (["hydra.run.dir=/proc/magexp-run"], ["/proc/magexp-run", "not writable"]),
    # the command line itself
    (["--bogus"], ["'--bogus'"]),
    (["scenario.noise=1,2"], ["needs -m"]),
    (["hydra.job.chdir=true"], ["hydra.job.chdir"]),
    (["scenario.noise=[1"], ["could not parse"]),
    # sweeps: every value checked before the first job (and no multirun folder)
    (["-m", "estimator=pso,bogus"], ["'bogus'"]),
    (["-m", "scenario.noise=2,-1", "seed=range(3)"], ["scenario.noise=-1"]),
    (["-m", "scenario.noise=1,2", "seed=0,1,-4"], ["seed=-4"]),  # a bad seed among many
    (["-m", "estimator=lm,ellipsoid", "scenario.n_readings=300,6"], ["n_readings=6"]),
    (["-m", "seed=range(2)", "scenario.nosie=1,2"], ["'nosie'"]),
    (["-m", "hydra/launcher=nope", "seed=1,2"], ["'nope'", "joblib"]),
    (["-m", "hydra.launcher.foo=1", "seed=1,2"], ["hydra.launcher.foo"]),
    (["-m", "hydra.launcher.jobs=abc", "seed=1,2"], ["hydra.launcher.jobs", "abc"]),
    (["-m", "hydra.launcher.executor=nope", "seed=1,2"], ["hydra.launcher.executor", "'nope'", "dask"]),
    (["-m", "hydra.launcher.scheduler=slurm", "seed=1,2"], ["hydra.launcher.scheduler", "executor=dask"]),
    (["-m", "hydra.sweep.dir=a_file", "seed=1,2"], ["a_file", "is a file"]),
    (["task=calibrate"], ["magexp calibrate"]),  # moved to its own command
    (["calibrate", "data.path=missing.csv", "data.unit=nT"], ["missing.csv"]),
    (["calibrate", "data.path=missing_column.csv"], ["bz"]),
    (["calibrate", "data.path=text.csv"], ["abc"]),
    (["calibrate", "data.path=nan.csv"], ["nan"]),
    (["calibrate", "data.path=short.csv", "estimator=lm"], ["3"]),
    (["calibrate", "data.path=unit.csv"], ["furlong"]),
    (["calibrate", "data.path=row_length.csv"], ["row_length.csv"]),
    (["calibrate", "data.path=good.csv", "out=a_file"], ["a_file"]),  # an output "folder" that is a file
]

REPRODUCE_CASES = [
    (["nopaper"], ["'nopaper'", "ding2024"]),
    (["ding2024", "--jobs", "-1"], ["--jobs -1"]),
    (["ding2024", "--only", "nothing"], ["'nothing'"]),
    (["ding2024", "--only", "ding2024_fig3", "--out", "a_file"], ["a_file", "is a file"]),
    (["ding2024", "--only", "ding2024_fig3", "--out", "/proc/magexp-results"], ["/proc/magexp-results", "not writable"]),
    (["all", "--out", "a_file/results"], ["a_file", "is a file"]),
]


def snapshot(folder):
    return {p: p.stat().st_mtime_ns for p in folder.rglob("*")} if folder.exists() else {}


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    tmp_path = tmp_path / "work"  # beside the test's own run cache (tmp_path/cache)
    tmp_path.mkdir()
    for name, text in FILES.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "binary.csv").write_bytes(BINARY)
    (tmp_path / "a_file").write_text("not a folder\n")
    (tmp_path / "a_folder").mkdir()
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.fixture(scope="module", autouse=True)
def results_untouched():
    before = snapshot(RESULTS)
    yield
    assert snapshot(RESULTS) == before, "a bad input wrote into results/"


def one_line_failure(call, capsys, words):
    with pytest.raises(SystemExit) as info:
        call()
    assert info.value.code not in (0, None)
    out, err = capsys.readouterr()
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in out + err and "unexpected" not in err, err
    for w in words:
        assert w in lines[0], (w, lines[0])


def test_table_has_every_case():
    assert len(CASES) + len(REPRODUCE_CASES) >= 60


@pytest.mark.parametrize("args, words", CASES, ids=[" ".join(a) for a, _ in CASES])
def test_bad_run_input(workdir, capsys, args, words):
    before = snapshot(workdir)
    one_line_failure(lambda: magexp_main(args), capsys, words)
    assert snapshot(workdir) == before, "a bad input wrote into the working folder"


@pytest.mark.parametrize("args, words", REPRODUCE_CASES, ids=[" ".join(a) for a, _ in REPRODUCE_CASES])
def test_bad_reproduce_input(workdir, capsys, args, words):
    from magexp.reproduce import main as reproduce_main

    before = snapshot(workdir)
    args = args if "--out" in args else [*args, "--out", str(workdir / "res")]

    def call():
        raise SystemExit(reproduce_main(args))

    one_line_failure(call, capsys, words)
    assert snapshot(workdir) == before


def test_missing_launcher_extra_names_the_pip_install(workdir, capsys, monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if "submitit" in name else real(name, *a))
    one_line_failure(lambda: magexp_main(["-m", "hydra/launcher=slurm", "seed=1,2"]), capsys,
                     ["hydra/launcher=slurm", "pip install 'magexp[cluster]'"])
    assert not (workdir / "multirun").exists()


def test_ctrl_c_is_one_line_and_leaves_no_folder(workdir, capsys, monkeypatch):
    def interrupted(cfg):
        raise KeyboardInterrupt

    monkeypatch.setattr("magexp.runner.run", interrupted)
    before = snapshot(workdir)
    one_line_failure(lambda: magexp_main(["estimator=ellipsoid"]), capsys, ["interrupted"])
    assert snapshot(workdir) == before  # the run's folder (and outputs/<date>/) removed again
    one_line_failure(lambda: magexp_main(["estimator=ellipsoid", "hydra.run.dir=mine/run"]), capsys, ["interrupted"])
    assert snapshot(workdir) == before  # a named folder made for the run, too


def test_unexpected_error_is_still_one_line(workdir, capsys, monkeypatch):
    def broken(cfg):
        raise RuntimeError("a bug\nsecond line")

    monkeypatch.setattr("magexp.runner.run", broken)
    with pytest.raises(SystemExit) as info:
        magexp_main(["estimator=ellipsoid"])
    assert info.value.code == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "RuntimeError: a bug" in err and "MAGEXP_DEBUG" in err


def test_utf8_byte_order_mark_is_accepted(workdir, capsys):
    good = MOCKUP_HEADER + ROWS
    (workdir / "bom.csv").write_bytes(b"\xef\xbb\xbf" + good.encode())
    magexp_main([*MOCKUP, "scenario.path=bom.csv", f"hydra.run.dir={workdir / 'run'}"])
    assert "fit_rms" in (workdir / "run" / "metrics.csv").read_text()
