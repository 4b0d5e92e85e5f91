"""The objective of the best particle against iteration: median over seeds with an interquartile band."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from magexp.artifacts.plot_keys import CommonPlot
from magexp.artifacts.schema import typed
from magexp.artifacts.tables import cell_runs, median, quartiles, successful


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``convergence``: those of every kind."""

    ylabel: str = "total-field RMS (nT)"


def _stack(histories: list[np.ndarray]) -> np.ndarray:
    """The histories as one array, each shorter one padded with its last value (a run that stopped holds its value)."""
    n = max(len(h) for h in histories)
    return np.vstack([np.pad(h, (0, n - len(h)), mode="edge") for h in histories])


def _count(sub: pd.DataFrame, column: str) -> int:
    """How many of a cell's runs have ``column`` true (-1: not recorded, or no run judged)."""
    return int(sub[column].sum()) if column in sub and sub[column].notna().any() else -1


def table(runs, plot) -> pd.DataFrame:
    """Per cell and iteration: quartiles over seeds of the best objective, median evaluations, floors,
    success counts and the median iterations to 1.1 x the final value (:mod:`magexp.artifacts.plots.convergence`)."""
    frames = []
    for ci, cell in enumerate(runs.cells):
        seeds = sorted(s for (c, s) in runs.outputs if c == ci)
        hist = _stack([runs.outputs[(ci, s)].history for s in seeds])
        nfev = _stack([runs.outputs[(ci, s)].history_nfev for s in seeds])
        q50, q25, q75 = quartiles(hist, axis=0)
        sub = cell_runs(runs, ci)
        speed = successful(sub)["iterations_to_1.1"] if "iterations_to_1.1" in sub else []
        frames.append(pd.DataFrame({
            **cell, "estimator": sub.estimator.iloc[0], "iteration": np.arange(hist.shape[1]),
            "nfev": quartiles(nfev, axis=0)[0], "median": q50, "q25": q25, "q75": q75,
            "noise_floor": median(sub.noise_floor) if "noise_floor" in sub else np.nan,
            "rms_bound": median(sub.rms_bound) if "rms_bound" in sub else np.nan, "n_seeds": len(seeds),
            "converged": int(sub.converged.sum()) if "converged" in sub else -1, "succeeded": _count(sub, "succeeded"),
            "iterations_to_1.1": median(speed),
        }))
    return pd.concat(frames, ignore_index=True)



def draw(table, spec, axes=None):
    """Draws the best objective against iteration, median and interquartile band per cell
    (:func:`magexp.artifacts.plots.convergence.draw`)."""
    from magexp.artifacts.plots import convergence
    return convergence.draw(table, spec, axes)
