"""The formats of the results files: a results CSV (every float rounded to :data:`DIGITS` significant digits,
round-off floored: :func:`tidy`, :func:`write_csv`), a runs CSV read back (:func:`read_runs`), and a table as
Markdown and LaTeX (:func:`markdown_table`, :func:`latex_table`); what ``magexp verify`` leaves out by design
(:data:`MEASURED` columns, the report's sections of :data:`PEERS_HEADING` and :data:`SPEED_HEADING`).
Identical bytes on every fresh clone when only round-off differs; ``magexp verify`` holds a reproduction to
one unit of these digits."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd

from magexp.core.outcomes import ROUNDOFF_FLOOR
from magexp.core.atomic import atomic_path, write_text
from magexp.errors import MagexpError

#: significant digits of every float written to a results CSV (round-off must not churn files)
DIGITS = 6
#: a column of wall times measured on this machine has this in its name (an artifact's table keeps them in
#: ``results/timing/``, :func:`magexp.artifacts.reproduce.split_timing`)
MEASURED = "wall_time"
#: the headings of the report's sections on what ``make reproduce`` does not write (``magexp verify`` leaves
#: them out unless both sides have their source)
PEERS_HEADING, SPEED_HEADING = "## magexp beside MAGYC", "## Speed of the core"
#: the heading of the report's section holding the legends every paper's section links (``#how-to-read``)
HOW_TO_READ = "## How to read"
#: the longest line the report's Markdown holds (issue 43): a longer paragraph or list item is wrapped at
#: :data:`WRAP` columns (the rendered page is the same), a table with a longer row is written as a list
LINE_LIMIT, WRAP = 500, 480


def _floats(column: pd.Series) -> np.ndarray | None:
    """The column as floats if it holds floats: a float column, or an object column whose values are
    floats and missing values (e.g. a truth that some rows lack); else None (text, integers, flags)."""
    if pd.api.types.is_float_dtype(column):
        return column.to_numpy(float)
    if column.dtype == object:
        present = [v for v in column if v is not None and not (isinstance(v, float) and np.isnan(v))]
        if present and all(isinstance(v, (float, np.floating)) for v in present):
            return np.array([np.nan if v is None else float(v) for v in column])
    return None


#: columns of probabilities: never floored as round-off (a p of 1e-22 is written as it is)
EXACT = ("p", "p_adjusted", "p_min")


def _round(v: np.ndarray, col: str, floor: float) -> np.ndarray:
    """Floats ``v`` of column ``col`` as :func:`tidy` writes them: round-off floored, :data:`DIGITS` digits."""
    small = np.isfinite(v) & (v != 0) & (np.abs(v) < (0 if col in EXACT else floor))
    v = np.where(small, np.sign(v) * floor, v)
    with np.errstate(divide="ignore", invalid="ignore"):
        mag = np.where(np.isfinite(v) & (v != 0), np.floor(np.log10(np.abs(np.where(v == 0, 1, v)))), 0)
    scale = 10.0 ** (DIGITS - 1 - mag)
    return np.where(np.isfinite(v), np.round(v * scale) / scale, v)


def _rounded(x, col: str, floor: float):
    """A value of a mixed column: a float rounded as :func:`_round`; anything else (text, integer, flag) as it is."""
    if isinstance(x, (float, np.floating)) and not isinstance(x, bool):
        return float(_round(np.array([float(x)]), col, floor)[0])
    return x


def tidy(frame: pd.DataFrame, floor: float = ROUNDOFF_FLOOR) -> pd.DataFrame:
    """Float columns with magnitudes below ``floor`` (round-off, e.g. a noise-free RMS of 1e-11)
    written as ``±floor`` (not the :data:`EXACT` ones); every float then rounded to :data:`DIGITS`
    significant digits, also where its column holds integers, text or flags beside it.
    """
    out = frame.copy()
    for col in out.columns:
        v = _floats(out[col])
        if v is not None:
            out[col] = _round(v, col, floor)
        elif out[col].dtype == object:  # floats beside integers, text or flags: each rounded alone
            out[col] = out[col].map(lambda x: _rounded(x, col, floor))
    return out


def _one_form(column: pd.Series) -> pd.Series:
    """A mixed column (text, flags, integers beside floats) with each float as ``%.6g`` text: pandas writes a
    float of an object column as ``repr`` (``1.0``), so its form would depend on the other rows (issue 44)."""
    def form(v):
        return f"{v:.{DIGITS}g}" if isinstance(v, (float, np.floating)) and np.isfinite(v) else v

    return column.map(form) if column.dtype == object else column


def write_csv(frame: pd.DataFrame, path: Path) -> None:
    """A results CSV: :func:`tidy` values, every float written ``%.6g`` whatever else its column holds (a
    paper's rows read the same beside any other paper's), so identical bytes on every fresh clone when only
    round-off differs.
    """
    out = tidy(frame)
    out = out.apply(_one_form) if len(out.columns) else out
    with atomic_path(path) as tmp:  # an interrupt leaves the old file or the new one
        out.to_csv(tmp, index=False, float_format=f"%.{DIGITS}g")


def read_runs(path: Path) -> pd.DataFrame:
    """A runs CSV, consolidated: ``read_csv`` leaves one block per column (95 in ``benchmark_heatmap``),
    a copy one per dtype, and the claims and the summary take rows from it hundreds of times (a
    selection of ``benchmark_heatmap``'s cells: 1.7 ms as read, 1.0 ms consolidated).
    """
    return pd.read_csv(path).copy()


def fmt(v) -> str:
    """A value as a table shows it: 4 significant digits, ``yes``/``no``, '' for a missing number."""
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return ""
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (float, np.floating)):
        return f"{v:.4g}"
    return str(v)


_LATEX = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_", "{": r"\{",
          "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}"}


def _tex(text: str) -> str:
    """``text`` with LaTeX's special characters escaped."""
    return "".join(_LATEX.get(ch, ch) for ch in str(text))


def latex_table(frame: pd.DataFrame, columns: list[str]) -> str:
    """The same table as :func:`markdown_table`, as a LaTeX ``tabular`` with ``booktabs`` rules
    (``\\usepackage{booktabs}``), ready to ``\\input`` into a paper.
    """
    lines = [r"\begin{tabular}{" + "l" * len(columns) + "}", r"\toprule",
             " & ".join(_tex(c) for c in columns) + r" \\", r"\midrule"]
    lines += [" & ".join(_tex(fmt(r[c])) for c in columns) + r" \\" for _, r in frame.iterrows()]
    return "\n".join(lines + [r"\bottomrule", r"\end{tabular}", ""])


def _cell(v) -> str:
    """A Markdown table cell: :func:`fmt`, with ``|`` escaped and line breaks flattened."""
    return " ".join(fmt(v).split()).replace("|", "\\|")


def markdown_table(frame: pd.DataFrame, columns: list[str], tex: Path | None = None, names: list[str] | None = None) -> str:
    """A Markdown table of ``columns`` (headed ``names``, default the columns); with ``tex``, its
    LaTeX twin (:func:`latex_table`) is written there. A table without rows is an error: the
    caller says in words that there is nothing to show.
    """
    if not len(frame):
        raise MagexpError(f"an empty table ({', '.join(columns)}) would be printed: say so in words instead")
    if tex is not None:
        write_text(tex, latex_table(frame, columns))
    names = names or columns
    rows = [[_cell(r[c]) for c in columns] for _, r in frame.iterrows()]
    lines = ["| " + " | ".join(cells) + " |" for cells in rows]
    if max(map(len, lines)) <= LINE_LIMIT:
        return "| " + " | ".join(names) + " |\n|" + "---|" * len(columns) + "\n" + "".join(f"{x}\n" for x in lines)
    return "".join(f"- **{cells[0]}** — " + "; ".join(f"{n}: {c}" for n, c in zip(names[1:], cells[1:])) + "\n"
                   for cells in rows)


#: a Markdown line that is not prose: a table row, a heading, a code fence, a raw HTML line
_NOT_PROSE = re.compile(r"^\s*(\||#|```|<)")


def wrap_markdown(text: str) -> str:
    """``text`` with every prose line (paragraph or list item) longer than :data:`LINE_LIMIT` wrapped at
    :data:`WRAP` columns, list items with their continuation indented: the same page rendered, a source a
    reviewer can read and diff."""
    out = []
    for line in text.split("\n"):
        if len(line) <= LINE_LIMIT or _NOT_PROSE.match(line):
            out.append(line)
            continue
        item = re.match(r"^(\s*(?:[-*]|\d+\.)\s+)", line)
        indent = " " * len(item.group(1)) if item else re.match(r"^\s*", line).group(0)
        out += textwrap.wrap(line, WRAP, subsequent_indent=indent, break_long_words=False, break_on_hyphens=False)
    return "\n".join(out)
