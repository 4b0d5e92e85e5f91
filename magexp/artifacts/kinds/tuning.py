"""The settings of one method as a distribution, beside its `default`; `names`: each estimator name's words on the x axis (default its label)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from magexp.artifacts.plot_keys import CommonPlot
from magexp.artifacts.schema import typed
from magexp.artifacts.tables import cell_overrides, cell_runs, fraction, median, quartiles
from magexp.run.compose import estimator_label


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``tuning``: ``metric`` (the runs column compared), ``label`` (the setting
    keys naming a bar), ``default`` (``{family: {key: value}}``: each family's default setting),
    ``names`` (``{estimator: words}``)."""

    metric: str = "fun"
    label: list[str] = field(default_factory=list)
    default: dict[str, dict[str, Any]] = field(default_factory=dict)
    names: dict[str, str] = field(default_factory=dict)


def _rate(values) -> float:
    """The success rate of the known 0/1 ``values`` (:func:`fraction`)."""
    return fraction(pd.Series(values).dropna().astype(float))


def table(runs, plot) -> pd.DataFrame:
    """One row per setting (cell), with per (family, scenario) the ``best``, ``median`` and ``worst``
    setting by the median metric (:mod:`magexp.artifacts.plots.tuning`)."""
    spec = runs.spec
    defaults = {k: {kk: str(vv) for kk, vv in v.items()} for k, v in plot.default.items()}
    frame = pd.DataFrame([_setting_row(runs, ci, defaults) for ci in range(len(runs.cells))])
    frame["role"] = ""
    for _, idx in frame.groupby(["family", "scenario"], sort=False).groups.items():
        group = frame.loc[idx].sort_values("median", kind="stable")
        if len(group) >= 3:
            frame.loc[group.index[0], "role"] = "best"
            frame.loc[group.index[len(group) // 2], "role"] = "median"
            frame.loc[group.index[-1], "role"] = "worst"
    return frame


ESTIMATOR_KEYS = {"estimator", "estimator.name"}  # the settings naming an estimator: in words in a legend


def family_words(spec, family: str) -> str:
    """An estimator's name in words on a tuning figure: ``plot.names[family]``, else its label."""
    return str(dict(spec.plot.get("names", {}) or {}).get(family) or estimator_label(family))


def _setting_row(runs, ci: int, defaults: dict) -> dict:
    """The row of cell ``ci``; ``defaults``: ``plot.default`` with text values."""
    spec = runs.spec
    metric = spec.plot.get("metric", "fun")
    short = dict(spec.plot.get("labels", {}) or {})
    sub = cell_runs(runs, ci)
    family = str(sub.estimator.iloc[0])
    settings = cell_overrides(runs, ci)
    named = {**settings, **{k: family_words(spec, settings[k]) for k in ESTIMATOR_KEYS & set(settings)}}
    label = ", ".join(f"{short.get(k, k.split('.')[-1])} = {named[k]}" for k in spec.plot.get("label", []) if k in named)
    med, q25, q75 = quartiles(sub[metric])
    default = family in defaults and all(settings.get(k) == v for k, v in defaults[family].items())
    rate = _rate(sub["succeeded"]) if "succeeded" in sub and sub.succeeded.notna().any() else (
        _rate(sub["converged"]) if "converged" in sub else np.nan)  # else converged: the 1 % rule
    return {"family": family, "family_label": family_words(spec, family), "label": label or family,
            "scenario": str(sub.scenario.iloc[0]), "metric": metric, "median": med, "q25": q25, "q75": q75, "n_seeds": len(sub), "success_rate": rate,
            "bound_success_rate": _rate(sub["offset_error_ratio"] <= 2.0) if "offset_error_ratio" in sub else np.nan,
            "on_boundary_rate": _rate(sub["on_boundary"] > 0) if "on_boundary" in sub else np.nan,
            **{c: median(sub[c]) if c in sub else np.nan for c in ("offset_error_ratio", "wall_time", "nfev_to_1.1")},
            "default": default, "setting": sub.setting.iloc[0]}


def draw(table, spec, axes=None):
    """Draws the distribution of the metric over the settings of one method, beside its default
    (:func:`magexp.artifacts.plots.tuning.draw`)."""
    from magexp.artifacts.plots import tuning
    return tuning.draw(table, spec, axes)
