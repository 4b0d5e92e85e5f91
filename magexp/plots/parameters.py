"""Every parameter estimate per cell: median and interquartile range over the successful seeds (the
failed ones counted in ``n_failed``), beside the truth and the paper's value (the tables of Yuan 2018).
The figure shows errors against the truth; the legend gives each cell's success rate."""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts import quantiles
from magexp.plots.style import panels
from magexp.summary import cell_settings, parameter_values, reported_value


def cell_label(cell: dict, estimator: str) -> str:
    """A short legend text of a cell: its swept values, with the estimator first."""
    rest = [f"{k.split('.')[-1]}={v}" for k, v in cell.items() if k != "estimator"]
    return ", ".join([estimator] + rest)


def tabulate(runs) -> pd.DataFrame:
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = runs.table[runs.table.cell == ci]
        names, values, truth = parameter_values(runs, ci)
        settings = cell_settings(runs, ci)
        ok = sub.sort_values("seed")["succeeded"].to_numpy(float) if "succeeded" in sub else np.full(len(values), np.nan)
        judged = np.isfinite(ok)
        kept = values[ok == 1] if judged.any() else values  # over the successful runs; failures counted beside
        for k, name in enumerate(names):
            med, q25, q75 = quantiles(kept[:, k])
            paper, _ = reported_value(runs.spec, name, settings)
            rows.append({**cell, "label": cell_label(cell, sub.estimator.iloc[0]), "estimator": sub.estimator.iloc[0],
                         "objective": sub.objective.iloc[0], "parameter": name,
                         "truth": np.nan if truth is None else float(truth[k]), "median": med, "q25": q25,
                         "q75": q75, "paper_value": np.nan if paper is None else paper, "n_seeds": len(values),
                         "n_failed": int((ok[judged] == 0).sum()),
                         "success_rate": float(ok[judged].mean()) if judged.any() else np.nan})
    return pd.DataFrame(rows)


def draw(frame: pd.DataFrame, spec, axes=None):
    """Two panels (matrix entries, offsets): estimate minus truth, symlog axis; filled marker and
    bar: median and IQR over seeds; open marker: the paper's value minus the truth."""
    names = list(dict.fromkeys(frame.parameter))
    groups = [names[:9], names[9:]]
    labels = list(dict.fromkeys(frame.label))
    fig, axes = panels(2, width=5.2, height=3.2, axes=axes)
    for ax, group, linthresh in zip(axes, groups, (1e-3, 0.1)):
        width = 0.8 / max(len(labels), 1)
        for j, lab in enumerate(labels):
            sub = frame[(frame.label == lab) & frame.parameter.isin(group)].set_index("parameter").loc[group]
            x = np.arange(len(group)) - 0.4 + width * (j + 0.5)
            err = sub["median"] - sub.truth
            yerr = np.vstack([sub["median"] - sub.q25, sub.q75 - sub["median"]])
            rate = sub.success_rate.iloc[0] if "success_rate" in sub else np.nan
            line = ax.errorbar(x, err, yerr=yerr, fmt="o", ms=3.5, capsize=2, lw=1,
                               label=lab + (f" ({rate:.0%} ok)" if np.isfinite(rate) else ""))
            if sub.paper_value.notna().any():
                ax.plot(x, sub.paper_value - sub.truth, "o", mfc="none", ms=6, color=line[0].get_color())
        ax.axhline(0, color="k", lw=0.8)
        ax.set_yscale("symlog", linthresh=linthresh)
        ax.set_xticks(np.arange(len(group)), group)
        ax.set_ylabel("estimate - truth")
    axes[0].legend(loc="best", fontsize=7)
    axes[1].set_title("open: paper's value - truth", fontsize=8)
    fig.suptitle(spec.title, fontsize=10)
    return fig
