"""Two results folders compared as ``magexp verify`` holds a reproduction to the published one (:func:`compare`).

On another machine (another CPU, numba kernels compiled for another target, the numpy path
``MAGEXP_NUMBA=0``) a reproduction differs from the committed ``results/`` in the last printed digits
of some numbers and in the pixels of its figures; it should not differ in a verdict. So:

* every verdict identical: the ``verdict`` column of every CSV (each summary row's verdict; in
  ``claims.csv`` each claim's result and each headline verdict);
* every number within a tolerance (:func:`~magexp.artifacts.tolerances.tolerance`):
  :data:`~magexp.artifacts.tolerances.RTOL` relative, or one unit of its printed precision, whichever is larger;
  a column of integers (seeds, cells, counts) is held to
  the relative tolerance alone, i.e. exactly;
* every text identical up to the numbers in it, which are held to the same tolerance
  (:func:`~magexp.artifacts.tolerances.compare_text`): the CSVs' labels, reasons and evidence,
  ``REPORT.md``, ``APPENDIX.md`` and the LaTeX tables;
* a path diagnostic (:data:`PATH_DIAGNOSTICS`: how many iterations or evaluations a minimiser took,
  where its path ended against the box) through the verdicts that read it, not to a number
  tolerance: present on both sides (or empty on both), its differences counted and the largest
  shown, in a CSV column of that name and in a report or LaTeX table's column of that name;
* a figure through the data it draws (its ``.csv`` and ``_runs.csv``), never its pixels: its PNG
  and PDF must exist on both sides;
* a file on one side only is a disagreement; what differs by design is left out, and listed
  (:data:`EXCLUDED`, :data:`OPTIONAL`, :data:`MEASURED`, :data:`SECTIONS`);
* a paper on one side only is named as added (the reproduction's) or missing, its files not compared one by
  one, and ``papers`` (``--paper``) scopes the comparison (:mod:`magexp.artifacts.scope`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from magexp.artifacts.formats import MEASURED, PEERS_HEADING, SPEED_HEADING
from magexp.artifacts.scope import (REPORTS, SHARED, Scope, paper_folders, paper_rows, paper_scope, papers_of,
                                   report_cut)
from magexp.artifacts.tolerances import NUMBER, RTOL, compare_text, csv_unit, relative, tolerance
from magexp.core.outcomes import ROUNDOFF_FLOOR

#: columns that describe a minimiser's path, not its result, with why they move between processors. A
#: termination test met on numbers at round-off level is met at another iteration when the round-off
#: differs, the result being the same to the printed digits (measured on this machine, a processor
#: simulated by ``NPY_DISABLE_CPU_FEATURES`` (numpy's AVX-512 loops off), ``OPENBLAS_CORETYPE=Haswell`` and
#: ``NUMBA_CPU_NAME=generic`` against the default: ``lm`` 40 vs 53 evaluations, one Jacobian of 13;
#: ``local`` 791 vs 2131; ``cmaes`` up to 11 %; no verdict changed). Such a column is compared through
#: the verdicts that read it (a claim's ``verdict``, exactly) and is otherwise only required to be a number,
#: or empty, on both sides; a claim's evidence text that prints one is held to
#: :data:`~magexp.artifacts.tolerances.RTOL` like every text.
PATH_DIAGNOSTICS = {
    "nit": "iterations: lm's and local's stopping tests (xtol/ftol at 1e-12, BFGS's line search at its "
           "precision) are met at a round-off-dependent iteration; CMA-ES's stopping tests likewise",
    "nfev": "evaluations, as nit",
    "iterations_to_1.1": "the first iteration within 1.1x the final value: a path's crossing of a threshold",
    "nfev_to_1.1": "as iterations_to_1.1, in evaluations",
    "nfev_to_floor": "the first evaluation at the noise floor: a path's crossing of a threshold",
    "on_boundary": "coordinates of a swarm's best within 1e-9 of the box's face: a failed run's end "
                   "state, its coordinates hovering at the band's edge",
}
#: files (and folders, ending in ``/``) of ``results/`` that differ by design, with why
EXCLUDED = {
    "versions.csv": "magexp's commit and the library versions",
    "timing.csv": "wall times of this machine",
    "timing/": "wall times of this machine",
    "bench.csv": "the speed benchmark of this machine (make bench)",
    "bench.tex": "the speed benchmark of this machine (make bench)",
}
#: folders compared only when both sides have them (only ``make peers-bench`` writes them)
OPTIONAL = {"peers/": "make peers-bench"}
#: the folders of a results folder that are no paper's (:mod:`magexp.artifacts.scope`)
NOT_PAPERS = tuple(r.rstrip("/") for r in (*EXCLUDED, *OPTIONAL) if r.endswith("/"))
#: sections of the report files left out: ``(file, heading, the folder or file it shows)``; a section
#: whose source is compared (on both sides) is compared too
SECTIONS = (("APPENDIX.md", SPEED_HEADING, "bench.csv"), ("REPORT.md", PEERS_HEADING, "peers/"))
#: files compared line by line, their numbers tokenised (:func:`~magexp.artifacts.tolerances.compare_text`)
TEXT = (".md", ".tex")
#: figures: present on both sides, their pixels never compared (their data is in the CSVs)
FIGURES = (".png", ".pdf")
#: columns that name a row in a disagreement (the first few present)
KEYS = ("artifact", "id", "role", "quantity", "parameter", "case", "family", "label", "scenario", "estimator",
        "objective", "cell", "seed", "measure", "metric")


@dataclass
class Difference:
    """One difference: where (``file``, ``row``, ``column``), the two values and how far apart."""

    file: str
    row: str
    column: str
    ours: str
    committed: str
    relative: float = math.nan

    def line(self) -> str:
        """The difference as one line: the file, where in it, both values."""
        where = ", ".join(x for x in (self.row, f"column {self.column}" if self.column else "") if x)
        return f"{self.file}{': ' + where if where else ''}: ours {_quote(self.ours)}, committed {_quote(self.committed)}"


@dataclass
class Comparison:
    """What :func:`compare` found (counts, the disagreements, the differences within the tolerance)."""

    rtol: float
    csv_files: int = 0
    rows: int = 0
    values: int = 0
    text_files: int = 0
    lines: int = 0
    figures: int = 0
    verdicts: dict = field(default_factory=dict)  # {what: number compared} (summary rows, claims, headlines)
    changed: list = field(default_factory=list)  # verdicts that changed (Differences)
    disagreements: list = field(default_factory=list)  # everything else beyond the tolerance
    below: dict = field(default_factory=dict)  # {file: values that differ within the tolerance}
    paths: dict = field(default_factory=dict)  # {file: path diagnostics that differ (PATH_DIAGNOSTICS)}
    path_largest: Difference | None = None  # the largest relative difference of a path diagnostic
    largest: Difference | None = None  # the largest relative difference within the tolerance
    excluded: list = field(default_factory=list)  # what was left out, and why
    scope: Scope = field(default_factory=Scope)  # the papers compared, added and missing

    @property
    def agrees(self) -> bool:
        """Whether no verdict changed, nothing disagrees beyond the tolerance and no paper is missing."""
        return not self.changed and not self.disagreements and not self.scope.missing

    def within(self, diff: Difference, count: int = 1) -> None:
        """Count ``count`` differences within the tolerance in ``diff.file``, ``diff`` the largest of them."""
        self.below[diff.file] = self.below.get(diff.file, 0) + count
        if self.largest is None or diff.relative > self.largest.relative:
            self.largest = diff

    def path(self, diff: Difference, count: int = 1) -> None:
        """Count ``count`` differing path diagnostics in ``diff.file``, ``diff`` the largest of them."""
        self.paths[diff.file] = self.paths.get(diff.file, 0) + count
        if self.path_largest is None or diff.relative > self.path_largest.relative:
            self.path_largest = diff


def _quote(text: str, n: int = 60) -> str:
    """``text`` quoted, cut to ``n`` characters: a value as a difference's line shows it."""
    text = str(text)
    return repr(text if len(text) <= n else text[: n - 3] + "...")


