"""``magexp new-paper NAME`` (issue 44 item 1): the scaffold writes a paper whose spec loads and is checked
whole, refuses an existing folder and a bad name in one line (exit 2, nothing written); its reproduction
is tests/test_extending.py's (full)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from magexp.artifacts import scaffold
from magexp.artifacts.paper_spec import check_headlines, load_paper, papers
from magexp.artifacts.spec import load
from magexp.errors import MagexpError

ROOT = Path(__file__).resolve().parents[1]


def test_the_scaffold_writes_a_paper_that_loads_with_a_claim_of_each_kind(tmp_path):
    written = scaffold.new_paper("demo", tmp_path)
    assert sorted(p.name for p in written) == ["demo_fig1.yaml", "paper.yaml"]
    assert papers(tmp_path) == ["demo"]
    meta = load_paper("demo", tmp_path)
    spec = load(tmp_path / "demo" / "demo_fig1.yaml")
    check_headlines("demo", meta.headline, [spec])  # every headline part names a claim
    assert "EDIT" in meta.title and "experiments/demo/paper.yaml" in meta.title
    assert "docs/extending.md" in meta.intro
    assert [h.figure for h in meta.headline] == ["demo/demo_fig1"] and meta.headline[0].section
    assert {c.kind for c in spec.claims} == {"trend", "threshold", "ordering"}
    assert all(c.effect for c in spec.claims if c.kind == "ordering")  # a comparison's seeds are planned
    assert [(r.statistic, r.trials) for r in spec.reported] == [("median", 1000)]
    assert spec.summarise and spec.paper == "demo" and spec.name == "demo_fig1"
    assert all("EDIT" in c.text for c in spec.claims)  # every placeholder shows in the report


@pytest.mark.parametrize("name", ["Demo", "1paper", "my-paper", "class", "", "demo/x", "../demo"])
def test_a_bad_name_is_refused_and_nothing_written(tmp_path, name):
    with pytest.raises(MagexpError, match="is not allowed: a lowercase identifier"):
        scaffold.new_paper(name, tmp_path)
    assert not any(tmp_path.iterdir())


def test_an_existing_folder_is_never_overwritten(tmp_path):
    (tmp_path / "ding2024").mkdir()
    (tmp_path / "ding2024" / "paper.yaml").write_text("title: mine\n")
    with pytest.raises(MagexpError, match="experiments/ding2024 exists and is never overwritten.*ding2024"):
        scaffold.new_paper("ding2024", tmp_path)
    assert [p.name for p in (tmp_path / "ding2024").iterdir()] == ["paper.yaml"]
    assert (tmp_path / "ding2024" / "paper.yaml").read_text() == "title: mine\n"


def test_the_command_refuses_in_one_line_with_exit_2(tmp_path):
    """Through ``magexp new-paper``: an existing paper and a bad name are one line on stderr, exit code 2, and
    the repository's experiments/ is unchanged."""
    before = sorted(p.name for p in (ROOT / "experiments").iterdir())
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MAGEXP_CACHE": str(tmp_path / "cache")}
    for name, says in (("yan2022", "exists and is never overwritten"), ("Bad-Name", "is not allowed")):
        proc = subprocess.run([sys.executable, "-m", "magexp", "new-paper", name], cwd=tmp_path, env=env,
                              capture_output=True, text=True, timeout=120)
        assert proc.returncode == 2 and says in proc.stderr, proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert sorted(p.name for p in (ROOT / "experiments").iterdir()) == before
