"""Results that cannot be clobbered: canonical results/, a cache key that sees data and only upstream
code, timing that says where its runs came from, redraw without runs, one-line refusals."""

import os
import shutil
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from omegaconf import OmegaConf

from magexp.run import cache

from magexp.run import executor

from magexp.artifacts import reproduce
from magexp.artifacts.memo import source_digest

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
    monkeypatch.setattr(reproduce, "plan_with_effects", lambda *a, **k: pytest.fail("planned before checking --out"))
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
    edit_first_reading(data / "yan2022_mockup.csv")  # bz of the first attitude, +50 nT
    again = executor.run_many(mockup + ding, jobs=1, counts=counts)
    assert counts["computed"] == 1 and counts["cached"] == 2  # the mock-up run only
    assert again.metrics(0)["fit_rms"] != first.metrics(0)["fit_rms"]


def test_redraw_rebuilds_figures_summary_and_report_without_a_run(tmp_path, monkeypatch, capsys, mockup_reproduction):
    out = tmp_path / "res"
    shutil.copytree(mockup_reproduction.out, out)
    name = "yan2022_table_mockup"
    png, csv = out / "yan2022" / f"{name}.png", out / "yan2022" / f"{name}.csv"
    png.unlink()
    (out / "REPORT.md").unlink()
    (out / "summary.csv").unlink()
    monkeypatch.setattr(runner, "run_batch", lambda *a: pytest.fail("--redraw ran something"))
    monkeypatch.setattr(executor, "run_many", lambda *a, **k: pytest.fail("--redraw ran something"))
    capsys.readouterr()
    assert reproduce.main(["all", "--only", name, "--redraw", "--out", str(out)]) == 0
    assert "redrew 1 figures" in capsys.readouterr().out
    for path in (png, out / "REPORT.md", out / "summary.csv", csv):  # as the reproduction wrote them
        assert path.read_bytes() == mockup_reproduction.files[path.relative_to(out).as_posix()], path


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
@pytest.mark.full  # a real process; make test: Ctrl-C in-process (tests/test_bad_input.py, exit 130)
def test_ctrl_c_ends_in_one_line_and_a_clean_state(tmp_path):
    out = tmp_path / "res"
    env = {**os.environ, "MAGEXP_CACHE": str(tmp_path / "cache")}
    proc = subprocess.Popen([sys.executable, "-c", CTRL_C, "yan2022", "--only", "yan2022_table_mockup",
                             "--seeds", "2", "--jobs", "2", "--out", str(out)],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 130
    lines = [ln for ln in err.splitlines() if ln.strip() and "Warning" not in ln and not ln.startswith("  ")]
    assert len(lines) == 1 and "interrupted" in lines[0] and "Traceback" not in err, err
    assert not list(tmp_path.rglob("*.tmp")), "a half-written file was left behind"
    assert not (out / "yan2022" / "yan2022_table_mockup.csv").exists()


@pytest.mark.slow
def test_an_unchanged_figure_is_kept_and_any_change_draws_it(tmp_path, monkeypatch, capsys, mockup_reproduction):
    """The figure cache (beside the run cache): a reproduction or a redraw draws a figure only when its
    CSV, spec or code changed, or its files are not what was drawn; ``--force`` draws every figure."""
    from matplotlib.text import Text

    from magexp.artifacts.plots import memo, style

    out = tmp_path / "res"
    shutil.copytree(mockup_reproduction.out, out)
    shutil.copytree(mockup_reproduction.runs, cache.CACHE)  # its runs: the reproduction reads them
    name = "yan2022_table_mockup"
    png, pdf, csv = (out / "yan2022" / f"{name}.{ext}" for ext in ("png", "pdf", "csv"))
    drawn = []
    argv = [*mockup_reproduction.args, "--out", str(out)]
    redraw = ["all", "--only", name, "--redraw", "--out", str(out)]

    # a drawing writes what it drew in a few bytes (the same figure, the same bytes: that saving a figure
    # gives the same bytes is test_figures.py's, that a redraw gives the reproduction's bytes
    # test_redraw_rebuilds_figures_summary_and_report_without_a_run's; here, only when the cache draws)
    def save(fig, path):
        drawn.append(path)
        text = "\n".join(t.get_text() for t in fig.findobj(Text)).encode()  # its words
        style.plt.close(fig)
        for twin in (path, path.with_suffix(".pdf")):
            twin.write_bytes(text)
        return [path, path.with_suffix(".pdf")]

    monkeypatch.setattr(style, "save", save)
    assert reproduce.main(argv) == 0 and len(drawn) == 1  # this figure cache is empty: drawn
    assert "0 computed, 6 from the cache" in capsys.readouterr().out
    first = png.read_bytes(), pdf.read_bytes()
    assert first[0] != mockup_reproduction.files[f"yan2022/{name}.png"]  # what this drawing wrote
    assert memo.root() == tmp_path / "cache-figures" and any(memo.root().rglob("*.memo"))  # beside the run cache
    assert reproduce.main(redraw) == 0 and len(drawn) == 1  # unchanged: kept
    assert "redrew 0 figures (1 unchanged" in capsys.readouterr().out
    assert reproduce.main(argv) == 0 and len(drawn) == 1  # a cached reproduction keeps it too
    assert (png.read_bytes(), pdf.read_bytes()) == first

    pdf.write_bytes(b"%PDF edited")  # a figure file that is not what was drawn: drawn again
    assert reproduce.main(redraw) == 0 and len(drawn) == 2
    again = png.read_bytes()
    assert pdf.read_bytes() == again
    assert reproduce.main(redraw) == 0 and len(drawn) == 2  # what was drawn is kept
    assert reproduce.main(redraw + ["--force"]) == 0 and len(drawn) == 3  # --force draws every figure
    assert png.read_bytes() == again

    frame = pd.read_csv(csv)  # a new CSV: drawn again from it
    frame.loc[frame.quantity == "fit_rms", "median"] *= 3
    frame.to_csv(csv, index=False)
    assert reproduce.main(redraw) == 0 and len(drawn) == 4


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
    source_digest.cache_clear()
    copy = tmp_path / "pkg"
    shutil.copytree(ROOT / "magexp", copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr("magexp.paths.PACKAGE", copy)
    try:
        assert memo.key(spec, b"a,b\n1,2\n") == k
        memo.figure_code_version.cache_clear()
        source_digest.cache_clear()
        with (copy / "artifacts" / "plots" / "style.py").open("a") as fh:
            fh.write("\n# a style edit\n")
        assert memo.key(spec, b"a,b\n1,2\n") != k
    finally:
        memo.figure_code_version.cache_clear()
        source_digest.cache_clear()


#: t(0.975, 8): the two-sided 95 % quantile of Student's t with 8 degrees of freedom (printed tables: 2.306)
T_975_8 = 2.3060041350333704


def edit_first_reading(path, delta=50):
    """Add ``delta`` nT to bz of the first reading of a recording file."""
    lines = path.read_text().splitlines(keepends=True)
    row = next(i for i, ln in enumerate(lines) if ln.strip() and not ln.startswith("#") and ln[0] in "-0123456789")
    values = lines[row].split(",")
    values[2] = str(int(values[2]) + delta)
    lines[row] = ",".join(values)
    path.write_text("".join(lines))


def test_mockup_summary_is_the_least_squares_t_interval_and_f_test_from_the_stored_runs(tmp_path, monkeypatch, make_cfg):
    """The mock-up's rows judged against least squares: ``lo``, ``hi`` are the estimate -+ t(0.975, 8)
    standard errors (per axis, 12 readings, 4 parameters), the F-test rows give the p-value of the
    paper's solution; the summary reads the design each run stored (its readings are not stored) and
    simulates nothing: a data file edited afterwards changes nothing of it."""
    from scipy import stats

    from magexp.artifacts import summary
    from magexp.artifacts.plan import collect, plan_artifact
    from magexp.artifacts.spec import load
    from magexp.problems import make_problem
    from magexp.run.executor import run_many
    from magexp.scenarios.ship import ShipRecording

    data = tmp_path / "data"
    data.mkdir()
    shutil.copy(DATA / "yan2022_mockup.csv", data / "yan2022_mockup.csv")
    monkeypatch.setattr("magexp.core.datafiles.DATA", data)
    monkeypatch.setattr("magexp.core.recordings.DATA", data)
    spec = load(ROOT / "experiments" / "yan2022" / "yan2022_table_mockup.yaml")
    plan = plan_artifact(spec, seeds=1, tiny=True)
    runs = collect(plan, run_many(plan.configs, jobs=1))
    built = []
    real = ShipRecording.generate
    monkeypatch.setattr(ShipRecording, "generate", lambda self, **k: built.append(1) or real(self, **k))
    rows = summary.summarise(runs)
    assert built == []  # nothing simulated again: every fact comes from the stored runs
    design = runs.outputs[(0, 0)].design
    assert sorted(design) == ["coef", "gram", "n", "rss"] and design["n"] == 12
    assert max(np.size(v) for v in design.values()) == 16  # C^T C, not the 12 x 4 design or the readings

    scenario = runner.build(make_cfg("scenario=yan2022_mockup").scenario, "scenario")
    c, y = (np.asarray(a, float) for a in make_problem("ship", scenario.generate(), scenario.search).design())
    coef = np.linalg.solve(c.T @ c, c.T @ y)  # (4, 3): per axis [K_a1, K_a2, K_a3, Bp_a]
    s2 = ((y - c @ coef) ** 2).sum(axis=0) / (12 - 4)
    se = np.sqrt(np.outer(np.diag(np.linalg.inv(c.T @ c)), s2))
    kf = rows[rows.estimator == "kf"].set_index("quantity")
    for a in range(3):
        for name, j in [*((f"K{a + 1}{k + 1}", k) for k in range(3)), (f"Bp{a + 1}", 3)]:
            lo, hi = coef[j, a] - T_975_8 * se[j, a], coef[j, a] + T_975_8 * se[j, a]
            assert kf.loc[name, "lo"] == pytest.approx(lo, rel=1e-9, abs=1e-9), name
            assert kf.loc[name, "hi"] == pytest.approx(hi, rel=1e-9, abs=1e-9), name
    ci = next(i for i, cell in enumerate(runs.cells) if cell["estimator"] == "yan2022_paper_mockup")
    theta = runs.outputs[(ci, 0)].x
    k, bp = np.asarray(theta[:9]).reshape(3, 3), np.asarray(theta[9:])
    ftest = rows[rows.quantity.str.startswith("paper_solution_F_p")].set_index("quantity")
    assert len(ftest) == 3
    for a in range(3):
        d = np.append(k[a], bp[a]) - coef[:, a]
        f = d @ c.T @ c @ d / 4 / s2[a]
        row = ftest.loc[f"paper_solution_F_p_axis{a + 1}"]
        assert f"F={f:.4g};dof=4,8" in row.setting
        assert row.value == pytest.approx(stats.f.sf(f, 4, 8), rel=1e-6)
    assert stats.f.sf(3.838, 4, 8) == pytest.approx(0.05, abs=2e-4)  # the table's 5 % point: the p-value's scale

    edit_first_reading(data / "yan2022_mockup.csv")  # the runs' data: read by a run, never by the summary
    pd.testing.assert_frame_equal(rows, summary.summarise(runs), check_exact=True)