# ---------------------------------------------------------------------------------------------
# files

def read_table(path: Path) -> pd.DataFrame:
    """A results CSV as text (every cell as written; an empty cell ``""``)."""
    return pd.read_csv(path, dtype=str, keep_default_na=False)


def row_name(frame: pd.DataFrame, i: int) -> str:
    """``row N (key=value, ...)``: the row's number (1 = the first after the header) and its first
    :data:`KEYS` present, each cut to 40 characters.
    """
    keys = [c for c in KEYS if c in frame.columns][:3]
    shown = ", ".join(f"{k}={_cut(frame[k].iat[i])}" for k in keys)
    return f"row {i + 1}" + (f" ({shown})" if shown else "")


def _cut(text: str, n: int = 40) -> str:
    """``text`` cut to ``n`` characters (``...`` marking the cut)."""
    return text if len(text) <= n else text[: n - 3] + "..."


def compare_csv(name: str, ours: Path, committed: Path, result: Comparison) -> None:
    """Compare two results CSVs cell by cell (by row position; a different row count is one
    disagreement): a ``verdict`` cell exactly, numbers within the tolerance, texts by
    :func:`~magexp.artifacts.tolerances.compare_text`. Only the cells whose text differs are looked at further;
    a shared CSV only in the rows of the papers compared (:func:`~magexp.artifacts.scope.paper_rows`).
    """
    a, b = read_table(ours), read_table(committed)
    if name in SHARED:
        a, b = paper_rows(a, result.scope), paper_rows(b, result.scope)
    columns = _columns(name, a, b, result)
    result.csv_files += 1
    result.rows += len(b)
    result.values += len(b) * len(columns)
    if len(a) != len(b):
        result.disagreements.append(Difference(name, "rows", "", f"{len(a)} rows", f"{len(b)} rows"))
        return
    if not len(b) or not columns:
        return
    differ = a[columns].to_numpy() != b[columns].to_numpy()
    for j in np.flatnonzero(differ.any(axis=0)):
        _compare_column(name, columns[j], a, b, np.flatnonzero(differ[:, j]), result)


