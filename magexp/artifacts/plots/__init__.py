"""The drawings of the artifact kinds: each module draws a figure from the CSV behind it, and aggregates nothing.

A kind (:mod:`magexp.artifacts.kinds`) draws through one of these modules' ``draw(frame, spec)``;
the CSV it draws is the table the kind's ``table(runs, plot)`` builds from the runs (every median,
quantile and interval is computed there and in :mod:`magexp.artifacts.tables`). The style shared by
every figure is :mod:`magexp.artifacts.plots.style`.
"""

from __future__ import annotations

#: the vector twin written beside every PNG (for a paper: LaTeX's includegraphics takes it as is)
VECTOR = ".pdf"
