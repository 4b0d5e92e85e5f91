"""Chosen metrics against a swept key: median and interquartile bars over seeds.

``plot.metrics``: the metrics, one row of panels each; ``plot.x``: the swept grid key;
``plot.hue``: one line per value (default ``estimator``); ``plot.panels``: one column of
panels per value (optional); ``plot.xscale``: ``linear``, ``log`` or ``symlog`` (with
``plot.linthresh``, for sweeps that include 0); ``plot.targets``: ``{metric: value}`` drawn
as a dashed line (e.g. a paper's stated accuracy).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts import quantiles
from magexp.plots.style import group_values, label, panels


def metric_list(spec) -> list[str]:
    """The metric columns drawn (``plot.metric``: one name or a list)."""
    metric = spec.plot.get("metric", "fun")
    return [metric] if isinstance(metric, str) else list(metric)


def tabulate(runs) -> pd.DataFrame:
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = runs.table[runs.table.cell == ci]
        for metric in metric_list(runs.spec):
            med, q25, q75 = quantiles(sub[metric]) if metric in sub else (np.nan,) * 3
            rows.append({**cell, "estimator": sub.estimator.iloc[0], "metric": metric, "median": med, "q25": q25,
                         "q75": q75, "n_seeds": len(sub)})
    return pd.DataFrame(rows)


def draw(frame: pd.DataFrame, spec):
    x_key, hue_key, panel_key = spec.plot.x, spec.plot.get("hue", "estimator"), spec.plot.get("panels")
    metrics, columns = metric_list(spec), group_values(frame, panel_key)
    targets = dict(spec.plot.get("targets", {}) or {})
    ylabels = dict(spec.plot.get("ylabels", {}) or {})
    fig, axes = panels(len(metrics) * len(columns), rows=len(metrics) if len(columns) > 1 else 1, width=3.8)
    for i, metric in enumerate(metrics):
        for j, pv in enumerate(columns):
            ax = axes[i * len(columns) + j]
            sub = frame[frame.metric == metric]
            sub = sub if pv is None else sub[sub[panel_key] == pv]
            for hv in group_values(sub, hue_key):
                line = sub[sub[hue_key] == hv].sort_values(x_key, key=lambda c: c.astype(float))
                y = line["median"].to_numpy(float)
                err = np.vstack([y - line.q25.to_numpy(float), line.q75.to_numpy(float) - y])
                ax.errorbar(line[x_key].astype(float), y, yerr=np.where(np.isfinite(err), err, 0), marker="o", ms=3,
                            capsize=2, lw=1, label=label(spec, hue_key, hv) if hue_key != "estimator" else str(hv))
            if metric in targets:
                ax.axhline(float(targets[metric]), color="k", ls="--", lw=0.9, label="paper's stated level")
            scale = spec.plot.get("xscale", "log")
            ax.set_xscale(scale, **({"linthresh": float(spec.plot.get("linthresh", 1.0))} if scale == "symlog" else {}))
            if scale == "symlog" and (frame[x_key].astype(float) >= 0).all():
                ax.set_xlim(left=0)
            if spec.plot.get("ylog", True):
                ax.set_yscale("log")
            ax.set_xlabel(label(spec, x_key))
            ax.set_ylabel(ylabels.get(metric, metric))
            if pv is not None:
                ax.set_title(label(spec, panel_key, pv))
    axes[0].legend()
    fig.suptitle(spec.title, fontsize=10)
    return fig
