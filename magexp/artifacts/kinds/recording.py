"""Recordings, which have no truth: gyro-aided fits (the objective, the spread, the estimates with their standard errors)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from magexp.artifacts.plot_keys import CommonPlot
from magexp.artifacts.schema import typed
from magexp.artifacts.tables import cell_runs, fraction, median, outcomes, parameter_values, scenario_label


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``recording``: ``metric`` (the fit's objective per seed)."""

    metric: str = "fg"


#: per-run quantities of the ``recording`` table (one row per seed)
RUN_QUANTITIES = ("fg", "vector_residual_fraction", "spread_before", "spread_after", "weakest_relative_sv",
                  "gyro_bias_rest_x", "gyro_bias_rest_y", "gyro_bias_rest_z")


def canonical_sign(names: list[str], x: np.ndarray) -> np.ndarray:
    """The member with ``det S > 0`` of the pair ``(S, b, h)``, ``(-S, b, -h)`` that the gyro-aided
    objective cannot tell apart (``h`` by azimuth ``a`` and elevation ``e``: ``-h`` is ``(a + pi, -e)``);
    other parameter vectors are returned as they are.
    """
    x = np.array(x, float)
    if "field_azimuth" not in names or np.linalg.det(x[:9].reshape(3, 3)) >= 0:
        return x
    a, e = names.index("field_azimuth"), names.index("field_elevation")
    x[:9] *= -1
    x[a] = np.mod(x[a] + 2 * np.pi, 2 * np.pi) - np.pi
    x[e] = -x[e]
    return x


def _hue_labels(runs) -> list[str]:
    """One readable label per cell: the estimator where one recording is fitted, the recording where
    one estimator is, both otherwise; an estimator setting the cell sets in brackets."""
    firsts = runs.table.drop_duplicates("cell").sort_values("cell")
    one_scenario, one_estimator = firsts.scenario.nunique() == 1, firsts.estimator.nunique() == 1
    out = []
    for (_, r), cell in zip(firsts.iterrows(), runs.cells):
        parts = ([] if one_scenario else [scenario_label(r.scenario)]) + ([] if one_estimator and not one_scenario
                                                                        else [r.estimator])
        own = [str(v) for k, v in cell.items() if k.startswith("estimator.")]
        out.append(", ".join(parts) + (f" ({', '.join(own)})" if own else ""))
    return out


def table(runs, plot) -> pd.DataFrame:
    """Rows ``row = run`` (a per-run quantity of one seed) and ``row = estimate`` (a parameter: median over the
    successful seeds, and of their standard errors) (:mod:`magexp.artifacts.plots.real`)."""
    rows = []
    for ci, label in enumerate(_hue_labels(runs)):
        sub = cell_runs(runs, ci, by_seed=True)
        ok = outcomes(sub)
        head = {"label": label, "estimator": sub.estimator.iloc[0], "scenario": sub.scenario.iloc[0],
                "n_seeds": len(sub), "n_success": int(np.nansum(ok)), "success_rate": fraction(ok)}
        for (_, run), good in zip(sub.iterrows(), ok):
            rows += [{**head, "row": "run", "quantity": q, "seed": int(run.seed), "value": float(run[q]), "se": np.nan,
                      "succeeded": good} for q in RUN_QUANTITIES if q in run and np.isfinite(run[q])]
        names, values, _ = parameter_values(runs, ci)
        values = np.array([canonical_sign(names, v) for v in values])
        kept = (ok == 1) if np.isfinite(ok).any() else np.ones(len(ok), bool)
        for k, name in enumerate(names):
            se = sub[f"se_{name}"].to_numpy(float)[kept] if f"se_{name}" in sub else np.array([])
            rows.append({**head, "row": "estimate", "quantity": name, "seed": np.nan,
                         "value": median(values[kept, k]) if kept.any() else np.nan,
                         "se": median(se) if se.size and not np.isnan(se).any() else np.nan, "succeeded": np.nan})
    return pd.DataFrame(rows)


def draw(table, spec, axes=None):
    """Draws per recording the objective, the spread and the estimates with their standard errors
    (:func:`magexp.artifacts.plots.real.draw`)."""
    from magexp.artifacts.plots import real
    return real.draw(table, spec, axes)
