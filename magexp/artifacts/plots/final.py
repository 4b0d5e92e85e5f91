"""Final values per cell against a swept key: median and interquartile bars over seeds (the kinds
``final`` and ``sweep``, one kind).

``plot.x``: the swept grid key; ``plot.metric``: one runs column or a list of them (one row of
panels each; default ``fun``); ``plot.hue``: one line per value (default ``estimator``; a list of keys:
one line per combination; ``plot.names``: ``{value: legend text}``); ``plot.panels``: one column
of panels per value; ``plot.xscale``:
``linear``, ``log`` or ``symlog`` (with ``plot.linthresh``, for sweeps that include 0; its ticks are
0 and the decades from ``linthresh`` up, and it starts a little below 0 so that the markers at 0 are whole);
``plot.ylog`` (default true; ``{metric: false}`` for a linear y axis of that metric's panels only);
``plot.ylabel`` / ``plot.ylabels`` (per metric); ``plot.bound``: a
bound column of the metric drawn per objective (e.g. ``offset_bound``); ``plot.targets``:
``{metric: value}`` drawn dashed (e.g. a paper's stated accuracy); ``plot.levels``: a paper's values
that are not compared cell by cell (``[{label, match, value}]``, e.g. the paper's PSO at each noise
level beside every PSO setting of a sweep), each a horizontal line across the panels whose settings
``match`` selects (of its ``metrics``, default the first; where ``match`` names a value of ``plot.x``:
a short line at that x only), one style per ``label``. Against the objective ``fun`` the
noise floor and the Cramér-Rao RMS floor are drawn (over the lines, which run close to them);
against ``rms_ratio`` (the residual RMS over that floor) the floor is the line at 1. A cell where fewer than half the runs succeeded
is ringed in red. A cell without a value is marked by a cross at the top of its panel (legend text:
``plot.labels.missing``, e.g. "never within 600 steps"). A censored metric (a step of convergence
observed within a horizon, :mod:`magexp.artifacts.censoring`) is never drawn as a median of its
observed values: its censoring point is dotted, a cell with censored seeds gets an up-arrow there
with "k/n" censored (its median too when ``k >= n/2``), and the earliest and latest seed are marked. The paper's values (the artifact's
``reported:`` entries of the quantities summarised from the metric) are open diamonds in the colour of
their line. Each of the artifact's ``ratios:`` (per seed, numerator over denominator cell) adds a row
of panels: its median and quartiles over seeds, with the paper's ratios and the line of equality.
A trend claim drawn on the figure (:mod:`magexp.artifacts.trends`) is its fitted line, solid black, with the
95 % band of its bootstrap lines in grey. The table: :func:`magexp.artifacts.kinds.final.table`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd
from matplotlib.ticker import FixedLocator

from magexp.artifacts.plot_keys import metric_list
from magexp.artifacts.plots.style import (group_values, label, legend_entries, panels, paper_values, plt, scenario_label,
                                         shared_legend, tidy_log_axes)
from magexp.artifacts.tables import matches
from magexp.core.outcomes import failed_majority

TINY = 1e-14  # log axes: values at or below zero are drawn here
SYMLOG_PAD = 0.12  # a symlog x axis from 0 starts this fraction of its linear part below 0
CRB_FLOOR = "Cramér-Rao floor (Gaussian)"


def ylog(spec, metric: str) -> bool:
    """Whether ``metric``'s panels have a log y axis (``plot.ylog``: one flag, or ``{metric: flag}``,
    default true).
    """
    flag = spec.plot.get("ylog", True)
    return bool(flag.get(metric, True)) if isinstance(flag, Mapping) else bool(flag)


def _colours(frame, hue_key) -> dict:
    """One colour per line, fixed over panels (markers drawn beside never take a line's colour)."""
    cycle = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    return {hv: cycle[k % len(cycle)] for k, hv in enumerate(group_values(frame, hue_key))}


def _spread(x, k: int, n: int, scale: str) -> np.ndarray:
    """Lines side by side: a few per cent apart (in ratio on log-like axes, in the range on linear)."""
    offset = k - (n - 1) / 2
    if scale == "linear":
        span = float(np.ptp(x)) if len(x) > 1 else 1.0
        return x + 0.012 * span * offset
    return x * (1 + 0.03 * offset)


def _lines(ax, sub, spec, x_key, hue_key, colours):
    """One errorbar line per hue value (slightly spread on the x axis), failed majorities ringed,
    cells without a value crossed at the top of the panel; returns the x of every line's cells."""
    hues = group_values(sub, hue_key)
    scale = spec.plot.get("xscale", "linear")
    placed = {}
    for k, hv in enumerate(hues):
        line = sub[sub[hue_key] == hv].sort_values(x_key, key=lambda c: c.astype(float))
        x = _spread(line[x_key].astype(float).to_numpy(), k, len(hues), scale)
        placed[hv] = (line, x)
        y = line["median"].to_numpy(float)
        censored = np.isposinf(y)  # a censored median: drawn at its censoring point by _censored
        y = np.where(censored, np.nan, y)
        err = np.vstack([y - line.q25.to_numpy(float), line.q75.to_numpy(float) - y])
        name = label(spec, hue_key, hv) if hue_key not in ("estimator", "_hue") else str(hv)
        name = dict(spec.plot.get("names", {}) or {}).get(str(hv), name)  # plot.names: a value's legend text
        colour = colours[hv]
        ax.errorbar(x, np.maximum(y, TINY), yerr=np.where(np.isfinite(err), np.maximum(err, 0), 0), marker="o",
                    ms=3.5, capsize=2, lw=1, label=name, color=colour)
        _censored(ax, line, x, colour, k)
        _extremes(ax, line, x, colour)
        missing = np.isnan(y) & ~censored
        if missing.any():
            ax.plot(x[missing], np.full(missing.sum(), 0.96), "x", color=colour, ms=6, mew=1.4,
                    transform=ax.get_xaxis_transform(), label=f"x at the top: {label(spec, 'missing')}")
        if "success_rate" in line:
            bad = failed_majority(line.success_rate)
            if bad.any():
                ax.plot(x[bad], np.maximum(y[bad], TINY), "o", mfc="none", mec="r", ms=9, mew=1.2,
                        label="fewer than half succeeded")
    return placed


def _censored(ax, line, x, colour, k: int = 0) -> None:
    """A censored metric (:mod:`magexp.artifacts.censoring`): the censoring point dotted, and at each
    cell with censored runs an up-arrow there with "k/n" (k of n seeds later than it; the ``k``-th line's
    text stacked above the others'); a censored upper quartile or median is a bar up to the arrow."""
    if "n_censored" not in line or not (line.n_censored.fillna(0) > 0).any():
        return
    for xi, (_, row) in zip(x, line.iterrows()):
        if not row.n_censored > 0:
            continue
        point = float(row.censor_point)
        ax.axhline(point, color="0.45", ls=":", lw=1.0, zorder=1, label="censoring point: half the horizon")
        if not np.isfinite(row.q75):  # the interquartile bar runs on past the censoring point
            low = next((v for v in (row["median"], row.q25) if np.isfinite(v)), point)
            ax.plot([xi, xi], [max(low, TINY), point], color=colour, lw=1, ls="--")
        ax.plot([xi], [point], "^", color=colour, ms=7, mew=1.2, mfc="none", zorder=5,
                label="seeds later than the censoring point (k/n)")
        if row.n_seeds > 1:  # one seed: the arrow says it all
            ax.annotate(f"{int(row.n_censored)}/{int(row.n_seeds)}", (xi, point), xytext=(5, 4 + 9 * k),
                        textcoords="offset points", fontsize=7, color=colour)


def _extremes(ax, line, x, colour) -> None:
    """The earliest and the latest seed of a censored metric (``min``, ``max`` columns): a small
    down-triangle and bar; a censored maximum is the arrow of :func:`_censored`."""
    if "min" not in line or not (line.n_seeds > 1).any():  # one seed: its value is the median
        return
    lo, hi = line["min"].to_numpy(float), line["max"].to_numpy(float)
    shown = np.isfinite(lo)
    ax.plot(x[shown], np.maximum(lo[shown], TINY), "v", color=colour, ms=4.5, zorder=4, label="earliest seed (v), latest (_)")
    shown = np.isfinite(hi)
    ax.plot(x[shown], np.maximum(hi[shown], TINY), "_", color=colour, ms=9, mew=1.5, zorder=4,
            label="earliest seed (v), latest (_)")


def _paper(ax, spec, placed, metric, colours):
    """The paper's values of the quantities summarised from ``metric``: an open diamond at the cell
    (in its line's colour) whose settings the ``reported:`` entry matches."""
    for entry in paper_values(spec, metric):
        for hv, (line, x) in placed.items():
            for xi, (_, row) in zip(x, line.iterrows()):
                if matches(dict(entry.match), row.to_dict()):
                    ax.plot([xi], [max(float(entry.value), TINY)], "D", mfc="none", mec=colours[hv], ms=7,
                            mew=1.3, zorder=4, label="paper's value (open diamond)")


#: styles of the ``plot.levels`` lines, one per label (in the order first seen)
LEVEL_STYLES = ({"color": "k", "ls": "-.", "lw": 1.3}, {"color": "C4", "ls": (0, (1, 1)), "lw": 1.3},
                {"color": "0.3", "ls": (0, (5, 2, 1, 2, 1, 2)), "lw": 1.1})


def _levels(ax, spec, sub: pd.DataFrame, metric: str, x_key: str) -> None:
    """The ``plot.levels`` whose ``match`` selects the panel's cells (a key the cells lack is no
    match): across the panel, or, where ``match`` names a value of the x key, a short line at that x
    only (drawn after the axes are scaled, within their x range); against the metrics of the level's
    ``metrics`` (default: ``plot.metric``'s first)."""
    levels = list(spec.plot.get("levels", []) or [])
    styles = {}
    xs = sorted(set(sub[x_key].astype(float))) if x_key in sub else []
    for level in levels:
        style = styles.setdefault(str(level["label"]), LEVEL_STYLES[len(styles) % len(LEVEL_STYLES)])
        if metric not in list(level.get("metrics", metric_list(spec.plot)[:1])):
            continue
        match = dict(level.get("match", {}) or {})
        if not (all(k in sub for k in match) and any(matches(match, row) for row in sub.to_dict("records"))):
            continue
        value, name = float(level["value"]), str(level["label"])
        if x_key in match and xs:
            lo, hi = level_span(float(match[x_key]), xs, ax.get_xscale() == "log")
            xlim = ax.get_xlim()  # the cells' x range: the line does not widen it
            ax.plot([lo, hi], [value, value], zorder=4, label=name, **style)
            ax.set_xlim(xlim)
        else:
            ax.axhline(value, zorder=4, label=name, **style)


def level_span(x: float, xs: list[float], log: bool = False) -> tuple[float, float]:
    """The ends of a level's line drawn at ``x`` only: 0.4 of the gap to each neighbouring x; beyond
    the first or last x, the axis's default margin (5 % of the range of ``xs``), so that the line does
    not widen the x range; on a log axis, in the logarithm.
    """
    f, inv = (math.log10, lambda v: 10.0 ** v) if log and min(xs) > 0 else (float, float)
    at, margin = f(x), 0.05 * (f(max(xs)) - f(min(xs))) or 0.5
    left = min((0.4 * (at - f(v)) for v in xs if f(v) < at), default=margin)
    right = min((0.4 * (f(v) - at) for v in xs if f(v) > at), default=margin)
    return inv(at - left), inv(at + right)


def _references(ax, sub, spec, x_key, metric):
    """The bound per objective, the floors (against ``fun``) and the paper's target."""
    if "bound" in sub and sub.bound.notna().any():  # the bound belongs to the problem: one per objective
        objectives = list(dict.fromkeys(sub.objective))
        for j, obj in enumerate(objectives):
            fl = sub[sub.objective == obj].drop_duplicates(x_key).sort_values(x_key, key=lambda c: c.astype(float))
            if not np.isfinite(fl.bound.astype(float)).any():  # not identified: nothing to draw, no legend
                continue
            name = "Cramér-Rao bound (Gaussian)" + (f" ({obj})" if len(objectives) > 1 else "")
            ax.plot(fl[x_key].astype(float), fl.bound.clip(lower=TINY), ["k--", "k-."][j % 2], lw=0.9, label=name)
    fl = sub.drop_duplicates(x_key).sort_values(x_key, key=lambda c: c.astype(float))
    if metric == "fun" and "noise_floor" in sub:
        ax.plot(fl[x_key].astype(float), fl.noise_floor.clip(lower=TINY), "k--", lw=0.9, zorder=5, label="noise floor")
    if metric == "fun" and "rms_bound" in sub:
        ax.plot(fl[x_key].astype(float), fl.rms_bound.clip(lower=TINY), ":", color="0.4", lw=1.1, zorder=5,
                label=CRB_FLOOR)
    if metric == "rms_ratio":
        ax.axhline(1.0, ls=":", color="0.4", lw=1.1, zorder=5, label=CRB_FLOOR)
    targets = dict(spec.plot.get("targets", {}) or {})
    if metric in targets:
        ax.axhline(float(targets[metric]), color="k", ls="--", lw=0.9, label="paper's stated level")
    if metric in {r.quantity for r in spec.get("ratios", [])}:
        ax.axhline(1.0, color="0.3", ls="-", lw=0.8, label="ratio 1 (equal)")


def draw(frame: pd.DataFrame, spec, axes=None):
    """The final value of each metric against the swept key ``plot.x``: median and IQR per hue, a panel per metric."""
    x_key, panel_key = spec.plot.x, spec.plot.get("panels")
    frame, fits = _split_trends(frame)
    frame, hue_key = _with_hue(frame, spec, spec.plot.get("hue", "estimator"))
    metrics = metric_list(spec.plot) + [r.quantity for r in spec.get("ratios", []) if (frame.get("metric") == r.quantity).any()]
    columns = group_values(frame, panel_key)
    colours = _colours(frame, hue_key)
    fig, axes = panels(len(metrics) * len(columns), rows=len(metrics) if len(columns) > 1 else 1,
                       width=3.8 if len(metrics) > 1 else 3.4, axes=axes)
    for i, metric in enumerate(metrics):
        for j, pv in enumerate(columns):
            ax = axes[i * len(columns) + j]
            sub = frame[frame.metric == metric] if "metric" in frame else frame
            sub = sub if pv is None else sub[sub[panel_key] == pv]
            placed = _lines(ax, sub, spec, x_key, hue_key, colours)
            _paper(ax, spec, placed, metric, colours)
            _references(ax, sub, spec, x_key, metric)
            _trends(ax, fits, x_key, metric, panel_key, pv)
            _scale_axes(ax, spec, sub, frame[x_key], ylog(spec, metric))
            _levels(ax, spec, sub, metric, x_key)
            _label_panel(ax, spec, metric, len(metrics), panel_key, pv)
    entries = legend_entries(axes)  # one legend: every entry once (markers of later panels included)
    shared_legend(fig, axes, entries, inside=len(axes) == 1 and len(entries) <= 6)
    fig.suptitle(spec.title, fontsize=10)
    return tidy_log_axes(fig)


def _split_trends(frame: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The cells' rows and the trend claims' rows (a ``trend`` id; none in a table without trends)."""
    if "trend" not in frame:
        return frame, frame.iloc[:0]
    drawn = frame.trend.notna()
    return frame[~drawn].drop(columns=["trend", "fit", "fit_lo", "fit_hi"]), frame[drawn]


def _trends(ax, fits: pd.DataFrame, x_key: str, metric: str, panel_key, pv) -> None:
    """Each trend claim of the panel's metric (and panel, where its ``where`` names it): its fitted line,
    solid black, and the 2.5-97.5 % band of its bootstrap lines, grey (:mod:`magexp.artifacts.trends`)."""
    if not len(fits):
        return
    mine = fits[fits.metric == metric]
    if pv is not None:
        mine = mine[mine[panel_key].astype(str) == str(pv)] if panel_key in mine else mine.iloc[:0]
    for name in mine.trend.unique():  # each claim's rows, as its table wrote them
        line = mine[mine.trend == name]
        x = line[x_key].astype(float).to_numpy()
        ax.fill_between(x, line.fit_lo.astype(float), line.fit_hi.astype(float), color="0.6", alpha=0.3, lw=0,
                        zorder=2, label="trend claim: 95 % band of the fitted line")
        ax.plot(x, line.fit.astype(float), color="k", lw=1.2, zorder=3, label=f"trend claim {name}: least-squares fit")


def _with_hue(frame: pd.DataFrame, spec, hue_key) -> tuple[pd.DataFrame, str]:
    """The frame and the column naming its lines: ``hue_key`` itself, or for several keys a column
    ``_hue`` of one label per combination (``pso, c1 = c2 = 2.0``: the first key's value, then the
    others named)."""
    if isinstance(hue_key, str):
        return frame, hue_key
    first, *rest = list(hue_key)
    named = [frame[k].astype(str).map(lambda v, k=k: label(spec, k, v)) for k in rest]
    return frame.assign(_hue=frame[first].astype(str).str.cat(named, sep=", ")), "_hue"


def _scale_axes(ax, spec, sub: pd.DataFrame, xs: pd.Series, log_y: bool) -> None:
    """The panel's scales: room above the values for the crosses of missing ones, ``xscale`` (a
    ``symlog`` axis of non-negative ``xs`` starts at 0) and a log y axis if ``log_y``."""
    if sub["median"].isna().any() or np.isposinf(sub["median"].astype(float)).any():  # room above: crosses, arrows
        ax.set_yscale("log" if log_y else "linear")
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi * (hi / lo) ** 0.25 if ax.get_yscale() == "log" else hi + 0.25 * (hi - lo))
    scale, linthresh = spec.plot.get("xscale", "linear"), float(spec.plot.get("linthresh", 1.0))
    ax.set_xscale(scale, **({"linthresh": linthresh} if scale == "symlog" else {}))
    ax.autoscale_view(scaley=False)  # the margins of the new scale: the markers at the ends are drawn whole
    if scale == "symlog" and (xs.astype(float) >= 0).all():
        ax.set_xlim(left=-SYMLOG_PAD * linthresh)  # from 0, with room for the markers drawn at 0
        ax.xaxis.set_major_locator(FixedLocator(symlog_ticks(xs, linthresh)))
    if log_y:
        ax.set_yscale("log")
    if "min" in sub and (sub.n_seeds > 1).any():  # room below for the earliest seed's marker
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo / (hi / lo) ** 0.06 if ax.get_yscale() == "log" else lo - 0.04 * (hi - lo), hi)


def symlog_ticks(xs: pd.Series, linthresh: float) -> list[float]:
    """Major ticks of a ``symlog`` axis from 0: 0, then the decades from the first at or above
    ``linthresh`` to the largest value's (a decade inside the linear part would be printed beside 0).
    """
    top = float(xs.astype(float).max())
    first = math.ceil(math.log10(linthresh))
    last = math.floor(math.log10(top)) if top > 0 else first
    return [0.0] + [10.0 ** k for k in range(first, max(last, first) + 1)]


def _label_panel(ax, spec, metric: str, n_metrics: int, panel_key, pv) -> None:
    """Axis labels (``ylabels`` per metric, else ``ylabel`` for a single metric) and the panel's title."""
    default_ylabel = spec.plot.get("ylabel", "final total-field RMS (nT)")
    ylabels = dict(spec.plot.get("ylabels", {}) or {})
    ax.set_xlabel(label(spec, spec.plot.x))
    ax.set_ylabel(ylabels.get(metric, default_ylabel if n_metrics == 1 else metric.replace("_", " ")))
    if pv is not None:
        ax.set_title(scenario_label(pv) if panel_key == "scenario" else label(spec, panel_key, pv))
