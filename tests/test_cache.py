"""The run cache proves what it returns and runs no code: entries swapped between keys, crafted
entries (a pickle that would run a shell command, forged entries of the current format), a cache
that cannot be written, entries of another user, and two reproductions sharing one cache; and what a
run's key holds: the code of the classes it builds and what they import, and the core every run executes."""

import hashlib
import os
import pickle
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf

from magexp.run import cache, codekey, runkeys

from magexp.artifacts import reproduce
from magexp.estimators.result import RunOutput
from magexp.paths import ROOT
from magexp.run.compose import compose_config

RUNS = 6


FIGURES = (".png", ".pdf")


def files(out: Path) -> dict:
    """Every file a reproduction wrote but its figures, by relative path, with its bytes: the reproductions
    here build their figures without rendering them (conftest.py's ``figures_not_rendered``: what is
    tested is the cache, and the same CSV giving the same figure is test_reproduce.py's)."""
    return {p.relative_to(out).as_posix(): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and p.suffix not in FIGURES}


def entries(cache_dir: Path) -> list[Path]:
    return sorted(cache_dir.rglob(f"*{cache.SUFFIX}"))


@pytest.fixture
def clean(mockup_reproduction, figures_not_rendered):
    """A clean reproduction (conftest.py's, shared): its run cache and its files but its figures; the
    test's own reproductions build their figures without rendering them."""
    assert len(entries(mockup_reproduction.runs)) == RUNS
    return mockup_reproduction.runs, files(mockup_reproduction.out)


@pytest.fixture
def reproduce_into(mockup_reproduction):
    """``reproduce_into(out, cache_dir)``: the clean reproduction's command again, into ``out``."""
    return mockup_reproduction.reproduce_into


@pytest.fixture
def artifact(mockup_reproduction):
    return mockup_reproduction.args


def forge(data: bytes, old: bytes, new: bytes) -> bytes:
    """An entry with ``old`` replaced by ``new`` in its body and the digest made to match (as a forger
    would: the layout is documented in :func:`magexp.run.cache.pack`)."""
    first, _, body = data.partition(b"\n")
    body = body.replace(old, new)
    magic, _, m, n = first.split()
    return b" ".join([magic, hashlib.sha256(body).hexdigest().encode(), m, n]) + b"\n" + body


class Shell:
    """Unpickling this runs a shell command (what the former pickle cache would have done)."""

    def __init__(self, command: str):
        self.command = command

    def __reduce__(self):
        return os.system, (self.command,)


def a_run(**changes) -> RunOutput:
    fields = dict(metrics={"scenario": "s", "seed": 1, "fun": 0.5, "ok": True, "none": None},
                  history=np.array([2.0, 1.0]), history_nfev=np.array([0, 10]), x=np.arange(3.0),
                  parameter_names=["a", "b", "c"], trace={"state": np.ones((2, 3)), "names": ["p", "q"]},
                  readings=np.arange(6.0).reshape(2, 3).T, calibrated=None, reference_norm=np.array(1.5),
                  truth_x=np.arange(3, dtype=np.int32), fit_cpu=0.25)
    return RunOutput(**{**fields, **changes})


def same_run(a: RunOutput, b: RunOutput) -> bool:
    for name in vars(a):
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, np.ndarray):
            if not (isinstance(y, np.ndarray) and x.dtype == y.dtype and x.shape == y.shape and np.array_equal(x, y)):
                return False
        elif name == "trace":
            if x.keys() != y.keys() or not all(np.array_equal(x[k], y[k]) for k in x):
                return False
        elif x != y or type(x) is not type(y):
            return False
    return True


def test_a_stored_run_comes_back_exactly(tmp_path):
    run = a_run()
    assert cache.store("k1", run, tmp_path)
    back = cache.load("k1", tmp_path)
    assert same_run(run, back) and back.readings.flags.writeable
    assert cache.say_notes() == []


