"""A table of fitted values per estimator against the truth (Yan & Zhou 2022); `names`: column headers in words."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from magexp.artifacts.plot_keys import CommonPlot
from magexp.artifacts.schema import typed
from magexp.artifacts.tables import cell_runs, median, quartiles


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``estimates``: ``rows`` (runs columns shown after the parameters),
    ``names`` (``{estimator: header}``)."""

    rows: list[str] = field(default_factory=list)
    names: dict[str, str] = field(default_factory=dict)


def table(runs, plot) -> pd.DataFrame:
    """Per cell and quantity (the run's parameters, then ``plot.rows``): quartiles over seeds and the
    median truth (:mod:`magexp.artifacts.plots.estimates`)."""
    names = list(next(iter(runs.outputs.values())).parameter_names) + list(plot.rows)
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = cell_runs(runs, ci)
        for name in (n for n in names if n in sub):
            med, q25, q75 = quartiles(sub[name])
            truth = f"truth_{name}"
            rows.append({**cell, "estimator": sub.estimator.iloc[0], "quantity": name, "median": med, "q25": q25,
                         "q75": q75, "truth": median(sub[truth]) if truth in sub else np.nan, "n_seeds": len(sub)})
    return pd.DataFrame(rows)


def draw(table, spec, axes=None):
    """Draws the fitted values per estimator beside the truth, as a table figure
    (:func:`magexp.artifacts.plots.estimates.draw`)."""
    from magexp.artifacts.plots import estimates
    return estimates.draw(table, spec, axes)
