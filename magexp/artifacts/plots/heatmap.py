"""Heat map estimator x case of one column of the benchmark table (default: the bound ratio).

Colour and text on one scale: each cell is coloured by the value it prints, on a logarithmic colour
scale symmetric about 1 (the efficient value): at or below 1 green, above it yellow to red; the
colour bar is labelled in the ratio itself (0.5, 1, 2), not in its logarithm. The bound ratio is
computed over the successful runs only (:func:`magexp.artifacts.kinds.heatmap.table`); failures
never enter a colour: a cell with failed runs is hatched (``//`` when some failed, ``xx`` when fewer
than half succeeded, :func:`magexp.core.outcomes.failed_majority`) and prints how many. Each cell prints the value, its 95 % interval (where the table
has one) and the failures, in :data:`CELL_POINTS` type. A case where no estimator has a value (no
truth, so no bound) is left out of the map (it stays in the table). The colour bar names the column
drawn (:func:`magexp.artifacts.plots.style.colorbar`).
"""

from __future__ import annotations

import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.patches import Rectangle

from magexp.artifacts.columns import column_label
from magexp.artifacts.plots.style import colorbar, drawn_from, narrow_log_ticks, plt
from magexp.core.outcomes import failed_majority


def readable_case(case: str) -> str:
    """A case's tick label: ``key=value`` settings as ``key = value`` on their own line, unset ones
    (``=null``) left out.
    """
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
    return f"\n{failed} of {n} failed", "xx" if failed_majority(rate) else "//"


#: type size of the cells' text (points at the saved size)
CELL_POINTS = 8.0
#: the colour scale's half range (a ratio): the smallest of these that holds every value, or the largest
SCALE_RANGES = (2.0, 3.0, 5.0, 10.0, 100.0, 1.0e4)


def colour_range(values: np.ndarray) -> float:
    """``R`` of the colour scale ``[1/R, R]``: the smallest of :data:`SCALE_RANGES` that holds every
    finite positive value (ratios above or below 1 by the same factor get the same depth of colour).
    """
    v = values[np.isfinite(values) & (values > 0)]
    widest = float(np.max(np.maximum(v, 1 / v))) if v.size else 1.0
    return next((r for r in SCALE_RANGES if r >= widest), SCALE_RANGES[-1])


def _cell_text(r, value: str) -> tuple[str, str | None]:
    """A cell's text (value, interval, failures) and its hatch."""
    v = r[value]
    text = "—" if not np.isfinite(v) else f"{v:.3g}"
    if np.isfinite(v) and f"{value}_lo" in r and np.isfinite(r[f"{value}_lo"]):
        text += f"\n[{r[f'{value}_lo']:.2g}, {r[f'{value}_hi']:.2g}]"
    line, hatch = _failures(r)
    return text + line, hatch


def draw(frame, spec, ax=None):
    """Estimator against case, coloured by ``plot.metric`` (default the error over the Cramér-Rao bound)."""
    value = spec.plot.get("metric", "bound_ratio")
    valued = set(frame.case[np.isfinite(frame[value].astype(float))])
    frame = frame[frame.case.isin(valued)]  # a case with no value anywhere: in the table only
    cases = list(dict.fromkeys(frame.case))
    estimators = list(dict.fromkeys(frame.estimator))
    index = {(r.estimator, r.case): r for _, r in frame.iterrows()}
    grid = np.full((len(estimators), len(cases)), np.nan)
    for (est, case), r in index.items():
        grid[estimators.index(est), cases.index(case)] = r[value]
    fig, ax = (ax.figure, ax) if ax is not None else plt.subplots(
        figsize=(max(7.0, 2.6 + 1.25 * len(cases)), 1.9 + 0.55 * len(estimators)), layout="constrained")
    span = colour_range(grid)
    im = drawn_from(ax.imshow(np.where(grid > 0, grid, np.nan), cmap="RdYlGn_r", norm=LogNorm(vmin=1 / span, vmax=span),
                              aspect="auto"), value)
    for (est, case), r in index.items():
        i, j = estimators.index(est), cases.index(case)
        text, hatch = _cell_text(r, value)
        if hatch:
            ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, hatch=hatch, ec="k", lw=0.8, alpha=0.6))
        dark = bool(np.isfinite(grid[i, j]) and grid[i, j] > span ** 0.6)  # white on the dark red cells
        ax.text(j, i, text, ha="center", va="center", fontsize=CELL_POINTS, color="w" if dark else "k",
                bbox={"boxstyle": "round,pad=0.15", "fc": "none" if not hatch else ("0.15" if dark else "w"),
                      "ec": "none", "alpha": 0.8})
    ax.set_xticks(range(len(cases)), [readable_case(c) for c in cases], rotation=35, ha="right", fontsize=8)
    ax.set_yticks(range(len(estimators)), estimators)
    ax.grid(False)
    bar = colorbar(im, ax, column=value, label=f"{column_label(value)}\n(log colour scale; 1: at the bound)", shrink=0.8)
    ticks = narrow_log_ticks(1 / span, span, at_least=5) if span < 10 else [t for t in 10.0 ** np.arange(-8, 9) if 1 / span <= t <= span]
    bar.set_ticks(ticks, labels=[f"{t:g}" for t in ticks])  # the ratio, as the cells print it
    bar.minorticks_off()
    ax.set_title(spec.title, fontsize=10)
    return fig
