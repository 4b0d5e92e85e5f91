"""Accuracy vs wall time: the bound ratio (RMS over the successful runs of error / sqrt(tr CRB)) against the
median fit time; one marker per estimator (grey in the legend), one colour per paper of the scenario. The
log axes get readable ticks (:func:`magexp.artifacts.plots.style.tidy_log_axes`: a ratio axis from 0.85
to 1.8 is labelled at 0.9, 1, 1.2 and 1.5)."""

from __future__ import annotations


from magexp.artifacts.columns import column_label
from magexp.artifacts.plots.style import plt, tidy_log_axes

MARKERS = "osD^v<>PX*hp"


def draw(frame, spec, ax=None):
    """The speed benchmark: ``plot.metric`` per estimator and case, grouped by paper, on a log axis."""
    value = spec.plot.get("metric", "bound_ratio")
    fig, ax = (ax.figure, ax) if ax is not None else plt.subplots(figsize=(7.5, 4.8), layout="constrained")
    papers = list(dict.fromkeys(s.split("_")[0] for s in frame.scenario))
    colours = {p: f"C{i}" for i, p in enumerate(papers)}
    handles, labels = [], []
    for k, est in enumerate(dict.fromkeys(frame.estimator)):
        sub = frame[frame.estimator == est]
        ax.scatter(sub.wall_time.clip(lower=1e-5), sub[value].clip(lower=1e-3), marker=MARKERS[k % len(MARKERS)],
                   c=[colours[s.split("_")[0]] for s in sub.scenario], s=36, edgecolors="k", linewidths=0.4)
        # the legend gives the marker alone (grey): the colour is the paper's, keyed below
        handles.append(plt.Line2D([], [], ls="", marker=MARKERS[k % len(MARKERS)], color="0.6", mec="k", mew=0.4))
        labels.append(est)
    handles.append(ax.axhline(1.0, color="k", lw=0.8, ls="--"))
    labels.append("efficient (Gaussian bound of matched covariance)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median fit wall time (s)")
    ax.set_ylabel(column_label(value))
    for p in papers:
        handles.append(plt.Line2D([], [], ls="", marker="s", color=colours[p]))
        labels.append(p)
    ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title(spec.title, fontsize=10)
    return tidy_log_axes(fig)
