"""The old name of `field` with `quantity: sphere`: the readings against the sphere of the field magnitude in 3-D (Yuan 2018 figs 2-4)."""

from __future__ import annotations

from dataclasses import dataclass

from magexp.artifacts.plot_keys import CommonPlot
from magexp.artifacts.kinds.field import draw, table  # noqa: F401 (the kind's table and drawing: field's)
from magexp.artifacts.schema import typed


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``sphere``: ``unit`` (the readings' unit)."""

    unit: str = "nT"
