"""A table of fitted values per estimator: parameters (and chosen metrics) vs truth.

Rows are the run's ``parameter_names`` followed by ``plot.rows`` (extra metrics, e.g. ``fit_rms``);
columns are ``truth`` (if the runs know it) and one per cell (its estimator, median over seeds,
with the interquartile range when there are several seeds; ``plot.names``: ``{estimator: header}``).
The artifact's ``reported:`` value of a row stated for one estimator is printed in that estimator's
cell (``paper: 0.0001``), unless the row prints it already (a column of the paper's own estimate);
one stated for none gets a ``paper states`` column (only then: a column
empty on most rows says nothing). The CSV is long: one row per (quantity, cell). The figure renders
the table, each row as tall as its cell of most lines (the table:
:func:`magexp.artifacts.kinds.estimates.table`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts.plots.style import panels, paper_values, plt


def _cell(row) -> str:
    """A table cell's text: the median, and its quartiles below it when there are several seeds."""
    if not np.isfinite(row["median"]):
        return ""
    text = f"{row['median']:.6g}"
    return text + (f"\n[{row.q25:.4g}, {row.q75:.4g}]" if row.n_seeds > 1 and np.isfinite(row.q25) else "")


def draw(frame: pd.DataFrame, spec, axes=None):
    """The estimates as a table figure: per cell and quantity, median and IQR over seeds beside the truth."""
    quantities, columns, body = _table(frame, spec)
    widths = _column_widths(columns, body)
    lines = [max(1, *(c.count("\n") + 1 for c in cells)) for cells in body]
    fig, ax = _figure(frame, quantities, lines, widths, axes)
    ax.axis("off")
    # the table fills its axes (bbox), so the layout keeps the title clear of it
    table = ax.table(cellText=body, rowLabels=quantities, colLabels=columns, cellLoc="center", bbox=[0, 0, 1, 1],
                     colWidths=[w / sum(widths) for w in widths])
    table.auto_set_font_size(False)
    table.set_fontsize(7.5)
    for (row, col), cell in table.get_celld().items():  # rows as tall as their lines (the bbox keeps the ratios)
        cell.set_height(_row_height(lines[row - 1]) if row > 0 else _row_height(1))
    fig.suptitle(spec.title, fontsize=9)
    return fig


def _stated(spec, quantity: str, estimators: list[str], shown: set[str]) -> tuple[dict, str]:
    """The paper's values of ``quantity`` not already printed in its row (``shown``: the row's
    medians as printed, e.g. a column of the paper's own estimate): ``{estimator: "paper: v"}`` for
    those stated for one of ``estimators``, and the text of the others (for a ``paper states`` column)."""
    own, other = {}, []
    for e in paper_values(spec, quantity):
        if f"{float(e.value):.6g}" in shown:
            continue
        est = e.match.get("estimator") if "estimator" in e.match else None
        if est in estimators:
            own[est] = f"paper: {e.value:g}"
        else:
            other.append(f"{e.value:g}" + (f" ({est})" if est else ""))
    return own, "\n".join(other)


def _table(frame: pd.DataFrame, spec) -> tuple[list[str], list[str], list[list[str]]]:
    """The table's row labels (quantities), column labels (``truth`` if known, one per estimator,
    ``paper states`` if the spec reports a row for no estimator of the table) and cell texts."""
    quantities = list(dict.fromkeys(frame.quantity))
    estimators = list(dict.fromkeys(frame.estimator))
    names = dict(spec.plot.get("names", {}) or {})
    truth = frame.dropna(subset=["truth"]).drop_duplicates("quantity").set_index("quantity").truth.reindex(quantities)
    stated = {q: _stated(spec, q, estimators, {f"{v:.6g}" for v in frame[frame.quantity == q]["median"]})
              for q in quantities}
    others = any(text for _, text in stated.values())
    columns = ((["truth"] if truth.notna().any() else []) + [str(names.get(e, e)) for e in estimators]
               + (["paper states"] if others else []))
    body = []
    for q in quantities:
        cells = [f"{truth[q]:.6g}" if np.isfinite(truth[q]) else ""] if truth.notna().any() else []
        own, text = stated[q]
        cells += [_estimate(frame, q, est, own.get(est, "")) for est in estimators]
        body.append(cells + ([text] if others else []))
    return quantities, columns, body


def _estimate(frame: pd.DataFrame, quantity: str, estimator: str, stated: str) -> str:
    """The cell of ``quantity`` by ``estimator`` (empty without a run) and the paper's ``stated`` value."""
    row = frame[(frame.quantity == quantity) & (frame.estimator == estimator)]
    return "\n".join(t for t in (_cell(row.iloc[0]) if len(row) else "", stated) if t)


def _column_widths(columns: list[str], body: list[list[str]]) -> list[float]:
    """Inches per column: its longest line at 7.5 pt (about 0.062 in a character) and a margin."""
    longest = [max(len(line) for text in [name, *(cells[k] for cells in body)] for line in text.split("\n"))
               for k, name in enumerate(columns)]
    return [0.25 + 0.062 * n for n in longest]


def _row_height(lines: int) -> float:
    """Inches of a table row of ``lines`` lines of 7.5 pt text."""
    return 0.1 + 0.14 * lines


def _figure(frame: pd.DataFrame, quantities: list[str], lines: list[int], widths: list[float], axes):
    """The figure and axes of the table: the given ``axes``, else a figure sized to the table
    (:func:`panels` gives one panel a fixed size), each row as tall as its lines."""
    if axes is not None:
        fig, (ax,) = panels(1, axes=axes)
        return fig, ax
    label_width = 0.25 + 0.062 * max(len(q) for q in quantities)
    height = _row_height(1) + sum(_row_height(n) for n in lines)
    return plt.subplots(figsize=(label_width + sum(widths), 0.5 + height), layout="constrained")
