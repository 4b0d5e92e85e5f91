"""Accuracy against wall time (the same benchmark runs as `heatmap`)."""

from __future__ import annotations

from dataclasses import dataclass

from magexp.artifacts.plot_keys import CommonPlot
from magexp.artifacts.kinds.heatmap import table  # noqa: F401 (the benchmark table: heatmap's)
from magexp.artifacts.schema import typed


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``speed``: ``metric`` (the accuracy column on the log axis)."""

    metric: str = "bound_ratio"


def draw(table, spec, axes=None):
    """The figure of the ``speed`` table (:func:`magexp.artifacts.plots.speed.draw`; matplotlib loads only here).

    Parameters
    ----------
    table : pandas.DataFrame
        The table :func:`table` wrote (the artifact's CSV, read back).
    spec : Artifact
        The artifact: its title, its typed ``plot`` and what it compares.
    axes : matplotlib Axes or list of them, optional
        The caller's panels (default: a new figure).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    from magexp.artifacts.plots import speed
    return speed.draw(table, spec, axes)
