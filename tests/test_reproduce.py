"""Results that cannot be clobbered: canonical results/, a cache key that sees data and only upstream
code, timing that says where its runs came from, redraw without runs, one-line refusals."""

import os
import shutil
import subprocess
import sys

import pandas as pd
import pytest
from omegaconf import OmegaConf

from magexp.run import cache

from magexp.run import executor

from magexp.artifacts import reproduce

from magexp.run import runner
from magexp.run.compose import compose_config
from magexp.paths import DATA, RESULTS, ROOT


def snapshot(folder):
    return {p: p.stat().st_mtime_ns for p in folder.rglob("*")} if folder.exists() else {}


def one_line_error(capsys, argv, *words):
    before = snapshot(RESULTS)
    assert reproduce.main(argv) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    for w in words:
        assert w in lines[0], (w, lines[0])
    assert snapshot(RESULTS) == before


@pytest.mark.parametrize("argv, words", [
    (["ding2024", "--seeds", "3"], ["--seeds", "--out"]),
    (["ding2024", "--only", "ding2024_fig3", "--tiny"], ["--tiny", "--out"]),
    (["ding2024", "--seeds", "2", "--out", str(RESULTS)], ["--seeds"]),
    (["all", "--only", "nothing_like_this", "--out", "{tmp}/x"], ["'nothing_like_this'", "any paper"]),
    (["ding2024", "--seeds", "0", "--out", "{tmp}/x"], ["--seeds 0"]),
    (["ding2024", "--executor", "slurm", "--out", "{tmp}/x"], ["'slurm'"]),
])
def test_refusals_are_one_line_and_write_nothing(capsys, tmp_path, monkeypatch, argv, words):
    monkeypatch.setattr(runner, "run_batch", lambda *a: pytest.fail("a refused command ran something"))
    one_line_error(capsys, [a.replace("{tmp}", str(tmp_path)) for a in argv], *words)
    assert not (tmp_path / "x").exists()


