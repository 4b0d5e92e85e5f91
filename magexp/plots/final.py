"""Final objective per cell (median, IQR, converged fraction, success rate) and its plot against a swept key;
a cell where fewer than half the runs succeeded is ringed in red."""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts import quantiles
from magexp.plots.style import group_values, label, panels


def tabulate(runs) -> pd.DataFrame:
    """Per cell: median and quartiles of ``plot.metric`` (default ``fun``), the floors, and
    the median of ``plot.bound`` (a bound column of the metric, e.g. ``offset_bound``)."""
    metric = runs.spec.plot.get("metric", "fun")
    bound = runs.spec.plot.get("bound")
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = runs.table[runs.table.cell == ci]
        med, q25, q75 = quantiles(sub[metric])
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


def draw(frame: pd.DataFrame, spec):
    x_key, panel_key, hue_key = spec.plot.x, spec.plot.get("panels"), spec.plot.get("hue", "estimator")
    if not isinstance(hue_key, str):  # several keys: one line per combination
        keys = list(hue_key)
        frame = frame.assign(_hue=frame[keys].astype(str).agg(" / ".join, axis=1))
        hue_key = "_hue"
    on_objective = frame["metric"].iloc[0] == "fun" if "metric" in frame else True
    values = group_values(frame, panel_key)
    fig, axes = panels(len(values))
    for ax, pv in zip(axes, values):
        sub = frame if pv is None else frame[frame[panel_key] == pv]
        hues = group_values(sub, hue_key)
        for k, hv in enumerate(hues):
            line = sub[sub[hue_key] == hv]
            x = line[x_key].astype(float).to_numpy() * (1 + 0.03 * (k - (len(hues) - 1) / 2))
            y = line["median"].clip(lower=1e-14)
            err = np.vstack([y - line.q25.clip(lower=1e-14), line.q75.clip(lower=1e-14) - y])
            ax.errorbar(x, y, yerr=err, marker="o", ms=3.5, capsize=2, lw=1, label=str(hv))
            if "success_rate" in line:  # a failed majority stands out: a red ring around the median
                bad = (line.success_rate < 0.5).to_numpy()
                ax.plot(x[bad], y.to_numpy()[bad], "o", mfc="none", mec="r", ms=9, mew=1.2,
                        label="fewer than half succeeded" if bad.any() and k == 0 else None)
        if "bound" in sub and sub.bound.notna().any():  # the bound belongs to the problem: one per objective
            objectives = list(dict.fromkeys(sub.objective))
            for j, obj in enumerate(objectives):
                fl = sub[sub.objective == obj].drop_duplicates(x_key)
                name = "Cramér-Rao bound" + (f" ({obj})" if len(objectives) > 1 else "")
                ax.plot(fl[x_key].astype(float), fl.bound.clip(lower=1e-14), ["k--", "k-."][j % 2], lw=0.9,
                        label=name)
        if "noise_floor" in sub and on_objective:
            fl = sub.drop_duplicates(x_key)
            ax.plot(fl[x_key].astype(float), fl.noise_floor.clip(lower=1e-14), "k--", lw=0.9, label="noise floor")
        if "rms_bound" in sub and on_objective:
            fl = sub.drop_duplicates(x_key)
            ax.plot(fl[x_key].astype(float), fl.rms_bound.clip(lower=1e-14), ":", color="0.4", lw=1.1,
                    label="Cramér-Rao floor")
        ax.set_yscale("log")
        if spec.plot.get("xscale"):
            ax.set_xscale(spec.plot.xscale)
        ax.set_xlabel(label(spec, x_key))
        ax.set_ylabel(spec.plot.get("ylabel", "final total-field RMS (nT)"))
        if pv is not None:
            ax.set_title(str(pv) if panel_key == "scenario" else label(spec, panel_key, pv))
    axes[0].legend()
    fig.suptitle(spec.title, fontsize=10)
    return fig
