"""Which papers ``magexp verify`` compares (issue 44, item 7): ``--paper NAME`` (repeatable) scopes it to those
papers, and a paper on one side only is named, not compared file by file.

A paper of a results folder is a top-level folder of it (``results/<paper>/``) that no rule of what differs by
design covers (``timing/``, ``peers/``). A paper the reproduction has and the committed results lack is
*added*: reported as added, never a disagreement (``magexp reproduce`` of a new paper into a copy of
``results/``). One the committed results have and the reproduction lacks is *missing*: named, and the
reproduction does not agree (give ``--paper`` to check only the papers reproduced). Whenever the papers
compared are not all of both sides' (:attr:`Scope.partial`), the files every paper writes into
(:data:`SHARED`) are compared only in those papers' rows (``summary.csv``, ``claims.csv``: their ``paper``
column) and sections (``REPORT.md``, ``APPENDIX.md``: the section headed by the paper's title; the openings
and the other sections count or show every paper and are left out, and listed).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from magexp.artifacts.paper_spec import load_paper
from magexp.errors import MagexpError

#: the files of a results folder that hold every paper's rows or sections
SHARED = ("summary.csv", "claims.csv", "REPORT.md", "APPENDIX.md")
#: the report files, split into sections at their ``## `` headings
REPORTS = ("REPORT.md", "APPENDIX.md")
#: the anchor :mod:`magexp.artifacts.report` writes before a paper's appendix section
_ANCHOR = re.compile(r'^<a id="([\w.-]+)"></a>$')


@dataclass
class Scope:
    """The papers compared, and those on one side only (``added``: the reproduction's; ``missing``: the
    committed results')."""

    compared: set = field(default_factory=set)
    added: list = field(default_factory=list)
    missing: list = field(default_factory=list)
    scoped: bool = False

    @property
    def partial(self) -> bool:
        """Whether the papers compared are not every paper of both sides (shared files: their rows only)."""
        return self.scoped or bool(self.added or self.missing)

    def keeps(self, rel: str, papers: set) -> bool:
        """Whether the file ``rel`` is compared: a paper's file if the paper is, a shared file always, any
        other file (of no paper) unless ``--paper`` scoped the comparison."""
        top = rel.split("/", 1)[0]
        if top in papers and "/" in rel:
            return top in self.compared
        return rel in SHARED or not self.scoped


def paper_folders(files: set, others=()) -> set:
    """The top-level folders of ``files`` (relative paths) but ``others`` (the folders of no paper:
    ``peers``, ``timing``)."""
    return {f.split("/", 1)[0] for f in files if "/" in f} - set(others)


def papers_of(root: Path, files: set, others=()) -> set:
    """The papers of the results folder ``root``: its :func:`paper_folders` and the papers its ``summary.csv``
    has rows of."""
    path = root / "summary.csv"
    rows = set(pd.read_csv(path, usecols=["paper"], dtype=str).paper.dropna()) if "summary.csv" in files else set()
    return paper_folders(files, others) | rows


def paper_scope(ours: set, committed: set, papers: list | None) -> Scope:
    """The :class:`Scope` of a comparison of the reproduction's papers ``ours`` with the committed ``committed``
    (:func:`papers_of`); ``papers``: ``--paper`` (None: every paper). A paper named that neither side has is
    one line (:class:`~magexp.errors.MagexpError`)."""
    present = ours | committed
    unknown = [p for p in papers or [] if p not in present]
    if unknown:
        raise MagexpError(f"--paper {unknown[0]!r} is not allowed: neither results folder has it (they have: "
                          f"{', '.join(sorted(present)) or 'no paper'})")
    wanted = set(papers) if papers else present
    return Scope(compared=wanted & ours & committed, added=sorted(wanted & (ours - committed)),
                 missing=sorted(wanted & (committed - ours)), scoped=bool(papers))


def paper_rows(frame: pd.DataFrame, scope: Scope) -> pd.DataFrame:
    """The rows of a shared CSV of the papers compared (all of them when the scope is not partial)."""
    if not scope.partial or "paper" not in frame.columns:
        return frame
    return frame[frame["paper"].isin(scope.compared)].reset_index(drop=True)


def _titles(folders: list[Path]) -> dict:
    """``{paper: "## title"}``: each anchored section heading of the ``APPENDIX.md`` of ``folders``."""
    out = {}
    for folder in folders:
        path = folder / "APPENDIX.md"
        lines = path.read_text(encoding="utf-8").splitlines() if path.is_file() else []
        for i, line in enumerate(lines):
            m = _ANCHOR.match(line)
            heading = next((x for x in lines[i + 1:i + 3] if x.startswith("## ")), None)
            if m and heading:
                out.setdefault(m.group(1), heading)
    return out


def report_cut(scope: Scope, folders: list[Path]) -> list[str]:
    """The ``## `` headings of the report files of ``folders`` whose sections are left out: every one but the
    papers' compared (their titles from the appendix's anchors, else from their ``paper.yaml``)."""
    titles = _titles(folders)
    keep = {titles.get(p) or f"## {load_paper(p).title}" for p in scope.compared}
    headings = {line for folder in folders for name in REPORTS if (folder / name).is_file()
                for line in (folder / name).read_text(encoding="utf-8").splitlines() if line.startswith("## ")}
    return sorted(headings - keep)