def test_a_file_or_unwritable_out_is_refused_before_any_run(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr(runner, "run_batch", lambda *a: pytest.fail("ran before checking --out"))
    monkeypatch.setattr(reproduce, "plan_artifact", lambda *a, **k: pytest.fail("planned before checking --out"))
    afile = tmp_path / "afile"
    afile.write_text("x")
    one_line_error(capsys, ["ding2024", "--out", str(afile)], "is a file")
    one_line_error(capsys, ["ding2024", "--out", str(afile / "sub")], "is a file")
    if os.geteuid() != 0:  # root writes anywhere
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        one_line_error(capsys, ["ding2024", "--out", str(ro)], "not writable")
    assert afile.read_text() == "x"


def test_only_finds_the_artifact_in_its_paper():
    found = reproduce.select(reproduce.available_papers(), "yan2022_table_mockup")
    assert list(found) == ["yan2022"] and [s.name for s in found["yan2022"]] == ["yan2022_table_mockup"]


def test_timing_says_whether_runs_were_computed_or_cached(tmp_path):
    reproduce.record_timing(tmp_path, "all", 12.0, {"requested": 10, "distinct": 8, "computed": 8, "cached": 0})
    reproduce.record_timing(tmp_path, "ding2024", 1.0, {"requested": 4, "distinct": 4, "computed": 0, "cached": 4})
    reproduce.record_timing(tmp_path, "all", 5.0, {"requested": 10, "distinct": 8, "computed": 3, "cached": 5})
    rows = pd.read_csv(tmp_path / "timing.csv").set_index("target")
    assert rows.loc["all", "source"] == "mixed" and rows.loc["all", "computed"] == 3
    assert rows.loc["ding2024", "source"] == "cached" and len(rows) == 2


def run_configs(*overrides, seeds=(0,)):
    base = OmegaConf.to_container(compose_config(list(overrides)), resolve=True)
    return [{**base, "seed": s} for s in seeds]


def test_a_data_edit_reruns_exactly_the_runs_that_read_it(tmp_path, monkeypatch):
    data = tmp_path / "data"
    data.mkdir()
    shutil.copy(DATA / "yan2022_mockup.csv", data / "yan2022_mockup.csv")
    monkeypatch.setattr("magexp.core.datafiles.DATA", data)  # looked up where recordings are
    monkeypatch.setattr("magexp.core.recordings.DATA", data)
    mockup = run_configs("scenario=yan2022_mockup", "estimator=ls")
    ding = run_configs("scenario=ding2024_exp1", "scenario.n_readings=40", "estimator=ellipsoid", seeds=(0, 1))
    counts = {}
    first = executor.run_many(mockup + ding, jobs=1, counts=counts)
    assert counts["computed"] == 3
    executor.run_many(mockup + ding, jobs=1, counts=counts)
    assert counts["computed"] == 0
    path = data / "yan2022_mockup.csv"
    lines = path.read_text().splitlines(keepends=True)
    row = next(i for i, ln in enumerate(lines) if ln.strip() and not ln.startswith("#") and ln[0] in "-0123456789")
    values = lines[row].split(",")
    values[2] = str(int(values[2]) + 50)  # bz of the first attitude, +50 nT
    lines[row] = ",".join(values)
    path.write_text("".join(lines))
    again = executor.run_many(mockup + ding, jobs=1, counts=counts)
    assert counts["computed"] == 1 and counts["cached"] == 2  # the mock-up run only
    assert again.metrics(0)["fit_rms"] != first.metrics(0)["fit_rms"]


def test_upstream_code_is_the_runs_import_closure():
    files = {p.relative_to(ROOT).as_posix() for p in cache.upstream_files()}
    for needed in ("magexp/run/runner.py", "magexp/core/metrics.py", "magexp/core/bounds.py", "magexp/core/seeding.py",
                   "magexp/problems/scalar.py", "magexp/scenarios/ding.py", "magexp/estimators/swarm.py",
                   "magexp/core/recordings.py", "magexp/__init__.py"):
        assert needed in files, needed
    for downstream in ("magexp/artifacts/reproduce.py", "magexp/artifacts/report.py", "magexp/artifacts/summary.py", "magexp/run/executor.py",
                       "magexp/run/progress.py", "magexp/artifacts/plots/style.py", "magexp/artifacts/plots/convergence.py"):
        assert downstream not in files, downstream


def test_a_plot_edit_reruns_nothing_and_a_bound_edit_reruns_all(tmp_path, monkeypatch):
    copy = tmp_path / "repo"
    shutil.copytree(ROOT / "magexp", copy / "magexp", ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(cache, "ROOT", copy)
    cache.code_version.cache_clear()
    try:
        before = cache.code_version()
        with (copy / "magexp/artifacts/plots/convergence.py").open("a") as fh:
            fh.write("\n# a new label\n")
        with (copy / "magexp/artifacts/report.py").open("a") as fh:
            fh.write("\n# new wording\n")
        cache.code_version.cache_clear()
        assert cache.code_version() == before
        with (copy / "magexp/core/bounds.py").open("a") as fh:
            fh.write("\n# a change upstream of every run\n")
        cache.code_version.cache_clear()
        assert cache.code_version() != before
    finally:
        cache.code_version.cache_clear()


def test_redraw_rebuilds_figures_summary_and_report_without_a_run(tmp_path, monkeypatch, capsys):
    out = tmp_path / "res"
    argv = ["yuan2018", "--only", "yuan2018_fig6", "--seeds", "2", "--tiny", "--jobs", "1", "--out", str(out)]
    assert reproduce.main(argv) == 0
    capsys.readouterr()
    png, csv = out / "yuan2018" / "yuan2018_fig6.png", out / "yuan2018" / "yuan2018_fig6.csv"
    data = csv.read_bytes()
    png.unlink()
    (out / "REPORT.md").unlink()
    (out / "summary.csv").unlink()
    monkeypatch.setattr(runner, "run_batch", lambda *a: pytest.fail("--redraw ran something"))
    monkeypatch.setattr(executor, "run_many", lambda *a, **k: pytest.fail("--redraw ran something"))
    assert reproduce.main(["all", "--only", "yuan2018_fig6", "--redraw", "--out", str(out)]) == 0
    assert png.stat().st_size > 0 and (out / "REPORT.md").exists() and (out / "summary.csv").exists()
    assert csv.read_bytes() == data
    assert "redrew 1 figures" in capsys.readouterr().out


# Ctrl-C at a fixed point: SIGINT to the process as its first run is counted, while its workers are busy
# (Python's own SIGINT handler first: a test run started as a background job inherits SIGINT ignored)
CTRL_C = """
import os, signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)
from magexp.run import progress
from magexp.artifacts.reproduce import main
count = progress.Progress.__call__
def count_then_interrupt(self, n=1):
    count(self, n)
    if self.done >= 1:
        os.kill(os.getpid(), signal.SIGINT)
progress.Progress.__call__ = count_then_interrupt
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.slow
def test_ctrl_c_ends_in_one_line_and_a_clean_state(tmp_path):
    out = tmp_path / "res"
    env = {**os.environ, "MAGEXP_CACHE": str(tmp_path / "cache")}
    proc = subprocess.Popen([sys.executable, "-c", CTRL_C, "ding2024", "--only", "ding2024_table_rms",
                             "--seeds", "3", "--jobs", "2", "--out", str(out)],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 130
    lines = [ln for ln in err.splitlines() if ln.strip() and "Warning" not in ln and not ln.startswith("  ")]
    assert len(lines) == 1 and "interrupted" in lines[0] and "Traceback" not in err, err
    assert not list(tmp_path.rglob("*.tmp")), "a half-written file was left behind"
    assert not (out / "ding2024" / "ding2024_table_rms.csv").exists()


@pytest.mark.slow
def test_an_unchanged_figure_is_kept_and_any_change_draws_it(tmp_path, monkeypatch, capsys):
    from magexp.artifacts.plots import memo, style

    out = tmp_path / "res"
    argv = ["ding2024", "--only", "ding2024_fig2", "--seeds", "2", "--tiny", "--jobs", "1", "--out", str(out)]
    assert reproduce.main(argv) == 0
    png, pdf = out / "ding2024" / "ding2024_fig2.png", out / "ding2024" / "ding2024_fig2.pdf"
    csv = out / "ding2024" / "ding2024_fig2.csv"
    first = png.read_bytes(), pdf.read_bytes()
    assert memo.root() == tmp_path / "cache-figures" and any(memo.root().rglob("*.json"))  # beside the run cache
    drawn = []
    real_save = style.save
    monkeypatch.setattr(style, "save", lambda fig, path: drawn.append(path) or real_save(fig, path))
    redraw = ["all", "--only", "ding2024_fig2", "--redraw", "--out", str(out)]

    assert reproduce.main(redraw) == 0 and drawn == []  # unchanged: kept
    assert "redrew 0 figures (1 unchanged" in capsys.readouterr().out
    assert reproduce.main(argv) == 0 and drawn == []  # a cached reproduction keeps it too

    pdf.write_bytes(b"%PDF edited")  # a figure file that is not what was drawn: drawn again, same bytes
    assert reproduce.main(redraw) == 0 and len(drawn) == 1
    assert (png.read_bytes(), pdf.read_bytes()) == first
    assert reproduce.main(redraw + ["--force"]) == 0 and len(drawn) == 2  # --force draws every figure
    assert (png.read_bytes(), pdf.read_bytes()) == first

    frame = pd.read_csv(csv)  # a new CSV: drawn again from it
    frame.loc[0, "error"] = frame["error"].abs().max() * 3
    frame.to_csv(csv, index=False)
    assert reproduce.main(redraw) == 0 and len(drawn) == 3 and png.read_bytes() != first[0]


def test_figure_key_sees_the_csv_the_spec_and_the_code(tmp_path, monkeypatch):
    from magexp.artifacts.plots import memo
    from magexp.artifacts.spec import load

    spec = load(next(p for p in (ROOT / "experiments" / "ding2024").glob("ding2024_fig2.yaml")))
    other = load(next(p for p in (ROOT / "experiments" / "ding2024").glob("ding2024_fig3.yaml")))
    k = memo.key(spec, b"a,b\n1,2\n")
    assert k == memo.key(spec, b"a,b\n1,2\n")
    assert k != memo.key(spec, b"a,b\n1,3\n") and k != memo.key(other, b"a,b\n1,2\n")
    import matplotlib

    with matplotlib.rc_context({"font.size": 11}):  # e.g. a user's matplotlibrc
        assert memo.key(spec, b"a,b\n1,2\n") != k
    assert memo.key(spec, b"a,b\n1,2\n") == k
    memo.figure_code_version.cache_clear()
    copy = tmp_path / "pkg"
    shutil.copytree(ROOT / "magexp", copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr("magexp.paths.PACKAGE", copy)
    try:
        assert memo.key(spec, b"a,b\n1,2\n") == k
        memo.figure_code_version.cache_clear()
        with (copy / "artifacts" / "plots" / "style.py").open("a") as fh:
            fh.write("\n# a style edit\n")
        assert memo.key(spec, b"a,b\n1,2\n") != k
    finally:
        memo.figure_code_version.cache_clear()


def test_mockup_summary_builds_each_cells_problem_once_with_the_same_rows(tmp_path, monkeypatch):
    from magexp.artifacts import summary
    from magexp.artifacts.plan import collect, plan_artifact
    from magexp.artifacts.spec import load
    from magexp.run.executor import run_many

    spec = load(ROOT / "experiments" / "yan2022" / "yan2022_table_mockup.yaml")
    plan = plan_artifact(spec, seeds=1, tiny=True)
    runs = collect(plan, run_many(plan.configs, jobs=1))
    built = []
    real = summary.rebuild_problem
    monkeypatch.setattr(summary, "rebuild_problem", lambda *a: built.append(a) or real(*a))
    rows = summary.summarise(runs)
    ls_rows = sum(1 for item in spec.summarise if item.interval == "ls") * len(runs.cells)
    assert len(built) == len(runs.cells) < ls_rows  # once per cell, not once per row
    assert summary._design.cache_info().currsize == 0  # emptied when summarise returns

    def rebuilt(runs, ci):  # the old path: the problem rebuilt for every row
        problem = real(tuple(runs.overrides[ci]), int(runs.table[runs.table.cell == ci].seed.min()))
        return (*problem.design(), problem.parameter_names())

    monkeypatch.setattr(summary, "_design_of", rebuilt)
    pd.testing.assert_frame_equal(rows, summary.summarise(runs), check_exact=True)


def test_the_special_functions_are_scipy_stats_quantile_and_tail():
    from scipy import special, stats

    for dof in (2, 8, 11, 40):
        for level in (0.9, 0.95, 0.99):
            assert special.stdtrit(dof, 0.5 + level / 2) == stats.t.ppf(0.5 + level / 2, dof)
        for f in (0.01, 0.7, 3.0, 40.0):
            assert special.fdtrc(4, dof, f) == stats.f.sf(f, 4, dof)
