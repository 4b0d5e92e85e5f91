"""Heat map estimator x case of the median error relative to the Cramér-Rao bound."""

from __future__ import annotations

import numpy as np

from magexp.plots.benchmark_table import tabulate  # noqa: F401  (the kind's table)
from magexp.plots.style import plt


def draw(frame, spec, ax=None):
    value = spec.plot.get("value", "offset_error_ratio")
    cases = list(dict.fromkeys(frame.case))
    estimators = list(dict.fromkeys(frame.estimator))
    grid = np.full((len(estimators), len(cases)), np.nan)
    for _, r in frame.iterrows():
        grid[estimators.index(r.estimator), cases.index(r.case)] = r[value]
    fig, ax = (ax.figure, ax) if ax is not None else plt.subplots(
        figsize=(1.0 + 0.95 * len(cases), 1.2 + 0.5 * len(estimators)), layout="constrained")
    shown = np.log10(np.clip(grid, 1e-2, 1e4))
    im = ax.imshow(shown, cmap="RdYlGn_r", vmin=0, vmax=3, aspect="auto")
    for i in range(len(estimators)):
        for j in range(len(cases)):
            v = grid[i, j]
            ax.text(j, i, "—" if not np.isfinite(v) else f"{v:.3g}", ha="center", va="center", fontsize=7)
    ax.set_xticks(range(len(cases)), cases, rotation=40, ha="right")
    ax.set_yticks(range(len(estimators)), estimators)
    ax.grid(False)
    bar = fig.colorbar(im, ax=ax, shrink=0.8)
    bar.set_label(f"log10 median {value.replace('_', ' ')}")
    ax.set_title(spec.title, fontsize=10)
    return fig
