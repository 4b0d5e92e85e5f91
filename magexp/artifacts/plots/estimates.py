"""A table of fitted values per estimator: parameters (and chosen metrics) vs truth.

Rows are the run's ``parameter_names`` followed by ``plot.rows`` (extra metrics, e.g. ``fit_rms``);
columns are ``truth`` (if the runs know it) and one per cell (its estimator, median over seeds,
with the interquartile range when there are several seeds), and ``paper states``: the artifact's
``reported:`` values of the row (with the estimator they are stated for). The CSV is long: one row
per (quantity, cell). The figure renders the table.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts.plan import quantiles
from magexp.artifacts.plots.style import panels, paper_values, plt


def tabulate(runs) -> pd.DataFrame:
    names = list(next(iter(runs.outputs.values())).parameter_names) + list(runs.spec.plot.get("rows", []))
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = runs.table[runs.table.cell == ci]
        for name in names:
            if name not in sub:
                continue
            med, q25, q75 = quantiles(sub[name])
            truth = f"truth_{name}"
            rows.append({**cell, "estimator": sub.estimator.iloc[0], "quantity": name, "median": med, "q25": q25,
                         "q75": q75, "truth": float(sub[truth].median()) if truth in sub else np.nan,
                         "n_seeds": len(sub)})
    return pd.DataFrame(rows)


def _cell(row) -> str:
    if not np.isfinite(row["median"]):
        return ""
    text = f"{row['median']:.6g}"
    return text + (f"\n[{row.q25:.4g}, {row.q75:.4g}]" if row.n_seeds > 1 and np.isfinite(row.q25) else "")


def draw(frame: pd.DataFrame, spec, axes=None):
    quantities, columns, body = _table(frame, spec)
    widths = _column_widths(columns, body)
    fig, ax = _figure(frame, quantities, body, widths, axes)
    ax.axis("off")
    # the table fills its axes (bbox), so the layout keeps the title clear of it
    table = ax.table(cellText=body, rowLabels=quantities, colLabels=columns, cellLoc="center", bbox=[0, 0, 1, 1],
                     colWidths=[w / sum(widths) for w in widths])
    table.auto_set_font_size(False)
    table.set_fontsize(7.5)
    fig.suptitle(spec.title, fontsize=9)
    return fig


def _table(frame: pd.DataFrame, spec) -> tuple[list[str], list[str], list[list[str]]]:
    """The table's row labels (quantities), column labels (``truth`` if known, one per estimator,
    ``paper states`` if the spec reports a row) and cell texts."""
    quantities = list(dict.fromkeys(frame.quantity))
    estimators = list(dict.fromkeys(frame.estimator))
    truth = frame.groupby("quantity", sort=False).truth.first()
    paper = {q: "\n".join(f"{e.value:g}" + (f" ({e.match['estimator']})" if "estimator" in e.match else "")
                           for e in paper_values(spec, q)) for q in quantities}
    columns = (["truth"] if truth.notna().any() else []) + estimators + (["paper states"] if any(paper.values()) else [])
    body = []
    for q in quantities:
        cells = [f"{truth[q]:.6g}" if np.isfinite(truth[q]) else ""] if columns[0] == "truth" else []
        for est in estimators:
            row = frame[(frame.quantity == q) & (frame.estimator == est)]
            cells.append(_cell(row.iloc[0]) if len(row) else "")
        body.append(cells + ([paper[q]] if columns[-1] == "paper states" else []))
    return quantities, columns, body


def _column_widths(columns: list[str], body: list[list[str]]) -> list[float]:
    """Inches per column: its longest line at 7.5 pt (about 0.062 in a character) and a margin."""
    longest = [max(len(line) for text in [name, *(cells[k] for cells in body)] for line in text.split("\n"))
               for k, name in enumerate(columns)]
    return [0.25 + 0.062 * n for n in longest]


def _figure(frame: pd.DataFrame, quantities: list[str], body: list[list[str]], widths: list[float], axes):
    """The figure and axes of the table: the given ``axes``, else a figure sized to the table
    (:func:`panels` gives one panel a fixed size) with rows of two lines (median, IQR) or one."""
    if axes is not None:
        fig, (ax,) = panels(1, axes=axes)
        return fig, ax
    tall = frame.n_seeds.max() > 1 or any("\n" in c for cells in body for c in cells)
    row_height = 0.42 if tall else 0.24  # inches: two lines (median, IQR) or one
    label_width = 0.25 + 0.062 * max(len(q) for q in quantities)
    return plt.subplots(figsize=(label_width + sum(widths), 0.5 + row_height * (len(quantities) + 1)),
                        layout="constrained")
