"""Heat map estimator x case of one column of the benchmark table (default: the bound ratio).

Colour: log10 of the column on a diverging scale centred at 1 (the efficient value): at or below
1 green, above it yellow to red. The bound ratio is computed over the successful runs only
(:mod:`magexp.artifacts.plots.benchmark_table`); failures never enter a colour: a cell with failed runs is
hatched (``//`` when some failed, ``xx`` when at least half did) and prints how many. Each cell prints
the value, its 95 % interval (where the table has one) and the failures or the success rate. The colour
bar names the column drawn (:func:`magexp.artifacts.plots.style.colorbar`).
"""

from __future__ import annotations

import numpy as np
from matplotlib.colors import TwoSlopeNorm
from matplotlib.patches import Rectangle

from magexp.artifacts.plots.benchmark_table import column_label, tabulate  # noqa: F401  (tabulate: the kind's interface, kind_module(kind).tabulate)
from magexp.artifacts.plots.style import colorbar, drawn_from, plt


def readable_case(case: str) -> str:
    """A case's tick label: ``key=value`` settings as ``key = value`` on their own line, unset ones
    (``=null``) left out."""
    parts = str(case).split(" ")
    settings = [p.replace("=", " = ") for p in parts[1:] if "=" in p and not p.endswith("=null")]
    return "\n".join([parts[0], *settings])


def _failures(r) -> tuple[str, str | None]:
    """The failure line of a cell and its hatch (None: no failure, or no run judged)."""
    rate, n = r.get("success_rate", np.nan), int(r.get("n_seeds", 0))
    if not np.isfinite(rate):
        return "", None
    failed = int(r["n_failed"]) if "n_failed" in r and np.isfinite(r["n_failed"]) else int(round((1 - rate) * n))
    if failed == 0:
        return f"\nall {n} ok", None
    return f"\n{failed} of {n} failed", "xx" if failed >= n / 2 else "//"


def draw(frame, spec, ax=None):
    value = spec.plot.get("metric", "bound_ratio")
    cases = list(dict.fromkeys(frame.case))
    estimators = list(dict.fromkeys(frame.estimator))
    index = {(r.estimator, r.case): r for _, r in frame.iterrows()}
    grid = np.full((len(estimators), len(cases)), np.nan)
    for (est, case), r in index.items():
        grid[estimators.index(est), cases.index(case)] = r[value]
    fig, ax = (ax.figure, ax) if ax is not None else plt.subplots(
        figsize=(max(7.0, 2.2 + 1.2 * len(cases)), 1.6 + 0.5 * len(estimators)), layout="constrained")
    shown = np.log10(np.clip(grid, 1e-2, 1e4))
    im = drawn_from(ax.imshow(shown, cmap="RdYlGn_r", norm=TwoSlopeNorm(vmin=-0.5, vcenter=0.0, vmax=2.0),
                              aspect="auto"), value)
    for (est, case), r in index.items():
        i, j = estimators.index(est), cases.index(case)
        v = r[value]
        text = "—" if not np.isfinite(v) else f"{v:.3g}"
        if np.isfinite(v) and f"{value}_lo" in r and np.isfinite(r[f"{value}_lo"]):
            text += f"\n[{r[f'{value}_lo']:.2g}, {r[f'{value}_hi']:.2g}]"
        line, hatch = _failures(r)
        text += line
        if hatch:
            ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, hatch=hatch, ec="k", lw=0.8, alpha=0.6))
        dark = np.isfinite(v) and shown[i, j] > 1.2  # white on the dark red cells
        ax.text(j, i, text, ha="center", va="center", fontsize=6, color="w" if dark else "k",
                bbox={"boxstyle": "round,pad=0.15", "fc": "none" if not hatch else ("0.15" if dark else "w"),
                      "ec": "none", "alpha": 0.8})
    ax.set_xticks(range(len(cases)), [readable_case(c) for c in cases], rotation=35, ha="right", fontsize=7)
    ax.set_yticks(range(len(estimators)), estimators)
    ax.grid(False)
    colorbar(im, ax, column=value, label=f"log10 {column_label(value)}\n(0: at the bound)", shrink=0.8)
    ax.set_title(spec.title, fontsize=10)
    return fig
