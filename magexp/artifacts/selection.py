"""The runs a claim or a note field is about: each cell's settings (:func:`cell_settings`), the rows of the
cells a selection names (:func:`select`, after its row filters: :func:`restrict`), and the per-seed values a
statistic is taken over (:func:`values`; a censored value is ``+inf``, never dropped).
"""

from __future__ import annotations

import re
import numpy as np
import pandas as pd

from magexp.artifacts.censoring import censored_mask, with_censored
from magexp.artifacts.tables import matches, same
from magexp.errors import MagexpError


def cell_settings(table: pd.DataFrame) -> dict[int, dict]:
    """``{cell: {key: value}}`` of a runs table: its ``setting`` pairs, estimator and objective."""
    if "cell" not in table or not len(table):
        return {}
    cell = table["cell"].to_numpy()
    rows = np.flatnonzero(pd.notna(cell))
    cells, first = np.unique(cell[rows], return_index=True)  # each cell's first row: its setting is the cell's
    named = [k for k in ("estimator", "objective", "scenario", "case") if k in table]
    columns = {c: table[c].to_numpy()[rows[first]].tolist() for c in ["setting", *named] if c in table}
    records = [dict(zip(columns, values)) for values in zip(*columns.values())] if columns else [{}] * len(cells)
    out = {}
    for ci, first in zip(cells.tolist(), records):
        pairs = dict(p.split("=", 1) for p in str(first.get("setting", "") or "").split(";") if "=" in p)
        for key in named:
            if key not in pairs:
                pairs[key] = first[key]
        out[int(ci)] = pairs
    return out


def restrict(table: pd.DataFrame, where: dict) -> tuple[pd.DataFrame, dict, dict]:
    """Apply the row filters of ``where``; return the rows, the rest of ``where`` (the cell settings
    to match) and the cells' settings (:func:`cell_settings`, the same for any of a cell's rows):
    ``seeds: n`` keeps the first ``n`` seeds (a conclusion at n and 2n seeds), ``succeeded: 1`` the
    successful runs (any runs column that is not a setting filters rows by its value).
    """
    where = dict(where)
    if "seeds" in where:
        table = table[table.seed < int(where.pop("seeds"))]
    settings = cell_settings(table)
    keys = {k for s in settings.values() for k in s}
    for key in [k for k in where if k not in keys and k in table]:
        value = where.pop(key)
        table = table[[same(v, value) for v in table[key]]]
    return table, where, settings


def select(table: pd.DataFrame, where: dict) -> pd.DataFrame:
    """The runs of every cell whose settings include every ``key: value`` of ``where`` (after the
    row filters of :func:`restrict`).
    """
    table, where, settings = restrict(table, where)
    keep = [ci for ci, s in settings.items() if matches(where, s)]
    return table[table.cell.isin(keep)]


def values(runs: pd.DataFrame, metric: str, stat: str) -> np.ndarray:
    """The per-seed values a statistic is taken over (``succeeded`` for ``success_rate``); a censored
    value (:mod:`magexp.artifacts.censoring`) is ``+inf``, never dropped.
    """
    if stat == "success_rate":
        succeeded = runs["succeeded"] if "succeeded" in runs else pd.Series(dtype=float)
        return succeeded.dropna().astype(float).to_numpy()
    v = column(with_censored(runs), metric)
    return v[np.isfinite(v) | censored_mask(runs, metric)]


def column(runs: pd.DataFrame, metric: str) -> np.ndarray:
    """``metric`` per run (NaN kept: pairs stay aligned): a runs column, or a pandas expression of them
    whose column names are written as they are (:func:`expression`)."""
    try:
        return np.asarray(runs[metric] if metric in runs else runs.eval(expression(metric, runs.columns)), float)
    except Exception as exc:
        raise MagexpError(f"metric {metric!r} is not a column or an expression of the runs' columns: {exc}") from None


def expression(metric: str, columns) -> str:
    """``metric`` as ``pandas.eval`` reads it: every name of ``columns`` that is no Python identifier
    (``scenario.n_readings``, ``iterations_to_1.1``) put in backticks where it stands whole, so that
    a spec writes a dotted config key as it is (one already in backticks is left as written).

    Parameters
    ----------
    metric : str
        A runs column or a pandas expression of the runs' columns.
    columns : iterable of str
        The runs table's columns.

    Returns
    -------
    str
        The expression with its non-identifier column names quoted.
    """
    odd = sorted((str(c) for c in columns if not str(c).isidentifier()), key=len, reverse=True)
    for name in odd:
        metric = re.sub(rf"(?<![\w.`]){re.escape(name)}(?![\w`]|\.[A-Za-z_])", f"`{name}`", metric)
    return metric
