"""``magexp verify``: a reproduction against the committed results (magexp/artifacts/verify.py).

Small copies of the committed files in ``tmp_path`` (the comparison is given both folders: no git),
each edited in one place; and artifacts reproduced as another processor would (numba kernels
compiled for a generic CPU, the numpy path; numpy's loops without AVX-512 and OpenBLAS's Haswell
kernels) checked against their committed CSVs."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pandas as pd
import pytest
from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__

from magexp.artifacts.formats import SPEED_HEADING
from magexp.artifacts.compare import compare
from magexp.artifacts.tolerances import RTOL, compare_text
from magexp.artifacts.verify import committed_results, render
from magexp.paths import EXPERIMENTS, RESULTS, ROOT

#: the committed files copied into each test's two folders
FILES = ("summary.csv", "claims.csv", "REPORT.md", "yuan2018/yuan2018_table3.csv", "yuan2018/yuan2018_table3.png")


@pytest.fixture
def sides(tmp_path):
    """``(ours, committed)``: two identical small copies of the committed results."""
    for side in ("ours", "committed"):
        for rel in FILES:
            (tmp_path / side / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(RESULTS / rel, tmp_path / side / rel)
    return tmp_path / "ours", tmp_path / "committed"


def edit(path: Path, row: int, column: str, value) -> str:
    """Set one cell of a results CSV (read and written as text); returns the old value."""
    frame = pd.read_csv(path, dtype=str, keep_default_na=False)
    old = frame.at[row, column]
    frame.at[row, column] = str(value)
    frame.to_csv(path, index=False)
    return old


def first_row(path: Path, column: str, value: str) -> int:
    frame = pd.read_csv(path, dtype=str, keep_default_na=False)
    return int(frame.index[frame[column] == value][0])


def verify(cli, ours, committed, *more):
    return cli("verify", "--against", ours, "--committed", committed, *more)


def test_identical_folders_agree(cli, sides):
    done = verify(cli, *sides)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "AGREES" in done.stdout and "0 changed" in done.stdout
    assert "every number identical" in done.stdout
    result = compare(*sides)
    assert result.agrees and not result.below and result.csv_files == 3 and result.figures == 1
    assert result.verdicts["summary rows"] == len(pd.read_csv(RESULTS / "summary.csv"))


def test_a_changed_verdict_is_named(cli, sides):
    ours, committed = sides
    row = first_row(ours / "summary.csv", "verdict", "reproduced")
    edit(ours / "summary.csv", row, "verdict", "differs")
    done = verify(cli, ours, committed)
    assert done.returncode == 1
    assert "DISAGREES: 1 verdicts changed" in done.stdout
    assert f"summary.csv: row {row + 1} (" in done.stdout
    assert "column verdict: ours 'differs', committed 'reproduced'" in done.stdout


def test_a_claim_result_changed_is_a_verdict_changed(sides):
    ours, committed = sides
    row = first_row(ours / "claims.csv", "verdict", "holds")
    edit(ours / "claims.csv", row, "verdict", "does not hold")
    result = compare(ours, committed)
    assert [(d.file, d.column, d.ours) for d in result.changed] == [("claims.csv", "verdict", "does not hold")]


def test_a_number_beyond_the_tolerance_is_named(cli, sides):
    ours, committed = sides
    frame = pd.read_csv(committed / "summary.csv")
    row = int(frame.index[frame.value.abs() > 1][0])
    new = f"{frame.value[row] * (1 + 3 * RTOL):.6g}"
    edit(ours / "summary.csv", row, "value", new)
    done = verify(cli, ours, committed)
    assert done.returncode == 1
    assert "0 verdicts changed, 1 other disagreements" in done.stdout
    assert f"summary.csv: row {row + 1} (artifact={frame.artifact[row]}" in done.stdout
    assert f"column value: ours '{new}', committed '{frame.value[row]:.6g}' (relative 0.003)" in done.stdout


def test_a_number_below_the_tolerance_agrees_and_is_counted(cli, sides):
    ours, committed = sides
    frame = pd.read_csv(committed / "summary.csv")
    row = int(frame.index[frame.value.abs() > 1][0])
    new = f"{frame.value[row] * (1 + RTOL / 5):.6g}"
    assert new != f"{frame.value[row]:.6g}"
    edit(ours / "summary.csv", row, "value", new)
    done = verify(cli, ours, committed)
    assert done.returncode == 0, done.stdout
    assert "within the tolerance" in done.stdout and "1 values in 1 files differ" in done.stdout
    assert f"the largest: summary.csv: row {row + 1}" in done.stdout and "column value" in done.stdout


def test_one_unit_of_the_printed_digit_is_within_the_tolerance(sides):
    """A small number whose last printed digit moves by one is within the tolerance, however large
    that unit is relative to it; two units beyond the relative tolerance are not."""
    ours, committed = sides
    path = ours / "yuan2018/yuan2018_table3.csv"
    frame = pd.read_csv(path, dtype=str)
    row = int(frame.index[frame["median"].str.fullmatch(r"-?\d\.\d{5}")][0])  # six digits printed
    old = float(frame.at[row, "median"])
    edit(path, row, "median", f"{old + 1e-5:.5f}")
    assert compare(ours, committed, rtol=0).agrees
    edit(path, row, "median", f"{old + 2e-5:.5f}")
    assert not compare(ours, committed, rtol=0).agrees


def test_a_missing_or_extra_file_disagrees(cli, sides):
    ours, committed = sides
    (ours / "yuan2018/yuan2018_table3.png").unlink()
    (ours / "extra.csv").write_text("a\n1\n")
    done = verify(cli, ours, committed)
    assert done.returncode == 1
    assert "yuan2018/yuan2018_table3.png: ours '(missing)'" in done.stdout
    assert "extra.csv: ours '(a file)', committed '(not committed)'" in done.stdout


def test_report_words_are_identical_and_its_numbers_within_the_tolerance(sides):
    ours, committed = sides
    text = (committed / "REPORT.md").read_text()
    assert "**Overall.**" in text
    (ours / "REPORT.md").write_text(text.replace("**Overall.**", "**Overall:**", 1))
    result = compare(ours, committed)
    assert [d.file for d in result.disagreements] == ["REPORT.md"]
    assert compare_text("paper 1.5 inside our runs (0.3012 to 0.5123)", "paper 1.501 inside our runs (0.3012 to 0.5123)",
                        RTOL)[0]  # one unit of the finer printing: a rounding of the 4th digit
    assert not compare_text("IPSO final RMS, exp1", "IPSO final RMS, exp2", RTOL)[0]  # a word, not a number
    assert not compare_text("median 0.3012", "median 0.3020", RTOL)[0]  # 2.6e-3 relative, 8 units


def test_what_differs_by_design_is_left_out_and_listed(sides):
    ours, committed = sides
    (ours / "timing.csv").write_text("target,seconds\nall,1\n")
    (committed / "timing.csv").write_text("target,seconds\nall,2\n")
    (committed / "peers").mkdir()
    (committed / "peers" / "peers.csv").write_text("a\n1\n")
    for side, bench in ((ours, "1"), (committed, "2")):
        (side / "APPENDIX.md").write_text(f"# appendix\n\n## A\n\nsame\n\n{SPEED_HEADING} (`make bench`)\n\n| {bench} |\n")
    result = compare(ours, committed)
    assert result.agrees, [d.line() for d in result.disagreements]
    listed = "; ".join(result.excluded)
    assert "timing.csv" in listed and "peers/: on one side only" in listed and "Speed of the core" in listed


def test_path_diagnostics_are_compared_through_the_verdicts(tmp_path):
    """A minimiser's iteration count (a CSV column or a table's column) may differ: counted and shown, not
    a disagreement; a path diagnostic on one side only, or any other column beyond the tolerance, is one."""
    ours, committed = tmp_path / "ours", tmp_path / "committed"
    table = ("\\begin{tabular}{lll}\n\\toprule\nestimator & fun & nfev\\_to\\_1.1 \\\\\n\\midrule\n"
             "lm & {fun} & {nfev} \\\\\n\\bottomrule\n\\end{tabular}\n")
    for side, nit, nfev, fun in ((ours, "39", "1849", "16.92"), (committed, "52", "1986", "16.92")):
        side.mkdir()
        (side / "a_runs.csv").write_text(f"estimator,seed,fun,nit,nfev_to_1.1\nlm,0,{fun},{nit},{nfev}\nlm,1,1.5,40,7\n")
        (side / "a.tex").write_text(table.replace("{fun}", fun).replace("{nfev}", nfev))
    result = compare(ours, committed)
    assert result.agrees, [d.line() for d in result.disagreements]
    assert result.paths == {"a_runs.csv": 2, "a.tex": 1} and result.path_largest.column == "nit"
    assert "path diagnostics (nit, nfev," in render(result, "ours", "committed")
    (ours / "a_runs.csv").write_text("estimator,seed,fun,nit,nfev_to_1.1\nlm,0,16.95,39,\nlm,1,1.5,40,7\n")
    (ours / "a.tex").write_text(table.replace("{fun}", "16.95").replace("{nfev}", "1849"))
    wrong = {(d.file, d.column) for d in compare(ours, committed).disagreements}
    assert wrong == {("a_runs.csv", "fun"), ("a_runs.csv", "nfev_to_1.1"), ("a.tex", "fun")}


def test_bad_input_is_one_line_and_exit_2(cli, sides, tmp_path, monkeypatch):
    done = verify(cli, tmp_path / "nowhere", sides[1])
    assert done.returncode == 2 and "--against" in done.stderr and len(done.stderr.splitlines()) == 1
    done = verify(cli, *sides, "--rtol", "-1")
    assert done.returncode == 2 and "--rtol -1" in done.stderr
    monkeypatch.setenv("PATH", str(tmp_path))  # no git
    done = cli("verify", "--against", sides[0])
    assert done.returncode == 2 and "git is not installed" in done.stderr and not done.stdout


#: the artifact reproduced as another processor: the smallest whose runs are compiled swarm runs
#: (RDPSO's block of iterations and the vector cost in one numba call; 10 runs of 80 080 evaluations)
PAPER, ARTIFACT = "yuan2018", "yuan2018_fig2"
PROCESSORS = {"kernels compiled for a generic CPU": {"NUMBA_CPU_NAME": "generic"},
              "the numpy path": {"MAGEXP_NUMBA": "0"}}


def _reproduce_elsewhere(tmp_path: Path, name: str, env: dict, paper: str = PAPER, artifact: str = ARTIFACT,
                         runs: int = 10, numba: bool = True) -> Path:
    """``python -m magexp reproduce PAPER --only ARTIFACT`` in a fresh process, with its own empty run
    cache and (``numba``) numba cache, under ``env``; returns its output folder."""
    out, folder = tmp_path / name / "out", tmp_path / name
    fresh = {"NUMBA_CACHE_DIR": str(folder / "numba")} if numba else {}
    environment = {**os.environ, "MAGEXP_CACHE": str(folder / "runs"), **fresh, **env}
    done = subprocess.run([sys.executable, "-m", "magexp", "reproduce", paper, "--only", artifact, "--out", str(out),
                           "--jobs", "1"], env=environment, cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert f"{runs} computed, 0 from the cache" in done.stdout
    return out


def _committed(tmp_path: Path, paper: str, artifact: str) -> tuple[Path, list[str]]:
    """The committed CSVs and figures of ``artifact`` (read from git) in ``tmp_path/committed``, and their
    paths relative to ``results/``; skips where there is no git."""
    files = [f"{paper}/{artifact}{suffix}" for suffix in (".csv", "_runs.csv", ".png", ".pdf")]
    try:
        committed_results(tmp_path / "committed", [f"results/{f}" for f in files])
    except ValueError as exc:  # no git here: the committed files are those of the checkout
        pytest.skip(str(exc))
    return tmp_path / "committed" / "results", files


@pytest.mark.slow
@pytest.mark.full  # make test: the comparison itself, by the cheap cases above
def test_another_processor_agrees_with_the_committed_artifact(tmp_path):
    """One artifact reproduced twice from nothing, as on another processor (numba compiled for a
    generic CPU; numpy instead of numba), agrees with its committed CSVs (read from git) within the
    tolerance: the two reproductions run side by side (9.3 s of CPU in all, two processes)."""
    committed, files = _committed(tmp_path, PAPER, ARTIFACT)
    with ThreadPoolExecutor(len(PROCESSORS)) as pool:
        outs = dict(zip(PROCESSORS, pool.map(lambda item: _reproduce_elsewhere(tmp_path, f"p{item[0]}", item[1][1]),
                                             enumerate(PROCESSORS.items()))))
    for name, out in outs.items():
        result = compare(out, committed, files=files)
        assert result.agrees, f"{name}: " + "; ".join(d.line() for d in result.disagreements[:5])
        assert result.csv_files == 2 and result.figures == 2 and result.rows == 40


#: numpy's SIMD loops above AVX2 (``log``, ``exp``, ``power`` give other last bits without them) and
#: OpenBLAS's Haswell kernels instead of this CPU's: another processor's numpy and BLAS on this one
AVX512_TARGETS = [t for t in __cpu_dispatch__ if t == "X86_V4" or t.startswith("AVX512")]
OTHER_KERNELS = {"NPY_DISABLE_CPU_FEATURES": " ".join(AVX512_TARGETS), "OPENBLAS_CORETYPE": "Haswell"}


@pytest.mark.slow
@pytest.mark.full
@pytest.mark.parametrize("spec", [EXPERIMENTS / "real" / "real_modes.yaml"], ids=["real_modes"])
def test_another_processors_numpy_and_blas_kernels_agree_on_lm(tmp_path, spec):
    """``real_modes`` (five lm fits on recordings) reproduced with numpy's AVX-512 loops disabled and
    OpenBLAS's Haswell kernels (where this CPU has AVX-512 and AVX2; skipped elsewhere, and without the
    recording) agrees with its committed CSVs: lm's fits within the tolerance, its evaluation counts
    (``nit``, ``nfev``: other round-off meets its stopping test at another iteration) as path
    diagnostics (6.2 s of CPU, one process)."""
    if not (AVX512_TARGETS and __cpu_features__.get("AVX2") and
            any(__cpu_features__.get(t) for t in ("X86_V4", "AVX512F"))):
        pytest.skip("this CPU has no AVX-512 loops to turn off, or no AVX2 for OpenBLAS's Haswell kernels")
    committed, files = _committed(tmp_path, spec.parent.name, spec.stem)
    # numba's kernels are this CPU's (compiled for a generic one in the test above): its cache is reused
    out = _reproduce_elsewhere(tmp_path, "other", OTHER_KERNELS, spec.parent.name, spec.stem, runs=5, numba=False)
    result = compare(out, committed, files=files)
    assert result.agrees, "; ".join(d.line() for d in result.disagreements[:5])
    assert result.csv_files == 2 and result.figures == 2


def test_which_reproduction_is_checked(cli, sides, monkeypatch):
    """Without --against: results/ when it differs from the committed one, else a reproduction into
    the scratch folder (here a stand-in that returns a copy with one verdict changed)."""
    ours, committed = sides
    monkeypatch.setattr("magexp.artifacts.verify.changed_results", lambda: True)
    monkeypatch.setattr("magexp.paths.RESULTS", ours)
    done = cli("verify", "--committed", committed)
    assert done.returncode == 0 and "verify: results/ (the working tree" in done.stdout
    edit(ours / "summary.csv", first_row(ours / "summary.csv", "verdict", "reproduced"), "verdict", "differs")
    monkeypatch.setattr("magexp.artifacts.verify.changed_results", lambda: False)
    monkeypatch.setattr("magexp.artifacts.verify.reproduce_scratch", lambda jobs, out, only=None: ours)
    done = cli("verify", "--committed", committed)
    assert done.returncode == 1 and "reproducing every paper into" in done.stdout
    assert "(reproduced now: results/ is the committed one)" in done.stdout and "1 verdicts changed" in done.stdout
