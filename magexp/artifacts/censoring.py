"""Censored time-to-event metrics: a step of convergence measured inside a finite horizon.

A run's metric ``m`` (e.g. ``steps_to_ls``, :mod:`magexp.estimators.kalman`) is *right-censored*
when the event was not observed within the run's horizon: its runs column is NaN and the column
``m_censored`` holds the censoring point ``c`` (the event is later than ``c``; 0 when observed).
With one censoring point for all runs of a cell, every censored value exceeds every observed one,
so an order statistic of the ``n`` values is known exactly when it falls among the observed ones
and is only known to exceed ``c`` otherwise:

.. math::
    \\operatorname{median}(v) = \\begin{cases} \\text{its observed value}, & k < n/2 \\\\
    > c, & \\text{else} \\end{cases}

with ``k`` the number of censored values (likewise a quantile, the maximum when ``k > 0``, the
minimum when ``k = n``; a mean is unknown as soon as ``k > 0``). :func:`with_censored` gives each
censored value as ``+inf`` (a comparison ``m <= x`` with ``x < c`` is then correctly false),
:func:`censored_statistic` a statistic that is ``+inf`` when censored, and :func:`censored_text`
what a report prints in its place: "> 1200 (censored in 19 of 30 seeds)". A median of the
observed values alone is never reported (it would be biased low).

References: Kalbfleisch & Prentice (2002), *The Statistical Analysis of Failure Time Data*, ch. 1
(right censoring).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts.tables import statistic

SUFFIX = "_censored"
_BIG = 1e300  # a censored value inside a quantile's interpolation (any result near it is censored)


def censored_mask(runs: pd.DataFrame, metric: str) -> np.ndarray:
    """Per run, whether ``metric`` (a runs column) is censored (False for an expression or no flag)."""
    flag = f"{metric}{SUFFIX}"
    if metric not in runs or flag not in runs:
        return np.zeros(len(runs), bool)
    return pd.to_numeric(runs[flag], errors="coerce").fillna(0).to_numpy(float) > 0


def with_censored(runs: pd.DataFrame) -> pd.DataFrame:
    """``runs`` with every censored value of a column that has a ``_censored`` flag as ``+inf``."""
    flagged = [c[: -len(SUFFIX)] for c in runs.columns if c.endswith(SUFFIX) and c[: -len(SUFFIX)] in runs]
    masks = {c: censored_mask(runs, c) for c in flagged}
    if not any(m.any() for m in masks.values()):
        return runs
    runs = runs.copy()
    for column, mask in masks.items():
        runs[column] = np.where(mask, np.inf, pd.to_numeric(runs[column], errors="coerce"))
    return runs


def censored_statistic(v: np.ndarray, stat: str) -> float:
    """``stat`` of ``v`` where ``+inf`` marks a censored value: ``+inf`` when the statistic is not
    known (module docstring), else its value.
    """
    v = np.asarray(v, float)
    censored = np.isposinf(v)
    if not censored.any():
        return statistic(v, stat)
    if stat in ("mean", "rms"):
        return np.inf
    s = statistic(np.where(censored, _BIG, v), stat)
    return np.inf if s >= _BIG * 1e-6 else s


def censored_text(runs: pd.DataFrame, metric: str, fmt: str = "g") -> str:
    """The words printed for a censored statistic of ``metric``: "> c (censored in k of n seeds)"."""
    mask = censored_mask(runs, metric)
    points = pd.to_numeric(runs[f"{metric}{SUFFIX}"], errors="coerce").to_numpy(float)[mask]
    return f"> {format(float(points.min()), fmt)} (censored in {int(mask.sum())} of {len(mask)} seeds)"


def cell_quartiles(runs: pd.DataFrame, metric: str) -> dict:
    """The median and quartiles of ``metric`` over one cell's runs; for a censored metric also its
    extremes, the number of censored runs and the censoring point (``+inf``: a statistic not known).
    """
    if metric not in runs:
        return {"median": np.nan, "q25": np.nan, "q75": np.nan}
    mask = censored_mask(runs, metric)
    v = np.where(mask, np.inf, pd.to_numeric(runs[metric], errors="coerce").to_numpy(float))
    v = v[np.isfinite(v) | mask]
    out = {stat: censored_statistic(v, stat) if len(v) else np.nan for stat in ("median", "q25", "q75")}
    if f"{metric}{SUFFIX}" not in runs:
        return out
    points = pd.to_numeric(runs[f"{metric}{SUFFIX}"], errors="coerce").to_numpy(float)[mask]
    return {**out, **{stat: censored_statistic(v, stat) if len(v) else np.nan for stat in ("min", "max")},
            "n_censored": int(mask.sum()), "censor_point": float(points.min()) if mask.any() else np.nan}


def censor_row(row: dict, runs: pd.DataFrame, metric: str) -> dict:
    """A summary row of ``metric`` over one cell's ``runs`` with its censoring applied: its median,
    quartiles and judged value by :func:`cell_quartiles` (``+inf`` where censored), no interval (a
    bootstrap of censored values is none), every seed counted and the reason saying how many are
    censored. Unchanged when no run is censored.
    """
    mask = censored_mask(runs, metric)
    if not mask.any():
        return row
    q = cell_quartiles(runs, metric)
    why = f"{int(mask.sum())} of {len(mask)} seeds censored (later than {q['censor_point']:g})"
    return {**row, "value": q["median"], "q25": q["q25"], "q75": q["q75"], "judged_value": q["median"],
            "lo": np.nan, "hi": np.nan, "judged_lo": np.nan, "judged_hi": np.nan, "n_seeds": len(mask),
            "judged_n": len(mask), "reason": "; ".join(r for r in (str(row.get("reason") or ""), why) if r)}
