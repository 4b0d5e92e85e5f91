"""Parameters against filter step (Yan & Zhou 2022, figs 1, 3 and 4); `relative_to: ls` adds a row of each seed's distance from that estimator's solution on a log axis, with `tolerances` per group."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from magexp.artifacts.plot_keys import CommonPlot
from magexp.artifacts.schema import Float, typed
from magexp.artifacts.tables import cell_runs, quartiles


@typed
@dataclass(frozen=True, kw_only=True)
class Plot(CommonPlot):
    """The ``plot:`` keys of ``trace``: ``groups`` (lists of parameters, a panel each), ``trace`` (the
    runs' trace key), ``start`` (the first step drawn), ``names`` (``{estimator: words}``),
    ``relative_to`` (the reference estimator of the distance row) and ``tolerances`` (one per group)."""

    ylabel: str = "estimate"
    groups: list[list[str]] = field(default_factory=list)
    trace: str = "x"
    start: Float = 0.0
    names: dict[str, str] = field(default_factory=dict)
    relative_to: str | None = None
    tolerances: list[Float] = field(default_factory=list)


def _names(out, key: str) -> list[str]:
    """The names of the traced ``key`` columns (the estimator's parameter names unless the trace gives its own)."""
    return list(out.trace.get(f"{key}_names", out.parameter_names))


def _quantile_rows(stack: np.ndarray, names: list[str], fixed: dict, step=None) -> pd.DataFrame:
    """Quartiles over seeds (axis 0) of ``stack`` (seeds, steps, p), one row per (step, name)."""
    q50, q25, q75 = quartiles(stack, axis=0)
    steps = np.arange(stack.shape[1]) if step is None else np.full(stack.shape[1], step)
    return pd.concat([pd.DataFrame({**fixed, "parameter": name, "step": steps, "median": q50[:, j], "q25": q25[:, j],
                                    "q75": q75[:, j], "n_seeds": stack.shape[0]}) for j, name in enumerate(names)],
                     ignore_index=True)


def _levels(sub: pd.DataFrame, names: list[str], prefix: str, kind: str, cell: dict, estimator: str) -> list[dict]:
    """One row per parameter of a level drawn across the steps (a truth, a reference's estimate)."""
    rows = []
    for name in (n for n in names if f"{prefix}{n}" in sub and sub[f"{prefix}{n}"].notna().any()):
        med, q25, q75 = quartiles(sub[f"{prefix}{name}"])
        rows.append({**cell, "estimator": estimator, "kind": kind, "parameter": name, "step": np.nan,
                     "median": med, "q25": q25, "q75": q75, "n_seeds": len(sub)})
    return rows


def _distances(runs, key: str, names: list[str], traced: set) -> list[pd.DataFrame]:
    """Rows of ``|x - x_ref|`` per parameter (``plot.relative_to``: the reference estimator): each
    traced cell's trace per step (kind ``distance``), every other cell's estimate and the truth
    (kind ``distance_reference``, ``distance_truth``), quartiles over the seeds they share."""
    ref = runs.spec.plot.get("relative_to")
    table = runs.table
    ref_rows = table[table.estimator == ref].set_index("seed")[names] if ref else None
    if ref_rows is None or not len(ref_rows):
        return []
    frames = []
    for ci, cell in enumerate(runs.cells):
        sub = table[table.cell == ci].set_index("seed")
        est, seeds = sub.estimator.iloc[0], sorted(set(sub.index) & set(ref_rows.index))
        if est == ref or not seeds:
            continue
        ref_at = ref_rows.loc[seeds].to_numpy(float)
        if ci in traced:
            stack = np.stack([np.abs(np.asarray(runs.outputs[(ci, s)].trace[key]) - ref_rows.loc[s].to_numpy(float))
                              for s in seeds])
            frames.append(_quantile_rows(stack, names, {**cell, "estimator": est, "kind": "distance"}))
            truth = [f"truth_{n}" for n in names]
            if set(truth) <= set(sub.columns):
                gap = np.abs(sub.loc[seeds, truth].to_numpy(float) - ref_at)
                frames.append(_quantile_rows(gap[:, None, :], names, {**cell, "estimator": est, "kind": "distance_truth"},
                                             step=np.nan))
        else:
            gap = np.abs(sub.loc[seeds, names].to_numpy(float) - ref_at)
            frames.append(_quantile_rows(gap[:, None, :], names, {**cell, "estimator": est, "kind": "distance_reference"},
                                         step=np.nan))
    return frames


def table(runs, plot) -> pd.DataFrame:
    """Per traced cell, parameter and step: quartiles over seeds of ``trace[plot.trace]``; the truth and
    the untraced cells' estimates as levels; the distances from ``plot.relative_to``."""
    key = plot.trace
    traced = {ci for (ci, s), out in runs.outputs.items() if key in out.trace}
    names = _names(runs.outputs[min(k for k in runs.outputs if k[0] in traced)], key) if traced else []
    frames, levels = [], []
    for ci, cell in enumerate(runs.cells):
        seeds = sorted(s for (c, s) in runs.outputs if c == ci)
        sub = cell_runs(runs, ci)
        est = sub.estimator.iloc[0]
        if ci in traced:
            stack = np.stack([np.asarray(runs.outputs[(ci, s)].trace[key]) for s in seeds])  # (seeds, steps, p)
            frames.append(_quantile_rows(stack, _names(runs.outputs[(ci, seeds[0])], key),
                                         {**cell, "estimator": est, "kind": "trace"}))
            levels += _levels(sub, names, "truth_", "truth", cell, est)
        else:
            levels += _levels(sub, names, "", "reference", cell, est)
    truth = pd.DataFrame(levels)
    if len(truth):  # one truth line per parameter
        truth = pd.concat([truth[truth.kind == "truth"].drop_duplicates("parameter"), truth[truth.kind != "truth"]])
    return pd.concat(frames + [truth] + _distances(runs, key, names, traced), ignore_index=True)


def draw(table, spec, axes=None):
    """Draws each parameter's quartiles against filter step, with the levels and distances
    (:func:`magexp.artifacts.plots.trace.draw`)."""
    from magexp.artifacts.plots import trace
    return trace.draw(table, spec, axes)
