"""Settings of one method as a distribution: every setting's median beside the default.

One row per cell: ``family`` (the run's estimator name: settings of one method share it) and
``family_label`` (its words on the x axis: ``plot.names``, else the estimator's label),
``label`` (the cell's ``plot.label`` keys, short names from ``plot.labels``), ``scenario``, the
median and quartiles of ``plot.metric`` (default ``fun``), ``success_rate`` (fraction of seeds that
succeeded by the artifact's ``success:`` rule, :func:`magexp.artifacts.plan.succeeded`: the objective at
most 1.1 x the true calibration's on the same readings; ``converged``, the 1 % rule, where no run is
judged), ``bound_success_rate`` (offset error within 2x its Cramér-Rao bound), ``on_boundary_rate``
(fraction of seeds whose best has a coordinate on the search box's faces), median wall time and
evaluations to 1.1x the final value. Per (family, scenario) ``role`` marks the ``best``,
``median`` and ``worst`` setting by the median metric, and ``default`` the cell whose overrides
match ``plot.default`` (``{family: {key: value}}``; a family without one: no default).

The figure: one column of two panels per scenario, titled by ``plot.names[scenario]`` (else the scenario's
short name). Where every family has at most :data:`FEW` settings, each setting has its own colour and its own
tick, in both panels: on top its median metric (the default a star), below its success rate (the default's
bar outlined; a rate of 0, a bar of no height, is marked on the axis with its count, ``0 of 30``). The x axis
names on two levels, horizontally (no slanted word runs into the next panel): under each tick the
setting's values, one a line (``90``; ``reflect`` / ``400``), and under them, once per family, the family's
words and the keys its settings share (``RDPSO: arc (deg)``); a part of a label naming the family itself is
left out. Each family gets the same room, wide enough for its words (:func:`_panel_width`); a long y label
breaks at its ``;``, a long title wraps to the figure's width. With more settings, the top
panel shows every setting's median as a dot, the best / median / worst ones with their own markers
and the default as a star; below, the success rates of the median and best settings and the default
(of the one setting where a family has only one), under the family's words. The table: :func:`magexp.artifacts.kinds.tuning.table`.
"""

from __future__ import annotations

import re
import textwrap

import numpy as np
import pandas as pd

from magexp.artifacts.plots.style import legend_entries, panels, plt, scenario_label, shared_legend, tidy_log_axes
from magexp.artifacts.tables import median

#: families with at most this many settings show each setting by name (else best / median / worst)
FEW = 4
ROLE_MARKERS = {"best": "^", "median": "D", "worst": "v"}
#: tick words: a setting's values wrapped to :data:`WRAP` characters a line, a family's words to
#: :data:`WRAP_FAMILY`, in :data:`FONT` points (a character about :data:`CHAR` inches wide); a y label to
#: :data:`WRAP_YLABEL` characters (the height of a panel)
WRAP, WRAP_FAMILY, WRAP_YLABEL, FONT, CHAR = 11, 14, 30, 7, 0.055


def _named(top, bottom, sub, families, colours, words) -> tuple[list, list, list, list]:
    """Few settings per family: one colour per setting label, in both panels, each setting at its own tick;
    returns the settings' ticks and words and the families' ticks (the centre of their settings) and words
    (``words``: :func:`_words`)."""
    width = 0.8 / max(sub.family.value_counts().max(), 1)
    ticks, below, centres, names = [], [], [], []
    for k, fam in enumerate(families):
        f = sub[sub.family == fam]
        name, settings = words[(f.scenario.iloc[0], fam)]
        for j, (_, r) in enumerate(f.iterrows()):
            x = k - width * (len(f) - 1) / 2 + width * j
            top.scatter([x], [max(r["median"], 1e-14)], s=90 if r.default else 30, color=colours[r.label], zorder=3,
                        marker="*" if r.default else "o")
            top.plot([x, x], [max(r.q25, 1e-14), max(r.q75, 1e-14)], color=colours[r.label], lw=1)
            _rate_bar(bottom, x, width * 0.9, r, colours[r.label])
            ticks.append(x)
        below += settings
        centres.append(k)
        names.append(name)
    return ticks, below, centres, names


