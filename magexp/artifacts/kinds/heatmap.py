"""Estimator × case against the Cramér-Rao bound (benchmark runs)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from magexp.artifacts.columns import ACCURACY, COLUMNS
from magexp.artifacts.plot_keys import CommonPlot
from magexp.artifacts.schema import typed
from magexp.artifacts.tables import cell_runs, fraction, interval, median, successful
from magexp.core.metrics import rms
from magexp.core.outcomes import recording_succeeded


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``heatmap``: ``metric`` (the column colouring the cells)."""

    metric: str = "bound_ratio"


def _case_label(cell: dict, grid_keys) -> str:
    """A short name of the case: the scenario and its own settings."""
    parts = [cell.get("scenario", "")]
    parts += [f"{k.split('.')[-1]}={v}" for k, v in cell.items() if k not in grid_keys and k != "scenario"]
    return " ".join(p for p in parts if p)


def bound_ratio(sub: pd.DataFrame) -> tuple[float, float, float]:
    """RMS over the successful seeds (every seed where none is judged) of offset error / sqrt(tr CRB),
    and its 95 % bootstrap interval (NaN without a bound or without a successful run).
    """
    if "offset_error_ratio" not in sub:
        return (np.nan,) * 3
    r = successful(sub)["offset_error_ratio"].to_numpy(float)
    r = r[np.isfinite(r)]
    if r.size == 0:
        return (np.nan,) * 3
    lo, hi = interval(r, stat="rms")
    return float(rms(r)), lo, hi


def table(runs, plot) -> pd.DataFrame:
    """Per (case, estimator): accuracy medians over the successful runs, the bound ratio with its interval,
    success rate and failures (success on recordings: the fit's verdict and a spread below the raw one)."""
    grid_keys = set(runs.spec.grid)
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = cell_runs(runs, ci)
        row = {"case": _case_label(cell, grid_keys), "scenario": sub.scenario.iloc[0],
               "estimator": sub.estimator.iloc[0], "objective": sub.objective.iloc[0],
               "setting": sub.setting.iloc[0], "n_seeds": len(sub)}
        good = successful(sub)
        row.update({col: median((good if col in ACCURACY else sub)[col]) if col in sub else np.nan for col in COLUMNS})
        row["bound_ratio"], row["bound_ratio_lo"], row["bound_ratio_hi"] = bound_ratio(sub)
        ok = sub["succeeded"].dropna() if "succeeded" in sub else pd.Series(dtype=float)
        if not len(ok) and {"optimizer_flag", "spread_after", "spread_before"} <= set(sub.columns):
            ok = pd.Series(recording_succeeded(sub.optimizer_flag, sub.spread_before, sub.spread_after),
                           index=sub.index)  # no truth to compare with (recordings)
        row["success_rate"] = fraction(ok) if len(ok) else np.nan
        row["n_failed"] = int((ok == 0).sum()) if len(ok) else 0
        rows.append(row)
    return pd.DataFrame(rows)


def winners(frame: pd.DataFrame, by: str = "bound_ratio") -> pd.DataFrame:
    """Per case, the estimator with the lowest ``by``; it is the ``winner`` only where its 95 % CI
    lies entirely below every other estimator's, else ``tied`` lists those whose CIs overlap it.
    """
    out = []
    for case, sub in frame.groupby("case", sort=False):
        sub = sub[np.isfinite(sub[by])]
        if sub.empty:
            continue
        best = sub.loc[sub[by].idxmin()]
        others = sub.drop(index=best.name)
        overlap = others[others[f"{by}_lo"] <= best[f"{by}_hi"]]
        out.append({"case": case, "winner": best.estimator if overlap.empty else "none (CIs overlap)",
                    by: best[by], f"{by}_lo": best[f"{by}_lo"], f"{by}_hi": best[f"{by}_hi"],
                    "success_rate": best.success_rate, "best": best.estimator,
                    "tied": ", ".join([best.estimator, *overlap.estimator]) if len(overlap) else ""})
    return pd.DataFrame(out)


def draw(table, spec, axes=None):
    """Draws estimator against case, coloured by ``plot.metric`` (default the bound ratio)
    (:func:`magexp.artifacts.plots.heatmap.draw`)."""
    from magexp.artifacts.plots import heatmap
    return heatmap.draw(table, spec, axes)
