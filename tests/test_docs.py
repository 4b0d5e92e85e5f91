"""The documentation: the site builds strictly, the README stays short and its links resolve, every
page is in the nav, and the contracts the docs state match what magexp writes."""

from __future__ import annotations

import csv
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

pytest.importorskip("mkdocs", reason="mkdocs is not installed (pip install -e '.[docs]')")

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
README = ROOT / "README.md"
#: the README a newcomer reads in five minutes (issue 20)
README_MAX_BYTES = 12 * 1024
#: pages that record history: the files they name may be gone
HISTORY = {"measurements.md"}
#: a Markdown link or image target: [text](target)
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
#: a repository path in a code span, e.g. `magexp/executor.py` or `conf/calibrate.yaml`
REPO_PATH = re.compile(r"`((?:magexp|conf|experiments|data|tests|hydra_plugins)/[\w./-]+\.(?:py|yaml|csv))`")


def build(config: Path, site: Path) -> subprocess.CompletedProcess:
    """``mkdocs build --strict`` of ``config`` into ``site``, as ``make docs`` runs it."""
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file", str(config),
                           "--site-dir", str(site)], cwd=config.parent, capture_output=True, text=True,
                          env={**os.environ, "NO_MKDOCS_2_WARNING": "1"}, timeout=120)


def nav_pages(nav) -> list[str]:
    """Every page file named in an mkdocs ``nav`` (nested lists of ``{title: page | [..]}``)."""
    if isinstance(nav, str):
        return [nav]
    if isinstance(nav, list):
        return [page for item in nav for page in nav_pages(item)]
    return [page for value in nav.values() for page in nav_pages(value)]


def config() -> dict:
    return yaml.safe_load((ROOT / "mkdocs.yml").read_text())


def test_site_builds_strictly(tmp_path):
    site = tmp_path / "site"
    done = build(ROOT / "mkdocs.yml", site)
    assert done.returncode == 0, done.stderr[-2000:]
    for page in nav_pages(config()["nav"]):
        html = site / Path(page).with_suffix("") / "index.html" if page != "index.md" else site / "index.html"
        assert html.is_file(), f"{page} was not built"


@pytest.mark.full  # a second whole build; make test: the strict build itself
def test_strict_build_fails_on_a_broken_link(tmp_path):
    """The strict build is a check: a link to a missing heading fails it (mkdocs.yml's validation)."""
    shutil.copytree(DOCS, tmp_path / "docs")
    shutil.copy(ROOT / "mkdocs.yml", tmp_path / "mkdocs.yml")
    (tmp_path / "magexp").symlink_to(ROOT / "magexp")  # mkdocs.yml's hook (the results pages) beside it
    page = tmp_path / "docs" / "index.md"
    page.write_text(page.read_text() + "\n[broken](results.md#no-such-heading)\n")
    done = build(tmp_path / "mkdocs.yml", tmp_path / "site")
    assert done.returncode != 0 and "no-such-heading" in done.stderr


def test_every_page_is_in_the_nav():
    pages = {p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md")}
    listed = nav_pages(config()["nav"])
    assert sorted(pages) == sorted(listed), "docs/ pages and mkdocs.yml's nav differ"


def test_readme_is_short():
    size = len(README.read_bytes())
    assert size <= README_MAX_BYTES, f"README.md is {size} bytes, over {README_MAX_BYTES}: move the detail into docs/"


def test_readme_links_resolve():
    targets = [t for t in LINK.findall(README.read_text()) if not re.match(r"[a-z]+:", t)]
    assert targets, "the README links nowhere"
    missing = [t for t in targets if not (ROOT / t.split("#")[0]).exists()]
    assert not missing, f"README.md links to missing files: {missing}"
    docs_linked = {t.split("#")[0] for t in targets if t.startswith("docs/")}
    assert docs_linked, "the README links to no docs page"


@pytest.mark.parametrize("doc", [README, *sorted(DOCS.rglob("*.md"))], ids=lambda p: p.relative_to(ROOT).as_posix())
def test_named_files_exist(doc):
    """A file the docs name by its path exists (a moved module takes its docs along)."""
    if doc.name in HISTORY:
        pytest.skip(f"{doc.name} records history")
    missing = [p for p in REPO_PATH.findall(doc.read_text()) if not (ROOT / p).exists()]
    assert not missing, f"{doc.relative_to(ROOT)} names files that do not exist: {missing}"


@pytest.mark.parametrize("name, page", [("summary.csv", "results.md"), ("claims.csv", "results.md")])
def test_documented_columns_are_the_written_ones(name, page):
    """The column list the docs give for a results table is the header magexp writes."""
    with (ROOT / "results" / name).open(newline="") as fh:
        header = next(csv.reader(fh))
    text = (DOCS / page).read_text()
    blocks = re.findall(r"```text\n(.*?)```", text, flags=re.S)
    documented = [[c.strip() for c in " ".join(b.split()).split(",")] for b in blocks]
    assert header in documented, f"docs/{page} does not list the columns of results/{name}: {header}"