def _columns(name: str, a: pd.DataFrame, b: pd.DataFrame, result: Comparison) -> list[str]:
    """The columns of ``b`` (committed) that ``a`` has too, without this machine's wall times
    (:data:`magexp.artifacts.formats.MEASURED`, listed as excluded); a column on one side only
    is a disagreement."""
    measured = [c for c in b.columns if MEASURED in c]
    if measured:
        result.excluded.append(f"column {', '.join(measured)} of {name} (wall times of this machine)")
    for col in [c for c in b.columns if c not in a.columns and c not in measured]:
        result.disagreements.append(Difference(name, "", col, "(no such column)", "(a column)"))
    for col in [c for c in a.columns if c not in b.columns and MEASURED not in c]:
        result.disagreements.append(Difference(name, "", col, "(a column)", "(no such column)"))
    return [c for c in b.columns if c in a.columns and c not in measured]


def _compare_column(name: str, col: str, a: pd.DataFrame, b: pd.DataFrame, rows: np.ndarray,
                    result: Comparison) -> None:
    """The differing cells ``rows`` of column ``col``: a verdict changed, numbers judged together
    (vectorised), anything else as a text."""
    x, y = a[col].to_numpy()[rows], b[col].to_numpy()[rows]
    if col == "verdict":
        result.changed += [Difference(name, row_name(b, i), col, u, v) for i, u, v in zip(rows, x, y)]
        return
    fx = pd.to_numeric(pd.Series(x), errors="coerce").to_numpy(float)
    fy = pd.to_numeric(pd.Series(y), errors="coerce").to_numpy(float)
    numeric = np.isfinite(fx) & np.isfinite(fy)
    if numeric.any():
        floats = b[col].str.contains(r"[.eE]").any() or a[col].str.contains(r"[.eE]").any()
        gap, scale = np.abs(fx - fy), np.maximum(np.abs(fx), np.abs(fy))
        unit = csv_unit(scale) if floats else np.zeros(len(fx))
        beyond = numeric & (gap > tolerance(fx, fy, unit, result.rtol) * (1 + 1e-9))
        with np.errstate(invalid="ignore", divide="ignore"):  # round-off on both sides: no relative difference
            rel = np.where(numeric, np.where(scale > ROUNDOFF_FLOOR, gap / scale, 0.0), np.nan)
        if col in PATH_DIAGNOSTICS:  # compared through the verdicts that read it
            k = np.flatnonzero(numeric)[np.argmax(rel[numeric])]
            result.path(Difference(name, row_name(b, rows[k]), col, x[k], y[k], rel[k]), int(numeric.sum()))
        else:
            for k in np.flatnonzero(beyond):
                result.disagreements.append(Difference(name, row_name(b, rows[k]), col, x[k], y[k], rel[k]))
            within = np.flatnonzero(numeric & ~beyond)
            if within.size:
                k = within[np.argmax(rel[within])]
                result.within(Difference(name, row_name(b, rows[k]), col, x[k], y[k], rel[k]), within.size)
    for k in np.flatnonzero(~numeric):
        ok, rel, (u, v) = compare_text(x[k], y[k], result.rtol)
        diff = Difference(name, row_name(b, rows[k]), col, u, v, rel)
        result.within(diff) if ok else result.disagreements.append(diff)


