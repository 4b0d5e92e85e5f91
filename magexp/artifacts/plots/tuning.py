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

The figure: one column of two panels per scenario. Where every family has at most
:data:`FEW` settings, each setting has its own colour and its own tick, named by its family and label
(e.g. ``RDPSO: arc (deg) = 90``), in both panels: on top its median metric (the default a star), below
its success rate (the default's bar outlined; a rate of 0, a bar of no height, is marked on the axis with
its count, ``0 of 30``). With more settings, the top
panel shows every setting's median as a dot, the best / median / worst ones with their own markers
and the default as a star; below, the success rates of the median and best settings and the default
(of the one setting where a family has only one). The table: :func:`magexp.artifacts.kind_tables.tuning_table`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts.plots.style import legend_entries, panels, plt, scenario_label, shared_legend, tidy_log_axes
from magexp.artifacts.tables import median

#: families with at most this many settings show each setting by name (else best / median / worst)
FEW = 4
ROLE_MARKERS = {"best": "^", "median": "D", "worst": "v"}


def _named(top, bottom, sub, families, colours) -> tuple[list, list]:
    """Few settings per family: one colour per setting label, in both panels, each setting at its own tick
    (the family's words, and the setting's where the family has several); returns the ticks and their words."""
    width = 0.8 / max(sub.family.value_counts().max(), 1)
    ticks, words = [], []
    for k, fam in enumerate(families):
        f = sub[sub.family == fam]
        for j, (_, r) in enumerate(f.iterrows()):
            x = k - width * (len(f) - 1) / 2 + width * j
            top.scatter([x], [max(r["median"], 1e-14)], s=90 if r.default else 30, color=colours[r.label], zorder=3,
                        marker="*" if r.default else "o")
            top.plot([x, x], [max(r.q25, 1e-14), max(r.q75, 1e-14)], color=colours[r.label], lw=1)
            _rate_bar(bottom, x, width * 0.9, r, colours[r.label])
            ticks.append(x)
            words.append(r.family_label if len(f) == 1 or r.label == r.family else f"{r.family_label}: {r.label}")
    return ticks, words


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
    """The tuning sweep: per family and scenario, the metric of each setting, best, median and worst marked.

    Parameters
    ----------
    frame : pandas.DataFrame
        The table of :func:`magexp.artifacts.kind_tables.tuning_table`.
    spec : Artifact
        The artifact: ``plot.metric``, ``plot.names``, ``plot.labels``.
    axes : sequence of Axes, optional
        The caller's Axes: two rows, a column per scenario (default: a new figure).

    Returns
    -------
    matplotlib.figure.Figure
        The tuning sweep per family and scenario.
    """
    scenarios = list(dict.fromkeys(frame.scenario))
    families = list(dict.fromkeys(frame.family))
    ticks = dict(zip(frame.family, frame.family_label))  # each family's words (plot.names, else its label)
    few = frame.value_counts(["family", "scenario"]).max() <= FEW and frame.label.nunique() <= 2 * FEW
    cycle = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    colours = {lab: cycle[j % len(cycle)] for j, lab in enumerate(dict.fromkeys(frame.label))}
    width = max(3.6, 0.9 * len(families) + 1.5, 7.0 / len(scenarios))  # room for the title
    fig, axes = panels(2 * len(scenarios), rows=2, width=width, height=2.9, axes=axes)
    for j, sc in enumerate(scenarios):
        top, bottom = axes[j], axes[len(scenarios) + j]
        sub = frame[frame.scenario == sc]
        present = [f for f in families if (sub.family == f).any()]  # a family not run on this scenario: no tick
        if few:  # every setting at its own tick, named there: no legend of settings
            positions, words = _named(top, bottom, sub, present, colours)
        else:
            _ranked(top, bottom, sub, present)
            positions, words = list(range(len(present))), [ticks[f] for f in present]
        for ax in (top, bottom):
            ax.set_xticks(positions, words, rotation=30, ha="right", fontsize=7)
        top.set_yscale("log")
        top.set_ylabel(spec.plot.get("ylabel", f"median {frame.metric.iloc[0]} per setting"))
        top.set_title(scenario_label(sc), fontsize=9)
        bottom.set_ylim(0, 1.05)
        bottom.set_ylabel("success rate")
    entries = legend_entries(axes)
    if few and frame.default.any():
        entries["star, outlined bar: magexp's default"] = plt.Line2D([], [], ls="", marker="*", color="0.3", ms=9)
    shared_legend(fig, axes, entries, ncols=3, fontsize=7)
    fig.suptitle(spec.title, fontsize=10)
    return tidy_log_axes(fig)
