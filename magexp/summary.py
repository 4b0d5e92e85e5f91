"""Reproduced numbers beside the paper's: the rows of ``results/summary.csv``."""

from __future__ import annotations

import numpy as np
import pandas as pd
from omegaconf import OmegaConf

from magexp.artifacts import ArtifactRuns, quantiles

COLUMNS = ["paper", "artifact", "quantity", "estimator", "setting", "truth", "paper_value", "value",
           "q25", "q75", "n_seeds", "tolerance", "verdict"]


def _same(a, b) -> bool:
    try:
        return float(a) == float(b)
    except (TypeError, ValueError):
        return str(a) == str(b)


def matches(selection: dict, settings: dict) -> bool:
    """True if every ``key: value`` of ``selection`` is among ``settings``."""
    return all(k in settings and _same(settings[k], v) for k, v in selection.items())


def tolerance_text(tol: dict) -> str:
    for kind in ("below", "abs", "factor"):
        if kind in tol:
            return f"{kind} {float(tol[kind]):g}"
    return f"rel {float(tol['rel']):g}"


def verdict(value: float, paper_value: float | None, tol: dict) -> str:
    """``match``/``differs`` against the paper under ``tol``; ``n/a`` without a paper value.

    ``tol`` is ``{rel: r}`` (``|v - p| <= r |p|``), ``{abs: a}`` (``|v - p| <= a``),
    ``{factor: f}`` (``p/f <= v <= p f``, for "at the 1e-4 level" claims) or ``{below: b}``
    (both below ``b``).
    """
    if paper_value is None or not np.isfinite(paper_value):
        return "n/a"
    if not np.isfinite(value):
        return "differs"
    if "abs" in tol:
        return "match" if abs(value - paper_value) <= float(tol["abs"]) else "differs"
    if "below" in tol:
        return "match" if value < float(tol["below"]) and paper_value < float(tol["below"]) else "differs"
    if "factor" in tol:
        f = float(tol["factor"])
        return "match" if paper_value / f <= value <= paper_value * f else "differs"
    return "match" if abs(value - paper_value) <= float(tol["rel"]) * abs(paper_value) else "differs"


def cell_settings(runs: ArtifactRuns, ci: int) -> dict:
    """The ``{key: value}`` overrides of cell ``ci`` (base and grid)."""
    return dict(o.split("=", 1) for o in runs.overrides[ci])


def reported_entries(spec) -> list[dict]:
    """The spec's ``reported`` entries, a vector entry ``{quantities: [...], values: [...]}``
    (e.g. one column of a parameter table) expanded into one entry per quantity."""
    out = []
    for entry in OmegaConf.to_container(spec.reported, resolve=True):
        if "quantities" in entry:
            rest = {k: v for k, v in entry.items() if k not in ("quantities", "values")}
            out += [{**rest, "quantity": q, "value": v} for q, v in zip(entry["quantities"], entry["values"])]
        else:
            out.append(entry)
    return out


def reported_value(spec, quantity: str, settings: dict):
    """The paper's value of ``quantity`` for a cell with ``settings`` and its tolerance (None if absent)."""
    for entry in reported_entries(spec):
        if entry["quantity"] == quantity and matches(entry.get("match", {}), settings):
            return float(entry["value"]), entry.get("tolerance") or OmegaConf.to_container(spec.tolerance)
    return None, OmegaConf.to_container(spec.tolerance)


def _row(spec, quantity, estimator, setting, truth, values, settings, extra_setting: str = "",
         aggregate: str = "median") -> dict:
    if aggregate == "mean":  # fractions: the mean of 0/1 outcomes, no quantiles
        finite = np.asarray(values, float)
        med, q25, q75 = float(np.nanmean(finite)), np.nan, np.nan
    else:
        med, q25, q75 = quantiles(values)
    paper_value, tol = reported_value(spec, quantity, settings)
    return {
        "paper": spec.paper, "artifact": spec.name, "quantity": quantity, "estimator": estimator,
        "setting": setting + extra_setting, "truth": truth, "paper_value": paper_value, "value": med,
        "q25": q25, "q75": q75, "n_seeds": int(np.isfinite(np.asarray(values, float)).sum()),
        "tolerance": tolerance_text(tol) if paper_value is not None else "", "verdict": verdict(med, paper_value, tol),
    }


def parameter_values(runs: ArtifactRuns, ci: int) -> tuple[list[str], np.ndarray, np.ndarray | None]:
    """Parameter names, estimates ``(seeds, p)`` and the true vector of cell ``ci``."""
    outs = [runs.outputs[k] for k in sorted(runs.outputs) if k[0] == ci]
    truth = getattr(outs[0], "truth_x", None)
    return list(outs[0].parameter_names), np.array([o.x for o in outs]), truth


def _parameter_rows(runs: ArtifactRuns, item: dict) -> list[dict]:
    """``mode: parameters``: one row per (cell, parameter) with the median estimate and the truth;
    ``only`` (optional) restricts to those estimators."""
    rows = []
    for ci in range(len(runs.cells)):
        sub = runs.table[runs.table.cell == ci]
        if item.get("only") and sub.estimator.iloc[0] not in item["only"]:
            continue
        names, values, truth = parameter_values(runs, ci)
        for k, name in enumerate(names):
            rows.append(_row(runs.spec, name, sub.estimator.iloc[0], sub.setting.iloc[0],
                             None if truth is None else float(truth[k]), values[:, k], cell_settings(runs, ci)))
    return rows


def summarise(runs: ArtifactRuns) -> pd.DataFrame:
    """One row per (summarised quantity, cell) and per ratio group."""
    spec, table = runs.spec, runs.table
    rows = []
    for item in OmegaConf.to_container(spec.summarise, resolve=True):
        if item.get("mode") == "parameters":
            rows += _parameter_rows(runs, item)
            continue
        metric = item["metric"]
        truth_metric = item.get("truth_metric", f"truth_{metric}")
        for ci in range(len(runs.cells)):
            sub = table[table.cell == ci]
            if metric not in sub or sub[metric].isna().all():
                continue
            truth = float(np.median(sub[truth_metric])) if truth_metric in sub and sub[truth_metric].notna().all() else None
            rows.append(_row(spec, item["quantity"], sub.estimator.iloc[0], sub.setting.iloc[0], truth,
                             sub[metric].astype(float).to_numpy(), cell_settings(runs, ci),
                             aggregate=item.get("aggregate", "median")))
    for item in OmegaConf.to_container(spec.ratios, resolve=True):
        num_sel, den_sel, metric = item["numerator"], item["denominator"], item["metric"]
        for ci in range(len(runs.cells)):
            settings = cell_settings(runs, ci)
            if not matches(den_sel, settings):
                continue
            partner = {**settings, **num_sel}
            nj = [cj for cj in range(len(runs.cells)) if cell_settings(runs, cj) == partner]
            if not nj:
                continue
            den = table[table.cell == ci].set_index("seed")[metric].astype(float)
            num = table[table.cell == nj[0]].set_index("seed")[metric].astype(float)
            ratio = (num / den).dropna().to_numpy()
            sub = table[table.cell == ci]
            ref = ",".join(f"{k}={v}" for k, v in num_sel.items())
            rows.append(_row(spec, item["quantity"], sub.estimator.iloc[0], sub.setting.iloc[0], None, ratio,
                             settings, extra_setting=f";reference={ref}"))
    return pd.DataFrame(rows, columns=COLUMNS)
