"""Every estimator's spread on every recording, fitted and held out."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from magexp.artifacts.plot_keys import CommonPlot
from magexp.artifacts.schema import typed
from magexp.artifacts.tables import cell_runs, median, fraction, scenario_label
from magexp.core.outcomes import recording_succeeded


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``recording_spread``: ``metric`` (the column the report ranks by)."""

    metric: str | None = None


#: the per-cell medians of the ``recording_spread`` table
SPREAD_COLUMNS = ("spread_before", "spread_after", "heldout_spread", "coverage_cells", "wall_time")


def table(runs, plot) -> pd.DataFrame:
    """Per (recording, estimator): medians of :data:`SPREAD_COLUMNS`, the widest held-out spread interval
    of the seeds and the success rate (reported success and a spread below the raw one)."""
    rows = []
    for ci in range(len(runs.cells)):
        sub = cell_runs(runs, ci)
        row = {"case": scenario_label(sub.scenario.iloc[0]), "scenario": sub.scenario.iloc[0],
               "estimator": sub.estimator.iloc[0], "objective": sub.objective.iloc[0],
               "setting": sub.setting.iloc[0], "n_seeds": len(sub)}
        row.update({c: median(sub[c]) if c in sub else np.nan for c in SPREAD_COLUMNS})
        lo, hi = (sub[c].to_numpy(float) if c in sub else np.array([np.nan])
                  for c in ("heldout_spread_lo", "heldout_spread_hi"))
        row["heldout_spread_lo"] = float(np.min(lo)) if np.isfinite(lo).all() else np.nan
        row["heldout_spread_hi"] = float(np.max(hi)) if np.isfinite(hi).all() else np.nan
        row["success_rate"] = fraction(recording_succeeded(sub.optimizer_flag, sub.spread_before, sub.spread_after))
        rows.append(row)
    return pd.DataFrame(rows)


def draw(table, spec, axes=None):
    """Draws each estimator's fitted and held-out spread on every recording
    (:func:`magexp.artifacts.plots.real_spread.draw`)."""
    from magexp.artifacts.plots import real_spread
    return real_spread.draw(table, spec, axes)
