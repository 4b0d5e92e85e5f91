"""The readings of the first seed of each cell before and after calibration (the kinds ``field`` and
``sphere``, one kind): ``plot.quantity`` is ``magnitude`` (the total field per reading, before and
after; Ding 2024 fig 2), ``error`` (the calibrated total field minus the reference; fig 6) or
``sphere`` (a 3-D scatter against the sphere of radius the median reference; Yuan 2018 figs 2-4).
The default is ``sphere`` for the kind ``sphere``, else ``magnitude``. ``plot.unit``: the unit of the
readings (their scenario's, default ``nT``), printed on the axes and with the RMS.

An error panel whose every error is at or below the round-off floor (the CSV writes such values as
±1e-9, :data:`magexp.core.outcomes.ROUNDOFF_FLOOR`) draws them at 0 on the scale of its neighbour
and says so in its title: the floor is not data.

The seed shown is the first whose run succeeded (the artifact's ``success:`` rule); where none
did, or none is judged, the first seed. The CSV's ``seed`` and ``outcome`` columns and each panel's
title say which (the table: :func:`magexp.artifacts.kinds.field.table`).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from matplotlib.ticker import FixedLocator

from magexp.artifacts.plots.style import group_values, label, panels, plt, unit
from magexp.artifacts.tables import median
from magexp.core.metrics import rms as rms_of
from magexp.core.outcomes import ROUNDOFF_FLOOR


def _which(sub) -> str:
    """``seed k, outcome`` of the drawn run (older CSVs without the columns: empty)."""
    if "seed" not in sub:
        return ""
    outcome = f", {sub.outcome.iloc[0]}" if "outcome" in sub and sub.outcome.iloc[0] != "not judged" else ""
    return f"seed {sub.seed.iloc[0]}{outcome}"


def _lines(*parts: str) -> str:
    """The non-empty ``parts``, one a line."""
    return "\n".join(p for p in parts if p)


def draw(frame: pd.DataFrame, spec, axes=None):
    """The readings of the shown seed: total field against the reference, or in 3-D against the sphere."""
    quantity = spec.plot.get("quantity", "sphere" if spec.kind == "sphere" else "magnitude")
    if quantity == "sphere":
        return _draw_sphere(frame, spec, axes=axes)
    return _draw_field(frame, spec, show_raw=quantity == "magnitude", axes=axes)


def _draw_field(frame: pd.DataFrame, spec, show_raw: bool, axes=None):
    """The field panels of ``frame``, one per panel value: the error per reading (and, with ``show_raw``,
    the raw readings against the reference above it)."""
    key, readings_unit = spec.plot.get("panels"), unit(spec)
    values = group_values(frame, key)
    fig, axes = panels(len(values) * (2 if show_raw else 1), rows=2 if show_raw else 1, height=3.0, axes=axes)
    n, exact_panels = len(values), []
    for i, v in enumerate(values):
        sub = frame if v is None else frame[frame[key] == v]
        title = "" if v is None else label(spec, key, v)
        rms = rms_of(sub.error)
        if show_raw:
            ax = axes[i]
            ax.plot(sub.reading, sub.raw, ".", ms=2.5, color="0.5", label="before")
            ax.plot(sub.reading, sub.reference, "k--", lw=0.8, label="reference")
            ax.set_title(_lines(title, f"before calibration ({_which(sub)})"))
            ax.set_ylabel(f"total field ({readings_unit})")
            ax = axes[n + i]
            ax.plot(sub.reading, sub.calibrated, ".", ms=2.5, label="after")
            ax.plot(sub.reading, sub.reference, "k--", lw=0.8)
            ax.set_title(f"after (RMS {rms:.3g} {readings_unit})")
            ax.set_ylabel(f"total field ({readings_unit})")
            ax.ticklabel_format(axis="y", useOffset=True, style="plain")
        else:
            ax = axes[i]
            exact = bool((sub.error.abs() <= ROUNDOFF_FLOOR).all())  # written as ±floor: no value to draw
            ax.plot(sub.reading, np.where(exact, 0.0, sub.error), ".", ms=2.5)
            ax.axhline(0, color="k", lw=0.8)
            what = f"|error| ≤ {ROUNDOFF_FLOOR:g} {readings_unit} (round-off)" if exact else f"RMS {rms:.3g} {readings_unit}"
            ax.set_title(_lines(title, f"{what} ({_which(sub)})"))
            ax.set_ylabel(f"total-field error ({readings_unit})")
            exact_panels += [ax] if exact else []
        ax.set_xlabel("reading")
    scaled = [ax for ax in axes[:n] if ax not in exact_panels]
    for ax in exact_panels:  # the scale of the nearest panel with errors, so that 0 reads as 0
        if scaled:
            ax.set_ylim(min(scaled, key=lambda other: abs(axes.index(other) - axes.index(ax))).get_ylim())
    fig.suptitle(spec.title, fontsize=10)
    return fig


def _draw_sphere(frame: pd.DataFrame, spec, axes=None):
    """One 3-D panel per value of ``panels``; ``axes`` (3-D Axes of the caller's figure) draws there."""
    key, readings_unit = spec.plot.get("panels"), unit(spec)
    values = group_values(frame, key)
    fig, given = (plt.figure(figsize=(4.2 * len(values), 4.2)), None) if axes is None else panels(len(values), axes=axes)
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
    for i, val in enumerate(values):
        sub = frame if val is None else frame[frame[key] == val]
        ax = fig.add_subplot(1, len(values), i + 1, projection="3d") if given is None else given[i]
        r = median(sub.reference)
        ax.plot_wireframe(r * np.cos(u) * np.sin(v), r * np.sin(u) * np.sin(v), r * np.cos(v),
                          color="0.8", lw=0.4)
        ax.scatter(sub.raw_x, sub.raw_y, sub.raw_z, s=6, color="0.45", label="before")
        ax.scatter(sub.cal_x, sub.cal_y, sub.cal_z, s=8, color="C0", label="after")
        rms = rms_of(sub.error)
        title = "" if val is None else label(spec, key, val)
        ax.set_title(_lines(title, f"{_which(sub)}: RMS of |B| - |H| after {rms:.3g} {readings_unit}"), fontsize=8)
        ax.set_box_aspect((1, 1, 1))
        step = 10 ** math.floor(math.log10(r)) if r > 0 else 1.0
        ticks = [-(r // step) * step, 0.0, (r // step) * step] if r > 0 else [0.0]
        for axis, name in zip((ax.xaxis, ax.yaxis, ax.zaxis), "xyz"):
            axis.set_label_text(f"{name} ({readings_unit})")
            axis.set_major_locator(FixedLocator(ticks))  # -R, 0, R (R: |H| rounded down): no labels meet at a corner
        if i == 0:
            ax.legend(loc="upper left", fontsize=7)
    fig.suptitle(spec.title, fontsize=10)
    return fig