#: in a ``cut`` list: the opening of a report file (its lines above the first ``## `` heading) is left out
OPENING = "(opening)"


def text_lines(path: Path, cut: list[str]) -> list[str]:
    """The lines of a text file, without the sections whose heading line starts with one of ``cut``
    (a section ends at the next heading of its level or above), and without its opening if ``cut`` holds
    :data:`OPENING`.
    """
    lines, keep, level = path.read_text(encoding="utf-8").splitlines(), [], 0
    if OPENING in cut:
        lines = lines[next((i for i, line in enumerate(lines) if line.startswith("## ")), len(lines)):]
    for line in lines:
        heading = len(line) - len(line.lstrip("#")) if line.startswith("#") and " " in line else 0
        if level and heading and heading <= level:
            level = 0
        if not level and heading and any(line.startswith(h) for h in cut):
            level = heading
        if not level:
            keep.append(line)
    return keep


def compare_text_file(name: str, ours: Path, committed: Path, result: Comparison, cut: list[str]) -> None:
    """Compare two report or LaTeX files line by line (:func:`~magexp.artifacts.tolerances.compare_text`),
    without the sections ``cut``."""
    a, b = text_lines(ours, cut), text_lines(committed, cut)
    result.text_files += 1
    result.lines += len(b)
    if len(a) != len(b):
        i = next((k for k, (u, v) in enumerate(zip(a, b)) if u != v), min(len(a), len(b)))
        result.disagreements.append(Difference(name, f"{len(a)} lines vs {len(b)}, first difference at line {i + 1}",
                                               "", a[i] if i < len(a) else "", b[i] if i < len(b) else ""))
        return
    headers = table_headers(b)
    for i, (u, v) in enumerate(zip(a, b)):
        if u == v:
            continue
        if headers[i] and PATH_DIAGNOSTICS.keys() & set(headers[i]):
            _compare_table_row(name, i, headers[i], u, v, result)
            continue
        ok, rel, (x, y) = compare_text(u, v, result.rtol)
        diff = Difference(name, f"line {i + 1}", "", x, y, rel)
        result.within(diff) if ok else result.disagreements.append(diff)


