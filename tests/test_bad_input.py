"""Bad input, table-driven: one line naming the value, a non-zero exit, no traceback, nothing in results/."""

import os
import subprocess
import sys

import pytest

from magexp.paths import RESULTS

GOOD_HEADER = "# magexp-recording v1\n# unit: nT\nbx,by,bz\n"
ROWS = "".join(f"{1000 + 37 * i},{-500 + 11 * i * i % 700},{200 + 53 * i % 900}\n" for i in range(30))

FILES = {
    "missing_column.csv": "# magexp-recording v1\nbx,by\n1,2\n",
    "text.csv": GOOD_HEADER + ROWS + "1,abc,3\n",
    "nan.csv": GOOD_HEADER + ROWS + "1,nan,3\n",
    "short.csv": GOOD_HEADER + "1,2,3\n4,5,6\n7,8,10\n",
    "unit.csv": "# magexp-recording v1\n# unit: furlong\nbx,by,bz\n" + ROWS,
    "row_length.csv": GOOD_HEADER + ROWS + "1,2\n",
    "good.csv": GOOD_HEADER + ROWS,
}

CASES = [  # (arguments, words the one line must contain)
    (["estimator=foo"], ["'foo'", "ipso"]),
    (["scenario=nope"], ["'nope'", "ding2024_exp1"]),
    (["scenario.noise=-1"], ["-1", ">= 0"]),
    (["scenario.noise=nan"], ["nan"]),
    (["scenario.noise=inf"], ["inf"]),
    (["scenario.noise=abc"], ["abc"]),
    (["estimator.n_particles=0"], ["n_particles=0", ">= 1"]),
    (["estimator.n_particles=-3"], ["n_particles=-3"]),
    (["estimator.n_iterations=0"], ["n_iterations=0"]),
    (["estimator.n_particles=2.5"], ["2.5"]),
    (["scenario.n_readings=0"], ["n_readings=0"]),
    (["seed=-1"], ["seed=-1"]),
    (["seed=abc"], ["abc"]),
    (["scenario.search.diag=[2,1]"], ["search.diag", "low < high"]),
    (["scenario.search.offset=[0,inf]"], ["search.offset"]),
    (["scenario.nois=3"], ["scenario.nois"]),
    (["objective=bogus"], ["'bogus'", "scalar"]),
    (["task=bogus"], ["'bogus'"]),
    (["estimator.velocity_clamp=-0.1"], ["velocity_clamp=-0.1"]),
    (["estimator.init.form=weird"], ["'weird'", "printed"]),
    (["-m", "estimator=pso,bogus"], ["'bogus'"]),
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
]


def snapshot(folder):
    return {p: p.stat().st_mtime_ns for p in folder.rglob("*")} if folder.exists() else {}


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("bad")
    for name, text in FILES.items():
        (d / name).write_text(text)
    (d / "a_file").write_text("not a folder\n")
    return d


@pytest.fixture(scope="module", autouse=True)
def results_untouched():
    before = snapshot(RESULTS)
    yield
    assert snapshot(RESULTS) == before, "a bad input wrote into results/"


def check(proc, words):
    assert proc.returncode != 0
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout
    for w in words:
        assert w in lines[0], (w, lines[0])


def test_table_has_at_least_twenty_cases():
    assert len(CASES) + len(REPRODUCE_CASES) >= 20


@pytest.mark.parametrize("args, words", CASES, ids=[" ".join(a) for a, _ in CASES])
def test_bad_run_input(workdir, args, words):
    env = {**os.environ, "HYDRA_FULL_ERROR": "0"}
    proc = subprocess.run([sys.executable, "-m", "magexp", *args, f"hydra.run.dir={workdir / 'hydra'}"],
                          cwd=workdir, capture_output=True, text=True, timeout=120, env=env)
    check(proc, words)


@pytest.mark.parametrize("args, words", REPRODUCE_CASES, ids=[" ".join(a) for a, _ in REPRODUCE_CASES])
def test_bad_reproduce_input(workdir, args, words):
    proc = subprocess.run([sys.executable, "-m", "magexp.reproduce", *args, "--out", str(workdir / "res")],
                          cwd=workdir, capture_output=True, text=True, timeout=120)
    check(proc, words)