def _parts(row) -> list[tuple[str, str]]:
    """The ``(key, value)`` parts of a setting's label, a part naming the family itself left out."""
    parts = [p.split(" = ", 1) for p in re.split(r", (?=[^,=]+ = )", str(row.label)) if " = " in p]
    return [(k, v) for k, v in parts if v not in (str(row.family_label), str(row.family))]


def _family_words(f: pd.DataFrame) -> tuple[str, list[str]]:
    """A family's words (its name, and the keys its settings share) and each setting's words (its values,
    one a line; ``key = value`` where the settings differ in their keys)."""
    rows = [r for _, r in f.iterrows()]
    name = str(rows[0].family_label)
    if len(rows) == 1:
        return textwrap.fill(name, WRAP_FAMILY), [""]
    parts = [_parts(r) for r in rows]
    keys = {tuple(k for k, _ in p) for p in parts}
    if len(keys) == 1 and keys != {()}:
        name = f"{name}: {', '.join(next(iter(keys)))}"
        return textwrap.fill(name, WRAP_FAMILY), ["\n".join(textwrap.fill(v, WRAP) for _, v in p) for p in parts]
    return textwrap.fill(name, WRAP_FAMILY), ["\n".join(textwrap.fill(f"{k} = {v}", WRAP) for k, v in p) or
                                              textwrap.fill(str(r.label), WRAP) for p, r in zip(parts, rows)]


def _wrapped_ylabel(text: str) -> str:
    """A y label no taller than its panel: broken at its ``;`` first, then at :data:`WRAP_YLABEL` characters."""
    if len(text) <= WRAP_YLABEL:
        return text
    return "\n".join(textwrap.fill(part, WRAP_YLABEL) for part in text.split("; "))


def _words(frame: pd.DataFrame) -> dict:
    """:func:`_family_words` of every (scenario, family) of the frame."""
    keys = dict.fromkeys(zip(frame.scenario, frame.family))
    return {(sc, fam): _family_words(frame[(frame.scenario == sc) & (frame.family == fam)]) for sc, fam in keys}


def _panel_width(frame: pd.DataFrame, words: dict, few: bool) -> float:
    """The width of a panel (inches) that gives every family its words and every setting its own
    (:func:`_words`)."""
    longest = lambda texts: max((len(line) for t in texts for line in t.split("\n")), default=0)
    per_family = max(longest([name]) * CHAR * (FONT + 1) / FONT + 0.15 for name, _ in words.values())
    if few:
        per_family = max(per_family, *(len(s) / 0.8 * (longest(s) * CHAR + 0.15) for _, s in words.values()))
    families = max(sum(1 for key in words if key[0] == sc) for sc in set(frame.scenario))
    return max(3.6, families * per_family + 1.2)


def _two_level_ticks(ax, ticks: list, words: list, centres: list, names: list) -> None:
    """Each setting's words at its own (minor) tick and its family's words below them, at the family's
    centre (major ticks padded by the height of the tallest setting words): no label slants into the next
    panel. Without setting words (one setting per family) the families' words alone."""
    lines = max((w.count("\n") + 1 for w in words if w), default=0)
    ax.xaxis.remove_overlapping_locs = False  # a family's centre may be one of its settings' ticks
    ax.set_xticks(centres, names, fontsize=FONT + 1)
    ax.set_xticks(ticks, words, minor=True, fontsize=FONT)
    ax.tick_params(axis="x", which="minor", length=3, pad=2)
    ax.tick_params(axis="x", which="major", length=0, pad=6 + lines * FONT * 1.4 if lines else 3.5)
    ax.grid(False, axis="x", which="both")


def _rate_bar(ax, x: float, width: float, row, colour) -> None:
    """A success-rate bar, outlined where it is the default; a rate of 0 is drawn as a mark and its count."""
    rate = float(row.success_rate)
    ax.bar(x, rate, width=width, color=colour, edgecolor="k" if row.default else colour, lw=1.2 if row.default else 0)
    if rate == 0:  # a bar of height 0 is invisible: mark it on the axis and say so
        ax.plot([x - width / 2, x + width / 2], [0, 0], color=colour, lw=4, solid_capstyle="butt", clip_on=False, zorder=3)
        ax.annotate(f"0 of {int(row.n_seeds)}", (x, 0), xytext=(0, 4), textcoords="offset points", ha="center",
                    va="bottom", fontsize=7, color="0.2")


