"""The benchmark's tidy table: one row per (case, estimator) with accuracy, bound ratios and cost."""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts import quantiles

# what each column is computed from (median over seeds unless said)
COLUMNS = {
    "fun": "final objective (RMS, or F_g for the vector objective)",
    "rms_ratio": "residual RMS / Cramér-Rao RMS floor",
    "offset_error": "offset error (reading units)",
    "offset_error_ratio": "offset error / its Cramér-Rao bound",
    "gram_error_ratio": "W^T W error / its Cramér-Rao bound",
    "iterations_to_1.1": "iterations to reach 1.1 x the final objective",
    "nfev_to_1.1": "objective evaluations to reach 1.1 x the final objective",
    "wall_time": "fit wall time (s)",
    "spread_before": "recordings: std/mean of the raw magnitudes",
    "spread_after": "recordings: std/mean of the calibrated magnitudes (fitted readings)",
    "heldout_spread": "recordings: std/mean of the calibrated magnitudes of the held-out block",
    "coverage_cells": "recordings: fraction of 32 sphere cells the calibrated directions reach",
}


def case_label(cell: dict, grid_keys) -> str:
    """A short name of the case: the scenario and its own settings."""
    parts = [cell.get("scenario", "")]
    parts += [f"{k.split('.')[-1]}={v}" for k, v in cell.items() if k not in grid_keys and k != "scenario"]
    return " ".join(p for p in parts if p)


def tabulate(runs) -> pd.DataFrame:
    grid_keys = set(runs.spec.grid)
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = runs.table[runs.table.cell == ci]
        row = {"case": case_label(cell, grid_keys), "scenario": sub.scenario.iloc[0],
               "estimator": sub.estimator.iloc[0], "objective": sub.objective.iloc[0],
               "setting": sub.setting.iloc[0], "n_seeds": len(sub)}
        for col in COLUMNS:
            row[col] = quantiles(sub[col])[0] if col in sub else np.nan
        if "offset_error_ratio" in sub:
            ratio = sub["offset_error_ratio"].astype(float)
            row["success_rate"] = float((ratio <= 2.0).mean()) if ratio.notna().any() else np.nan
        elif "success" in sub:  # no bound to compare with (recordings): the estimator's own verdict
            row["success_rate"] = float(sub["success"].astype(bool).mean())
        else:
            row["success_rate"] = np.nan
        q = quantiles(sub["offset_error_ratio"]) if "offset_error_ratio" in sub else (np.nan,) * 3
        row["offset_error_ratio_q25"], row["offset_error_ratio_q75"] = q[1], q[2]
        rows.append(row)
    return pd.DataFrame(rows)


def best_per_case(frame: pd.DataFrame, by: str = "offset_error_ratio") -> pd.DataFrame:
    """The most accurate estimator of each case (ties within 5 % go to the fastest)."""
    out = []
    for case, sub in frame.groupby("case", sort=False):
        sub = sub[np.isfinite(sub[by])] if np.isfinite(sub[by]).any() else sub.assign(**{by: sub["fun"]})
        best = sub[by].min()
        near = sub[sub[by] <= 1.05 * best]
        out.append(near.sort_values("wall_time").iloc[0])
    return pd.DataFrame(out)