def test_invalid_entries_are_misses_said_once_in_one_line(tmp_path):
    for key in ("k1", "k2", "k3", "k4", "k5", "k6"):
        assert cache.store(key, a_run(), tmp_path)
    path = {key: cache.entry_path(key, tmp_path) for key in ("k1", "k2", "k3", "k4", "k5", "k6")}
    one, two = path["k1"].read_bytes(), path["k2"].read_bytes()
    path["k1"].write_bytes(two)  # swapped: each a valid entry of the other key
    path["k2"].write_bytes(one)
    path["k3"].write_bytes(path["k3"].read_bytes()[:-7])  # truncated
    path["k4"].write_bytes(forge(path["k4"].read_bytes(), b'"metrics": {', b'"metrics": [1], "x0": {'))
    path["k5"].write_bytes(cache.pack("k5", "config", {"a": 1}))  # an entry of another kind
    path["k6"].write_bytes(forge(path["k6"].read_bytes(), b'"<f8"', b'"|O8"'))  # an object array
    assert all(cache.load(key, tmp_path) is None for key in path)
    assert all(path[key].exists() for key in path)  # left in place: the recomputed run replaces it
    lines = cache.say_notes()
    assert len(lines) == 1 and "6 entries not valid" in lines[0] and "stored under another key: 2" in lines[0], lines
    assert cache.say_notes() == []  # said once


def test_a_fifo_in_place_of_an_entry_is_a_miss_not_a_hang(tmp_path):
    """A FIFO planted where an entry would be: ``exists`` and ``load`` answer at once (a plain open of it would
    wait for a writer forever), and storing the run replaces it."""
    path = cache.entry_path("k1", tmp_path)
    path.parent.mkdir(parents=True, exist_ok=True)
    os.mkfifo(path)
    assert cache.exists("k1", tmp_path) is False
    assert cache.load("k1", tmp_path) is None
    cache.say_notes()
    assert cache.store("k1", a_run(), tmp_path) and cache.exists("k1", tmp_path) and path.is_file()


def test_only_one_process_claims_a_run():
    first = cache.claim("k1")
    assert first is not None and first.fd is not None
    assert cache.claim("k1") is None  # another claimant (another open file) is refused, not queued
    first.release()
    again = cache.claim("k1")
    assert again is not None and again.fd is not None
    again.release()
    assert not list(cache.CACHE.rglob("*.lock"))  # a released claim leaves nothing behind


@pytest.mark.slow
def test_swapped_and_crafted_entries_are_recomputed_and_run_no_code(clean, reproduce_into, tmp_path, capsys):
    """A swapped pair of entries, a pickle that would run ``touch`` under the former loader, and a forged
    entry of the current format with a valid digest: recomputed, one line, the clean run's files."""
    clean_cache, clean_files = clean
    runs = tmp_path / "runs"
    shutil.copytree(clean_cache, runs)
    found = entries(runs)
    first, second = found[0].read_bytes(), found[1].read_bytes()
    found[0].write_bytes(second)
    found[1].write_bytes(first)
    marker = tmp_path / "pwned"
    crafted = pickle.dumps(Shell(f"touch {marker}"))
    found[2].write_bytes(crafted)
    found[2].with_suffix(".pkl").write_bytes(crafted)  # where the former cache kept it
    found[3].write_bytes(forge(found[3].read_bytes(), b'"metrics": {', b'"metrics": "x", "m0": {'))
    capsys.readouterr()
    assert reproduce_into(tmp_path / "out", runs) == 0
    said = capsys.readouterr()
    err = said.err.splitlines()
    assert not marker.exists()
    assert len(err) == 1 and "4 entries not valid" in err[0], err
    assert "4 computed, 2 from the cache" in said.out
    assert files(tmp_path / "out") == clean_files
    assert all(cache.load(p.stem, runs) is not None for p in found)  # replaced by the recomputed runs
    assert cache.say_notes() == []


