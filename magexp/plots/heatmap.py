"""Heat map estimator x case of the bound ratio (RMS over seeds of offset error / sqrt(tr CRB)).

Colour: log10 of the ratio on a diverging scale centred at 1 (the efficient value): at or below
1 green, above it yellow to red; a cell where fewer than half the runs succeeded is hatched and
outlined in black, whatever its ratio. Each cell prints the ratio, its 95 % interval and the
success rate."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import TwoSlopeNorm
from matplotlib.patches import Rectangle

from magexp.plots.benchmark_table import tabulate  # noqa: F401  (the kind's table)
from magexp.plots.style import plt


def draw(frame, spec, ax=None):
    value = spec.plot.get("metric", "bound_ratio")
    cases = list(dict.fromkeys(frame.case))
    estimators = list(dict.fromkeys(frame.estimator))
    index = {(r.estimator, r.case): r for _, r in frame.iterrows()}
    grid = np.full((len(estimators), len(cases)), np.nan)
    for (est, case), r in index.items():
        grid[estimators.index(est), cases.index(case)] = r[value]
    fig, ax = (ax.figure, ax) if ax is not None else plt.subplots(figsize=(1.3 + 1.15 * len(cases), 1.4 + 0.62 * len(estimators)), layout="constrained")
    shown = np.log10(np.clip(grid, 1e-2, 1e4))
    im = ax.imshow(shown, cmap="RdYlGn_r", norm=TwoSlopeNorm(vmin=-0.5, vcenter=0.0, vmax=2.0), aspect="auto")
    for (est, case), r in index.items():
        i, j = estimators.index(est), cases.index(case)
        v = r[value]
        text = "—" if not np.isfinite(v) else f"{v:.3g}"
        if np.isfinite(v) and f"{value}_lo" in r and np.isfinite(r[f"{value}_lo"]):
            text += f"\n[{r[f'{value}_lo']:.2g}, {r[f'{value}_hi']:.2g}]"
        if np.isfinite(r.get("success_rate", np.nan)):
            text += f"\n{r.success_rate:.0%} ok"
            if r.success_rate < 0.5:  # failures stand out whatever their ratio
                ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, hatch="///", ec="k", lw=1.5))
        dark = np.isfinite(v) and shown[i, j] > 1.2  # white on the dark red cells
        ax.text(j, i, text, ha="center", va="center", fontsize=6, color="w" if dark else "k")
    ax.set_xticks(range(len(cases)), cases, rotation=40, ha="right")
    ax.set_yticks(range(len(estimators)), estimators)
    ax.grid(False)
    bar = fig.colorbar(im, ax=ax, shrink=0.8)
    bar.set_label("log10 RMS(offset error / sqrt(tr CRB)); 0 = efficient")
    ax.set_title(spec.title, fontsize=10)
    return fig
