"""The columns of the benchmark table (the kinds ``heatmap`` and ``speed``): what each one shows, in words."""

from __future__ import annotations

#: what each benchmark column is computed from (median over seeds unless said)
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
#: the columns of :func:`magexp.artifacts.kinds.heatmap.table` computed here (not a median of a runs column)
DERIVED = {
    "bound_ratio": "RMS over successful runs of offset error / sqrt(tr CRB)",
    "success_rate": "fraction of runs that succeeded",
}


def column_label(column: str) -> str:
    """What a column of the benchmark table shows, in words."""
    return {**COLUMNS, **DERIVED}.get(column, column.replace("_", " "))