@pytest.mark.slow
def test_a_cache_that_cannot_be_written_gives_one_line_and_the_results(clean, reproduce_into, tmp_path, capsys, cli):
    """Every write into the cache folder fails (it lies under a file: for root as for anyone): the
    reproduction computes, says so in one line and writes the clean run's files; a single run too."""
    _, clean_files = clean
    (tmp_path / "file").write_text("not a folder")
    runs = tmp_path / "file" / "runs"
    capsys.readouterr()
    assert reproduce_into(tmp_path / "out", runs) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"note: run cache {runs} cannot be written") and f"{RUNS} computed" in err[0]
    assert files(tmp_path / "out") == clean_files
    cache.CACHE = runs  # undone by the test's own cache fixture
    done = cli("scenario=ding2024_exp1", "estimator=lm", "scenario.n_readings=60", f"hydra.run.dir={tmp_path / 'one'}")
    assert done.returncode == 0 and len(done.stderr.splitlines()) == 1 and "cannot be written" in done.stderr
    assert (tmp_path / "one" / "metrics.csv").is_file()


@pytest.mark.slow
@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into a read-only folder")
def test_a_read_only_cache_gives_one_line_and_the_results(clean, reproduce_into, tmp_path, capsys):
    clean_cache, clean_files = clean
    runs = tmp_path / "runs"
    shutil.copytree(clean_cache, runs)
    entries(runs)[0].unlink()
    for folder in [runs, *[p for p in runs.rglob("*") if p.is_dir()]]:
        folder.chmod(0o555)
    try:
        capsys.readouterr()
        assert reproduce_into(tmp_path / "out", runs) == 0
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and "cannot be written" in err[0] and "1 computed run not kept" in err[0], err
        assert files(tmp_path / "out") == clean_files
    finally:
        for folder in [runs, *[p for p in runs.rglob("*") if p.is_dir()]]:
            folder.chmod(0o755)


def test_entries_are_shared_with_the_group_of_a_shared_folder(tmp_path):
    """In a folder shared by a group (setgid, group-writable) entries are readable by the group and its
    sub-folders keep the group; an entry this user cannot read is a miss, never deleted or replaced."""
    shared = Path(os.environ.get("TMPDIR", "/tmp")) / f"magexp-shared-{os.getpid()}"
    shared.mkdir(mode=0o755)
    try:
        runs = shared / "runs"
        runs.mkdir()
        runs.chmod(0o2775)
        assert cache.store("ab12", a_run(), runs)
        entry = cache.entry_path("ab12", runs)
        assert entry.stat().st_mode & 0o777 == 0o644
        assert entry.parent.stat().st_mode & 0o7777 == 0o2775 and entry.parent.stat().st_gid == runs.stat().st_gid
        assert cache.store("cd34", a_run(), runs)
        mine = cache.entry_path("cd34", runs)
        mine.chmod(0o600)  # as the former cache wrote them
        data = mine.read_bytes()
        if os.geteuid() != 0:
            pytest.skip("another user's view needs root (seteuid)")
        cache.load("ab12", runs)  # imports what a load needs before this process gives up its rights
        os.setegid(65534)
        os.seteuid(65534)
        try:
            other_reads = cache.load("ab12", runs)
            unreadable = cache.load("cd34", runs)
            replaced = cache.store("cd34", a_run(fit_cpu=1.0), runs)
        finally:
            os.seteuid(0)
            os.setegid(0)
        assert other_reads is not None and unreadable is None and not replaced
        assert mine.read_bytes() == data  # left as it was
        lines = cache.say_notes()
        assert len(lines) == 1 and "not readable by this user" in lines[0], lines
    finally:
        shutil.rmtree(shared)


