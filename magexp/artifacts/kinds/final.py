"""Final values of one or more metrics against a swept key; `ylog: {metric: false}` puts one metric on a linear axis; `levels`: a paper's values not compared cell by cell, as lines across the panels they match."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import pandas as pd

from magexp.artifacts import trends
from magexp.artifacts.censoring import cell_quartiles
from magexp.artifacts.plot_keys import CommonPlot, choice, metric_list
from magexp.artifacts.schema import Bool, Float, typed
from magexp.artifacts.tables import cell_runs, fraction, matches, median, quartiles


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``final``: ``x`` (the swept key), ``metric`` (one runs column or a list),
    ``bound`` (a bound column drawn per objective), ``xscale`` (``linear``, ``log``, ``symlog`` with
    ``linthresh``), ``targets`` (``{metric: value}`` drawn dashed), ``ylabels`` (per metric), ``ylog``
    (one flag or ``{metric: flag}``), ``names`` (``{value: legend text}``), ``levels`` (a paper's values
    as lines: ``label``, ``match``, ``value``, ``metrics``)."""

    x: str | None = None  # the swept key (a final figure needs it; a table alone does not)
    hue: str | list[str] = "estimator"
    ylabel: str = "final total-field RMS (nT)"
    metric: str | list[str] = "fun"
    bound: str | None = None
    xscale: str = "linear"
    linthresh: Float = 1.0
    targets: dict[str, Float] = field(default_factory=dict)
    ylabels: dict[str, str] = field(default_factory=dict)
    ylog: Bool | dict[str, Bool] = True
    names: dict[str, str] = field(default_factory=dict)
    levels: list[dict[str, Any]] = field(default_factory=list)

    def __post_init__(self):
        choice("plot.xscale", self.xscale, ("linear", "log", "symlog"))


def _ratio_name(item) -> str:
    """The line name of a ratio: numerator over denominator (their distinguishing values)."""
    return " / ".join(", ".join(str(v) for v in side.values()) for side in (item.numerator, item.denominator))


def _ratio_rows(runs) -> list[dict]:
    """Per ``ratios:`` item and denominator cell: quartiles of the per-seed ratio (seeds share
    readings, so the ratio is paired), the fraction of seeds where both runs succeeded."""
    table, rows = runs.table, []
    for item in runs.spec.ratios:
        for ci, cell in enumerate(runs.cells):
            if not matches(item.denominator, cell):
                continue
            partner = {**cell, **{k: str(v) for k, v in item.numerator.items()}}
            nj = [cj for cj, other in enumerate(runs.cells) if all(matches({k: v}, other) for k, v in partner.items())]
            if not nj:
                continue
            den = table[table.cell == ci].set_index("seed")
            num = table[table.cell == nj[0]].set_index("seed")
            ratio = (num[item.metric].astype(float) / den[item.metric].astype(float)).dropna()
            med, q25, q75 = quartiles(ratio)
            row = {**cell, "estimator": _ratio_name(item), "objective": den.objective.iloc[0], "metric": item.quantity,
                   "median": med, "q25": q25, "q75": q75, "n_seeds": len(ratio)}
            if "succeeded" in den and den.succeeded.notna().any():
                row["success_rate"] = fraction((num.succeeded * den.succeeded).reindex(ratio.index))
            rows.append(row)
    return rows


def table(runs, plot) -> pd.DataFrame:
    """Per cell and metric: quartiles (censored ones with extremes, :func:`magexp.artifacts.censoring.cell_quartiles`),
    success and converged rates, the floors and the median of ``plot.bound``; then the ratios, then each
    trend claim's fitted line and band against ``plot.x`` (:func:`magexp.artifacts.trends.figure_rows`)."""
    bound = plot.bound
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = cell_runs(runs, ci)
        for metric in metric_list(plot):
            row = {**cell, "estimator": sub.estimator.iloc[0], "objective": sub.objective.iloc[0],  # censored: inf
                   "metric": metric, **cell_quartiles(sub, metric), "n_seeds": len(sub)}
            if bound and bound in sub:
                row["bound"] = median(sub[bound])
            row.update({extra: median(sub[extra]) for extra in ("noise_floor", "truth_fun", "rms_bound") if extra in sub})
            if "converged" in sub:
                row["converged_fraction"] = fraction(sub.converged.astype(float))
            if "succeeded" in sub and sub.succeeded.notna().any():
                row["success_rate"] = fraction(sub.succeeded)
            rows.append(row)
    trend = trends.figure_rows(runs.spec, runs.table, plot.x, metric_list(plot)) if plot.x else []
    return pd.DataFrame(rows + _ratio_rows(runs) + trend)


def draw(table, spec, axes=None):
    """Draws each metric's median and quartiles against the swept key, with floors and levels
    (:func:`magexp.artifacts.plots.final.draw`)."""
    from magexp.artifacts.plots import final
    return final.draw(table, spec, axes)
