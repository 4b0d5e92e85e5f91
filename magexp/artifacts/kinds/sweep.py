"""The old name of `final`."""

from __future__ import annotations

from magexp.artifacts.kinds.final import Plot, draw, table  # noqa: F401 (the kind is final's)
