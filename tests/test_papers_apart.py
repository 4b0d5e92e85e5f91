"""Papers do not touch each other (issue 44, item 7): a number is written in one form whatever the other
papers' rows beside it, redrawing one paper leaves every other paper's bytes as they were, and ``magexp
verify`` can be scoped to papers (``--paper``) and names a paper on one side only as added or missing."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from magexp.artifacts import reproduce
from magexp.artifacts.compare import compare
from magexp.artifacts.formats import write_csv
from magexp.artifacts.verify import render
from magexp.paths import RESULTS

#: the committed files both sides of a verify test start from
FILES = ("summary.csv", "claims.csv", "REPORT.md", "APPENDIX.md", "yuan2018/yuan2018_table3.csv",
         "yan2022/yan2022_fig_noise.csv")
#: the paper added on one side, and the title its report sections are headed by
ADDED, ADDED_TITLE = "yan2022", "## Yan & Zhou"


def test_a_float_is_written_in_one_form_whatever_the_other_rows(tmp_path):
    """Paper a's rows written alone and beside paper b's (integers and text in the same columns, and an empty
    part that makes every column of the concatenation ``object``): the same lines, the same values to full
    precision. Before issue 44 the second wrote ``1.0`` and an unrounded ``0.123456789``."""
    a = pd.DataFrame({"paper": ["a", "a"], "v": [1.0, 0.123456789], "n": [30, 31], "t": [np.nan, 2.5]})
    b = pd.DataFrame({"paper": ["b", "b"], "v": [2, 7], "n": [np.nan, 4], "t": ["text", "more"]})
    empty = pd.DataFrame({c: [] for c in a.columns}, dtype=object)
    write_csv(a, tmp_path / "alone.csv")
    write_csv(pd.concat([empty, a, b], ignore_index=True), tmp_path / "beside.csv")
    alone, beside = (tmp_path / "alone.csv").read_text().splitlines(), (tmp_path / "beside.csv").read_text().splitlines()
    assert beside[:3] == alone == ["paper,v,n,t", "a,1,30,", "a,0.123457,31,2.5"]
    assert beside[3:] == ["b,2,,text", "b,7,4,more"]
    back = pd.read_csv(tmp_path / "beside.csv")
    assert back.v.tolist() == [1.0, 0.123457, 2.0, 7.0] and back.n.iloc[1] == 31


def _sides(tmp_path: Path) -> tuple[Path, Path]:
    """``(ours, committed)``: copies of :data:`FILES`, the committed side without :data:`ADDED` (its folder,
    its rows of the shared CSVs, its report sections): the reproduction added a paper."""
    ours, committed = tmp_path / "ours", tmp_path / "committed"
    for side in (ours, committed):
        for rel in FILES:
            (side / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(RESULTS / rel, side / rel)
    shutil.rmtree(committed / ADDED)
    for name in ("summary.csv", "claims.csv"):
        frame = pd.read_csv(committed / name, dtype=str, keep_default_na=False)
        frame[frame.paper != ADDED].to_csv(committed / name, index=False)
    for name in ("REPORT.md", "APPENDIX.md"):
        parts = re.split(r"(?m)^(?=## )", (committed / name).read_text())
        (committed / name).write_text("".join(p for p in parts if not p.startswith(ADDED_TITLE)))
    return ours, committed


def _edit_first(path: Path, paper: str, column: str = "judged_value") -> None:
    """Change the first number of ``column`` in ``paper``'s rows of a shared CSV by 10 %."""
    frame = pd.read_csv(path, dtype=str, keep_default_na=False)
    row = frame.index[(frame.paper == paper) & (frame[column] != "")][0]
    frame.at[row, column] = f"{float(frame.at[row, column]) * 1.1:.6g}"
    frame.to_csv(path, index=False)


def test_an_added_paper_is_named_as_added_and_a_missing_one_as_missing(tmp_path):
    ours, committed = _sides(tmp_path)
    added = compare(ours, committed)
    assert added.agrees and added.scope.added == [ADDED] and not added.disagreements, [d.line() for d in added.disagreements]
    assert f"papers ADDED (in the reproduction, not in the committed results; not compared): {ADDED}" in render(
        added, "ours", "committed")
    missing = compare(committed, ours)
    assert not missing.agrees and missing.scope.missing == [ADDED] and not missing.disagreements
    assert "papers missing: 1" in render(missing, "ours", "committed")
    # a paper on both sides is still compared: a number of yuan2018 moved is a disagreement
    _edit_first(ours / "summary.csv", "yuan2018")
    assert [d.file for d in compare(ours, committed).disagreements] == ["summary.csv"]


def test_verify_paper_checks_only_that_papers_files_rows_and_sections(tmp_path, cli):
    ours, committed = _sides(tmp_path)
    _edit_first(committed / "summary.csv", "ding2024")
    (committed / "REPORT.md").write_text((committed / "REPORT.md").read_text().replace("**Overall.**", "**All:**"))
    done = cli("verify", "--against", ours, "--committed", committed, "--paper", "yuan2018")
    assert done.returncode == 0, done.stdout
    assert "papers compared (--paper): yuan2018" in done.stdout and "ADDED" not in done.stdout
    assert cli("verify", "--against", ours, "--committed", committed).returncode == 1  # ding2024 and the opening
    _edit_first(committed / "summary.csv", "yuan2018")
    done = cli("verify", "--against", ours, "--committed", committed, "--paper", "yuan2018")
    assert done.returncode == 1 and "summary.csv: row" in done.stdout
    done = cli("verify", "--against", ours, "--committed", committed, "--paper", "nope")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert "--paper 'nope' is not allowed" in done.stderr and "yuan2018" in done.stderr


def _other_papers(root: Path, paper: str) -> dict[str, bytes | list]:
    """What of ``root`` belongs to papers other than ``paper``: their files' bytes, their lines of the shared
    CSVs and their sections of the report files."""
    out: dict = {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*")
                 if p.is_file() and p.relative_to(root).parts[0] not in (paper, "timing")
                 and len(p.relative_to(root).parts) > 1}
    for name in ("summary.csv", "claims.csv"):
        lines = (root / name).read_text().splitlines()
        out[name] = [line for line in lines if not line.startswith(f"{paper},")]
    for name in ("REPORT.md", "APPENDIX.md"):
        parts = re.split(r"(?m)^(?=## )", (root / name).read_text())[1:]
        out[name] = [p for p in parts if not p.startswith(ADDED_TITLE)]
    return out


@pytest.mark.full  # make test: test_a_float_is_written_in_one_form_whatever_the_other_rows (the mechanism)
def test_redrawing_one_paper_leaves_every_other_papers_bytes(tmp_path):
    """``magexp reproduce yan2022 --redraw`` into a copy of the committed results: every file, shared-CSV
    line and report section of the other papers byte-identical to the committed one."""
    copy = tmp_path / "results"
    shutil.copytree(RESULTS, copy)
    assert reproduce.main([ADDED, "--redraw", "--out", str(copy)]) == 0
    before, after = _other_papers(RESULTS, ADDED), _other_papers(copy, ADDED)
    assert sorted(after) == sorted(before)
    assert [name for name in before if after[name] != before[name]] == []
