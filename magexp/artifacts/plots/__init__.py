"""Artifact kinds: each module draws a figure from the CSV behind it, and aggregates nothing.

A kind module has ``draw(frame, spec) -> Figure``; the CSV it draws is the table
:func:`magexp.artifacts.kind_tables.tabulate` builds from the runs (every median, quantile and
interval is computed there and in :mod:`magexp.artifacts.tables`). Kinds are looked up by name in
:data:`KINDS`.
"""

from __future__ import annotations

import importlib

from magexp.errors import MagexpError

#: the vector twin written beside every PNG (for a paper: LaTeX's includegraphics takes it as is)
VECTOR = ".pdf"

KINDS = {
    "convergence": "magexp.artifacts.plots.convergence",
    "field": "magexp.artifacts.plots.field",
    "final": "magexp.artifacts.plots.final",  # final values (one or more metrics) vs a swept key
    "sphere": "magexp.artifacts.plots.field",  # readings vs the sphere |H| in 3-D (Yuan 2018 figs 2-4): field, quantity sphere
    "parameters": "magexp.artifacts.plots.parameters",  # parameter estimates vs truth and paper (tables)
    "trace": "magexp.artifacts.plots.trace",  # parameters vs filter step (Yan & Zhou 2022 figs 1, 3, 4)
    "heatmap": "magexp.artifacts.plots.heatmap",  # estimator x case, error / Cramér-Rao bound (benchmark)
    "speed": "magexp.artifacts.plots.speed",  # accuracy vs wall time (benchmark)
    "estimates": "magexp.artifacts.plots.estimates",  # table of fitted values per estimator vs truth (Yan & Zhou 2022)
    "sweep": "magexp.artifacts.plots.final",  # the old name of `final` with several metrics (one kind)
    "tuning": "magexp.artifacts.plots.tuning",  # settings of a method as a distribution beside its default
    "recording": "magexp.artifacts.plots.real",  # gyro-aided fits of a recording: objective, spread, estimates ± SE
    "recording_spread": "magexp.artifacts.plots.real_spread",  # every estimator on every recording: spread, held out
}


def kind_module(kind: str):
    """The module that draws the artifact kind ``kind`` (:data:`KINDS`).

    Parameters
    ----------
    kind : str
        An artifact kind, a key of :data:`KINDS`.

    Returns
    -------
    module
        The kind's module (its ``draw(frame, spec)``).
    """
    if kind not in KINDS:
        raise MagexpError(f"artifact kind={kind!r} is not allowed: choose one of {', '.join(sorted(KINDS))}")
    return importlib.import_module(KINDS[kind])