# a reproduction that logs each run it computes (one line per run) and starts computing only once
# both processes have planned (so that they race for the same runs); its figure is not drawn (what
# is shared is the run cache: the figure cache is tested in test_reproduce.py)
CONCURRENT = """
import sys, time
from pathlib import Path
from magexp.artifacts.plots import style
from magexp.run import executor
from magexp.artifacts.reproduce import main
def save(fig, path):  # empty files where the figure goes
    style.plt.close(fig)
    for twin in (path, path.with_suffix(".pdf")):
        twin.write_bytes(b"")
    return [path, path.with_suffix(".pdf")]
style.save = save
log, me, other = Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3])
real_batch, real_many = executor.run_batch, executor.run_many
def run_batch(configs):
    for out in real_batch(configs):
        with log.open("a") as fh:
            fh.write(f"{out.metrics['estimator']} {out.metrics['seed']}\\n")
        time.sleep(0.3)  # long enough for the other process to reach the same runs
        yield out
def run_many(*args, **kw):
    me.touch()
    for _ in range(600):
        if other.exists():
            break
        time.sleep(0.05)
    return real_many(*args, **kw)
executor.run_batch, executor.run_many = run_batch, run_many
sys.exit(main(sys.argv[4:]))
"""


@pytest.mark.full  # two reproductions in subprocesses (make test-full); the claim each relies on: test_only_one_process_claims_a_run
def test_two_reproductions_on_one_cache_compute_each_run_once(clean, artifact, tmp_path):
    _, clean_files = clean
    env = {**os.environ, "MAGEXP_CACHE": str(tmp_path / "runs")}
    procs = [subprocess.Popen([sys.executable, "-c", CONCURRENT, str(tmp_path / f"{name}.log"),
                               str(tmp_path / f"{name}.ready"), str(tmp_path / f"{other}.ready"), *artifact,
                               "--out", str(tmp_path / name)], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True)
             for name, other in (("a", "b"), ("b", "a"))]
    done = [p.communicate(timeout=300) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], done
    computed = [line for name in "ab" if (tmp_path / f"{name}.log").exists()
                for line in (tmp_path / f"{name}.log").read_text().splitlines()]
    assert len(computed) == RUNS and len(set(computed)) == RUNS, computed  # each run once, by one of them
    assert files(tmp_path / "a") == files(tmp_path / "b") == clean_files
    assert all(err == "" for _, err in done)


def test_an_empty_cache_variable_means_the_default_folder():
    """``MAGEXP_CACHE=`` (set but empty) is the default cache, never the working folder."""
    import subprocess
    import sys

    code = "from magexp import paths; print(paths.CACHE)"
    env = {**os.environ, "MAGEXP_CACHE": ""}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout.split()
    assert out[0] != "." and out[0].endswith("runs"), out


# ---------------------------------------------------------------------------------------------
# what a run's key holds: the code of the classes it builds and what they import, and the core

#: runs keyed in these tests, each composed once: (scenario, estimator)
KEYED = [("yuan2018_mode1", e) for e in ("lm", "local", "pso", "ipso", "kf", "ekf", "ls")] + [
    ("ding2024_exp1", "pso"), ("ding2024_exp1", "ellipsoid"), ("yan2022_sim", "kf")]


@pytest.fixture(scope="module")
def keyed() -> dict:
    """``{(scenario, estimator): resolved config}`` of :data:`KEYED`."""
    return {(s, e): OmegaConf.to_container(compose_config([f"scenario={s}", f"estimator={e}"]), resolve=True)
            for s, e in KEYED}


