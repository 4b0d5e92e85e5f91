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
    """Draws ``plot.metric`` against wall time per estimator and case, on log axes
    (:func:`magexp.artifacts.plots.speed.draw`)."""
    from magexp.artifacts.plots import speed
    return speed.draw(table, spec, axes)
