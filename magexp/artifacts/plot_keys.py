"""The ``plot:`` keys every artifact kind takes (the base of each kind's ``Plot`` dataclass, :mod:`magexp.artifacts.kinds`)
and the helpers a kind's table and its drawing share."""

from __future__ import annotations

from dataclasses import dataclass, field

from magexp.artifacts.schema import typed
from magexp.errors import MagexpError


@typed
@dataclass(frozen=True, kw_only=True)
class CommonPlot:
    """The keys of every kind: ``labels`` (a grid key's words on axes and legends), ``ylabel`` (the y
    axis text; None: the kind's own), ``panels`` (one panel per value of this key) and ``hue`` (one
    line or colour per value of this key)."""

    labels: dict[str, str] = field(default_factory=dict)
    ylabel: str | None = None
    panels: str | None = None
    hue: str | None = None

    def get(self, key: str, default=None):
        """A key's value, or ``default`` where it is unset (None) or not a key of this kind: the drawings
        read the typed keys and a test's plain mapping alike.
        """
        value = getattr(self, key, None)
        return default if value is None else value


def choice(where: str, value, allowed: tuple) -> None:
    """Raise, in one line, unless ``value`` is one of ``allowed``."""
    if value not in allowed:
        raise MagexpError(f"{where}={value!r} is not allowed: choose one of {', '.join(allowed)}")


#: the fit-quality row a ``parameters`` cell gets where its runs measure it: (parameter name, runs column)
FIT = ("F_g", "fg")


def metric_list(plot) -> list[str]:
    """The metric columns a ``final`` figure draws."""
    metric = plot.get("metric", "fun")
    return [metric] if isinstance(metric, str) else list(metric)