@pytest.fixture
def sources(tmp_path, monkeypatch):
    """A copy of magexp's sources that run keys are worked out from (``codekey.ROOT``), to edit; what
    the process found of the sources is forgotten before and after."""
    copy = tmp_path / "repo"
    shutil.copytree(ROOT / "magexp", copy / "magexp", ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(codekey, "ROOT", copy)
    codekey.forget_code()
    yield copy
    codekey.forget_code()


def keys_of(configs: dict) -> dict:
    return dict(zip(configs, runkeys.run_keys(list(configs.values()))))


def edit(path: Path, old: str, new: str) -> None:
    """Replace ``old`` (present once) by ``new`` in ``path``; this process then forgets what it read."""
    text = path.read_text()
    assert text.count(old) == 1, old
    path.write_text(text.replace(old, new))
    codekey.forget_code()


def code_edit(path: Path) -> None:
    """Add a statement to ``path`` (a docstring edit is no code edit); this process then forgets what it read."""
    with path.open("a") as fh:
        fh.write("\nEDITED = 1\n")
    codekey.forget_code()


def changed(before: dict, after: dict) -> set:
    return {run for run in before if before[run] != after[run]}


def test_a_runs_code_is_the_closure_of_what_it_builds_and_of_the_core(keyed):
    files = set(codekey.code_files(runkeys.run_targets(keyed["ding2024_exp1", "pso"])))
    for needed in ("magexp.run.runner", "magexp.core.metrics", "magexp.core.bounds", "magexp.core.seeding", "magexp",
                   "magexp.scenarios.ding", "magexp.problems.scalar", "magexp.estimators.swarm",
                   "magexp.estimators.velocity", "magexp.estimators.schedules", "magexp.estimators.initialisers"):
        assert needed in files, needed  # the core, the scenario, its objective's problem, the nested strategies
    for other in ("magexp.artifacts.reproduce", "magexp.artifacts.report", "magexp.run.executor", "magexp.run.cache",
                  "magexp.artifacts.plots.style", "magexp.estimators.lm", "magexp.estimators.kalman",
                  "magexp.scenarios.yuan", "magexp.problems.vector", "magexp.problems.ship"):
        assert other not in files, other  # downstream code, and other runs' classes
    # a ship scenario's config names no objective: its class fixes it (``objective = "ship"``)
    assert [t for t in runkeys.run_targets(keyed["yan2022_sim", "kf"]) if t.startswith("magexp.problems.")] == [
        "magexp.problems.ship.ShipMagnetization"]


def test_an_unused_module_changes_no_key_and_a_plot_edit_none_either(sources, keyed):
    before = keys_of(keyed)
    (sources / "magexp/estimators/toy.py").write_text('"""A toy."""\n\n\nclass Toy:\n    """Empty."""\n')
    with (sources / "magexp/artifacts/plots/convergence.py").open("a") as fh:
        fh.write("\n# a new label\n")
    codekey.forget_code()
    assert keys_of(keyed) == before


def test_an_estimator_edit_changes_the_keys_of_its_runs_and_of_its_importers_only(sources, keyed):
    before = keys_of(keyed)
    code_edit(sources / "magexp/estimators/lm.py")
    assert changed(before, keys_of(keyed)) == {("yuan2018_mode1", "lm"), ("yuan2018_mode1", "local")}  # local imports lm


def test_a_core_edit_changes_every_key(sources, keyed):
    before = keys_of(keyed)
    code_edit(sources / "magexp/core/bounds.py")
    assert changed(before, keys_of(keyed)) == set(keyed)


def test_docstrings_comments_and_layout_change_no_key_but_code_does(sources, keyed):
    before = keys_of(keyed)
    path = sources / "magexp/core/bounds.py"
    text = path.read_text()
    first = text.index('"""', text.index("\ndef ")) + 3  # the first function's docstring
    path.write_text(text[:first] + "Rewritten. " + text[first:].replace("\n\n\n", "\n\n\n# a comment\n\n", 1))
    edit(sources / "magexp/estimators/lm.py", '"""Levenberg-Marquardt refinement', '"""Levenberg-Marquardt (LM) refinement')
    assert keys_of(keyed) == before
    code_edit(path)
    assert changed(before, keys_of(keyed)) == set(keyed)


TOY_INIT = '"""An estimator of another package."""\n\nfrom .methods import MyMethod\n'
TOY_METHODS = '''"""MyMethod."""

from magexp.estimators.lm import LevenbergMarquardt


class MyMethod(LevenbergMarquardt):
    """Levenberg-Marquardt under another name."""

    name = "my_method"
'''


def test_an_estimator_of_another_package_is_keyed_by_its_source_unimported(sources, keyed, tmp_path, monkeypatch):
    package = tmp_path / "outside" / "toypkg"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text(TOY_INIT)
    (package / "methods.py").write_text(TOY_METHODS)
    (package / "unused.py").write_text('"""Imported by nothing."""\n')
    monkeypatch.syspath_prepend(str(package.parent))
    codekey.forget_code()
    lm = keyed["yuan2018_mode1", "lm"]
    runs = {"docs": {**lm, "estimator": {**lm["estimator"], "_target_": "toypkg.MyMethod"}},  # docs/extending.md's way
            "module": {**lm, "estimator": {**lm["estimator"], "_target_": "toypkg.methods.MyMethod"}},
            "pso": keyed["yuan2018_mode1", "pso"]}
    before = keys_of(runs)
    assert "toypkg" not in sys.modules  # found from its source, not imported
    assert {"toypkg", "toypkg.methods", "magexp.estimators.lm"} <= set(codekey.code_files(runkeys.run_targets(runs["docs"])))
    code_edit(package / "methods.py")
    assert changed(before, keys_of(runs)) == {"docs", "module"}
    again = keys_of(runs)
    (package / "unused.py").write_text('"""Edited, still imported by nothing."""\n')
    codekey.forget_code()
    assert keys_of(runs) == again
    code_edit(sources / "magexp/estimators/lm.py")
    assert changed(again, keys_of(runs)) == {"docs", "module"}  # magexp code it imports is its code too
    again = keys_of(runs)
    edit(package / "methods.py", "class MyMethod(", "class MyMethod((")  # not Python: keyed all the same
    assert changed(again, keys_of(runs)) == {"docs", "module"}  # (building it says what is wrong)


def test_code_versions_are_kept_under_the_sources_stamp(sources, keyed):
    import json

    targets = runkeys.run_targets(keyed["ding2024_exp1", "pso"])
    version = runkeys.code_version(targets)
    memo = cache.CACHE / "code-version.json"
    (stamp, kept), = json.loads(memo.read_text()).items()  # the versions, under the sources' stamp
    assert kept == {"|".join(targets): version}
    memo.write_text(json.dumps({stamp: {"|".join(targets): "kept"}}))
    assert runkeys.code_version(targets) == "kept"  # read back, not worked out
    code_edit(sources / "magexp/estimators/swarm.py")
    new = runkeys.code_version(targets)
    assert new not in ("kept", version)  # a new stamp: worked out again
    assert json.loads(memo.read_text())[next(k for k in json.loads(memo.read_text()) if k != stamp)] == {
        "|".join(targets): new}


def reading(run: dict, file: Path, format: str = "auto") -> dict:
    """``run`` with a recording scenario that reads ``file`` in ``format``."""
    return {**run, "scenario": {"_target_": "magexp.scenarios.recording.RecordingScenario", "name": "reading",
                                "file": str(file), "format": format, "objective": "scalar"}}


def test_a_reader_edit_changes_the_keys_of_the_runs_reading_its_format_only(sources, keyed, tmp_path):
    logs = {"a.ulg": b"ULog\x01\x12", "b.dat": b"ULog\x01\x12", "c.bin": b"\xa3\x95\x80", "d.txt": b"1 2 3\n4 5 6\n"}
    for name, content in logs.items():  # keying a run reads no more than a text file's first lines
        (tmp_path / name).write_bytes(content)
    bag = tmp_path / "bag"  # a ROS 2 bag: a folder with metadata.yaml and its storage files
    bag.mkdir()
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information:\n  version: 5\n")
    (bag / "bag_0.db3").write_bytes(b"SQLite format 3\x00")
    lm = keyed["yuan2018_mode1", "lm"]
    runs = {"ulog": reading(lm, tmp_path / "a.ulg"), "named ulog": reading(lm, tmp_path / "b.dat", "ulog"),
            "dataflash": reading(lm, tmp_path / "c.bin"), "plain": reading(lm, tmp_path / "d.txt"),
            "ros2 bag": reading(lm, bag),
            "simulated": lm, "ding": keyed["ding2024_exp1", "pso"]}
    imported = {m for m in sys.modules if m.split(".")[0] in ("pyulog", "pymavlink", "rosbags")}
    assert "magexp.core.readers.ulog.read_ulog" in runkeys.run_targets(runs["named ulog"])  # the format named wins
    before = keys_of(runs)
    (sources / "magexp/core/readers/new.py").write_text('"""A reader of a new format."""\n')
    codekey.forget_code()
    assert keys_of(runs) == before  # a new reader reruns nothing
    code_edit(sources / "magexp/core/readers/ulog.py")
    assert changed(before, after := keys_of(runs)) == {"ulog", "named ulog"}
    code_edit(sources / "magexp/core/readers/dataflash.py")
    assert changed(after, again := keys_of(runs)) == {"dataflash"}
    code_edit(sources / "magexp/core/readers/rosbag.py")
    assert changed(again, again := keys_of(runs)) == {"ros2 bag"}
    (bag / "bag_0.db3").write_bytes(b"SQLite format 3\x00\x01")
    assert changed(again, again := keys_of(runs)) == {"ros2 bag"}  # a bag folder's files are its data
    code_edit(sources / "magexp/core/logfiles.py")
    assert changed(again, again := keys_of(runs)) == {"ulog", "named ulog", "dataflash", "ros2 bag"}  # what they import
    code_edit(sources / "magexp/core/readers/__init__.py")
    assert changed(again, keys_of(runs)) == {"ulog", "named ulog", "dataflash", "plain", "ros2 bag"}  # the registry
    assert {m for m in sys.modules if m.split(".")[0] in ("pyulog", "pymavlink", "rosbags")} == imported  # never read


def test_a_recording_of_the_shared_data_folder_is_keyed_by_its_content(tmp_path, monkeypatch):
    monkeypatch.setattr("magexp.core.datafiles.SHARED_DATA", tmp_path)
    for name in ("rec.txt", "pair_mag.csv", "pair_imu.csv"):
        (tmp_path / name).write_text("1 2 3\n4 5 6\n")
    runs = {name: reading({"seed": 0}, Path(name)) for name in ("rec.txt", "pair", "pair_mag.csv")}  # as the
    before = keys_of(runs)                            # real_* scenarios name theirs: a file, a two-stream stem
    (tmp_path / "rec.txt").write_text("1 2 3\n4 5 60\n")
    assert changed(before, after := keys_of(runs)) == {"rec.txt"}
    (tmp_path / "pair_imu.csv").write_text("1 2 3\n4 5 60\n")
    assert changed(after, keys_of(runs)) == {"pair", "pair_mag.csv"}  # a two-stream recording is its two files


def test_only_a_regular_file_of_plausible_size_is_read(tmp_path):
    """A FIFO in the cache is not opened for a blocking read (the sweep would hang) and a huge entry is
    refused by its size, unread (issue 34): each in well under a second."""
    import time

    fifo, huge = tmp_path / "fifo.mxc", tmp_path / "huge.mxc"
    os.mkfifo(fifo)
    with open(huge, "wb") as fh:  # sparse: 3 GiB that take no disk
        fh.truncate(3 * 2 ** 30)
    for path, words in ((fifo, "not a regular file"), (huge, "more than an entry holds")):
        start = time.perf_counter()
        with pytest.raises(cache.InvalidEntry, match=words):
            cache.read(path, "k" * 64, "RunOutput")
        assert time.perf_counter() - start < 1
