"""Final values per cell against a swept key: median and interquartile bars over seeds (the kinds
``final`` and ``sweep``, one kind).

``plot.x``: the swept grid key; ``plot.metric``: one runs column or a list of them (one row of
panels each; default ``fun``); ``plot.hue``: one line per value (default ``estimator``; a list of keys:
one line per combination); ``plot.panels``: one column of panels per value; ``plot.xscale``:
``linear``, ``log`` or ``symlog`` (with ``plot.linthresh``, for sweeps that include 0);
``plot.ylog`` (default true); ``plot.ylabel`` / ``plot.ylabels`` (per metric); ``plot.bound``: a
bound column of the metric drawn per objective (e.g. ``offset_bound``); ``plot.targets``:
``{metric: value}`` drawn dashed (e.g. a paper's stated accuracy). Against the objective ``fun`` the
noise floor and the Cramér-Rao RMS floor are drawn. A cell where fewer than half the runs succeeded
is ringed in red.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts import quantiles
from magexp.plots.style import group_values, label, panels

TINY = 1e-14  # log axes: values at or below zero are drawn here


def metric_list(spec) -> list[str]:
    """The metric columns drawn (``plot.metric``: one name or a list)."""
    metric = spec.plot.get("metric", "fun")
    return [metric] if isinstance(metric, str) else list(metric)


def tabulate(runs) -> pd.DataFrame:
    """Per cell and metric: median and quartiles, the success rate and converged fraction, the
    floors (``noise_floor``, ``truth_fun``, ``rms_bound``) and the median of ``plot.bound``."""
    bound = runs.spec.plot.get("bound")
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = runs.table[runs.table.cell == ci]
        for metric in metric_list(runs.spec):
            med, q25, q75 = quantiles(sub[metric]) if metric in sub else (np.nan,) * 3
            row = {**cell, "estimator": sub.estimator.iloc[0], "objective": sub.objective.iloc[0],
                   "metric": metric, "median": med, "q25": q25, "q75": q75, "n_seeds": len(sub)}
            if bound and bound in sub:
                row["bound"] = quantiles(sub[bound])[0]
            for extra in ("noise_floor", "truth_fun", "rms_bound"):
                if extra in sub:
                    row[extra] = float(sub[extra].median())
            if "converged" in sub:
                row["converged_fraction"] = float(sub.converged.astype(float).mean())
            if "succeeded" in sub and sub.succeeded.notna().any():
                row["success_rate"] = float(sub.succeeded.dropna().mean())
            rows.append(row)
    return pd.DataFrame(rows)


def _lines(ax, sub, spec, x_key, hue_key):
    """One errorbar line per hue value (slightly spread on the x axis), failed majorities ringed."""
    hues = group_values(sub, hue_key)
    for k, hv in enumerate(hues):
        line = sub[sub[hue_key] == hv].sort_values(x_key, key=lambda c: c.astype(float))
        x = line[x_key].astype(float).to_numpy() * (1 + 0.03 * (k - (len(hues) - 1) / 2))
        y = line["median"].to_numpy(float)
        err = np.vstack([y - line.q25.to_numpy(float), line.q75.to_numpy(float) - y])
        name = label(spec, hue_key, hv) if hue_key not in ("estimator", "_hue") else str(hv)
        ax.errorbar(x, np.maximum(y, TINY), yerr=np.where(np.isfinite(err), np.maximum(err, 0), 0), marker="o",
                    ms=3.5, capsize=2, lw=1, label=name)
        if "success_rate" in line:
            bad = (line.success_rate < 0.5).to_numpy()
            ax.plot(x[bad], np.maximum(y[bad], TINY), "o", mfc="none", mec="r", ms=9, mew=1.2,
                    label="fewer than half succeeded" if bad.any() else None)


def _references(ax, sub, spec, x_key, metric):
    """The bound per objective, the floors (against ``fun``) and the paper's target."""
    if "bound" in sub and sub.bound.notna().any():  # the bound belongs to the problem: one per objective
        objectives = list(dict.fromkeys(sub.objective))
        for j, obj in enumerate(objectives):
            fl = sub[sub.objective == obj].drop_duplicates(x_key).sort_values(x_key, key=lambda c: c.astype(float))
            name = "Cramér-Rao bound (Gaussian)" + (f" ({obj})" if len(objectives) > 1 else "")
            ax.plot(fl[x_key].astype(float), fl.bound.clip(lower=TINY), ["k--", "k-."][j % 2], lw=0.9, label=name)
    fl = sub.drop_duplicates(x_key).sort_values(x_key, key=lambda c: c.astype(float))
    if metric == "fun" and "noise_floor" in sub:
        ax.plot(fl[x_key].astype(float), fl.noise_floor.clip(lower=TINY), "k--", lw=0.9, label="noise floor")
    if metric == "fun" and "rms_bound" in sub:
        ax.plot(fl[x_key].astype(float), fl.rms_bound.clip(lower=TINY), ":", color="0.4", lw=1.1,
                label="Cramér-Rao floor (Gaussian)")
    targets = dict(spec.plot.get("targets", {}) or {})
    if metric in targets:
        ax.axhline(float(targets[metric]), color="k", ls="--", lw=0.9, label="paper's stated level")


def draw(frame: pd.DataFrame, spec, axes=None):
    x_key, panel_key, hue_key = spec.plot.x, spec.plot.get("panels"), spec.plot.get("hue", "estimator")
    if not isinstance(hue_key, str):  # several keys: one line per combination
        keys = list(hue_key)
        frame = frame.assign(_hue=frame[keys].astype(str).agg(" / ".join, axis=1))
        hue_key = "_hue"
    metrics, columns = metric_list(spec), group_values(frame, panel_key)
    ylabels = dict(spec.plot.get("ylabels", {}) or {})
    default_ylabel = spec.plot.get("ylabel", "final total-field RMS (nT)")
    fig, axes = panels(len(metrics) * len(columns), rows=len(metrics) if len(columns) > 1 else 1,
                       width=3.8 if len(metrics) > 1 else 3.4, axes=axes)
    for i, metric in enumerate(metrics):
        for j, pv in enumerate(columns):
            ax = axes[i * len(columns) + j]
            sub = frame[frame.metric == metric] if "metric" in frame else frame
            sub = sub if pv is None else sub[sub[panel_key] == pv]
            _lines(ax, sub, spec, x_key, hue_key)
            _references(ax, sub, spec, x_key, metric)
            scale = spec.plot.get("xscale", "linear")
            ax.set_xscale(scale, **({"linthresh": float(spec.plot.get("linthresh", 1.0))} if scale == "symlog" else {}))
            if scale == "symlog" and (frame[x_key].astype(float) >= 0).all():
                ax.set_xlim(left=0)
            if spec.plot.get("ylog", True):
                ax.set_yscale("log")
            ax.set_xlabel(label(spec, x_key))
            ax.set_ylabel(ylabels.get(metric, default_ylabel if len(metrics) == 1 else metric))
            if pv is not None:
                ax.set_title(str(pv) if panel_key == "scenario" else label(spec, panel_key, pv))
    handles, names = axes[0].get_legend_handles_labels()
    unique = dict(zip(names, handles))
    axes[0].legend(unique.values(), unique.keys())
    fig.suptitle(spec.title, fontsize=10)
    return fig