def _ranked(top, bottom, sub, families):
    """Many settings per family: every median as a dot, the best / median / worst and the default marked."""
    for k, fam in enumerate(families):
        f = sub[sub.family == fam]
        jitter = np.linspace(-0.2, 0.2, len(f)) if len(f) > 1 else np.zeros(1)
        top.scatter(k + jitter, f["median"].clip(lower=1e-14), s=12, color="C0", alpha=0.7,
                    label="one setting (median over seeds)")
        for x, (_, r) in zip(k + jitter, f.iterrows()):
            if r.default:
                top.scatter([x], [max(r["median"], 1e-14)], marker="*", s=120, color="C3", zorder=3, label="default")
            if r.role in ROLE_MARKERS:
                top.scatter([x], [max(r["median"], 1e-14)], marker=ROLE_MARKERS[r.role], s=40, facecolors="none",
                            edgecolors="k", zorder=4, label=f"{r.role} setting")
        if len(f) == 1:  # one setting (an ablation variant): its success rate
            bottom.bar(k, float(f.success_rate.iloc[0]), width=0.5, color="C0")
            continue
        bottom.bar(k - 0.2, median(f.success_rate), width=0.2, color="C0", label="success rate: median over settings")
        best = f[f.role == "best"] if (f.role == "best").any() else f
        bottom.bar(k, float(best.success_rate.iloc[0]), width=0.2, color="C2", label="success rate: best setting")
        if f.default.any():
            bottom.bar(k + 0.2, float(f[f.default].success_rate.iloc[0]), width=0.2, color="C3", label="success rate: default")


def draw(frame: pd.DataFrame, spec, axes=None):
    """The tuning sweep: per family and scenario, the metric of each setting, best, median and worst marked."""
    scenarios = list(dict.fromkeys(frame.scenario))
    families = list(dict.fromkeys(frame.family))
    ticks = dict(zip(frame.family, frame.family_label))  # each family's words (plot.names, else its label)
    few = frame.value_counts(["family", "scenario"]).max() <= FEW and frame.label.nunique() <= 2 * FEW
    cycle = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    colours = {lab: cycle[j % len(cycle)] for j, lab in enumerate(dict.fromkeys(frame.label))}
    words = _words(frame)
    width = max(_panel_width(frame, words, few), 7.0 / len(scenarios))  # room for the words and the title
    fig, axes = panels(2 * len(scenarios), rows=2, width=width, height=2.9, axes=axes)
    names = dict(spec.plot.get("names", {}) or {})
    for j, sc in enumerate(scenarios):
        top, bottom = axes[j], axes[len(scenarios) + j]
        sub = frame[frame.scenario == sc]
        present = [f for f in families if (sub.family == f).any()]  # a family not run on this scenario: no tick
        if few:  # every setting at its own tick, named there: no legend of settings
            levels = _named(top, bottom, sub, present, colours, words)
        else:
            _ranked(top, bottom, sub, present)
            levels = [], [], list(range(len(present))), [textwrap.fill(str(ticks[f]), WRAP_FAMILY) for f in present]
        for ax in (top, bottom):
            _two_level_ticks(ax, *levels)
            ax.set_xlim(-0.5, len(present) - 0.5)  # each family the same room for its words
        top.set_yscale("log")
        top.set_ylabel(_wrapped_ylabel(spec.plot.get("ylabel", f"median {frame.metric.iloc[0]} per setting")))
        top.set_title(str(names.get(sc) or scenario_label(sc)), fontsize=9)
        bottom.set_ylim(0, 1.05)
        bottom.set_ylabel("success rate")
    entries = legend_entries(axes)
    if few and frame.default.any():
        entries["star, outlined bar: magexp's default"] = plt.Line2D([], [], ls="", marker="*", color="0.3", ms=9)
    shared_legend(fig, axes, entries, ncols=3, fontsize=7)
    fig.suptitle(textwrap.fill(str(spec.title), int(fig.get_figwidth() / 0.08)), fontsize=10)
    return tidy_log_axes(fig)
