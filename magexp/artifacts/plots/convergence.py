"""RMS (objective) of the best particle vs iteration: median over seeds with an interquartile band
(the table: :func:`magexp.artifacts.kinds.convergence.table`).

A triangle on each curve marks the median, over the successful runs, of the iterations a run took to
come within 1.1 x its own final value (``iterations_to_1.1``): how fast it converged, whatever the
level it converged to."""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts.plots.style import group_values, label, panels, plt, shared_legend, tidy_log_axes


def draw(frame: pd.DataFrame, spec, axes=None):
    """The best objective against the iteration: median line and IQR band per cell, a panel per ``plot.panels``."""
    panel_key, hue_key = spec.plot.get("panels"), spec.plot.get("hue")
    panel_vals = group_values(frame, panel_key)
    fig, axes = panels(len(panel_vals), axes=axes)
    cycle = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    colours = {hv: cycle[k % len(cycle)] for k, hv in enumerate(group_values(frame, hue_key))}
    for ax, pv in zip(axes, panel_vals):
        sub = frame if pv is None else frame[frame[panel_key] == pv]
        counts = []
        for hv in group_values(sub, hue_key):
            line = sub if hv is None else sub[sub[hue_key] == hv]
            lab, count = _line_label(spec, line, hue_key, hv, one_panel=len(panel_vals) == 1)
            counts += [count] if count else []
            _draw_line(ax, sub, line, lab, colours[hv])
        _draw_references(ax, sub)
        _dress_panel(ax, spec, "" if pv is None else label(spec, panel_key, pv), counts)
    shared_legend(fig, axes, ncols=3)
    fig.suptitle(spec.title, fontsize=10)
    return tidy_log_axes(fig)


def _line_label(spec, line: pd.DataFrame, hue_key, hv, *, one_panel: bool) -> tuple[str, str]:
    """A line's legend label and its success count for the panel title: with one panel the count
    goes into the legend (``lm (28/30 ok)``), with several into each panel's title (the legend is
    shared); '' where it went into the legend or the runs are not judged."""
    lab = line.estimator.iloc[0] if hue_key in (None, "estimator") else label(spec, hue_key, hv)
    ok = int(line.succeeded.iloc[0]) if "succeeded" in line else -1
    if ok < 0:
        return lab, ""
    if one_panel:
        return lab + f" ({ok}/{line.n_seeds.iloc[0]} ok)", ""
    return lab, f"{lab} {ok}/{line.n_seeds.iloc[0]}"


def _draw_line(ax, sub: pd.DataFrame, line: pd.DataFrame, lab: str, colour) -> None:
    """One line of panel ``sub``: the median over seeds with its interquartile band, a triangle at
    the median iterations to 1.1 x final, and its own noise floor when the panel's lines differ in it."""
    floor_pos = line[["median", "q25", "q75"]].clip(lower=1e-14)
    (ln,) = ax.plot(line.iteration, floor_pos["median"], lw=1.2, label=lab, color=colour)
    ax.fill_between(line.iteration, floor_pos["q25"], floor_pos["q75"], color=ln.get_color(), alpha=0.2, lw=0)
    speed = float(line["iterations_to_1.1"].iloc[0]) if "iterations_to_1.1" in line else np.nan
    if np.isfinite(speed):
        at = floor_pos["median"].to_numpy()[min(int(round(speed)), len(line) - 1)]
        ax.plot([speed], [at], "v", color=ln.get_color(), mec="k", mew=0.6, ms=7, zorder=4,
                label="median iterations to 1.1 x final (successful runs)")
    if sub.noise_floor.nunique() > 1 and line.noise_floor.iloc[0] > 0:  # one floor per line
        ax.axhline(line.noise_floor.iloc[0], color=ln.get_color(), ls=":", lw=0.9)


def _draw_references(ax, sub: pd.DataFrame) -> None:
    """The noise floor and the Cramér-Rao floor of panel ``sub``, where one value holds for all its lines."""
    floor = _common(sub.noise_floor)
    if np.isfinite(floor) and floor > 0:
        ax.axhline(floor, color="k", ls="--", lw=0.9, label="noise floor")
    bound = _common(sub.rms_bound) if "rms_bound" in sub else np.nan
    if np.isfinite(bound) and bound > 0:
        ax.axhline(bound, color="0.4", ls=":", lw=1.1, label="Cramér-Rao floor")


def _common(column: pd.Series) -> float:
    """The one value every line of a panel has in ``column`` (NaN where they differ or have none)."""
    values = column.dropna().unique()
    return float(values[0]) if len(values) == 1 else np.nan


def _dress_panel(ax, spec, head: str, counts: list[str]) -> None:
    """Log y axis, axis labels and the title: the panel's setting ``head`` over the success counts."""
    ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel(spec.plot.get("ylabel", "total-field RMS (nT)"))
    ok = f"succeeded: {', '.join(counts)}" if counts else ""
    ax.set_title("\n".join(t for t in (head, ok) if t), fontsize=9)
