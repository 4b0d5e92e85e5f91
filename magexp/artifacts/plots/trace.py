"""Parameters vs filter step: median and interquartile band over seeds, references as lines.

Reads ``trace[key]`` (``plot.trace``, default ``"x"``) of every run, shape ``(steps + 1, p)``,
named by ``trace[key + "_names"]`` or the run's ``parameter_names``. Cells without that trace
(closed-form estimators, a paper's fixed solution) are drawn as horizontal lines (dotted, dash-dot,
...) at their final estimate; a known truth (``truth_<name>`` metrics) as dashed lines.

``plot.groups``: lists of parameter names, one panel each (default: one panel per parameter);
``plot.start``: first step drawn (to hide the transient from ``x(0) = 0``; default 0);
``plot.names``: ``{estimator: words}`` for the legend and the title.

``plot.relative_to``: an estimator of the artifact (e.g. ``ls``) whose final estimate the traces are
measured against. A second row of panels then draws, on a log axis, per parameter the distance
``|x(step) - x_ref|`` of each seed's trace from the reference's estimate on the same seed (median
over seeds, interquartile band), the distance of every other estimate from it (the paper's: dash-dot;
the truth: dashed) and ``plot.tolerances`` (one per group: the accuracy at which the caption calls the
trace converged) as a black line: differences of 1e-4 that the estimates' own scale hides.
The table: :func:`magexp.artifacts.kinds.trace.table`.
"""

from __future__ import annotations

import pandas as pd

from magexp.artifacts.plots.style import panels, plt, tidy_log_axes

TINY = 1e-12  # a log axis draws a distance of 0 (the reference's own seed, round-off) here
REFERENCE_STYLES = {":": "dotted", "-.": "dash-dot", (0, (5, 1, 1, 1, 1, 1)): "dash-dot-dot"}


def _name(spec, estimator: str) -> str:
    """An estimator in words (``plot.names``), else its config name."""
    return str(dict(spec.plot.get("names", {}) or {}).get(estimator, estimator))


def draw(frame: pd.DataFrame, spec, axes=None):
    """The traced parameters against the filter step: median and IQR per cell, a panel per group, truth as a level."""
    traces = frame[(frame.kind == "trace") & (frame.step >= float(spec.plot.get("start", 0)))]
    groups = [list(g) for g in spec.plot.get("groups", [])] or [[p] for p in dict.fromkeys(traces.parameter)]
    distance = "distance" in set(frame.kind)
    fig, top, bottom = _layout(len(groups), distance, axes)
    several = traces.estimator.nunique() > 1
    refs = list(dict.fromkeys(frame[frame.kind == "reference"].estimator))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, group in zip(top, groups):
        for k, (name, est) in enumerate((p, e) for e in dict.fromkeys(traces.estimator) for p in group):
            _draw_parameter(ax, frame, traces, name, _name(spec, est), est, colours[k % len(colours)], several=several, refs=refs)
        ax.set_xlabel("filter step")
        ax.set_ylabel(spec.plot.get("ylabel", "estimate"))
        ax.legend(loc="best", ncol=len(group) if not several else 1)
    tolerances = list(spec.plot.get("tolerances", []) or [])
    for j, (ax, group) in enumerate(zip(bottom, groups)):
        _draw_distances(ax, frame, group, colours, dict(zip(refs, REFERENCE_STYLES)),
                        tolerances[j] if j < len(tolerances) else None)
        ax.set_xlabel("filter step")
        ax.set_ylabel(f"|estimate - {_name(spec, spec.plot.relative_to)}|")
    lines = (["dashed: truth"] if (frame.kind == "truth").any() else []) + [
        f"{word}: {_name(spec, ref)}" for ref, word in zip(refs, REFERENCE_STYLES.values())]
    if distance:
        lines.append(f"bottom: distance from {_name(spec, spec.plot.relative_to)} on the same seed, same styles; "
                     "black: the stated accuracy")
    note = "; ".join(lines)
    fig.suptitle(f"{spec.title}\n{note}".strip(), fontsize=9)
    return tidy_log_axes(fig)


def _layout(n: int, distance: bool, axes):
    """The figure, the panels of the estimates and those of the distances (``distance``: a second
    row, one column per group; else none, and the groups two a row)."""
    if distance:
        fig, axes = panels(2 * n, width=3.4, height=2.9, rows=2, axes=axes)
        return fig, axes[:n], axes[n:]
    fig, top = panels(n, width=3.6, rows=-(-n // 2) if n > 2 else 1, axes=axes)
    return fig, top, []


def _draw_distances(ax, frame: pd.DataFrame, group: list[str], colours, styles: dict, tolerance) -> None:
    """Per parameter of ``group``: the distance of the trace from the reference (median, IQR band)
    and of the other estimates (truth dashed, the reference estimators in their ``styles``), on a
    log axis, and the ``tolerance`` as a black line."""
    for k, name in enumerate(group):
        colour = colours[k % len(colours)]
        line = frame[(frame.kind == "distance") & (frame.parameter == name)]
        ax.plot(line.step, line["median"].clip(lower=TINY), lw=1.1, color=colour, label=name)
        ax.fill_between(line.step, line.q25.clip(lower=TINY), line.q75.clip(lower=TINY), color=colour, alpha=0.2, lw=0)
        for _, row in frame[(frame.kind == "distance_truth") & (frame.parameter == name)].iterrows():
            ax.axhline(max(row["median"], TINY), color=colour, ls="--", lw=0.9)
        for _, row in frame[(frame.kind == "distance_reference") & (frame.parameter == name)].iterrows():
            ax.axhline(max(row["median"], TINY), color=colour, ls=styles.get(row.estimator, "-."), lw=0.9)
    if tolerance is not None:
        ax.axhline(float(tolerance), color="k", lw=1.0)
    ax.set_yscale("log")
    ax.legend(loc="best", ncol=len(group))


def _draw_parameter(ax, frame: pd.DataFrame, traces: pd.DataFrame, name: str, shown: str, est: str, colour, *,
                    several: bool, refs: list) -> None:
    """The trace of parameter ``name`` by estimator ``est`` (``shown``: its name in the legend;
    median over seeds, interquartile band), its true value (dashed; black when several estimators
    share the panel) and the final values of the reference estimators ``refs`` (one line style
    each, :data:`REFERENCE_STYLES`)."""
    line = traces[(traces.parameter == name) & (traces.estimator == est)]
    ax.plot(line.step, line["median"], lw=1.1, color=colour, label=f"{name} ({shown})" if several else name)
    ax.fill_between(line.step, line.q25, line.q75, color=colour, alpha=0.2, lw=0)
    for _, row in frame[(frame.kind == "truth") & (frame.parameter == name)].iterrows():
        ax.axhline(row["median"], color="k" if several else colour, ls="--", lw=0.9)
    for ref, style in zip(refs, REFERENCE_STYLES):
        for _, row in frame[(frame.kind == "reference") & (frame.parameter == name) & (frame.estimator == ref)].iterrows():
            ax.axhline(row["median"], color=colour, ls=style, lw=0.9)