def table_cells(line: str) -> list[str]:
    """The cells of a row of a Markdown (``| a | b |``) or LaTeX (``a & b \\\\``) table, ``\\_`` read as ``_``."""
    if line.startswith("|"):
        return [c.strip() for c in line.strip().strip("|").split("|")]
    return [c.strip().replace("\\_", "_") for c in line.strip().removesuffix("\\\\").split("&")]


def table_headers(lines: list[str]) -> list[list[str] | None]:
    """For each line, the column names of the table it is a body row of (None outside a table): a
    Markdown table's header is the line above its ``|---|`` rule, a LaTeX table's the line after
    ``\\toprule``; a table ends at a line that is not one of its rows (``\\bottomrule``).
    """
    out: list[list[str] | None] = [None] * len(lines)
    header = None
    for i, line in enumerate(lines):
        if line.startswith("|---") and i and lines[i - 1].startswith("|"):
            header = table_cells(lines[i - 1])
        elif i > 1 and lines[i - 2].strip() == "\\toprule":
            header = table_cells(lines[i - 1])
        elif header is not None and (line.startswith("|") or " & " in line) and len(table_cells(line)) == len(header):
            out[i] = header
        elif line.strip() != "\\midrule":
            header = None
    return out


def _compare_table_row(name: str, i: int, header: list[str], ours: str, committed: str, result: Comparison) -> None:
    """Line ``i`` of a table with a path diagnostic among its columns: cell by cell, a path diagnostic's
    numbers counted (:meth:`Comparison.path`), every other cell by :func:`~magexp.artifacts.tolerances.compare_text`."""
    for col, u, v in zip(header, table_cells(ours), table_cells(committed)):
        if u == v:
            continue
        ok, rel, (x, y) = compare_text(u, v, result.rtol)
        diff = Difference(name, f"line {i + 1}", col, x, y, rel)
        if col in PATH_DIAGNOSTICS and NUMBER.fullmatch(u) and NUMBER.fullmatch(v):
            result.path(Difference(name, f"line {i + 1}", col, u, v, relative(float(u), float(v))))
        else:
            result.within(diff) if ok else result.disagreements.append(diff)


# ---------------------------------------------------------------------------------------------
# two folders

def _files(root: Path) -> set[str]:
    """The files below ``root``, as POSIX paths relative to it."""
    return {p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file()}


def _left_out(rel: str, rules) -> str | None:
    """The rule of ``rules`` (:data:`EXCLUDED`, :data:`OPTIONAL`) that covers the relative path ``rel``."""
    return next((r for r in rules if rel == r or (r.endswith("/") and rel.startswith(r))), None)


def compare(ours: Path, committed: Path, *, rtol: float = RTOL, files=None, papers=None) -> Comparison:
    """Compare the reproduction ``ours`` with the committed results ``committed`` (two folders laid
    out as ``results/``), every file but those that differ by design (module docstring); ``files``:
    only these relative paths (e.g. one artifact's); ``papers``: only these papers (``--paper``; a paper on
    one side only is named in ``result.scope``, not compared: :mod:`magexp.artifacts.scope`).
    """
    ours, committed = Path(ours), Path(committed)
    result = Comparison(rtol=rtol)
    mine, theirs = _files(ours), _files(committed)
    if files is not None:
        mine, theirs = mine & set(files), theirs & set(files)
    by_design = _by_design(mine, theirs, result)
    mine, theirs = mine - by_design, theirs - by_design
    result.scope = paper_scope(papers_of(ours, mine, NOT_PAPERS), papers_of(committed, theirs, NOT_PAPERS), papers)
    folders = paper_folders(mine | theirs, NOT_PAPERS)
    mine = {f for f in mine if result.scope.keeps(f, folders)}
    theirs = {f for f in theirs if result.scope.keeps(f, folders)}
    both = sorted(mine & theirs)
    cut = _cut_sections(both, result)
    if result.scope.partial:
        _cut_papers(both, [ours, committed], cut, result)
    for rel in sorted(theirs - mine):
        result.disagreements.append(Difference(rel, "", "", "(missing)", "(a file)"))
    for rel in sorted(mine - theirs):
        result.disagreements.append(Difference(rel, "", "", "(a file)", "(not committed)"))
    for rel in both:
        _compare_file(rel, ours, committed, result, cut.get(rel, []))
    _count_verdicts(committed, both, result)
    return result


