"""Every parameter estimate per cell: median and interquartile range over the successful seeds (the
failed ones counted in ``n_failed``), beside the truth and the paper's value (the tables of Yuan 2018).
Where the runs measure F_g (eq 8 at the estimate, the ``fg`` column), one more row per cell holds
its median and quartiles over every seed (parameter ``F_g``). The figure shows errors against the
truth, and F_g in a third panel with the paper's F_g; the legend gives each cell's success rate. The
offsets and F_g are in the readings' unit (``plot.unit``, :func:`magexp.artifacts.plots.style.unit`);
the matrix entries have none. The table: :func:`magexp.artifacts.kinds.parameters.table`."""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts.plot_keys import FIT
from magexp.artifacts.plots.style import panels, shared_legend, tidy_log_axes, unit


def _fit_panel(ax, frame, labels, colours, readings_unit: str):
    """F_g per cell (median, IQR over seeds; log axis) and the paper's F_g (open marker) where it gives one."""
    papers = 0
    for j, lab in enumerate(labels):
        row = frame[(frame.label == lab) & (frame.parameter == FIT[0])]
        if row.empty:
            continue
        r = row.iloc[0]
        ax.errorbar([j], [r["median"]], yerr=[[r["median"] - r.q25], [r.q75 - r["median"]]], fmt="o", ms=4,
                    capsize=2, lw=1, color=colours[lab])
        if np.isfinite(r.paper_value):
            ax.plot([j], [r.paper_value], "o", mfc="none", ms=7, mew=1.2, color=colours[lab])
            papers += 1
    ax.set_yscale("log")
    ax.set_xticks(range(len(labels)), [lab.replace("objective = ", "") for lab in labels], rotation=30, ha="right",
                  fontsize=7)
    ax.set_xlim(-0.6, len(labels) - 0.4)
    ax.set_ylabel(f"F_g, eq 8 at the estimate ({readings_unit})")
    ax.set_title("F_g" + (" (open: paper's)" if papers else " (the paper gives none)"), fontsize=8)


def _room(ax, values, linthresh: float):
    """Limits of a symlog axis that hold every value with a margin (a marker at the edge is cut)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if not v.size:
        return
    t = np.arcsinh(v / linthresh)  # symlog-like, smooth through 0
    lo, hi = t.min(), t.max()
    pad = 0.08 * max(hi - lo, 1.0)
    ax.set_ylim(linthresh * np.sinh(lo - pad), linthresh * np.sinh(hi + pad))


def draw(frame: pd.DataFrame, spec, axes=None):
    """Two panels (matrix entries, offsets): estimate minus truth, symlog axis; filled marker and
    bar: median and IQR over seeds; open marker: the paper's value minus the truth. A third panel
    shows F_g where the runs measure it.
    """
    names = [n for n in dict.fromkeys(frame.parameter) if n != FIT[0]]
    groups = [names[:9], names[9:]]
    labels = list(dict.fromkeys(frame.label))
    fit = (frame.parameter == FIT[0]).any()
    fig, axes = panels(3 if fit else 2, width=4.6 if fit else 5.2, height=3.4, axes=axes)
    colours = {}
    for ax, group, linthresh in zip(axes, groups, (1e-3, 0.1)):
        width = 0.8 / max(len(labels), 1)
        drawn = []
        for j, lab in enumerate(labels):
            sub = frame[(frame.label == lab) & frame.parameter.isin(group)].set_index("parameter").loc[group]
            x = np.arange(len(group)) - 0.4 + width * (j + 0.5)
            err = sub["median"] - sub.truth
            yerr = np.vstack([sub["median"] - sub.q25, sub.q75 - sub["median"]])
            rate = sub.success_rate.iloc[0] if "success_rate" in sub else np.nan
            line = ax.errorbar(x, err, yerr=yerr, fmt="o", ms=3.5, capsize=2, lw=1,
                               label=lab + (f" ({rate:.0%} ok)" if np.isfinite(rate) else ""),
                               color=colours.get(lab))
            colours[lab] = line[0].get_color()
            drawn += [err, sub.q25 - sub.truth, sub.q75 - sub.truth]
            if sub.paper_value.notna().any():
                ax.plot(x, sub.paper_value - sub.truth, "o", mfc="none", ms=6, color=colours[lab])
                drawn.append(sub.paper_value - sub.truth)
        ax.axhline(0, color="k", lw=0.8)
        ax.set_yscale("symlog", linthresh=linthresh)
        _room(ax, np.concatenate([np.asarray(d, float) for d in drawn]) if drawn else [], linthresh)
        ax.set_xticks(np.arange(len(group)), group)
    readings_unit = unit(spec)
    axes[0].set_ylabel("estimate - truth")
    axes[1].set_ylabel(f"estimate - truth ({readings_unit})")
    if fit:
        _fit_panel(axes[2], frame, labels, colours, readings_unit)
    shared_legend(fig, axes[:1], fontsize=7)
    if frame[frame.parameter != FIT[0]].paper_value.notna().any():
        axes[1].set_title("open: paper's value - truth", fontsize=8)
    fig.suptitle(spec.title, fontsize=10)
    return tidy_log_axes(fig)
