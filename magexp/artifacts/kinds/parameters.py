"""Every parameter estimate per cell beside the truth and the paper's value (Yuan 2018's tables); `unit`: the readings' unit, of the offsets and F_g."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from magexp.artifacts.plot_keys import FIT, CommonPlot
from magexp.artifacts.schema import typed
from magexp.artifacts.tables import (cell_overrides, cell_runs, fraction, outcomes, parameter_values, quartiles,
                                     reported_value, scenario_label)


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``parameters``: ``unit`` (the readings' unit)."""

    unit: str = "nT"


def cell_label(cell: dict, estimator: str, spec) -> str:
    """A short legend text of a cell: the estimator, then its other swept values (a scenario by its
    readable name, :func:`scenario_label`; other keys as ``name = value`` with ``plot.labels``).
    """
    names = dict(spec.plot.get("labels", {}) or {})
    rest = [scenario_label(v) if k == "scenario" else f"{names.get(k, k.split('.')[-1].replace('_', ' '))} = {v}"
            for k, v in cell.items() if k != "estimator"]
    return ", ".join([estimator] + rest)


def table(runs, plot) -> pd.DataFrame:
    """Per cell and parameter: quartiles over the successful seeds (``n_failed`` counts the rest), the truth
    and the paper's value; F_g over every seed that measures it (:mod:`magexp.artifacts.plots.parameters`)."""
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = cell_runs(runs, ci)
        names, values, truth = parameter_values(runs, ci)
        settings = cell_overrides(runs, ci)
        ok = outcomes(sub.sort_values("seed")) if "succeeded" in sub else np.full(len(values), np.nan)
        judged = np.isfinite(ok)
        kept = values[ok == 1] if judged.any() else values  # over the successful runs; failures counted beside
        for k, name in enumerate(names):
            med, q25, q75 = quartiles(kept[:, k])
            paper, _ = reported_value(runs.spec, name, settings)
            rows.append({**cell, "label": cell_label(cell, sub.estimator.iloc[0], runs.spec),
                         "estimator": sub.estimator.iloc[0], "objective": sub.objective.iloc[0], "parameter": name,
                         "truth": np.nan if truth is None else float(truth[k]), "median": med, "q25": q25,
                         "q75": q75, "paper_value": np.nan if paper is None else paper, "n_seeds": len(values),
                         "n_failed": int((ok[judged] == 0).sum()), "success_rate": fraction(ok)})
        name, column = FIT
        if column in sub and sub[column].notna().any():  # over every seed, as the summary's F_g row
            med, q25, q75 = quartiles(sub[column])
            paper, _ = reported_value(runs.spec, name, settings)
            rows.append({**rows[-1], "parameter": name, "truth": np.nan, "median": med, "q25": q25, "q75": q75,
                         "paper_value": np.nan if paper is None else paper})
    return pd.DataFrame(rows)


def draw(table, spec, axes=None):
    """Draws each parameter's estimate minus truth per cell (median, IQR), beside the paper's value
    (:func:`magexp.artifacts.plots.parameters.draw`)."""
    from magexp.artifacts.plots import parameters
    return parameters.draw(table, spec, axes)
