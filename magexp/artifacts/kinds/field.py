"""The readings of the first seed before and after calibration: `quantity: magnitude`, `error` or `sphere`; `unit`: the readings' unit (Yuan's scenarios: `mG`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from magexp.artifacts.plot_keys import CommonPlot, choice
from magexp.artifacts.schema import typed
from magexp.artifacts.tables import cell_runs


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``field``: ``quantity`` (``magnitude``, ``error`` or ``sphere``) and
    ``unit`` (the readings' unit)."""

    quantity: str = "magnitude"
    unit: str = "nT"

    def __post_init__(self):
        choice("plot.quantity", self.quantity, ("magnitude", "error", "sphere"))


def shown_seed(runs, ci: int) -> tuple[int, str]:
    """The seed of cell ``ci`` whose readings are drawn and its outcome (``succeeded``, ``failed``
    or ``not judged``): the first successful seed, else the first seed.
    """
    seeds = sorted(s for (c, s) in runs.outputs if c == ci)
    sub = cell_runs(runs, ci)
    if "succeeded" not in sub or sub.succeeded.isna().all():
        return seeds[0], "not judged"
    ok = sub.set_index("seed").succeeded
    good = [s for s in seeds if ok.get(s) == 1]
    return (good[0], "succeeded") if good else (seeds[0], "failed")


def table(runs, plot) -> pd.DataFrame:
    """Per reading of each cell's :func:`shown_seed`: raw and calibrated vectors and total fields, the
    reference total field and the calibrated one's error (:mod:`magexp.artifacts.plots.field`)."""
    frames = []
    for ci, cell in enumerate(runs.cells):
        seed, outcome = shown_seed(runs, ci)
        out = runs.outputs[(ci, seed)]
        raw, cal = np.asarray(out.readings), np.asarray(out.calibrated)
        calibrated = np.linalg.norm(cal, axis=1)
        frames.append(pd.DataFrame({
            **cell, "seed": seed, "outcome": outcome, "reading": np.arange(len(raw)),
            "raw_x": raw[:, 0], "raw_y": raw[:, 1], "raw_z": raw[:, 2],
            "cal_x": cal[:, 0], "cal_y": cal[:, 1], "cal_z": cal[:, 2],
            "raw": np.linalg.norm(raw, axis=1), "calibrated": calibrated,
            "reference": out.reference_norm, "error": calibrated - out.reference_norm,
        }))
    return pd.concat(frames, ignore_index=True)


def draw(table, spec, axes=None):
    """Draws the shown seed's total field against the reference, or its readings in 3-D against the sphere
    (:func:`magexp.artifacts.plots.field.draw`)."""
    from magexp.artifacts.plots import field
    return field.draw(table, spec, axes)
