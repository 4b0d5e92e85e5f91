"""The benchmark's tidy table: one row per (case, estimator) with accuracy, bound ratios, success and cost.

The bound ratio is ``sqrt(mean_s (e_s / b_s)^2)`` over the runs that SUCCEEDED (the artifact's
``success:`` rule, :func:`magexp.artifacts.plan.succeeded`): the RMS of the offset error ``e_s = |o_s - o|``
over ``b_s = sqrt(tr CRB_s)`` of its seed. For an efficient unbiased estimator ``E e^2 = tr CRB``, so
the ratio is 1 (the median of ``e / b`` is not: about 0.89 for an isotropic 3-D error, less when one
direction dominates). A failed run is not an accuracy: one run stuck on the search box has an offset
error of hundreds of nT and alone would make the RMS of 40 runs read a thousand. Failures are counted
beside it (``n_failed``, ``success_rate``), never mixed in; where no run is judged (no truth) every
run counts. The medians of the accuracy columns (:data:`ACCURACY`) are over the successful runs too;
the objective, iterations, evaluations and times over every run. The bound is the Cramér-Rao bound of *Gaussian* reading noise of the same covariance
(:mod:`magexp.core.bounds`); for Ding's uniform noise an estimator may go below it. Its 95 % interval is
a bootstrap over those seeds (:func:`magexp.artifacts.claims.ci`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts.plan import quantiles
from magexp.artifacts.claims import ci
from magexp.core.outcomes import recording_succeeded

# what each column is computed from (median over seeds unless said)
COLUMNS = {
    "fun": "final objective (RMS, or F_g for the vector objective)",
    "rms_ratio": "residual RMS / Cramér-Rao RMS floor (median over successful runs)",
    "offset_error": "offset error (reading units; median over successful runs)",
    "offset_error_ratio": "offset error / sqrt(tr CRB) (median over successful runs)",
    "gram_error_ratio": "W^T W error / its Cramér-Rao bound (median over successful runs)",
    "iterations_to_1.1": "iterations to reach 1.1 x the final objective",
    "nfev_to_1.1": "objective evaluations to reach 1.1 x the final objective",
    "wall_time": "fit wall time (s)",
    "spread_before": "recordings: std/mean of the raw magnitudes",
    "spread_after": "recordings: std/mean of the calibrated magnitudes (fitted readings)",
    "heldout_spread": "recordings: std/mean of the calibrated magnitudes of the held-out block",
    "coverage_cells": "recordings: fraction of 32 sphere cells the calibrated directions reach",
}


#: accuracy columns: their medians are over the successful runs only (failures are counted beside)
ACCURACY = {"rms_ratio", "offset_error", "offset_error_ratio", "gram_error_ratio"}

#: the columns of :func:`tabulate` computed here (not a median of a runs column)
DERIVED = {
    "bound_ratio": "RMS over successful runs of offset error / sqrt(tr CRB)",
    "success_rate": "fraction of runs that succeeded",
}


def column_label(column: str) -> str:
    """What a column of the table shows, in words (:data:`COLUMNS`, :data:`DERIVED`)."""
    return {**COLUMNS, **DERIVED}.get(column, column.replace("_", " "))


def case_label(cell: dict, grid_keys) -> str:
    """A short name of the case: the scenario and its own settings."""
    parts = [cell.get("scenario", "")]
    parts += [f"{k.split('.')[-1]}={v}" for k, v in cell.items() if k not in grid_keys and k != "scenario"]
    return " ".join(p for p in parts if p)


def successful(sub: pd.DataFrame) -> pd.DataFrame:
    """The runs of ``sub`` that succeeded (all of them where none is judged: no truth)."""
    if "succeeded" in sub and sub.succeeded.notna().any():
        return sub[sub.succeeded == 1]
    return sub


def bound_ratio(sub: pd.DataFrame) -> tuple[float, float, float]:
    """RMS over the successful seeds (every seed where none is judged) of offset error / sqrt(tr CRB),
    and its 95 % bootstrap interval (NaN without a bound or without a successful run)."""
    if "offset_error_ratio" not in sub:
        return (np.nan,) * 3
    r = successful(sub)["offset_error_ratio"].to_numpy(float)
    r = r[np.isfinite(r)]
    if r.size == 0:
        return (np.nan,) * 3
    lo, hi = ci(r, "rms")
    return float(np.sqrt(np.mean(r ** 2))), lo, hi


def tabulate(runs) -> pd.DataFrame:
    grid_keys = set(runs.spec.grid)
    rows = []
    for ci_, cell in enumerate(runs.cells):
        sub = runs.table[runs.table.cell == ci_]
        row = {"case": case_label(cell, grid_keys), "scenario": sub.scenario.iloc[0],
               "estimator": sub.estimator.iloc[0], "objective": sub.objective.iloc[0],
               "setting": sub.setting.iloc[0], "n_seeds": len(sub)}
        good = successful(sub)
        for col in COLUMNS:
            row[col] = quantiles((good if col in ACCURACY else sub)[col])[0] if col in sub else np.nan
        row["bound_ratio"], row["bound_ratio_lo"], row["bound_ratio_hi"] = bound_ratio(sub)
        ok = sub["succeeded"].dropna() if "succeeded" in sub else pd.Series(dtype=float)
        if not len(ok) and {"optimizer_success", "spread_after", "spread_before"} <= set(sub.columns):
            ok = pd.Series(recording_succeeded(sub.optimizer_success, sub.spread_before, sub.spread_after),
                           index=sub.index)  # no truth to compare with (recordings)
        row["success_rate"] = float(ok.mean()) if len(ok) else np.nan
        row["n_failed"] = int((ok == 0).sum()) if len(ok) else 0
        rows.append(row)
    return pd.DataFrame(rows)


def winners(frame: pd.DataFrame, by: str = "bound_ratio") -> pd.DataFrame:
    """Per case, the estimator with the lowest ``by``; it is the ``winner`` only where its 95 % CI
    lies entirely below every other estimator's, else ``tied`` lists those whose CIs overlap it."""
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