def _by_design(mine: set[str], theirs: set[str], result: Comparison) -> set[str]:
    """The files of either side that differ by design (:data:`EXCLUDED`; :data:`OPTIONAL` when on one
    side only), each rule that left one out listed in ``result.excluded``."""
    left = set()
    for rule, why in EXCLUDED.items():
        hit = {f for f in mine | theirs if _left_out(f, [rule])}
        if hit:
            left |= hit
            result.excluded.append(rule + (f" ({len(hit)} files)" if rule.endswith("/") else "") + f": {why}")
    for rule, why in OPTIONAL.items():
        on = [{f for f in side if _left_out(f, [rule])} for side in (mine, theirs)]
        if bool(on[0]) != bool(on[1]):
            left |= on[0] | on[1]
            result.excluded.append(f"{rule}: on one side only (written by {why} alone)")
    return left


def _compare_file(rel: str, ours: Path, committed: Path, result: Comparison, cut: list[str]) -> None:
    """Compare the file ``rel`` of both folders by its kind: a CSV, a text, a figure (present), other bytes."""
    suffix = Path(rel).suffix
    if suffix == ".csv":
        compare_csv(rel, ours / rel, committed / rel, result)
    elif suffix in TEXT:
        compare_text_file(rel, ours / rel, committed / rel, result, cut)
    elif suffix in FIGURES:
        result.figures += 1
    elif (ours / rel).read_bytes() != (committed / rel).read_bytes():
        result.disagreements.append(Difference(rel, "", "", "(other bytes)", "(other bytes)"))


def _cut_sections(both: list[str], result: Comparison) -> dict[str, list[str]]:
    """``{report file: [headings left out]}``: a section of :data:`SECTIONS` whose source is not
    compared (excluded by design, or on one side only)."""
    cut: dict[str, list[str]] = {}
    for name, heading, source in SECTIONS:
        shown = any(f == source or (source.endswith("/") and f.startswith(source)) for f in both)
        if name in both and not shown:
            cut.setdefault(name, []).append(heading)
            result.excluded.append(f"{name} section {heading.lstrip('# ')!r}: it shows {source}")
    return cut


def _cut_papers(both: list[str], folders: list[Path], cut: dict, result: Comparison) -> None:
    """Add to ``cut`` every section of the report files but the papers' compared, and their openings."""
    sections = report_cut(result.scope, folders)
    for name in (n for n in REPORTS if n in both):
        cut.setdefault(name, []).extend([OPENING, *sections])
    if any(n in both for n in REPORTS):
        result.excluded.append("REPORT.md and APPENDIX.md outside the sections of the papers compared (their openings "
                               "and the other sections count or show every paper)")


def _count_verdicts(committed: Path, both: list[str], result: Comparison) -> None:
    """How many verdicts were compared: summary rows, claims and headline verdicts (of the papers compared)."""
    if "summary.csv" in both:
        result.verdicts["summary rows"] = len(paper_rows(read_table(committed / "summary.csv"), result.scope))
    if "claims.csv" in both:
        roles = paper_rows(read_table(committed / "claims.csv"), result.scope)["role"]
        result.verdicts["claims"] = int((roles != "headline").sum())
        result.verdicts["headline verdicts"] = int((roles == "headline").sum())
