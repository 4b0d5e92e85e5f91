"""The tables behind the figures: one builder per artifact kind (:data:`BUILDERS`), each a query of the
runs table and the runs' stored outputs that aggregates only through :mod:`magexp.artifacts.tables`
(medians, quartiles, success fractions, intervals). :mod:`magexp.artifacts.plots` draws what these
hand it, from the CSV alone (``draw(frame, spec)``), and aggregates nothing itself.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts.censoring import cell_quartiles
from magexp.artifacts.tables import (cell_overrides, cell_runs, fraction, interval, matches, median,
                                     outcomes, parameter_values, quartiles, reported_value, scenario_label, successful)
from magexp.core.metrics import rms
from magexp.core.outcomes import recording_succeeded
from magexp.run.compose import estimator_label

# convergence: the best objective per iteration

def _stack(histories: list[np.ndarray]) -> np.ndarray:
    n = max(len(h) for h in histories)
    return np.vstack([np.pad(h, (0, n - len(h)), mode="edge") for h in histories])


def _count(sub: pd.DataFrame, column: str) -> int:
    """How many of a cell's runs have ``column`` true (-1: not recorded, or no run judged)."""
    return int(sub[column].sum()) if column in sub and sub[column].notna().any() else -1


def convergence_table(runs) -> pd.DataFrame:
    """Per cell and iteration: the quartiles over seeds of the best objective, the median evaluations,
    the floors, the success counts, and the median iterations to 1.1 x the final value over the
    successful runs (:mod:`magexp.artifacts.plots.convergence`).

    Parameters
    ----------
    runs : ArtifactRuns
    """
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


# estimates: fitted values per estimator

def estimates_table(runs) -> pd.DataFrame:
    """Per cell and quantity (the run's parameters, then ``plot.rows``): quartiles over seeds and the
    median truth (:mod:`magexp.artifacts.plots.estimates`).

    Parameters
    ----------
    runs : ArtifactRuns
    """
    names = list(next(iter(runs.outputs.values())).parameter_names) + list(runs.spec.plot.get("rows", []))
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = cell_runs(runs, ci)
        for name in (n for n in names if n in sub):
            med, q25, q75 = quartiles(sub[name])
            truth = f"truth_{name}"
            rows.append({**cell, "estimator": sub.estimator.iloc[0], "quantity": name, "median": med, "q25": q25,
                         "q75": q75, "truth": median(sub[truth]) if truth in sub else np.nan, "n_seeds": len(sub)})
    return pd.DataFrame(rows)


# final: final values against a swept key

def metric_list(spec) -> list[str]:
    """The metric columns a ``final`` figure draws (``plot.metric``: one name or a list).

    Parameters
    ----------
    spec : Artifact
    """
    metric = spec.plot.get("metric", "fun")
    return [metric] if isinstance(metric, str) else list(metric)


def ratio_name(item) -> str:
    """The line name of a ratio: numerator over denominator (their distinguishing values)."""
    return " / ".join(", ".join(str(v) for v in side.values()) for side in (item.numerator, item.denominator))


def _ratio_rows(runs) -> list[dict]:
    """Per ``ratios:`` item and denominator cell: quartiles of the per-seed ratio (seeds share
    readings, so the ratio is paired), the fraction of seeds where both runs succeeded."""
    table, rows = runs.table, []
    for item in runs.spec.ratios:
        for ci, cell in enumerate(runs.cells):
            if not matches(item.denominator, cell):
                continue
            partner = {**cell, **{k: str(v) for k, v in item.numerator.items()}}
            nj = [cj for cj, other in enumerate(runs.cells) if all(matches({k: v}, other) for k, v in partner.items())]
            if not nj:
                continue
            den = table[table.cell == ci].set_index("seed")
            num = table[table.cell == nj[0]].set_index("seed")
            ratio = (num[item.metric].astype(float) / den[item.metric].astype(float)).dropna()
            med, q25, q75 = quartiles(ratio)
            row = {**cell, "estimator": ratio_name(item), "objective": den.objective.iloc[0], "metric": item.quantity,
                   "median": med, "q25": q25, "q75": q75, "n_seeds": len(ratio)}
            if "succeeded" in den and den.succeeded.notna().any():
                row["success_rate"] = fraction((num.succeeded * den.succeeded).reindex(ratio.index))
            rows.append(row)
    return rows


def final_table(runs) -> pd.DataFrame:
    """Per cell and metric: quartiles (of a censored metric also its extremes and censoring,
    :func:`magexp.artifacts.censoring.cell_quartiles`), the success rate and converged fraction, the floors
    (``noise_floor``, ``truth_fun``, ``rms_bound``) and the median of ``plot.bound``; then the ratios
    (:mod:`magexp.artifacts.plots.final`).

    Parameters
    ----------
    runs : ArtifactRuns
    """
    bound = runs.spec.plot.get("bound")
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = cell_runs(runs, ci)
        for metric in metric_list(runs.spec):
            row = {**cell, "estimator": sub.estimator.iloc[0], "objective": sub.objective.iloc[0],  # censored: inf
                   "metric": metric, **cell_quartiles(sub, metric), "n_seeds": len(sub)}
            if bound and bound in sub:
                row["bound"] = median(sub[bound])
            row.update({extra: median(sub[extra]) for extra in ("noise_floor", "truth_fun", "rms_bound") if extra in sub})
            if "converged" in sub:
                row["converged_fraction"] = fraction(sub.converged.astype(float))
            if "succeeded" in sub and sub.succeeded.notna().any():
                row["success_rate"] = fraction(sub.succeeded)
            rows.append(row)
    return pd.DataFrame(rows + _ratio_rows(runs))


# parameters: every parameter estimate per cell

#: the fit-quality row a cell gets where its runs measure it: (parameter name, runs column)
FIT = ("F_g", "fg")


def cell_label(cell: dict, estimator: str, spec) -> str:
    """A short legend text of a cell: the estimator, then its other swept values (a scenario by its
    readable name, :func:`scenario_label`; other keys as ``name = value`` with ``plot.labels``)."""
    names = dict(spec.plot.get("labels", {}) or {})
    rest = [scenario_label(v) if k == "scenario" else f"{names.get(k, k.split('.')[-1].replace('_', ' '))} = {v}"
            for k, v in cell.items() if k != "estimator"]
    return ", ".join([estimator] + rest)


def parameters_table(runs) -> pd.DataFrame:
    """Per cell and parameter: quartiles over the successful seeds (failures counted in ``n_failed``),
    the truth and the paper's value; F_g over every seed where the runs measure it
    (:mod:`magexp.artifacts.plots.parameters`).

    Parameters
    ----------
    runs : ArtifactRuns
    """
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = cell_runs(runs, ci)
        names, values, truth = parameter_values(runs, ci)
        settings = cell_overrides(runs, ci)
        ok = outcomes(sub.sort_values("seed")) if "succeeded" in sub else np.full(len(values), np.nan)
        judged = np.isfinite(ok)
        kept = values[ok == 1] if judged.any() else values  # over the successful runs; failures counted beside
        for k, name in enumerate(names):
            med, q25, q75 = quartiles(kept[:, k])
            paper, _ = reported_value(runs.spec, name, settings)
            rows.append({**cell, "label": cell_label(cell, sub.estimator.iloc[0], runs.spec),
                         "estimator": sub.estimator.iloc[0], "objective": sub.objective.iloc[0], "parameter": name,
                         "truth": np.nan if truth is None else float(truth[k]), "median": med, "q25": q25,
                         "q75": q75, "paper_value": np.nan if paper is None else paper, "n_seeds": len(values),
                         "n_failed": int((ok[judged] == 0).sum()), "success_rate": fraction(ok)})
        name, column = FIT
        if column in sub and sub[column].notna().any():  # over every seed, as the summary's F_g row
            med, q25, q75 = quartiles(sub[column])
            paper, _ = reported_value(runs.spec, name, settings)
            rows.append({**rows[-1], "parameter": name, "truth": np.nan, "median": med, "q25": q25, "q75": q75,
                         "paper_value": np.nan if paper is None else paper})
    return pd.DataFrame(rows)


# recordings

#: per-run quantities of the ``recording`` table (one row per seed)
RUN_QUANTITIES = ("fg", "vector_residual_fraction", "spread_before", "spread_after", "weakest_relative_sv",
                  "gyro_bias_rest_x", "gyro_bias_rest_y", "gyro_bias_rest_z")


def canonical_sign(names: list[str], x: np.ndarray) -> np.ndarray:
    """The member with ``det S > 0`` of the pair ``(S, b, h)``, ``(-S, b, -h)`` that the gyro-aided
    objective cannot tell apart (``h`` by azimuth ``a`` and elevation ``e``: ``-h`` is ``(a + pi, -e)``);
    other parameter vectors are returned as they are."""
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


def recording_table(runs) -> pd.DataFrame:
    """Rows ``row = run`` (a per-run quantity of one seed) and ``row = estimate`` (a parameter: median
    over the successful seeds, and the median of their standard errors) (:mod:`magexp.artifacts.plots.real`).

    Parameters
    ----------
    runs : ArtifactRuns
    """
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


#: the per-cell medians of the ``recording_spread`` table
SPREAD_COLUMNS = ("spread_before", "spread_after", "heldout_spread", "coverage_cells", "wall_time")


def spread_table(runs) -> pd.DataFrame:
    """Per (recording, estimator): the medians of :data:`SPREAD_COLUMNS`, the widest of the seeds'
    held-out spread intervals and the success rate (reported success and a spread below the raw one)
    (:mod:`magexp.artifacts.plots.real_spread`).

    Parameters
    ----------
    runs : ArtifactRuns
    """
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


# the benchmark: one row per (case, estimator)

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
#: the columns of :func:`benchmark_table` computed here (not a median of a runs column)
DERIVED = {
    "bound_ratio": "RMS over successful runs of offset error / sqrt(tr CRB)",
    "success_rate": "fraction of runs that succeeded",
}


def column_label(column: str) -> str:
    """What a column of the benchmark table shows, in words (:data:`COLUMNS`, :data:`DERIVED`)."""
    return {**COLUMNS, **DERIVED}.get(column, column.replace("_", " "))


def case_label(cell: dict, grid_keys) -> str:
    """A short name of the case: the scenario and its own settings."""
    parts = [cell.get("scenario", "")]
    parts += [f"{k.split('.')[-1]}={v}" for k, v in cell.items() if k not in grid_keys and k != "scenario"]
    return " ".join(p for p in parts if p)


def bound_ratio(sub: pd.DataFrame) -> tuple[float, float, float]:
    """RMS over the successful seeds (every seed where none is judged) of offset error / sqrt(tr CRB),
    and its 95 % bootstrap interval (NaN without a bound or without a successful run)."""
    if "offset_error_ratio" not in sub:
        return (np.nan,) * 3
    r = successful(sub)["offset_error_ratio"].to_numpy(float)
    r = r[np.isfinite(r)]
    if r.size == 0:
        return (np.nan,) * 3
    lo, hi = interval(r, stat="rms")
    return float(rms(r)), lo, hi


def benchmark_table(runs) -> pd.DataFrame:
    """One row per (case, estimator): medians (of the accuracy columns over the successful runs), the
    bound ratio with its interval, the success rate and the failures (module docstring of
    :mod:`magexp.artifacts.plots.heatmap`). Where no run is judged (recordings), the fit's own
    verdict and a spread below the raw one decide success.

    Parameters
    ----------
    runs : ArtifactRuns
    """
    grid_keys = set(runs.spec.grid)
    rows = []
    for ci, cell in enumerate(runs.cells):
        sub = cell_runs(runs, ci)
        row = {"case": case_label(cell, grid_keys), "scenario": sub.scenario.iloc[0],
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


# tuning: settings of one method as a distribution

def _rate(values) -> float:
    return fraction(pd.Series(values).dropna().astype(float))


def tuning_table(runs) -> pd.DataFrame:
    """One row per setting (cell), with per (family, scenario) the ``best``, ``median`` and ``worst``
    setting by the median metric (:mod:`magexp.artifacts.plots.tuning`).

    Parameters
    ----------
    runs : ArtifactRuns
    """
    spec = runs.spec
    defaults = {k: {kk: str(vv) for kk, vv in v.items()} for k, v in (spec.plot.get("default", {}) or {}).items()}
    frame = pd.DataFrame([_setting_row(runs, ci, defaults) for ci in range(len(runs.cells))])
    frame["role"] = ""
    for _, idx in frame.groupby(["family", "scenario"], sort=False).groups.items():
        group = frame.loc[idx].sort_values("median", kind="stable")
        if len(group) >= 3:
            frame.loc[group.index[0], "role"] = "best"
            frame.loc[group.index[len(group) // 2], "role"] = "median"
            frame.loc[group.index[-1], "role"] = "worst"
    return frame


ESTIMATOR_KEYS = {"estimator", "estimator.name"}  # the settings naming an estimator: in words in a legend


def family_words(spec, family: str) -> str:
    """An estimator's name in words on a tuning figure: ``plot.names[family]``, else its label.

    Parameters
    ----------
    spec, family : ArtifactSpec, str
        The artifact (its ``plot.names``); the estimator's name (a family, or a setting in a legend).

    Returns
    -------
    str
        The words (:func:`magexp.run.compose.estimator_label` when ``plot.names`` has none).
    """
    return str(dict(spec.plot.get("names", {}) or {}).get(family) or estimator_label(family))


def _setting_row(runs, ci: int, defaults: dict) -> dict:
    """The row of cell ``ci``; ``defaults``: ``plot.default`` with text values."""
    spec = runs.spec
    metric = spec.plot.get("metric", "fun")
    short = dict(spec.plot.get("labels", {}) or {})
    sub = cell_runs(runs, ci)
    family = str(sub.estimator.iloc[0])
    settings = cell_overrides(runs, ci)
    named = {**settings, **{k: family_words(spec, settings[k]) for k in ESTIMATOR_KEYS & set(settings)}}
    label = ", ".join(f"{short.get(k, k.split('.')[-1])} = {named[k]}" for k in spec.plot.get("label", []) if k in named)
    med, q25, q75 = quartiles(sub[metric])
    default = family in defaults and all(settings.get(k) == v for k, v in defaults[family].items())
    rate = _rate(sub["succeeded"]) if "succeeded" in sub and sub.succeeded.notna().any() else (
        _rate(sub["converged"]) if "converged" in sub else np.nan)  # else converged: the 1 % rule
    return {"family": family, "family_label": family_words(spec, family), "label": label or family,
            "scenario": str(sub.scenario.iloc[0]), "metric": metric, "median": med, "q25": q25, "q75": q75, "n_seeds": len(sub), "success_rate": rate,
            "bound_success_rate": _rate(sub["offset_error_ratio"] <= 2.0) if "offset_error_ratio" in sub else np.nan,
            "on_boundary_rate": _rate(sub["on_boundary"] > 0) if "on_boundary" in sub else np.nan,
            **{c: median(sub[c]) if c in sub else np.nan for c in ("offset_error_ratio", "wall_time", "nfev_to_1.1")},
            "default": default, "setting": sub.setting.iloc[0]}


# trace: parameters vs filter step

def _names(out, key: str) -> list[str]:
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


def trace_table(runs) -> pd.DataFrame:
    """Per traced cell, parameter and step: quartiles over seeds of ``trace[plot.trace]``; the truth
    and the untraced cells' estimates as levels; the distances from ``plot.relative_to``
    (:mod:`magexp.artifacts.plots.trace`).

    Parameters
    ----------
    runs : ArtifactRuns
    """
    key = runs.spec.plot.get("trace", "x")
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


# field: the readings of one seed per cell

def shown_seed(runs, ci: int) -> tuple[int, str]:
    """The seed of cell ``ci`` whose readings are drawn and its outcome (``succeeded``, ``failed``
    or ``not judged``): the first successful seed, else the first seed."""
    seeds = sorted(s for (c, s) in runs.outputs if c == ci)
    sub = cell_runs(runs, ci)
    if "succeeded" not in sub or sub.succeeded.isna().all():
        return seeds[0], "not judged"
    ok = sub.set_index("seed").succeeded
    good = [s for s in seeds if ok.get(s) == 1]
    return (good[0], "succeeded") if good else (seeds[0], "failed")


def field_table(runs) -> pd.DataFrame:
    """Per reading of the shown seed of each cell (:func:`shown_seed`): raw and calibrated vectors and
    total fields, the reference total field and the error of the calibrated one
    (:mod:`magexp.artifacts.plots.field`).

    Parameters
    ----------
    runs : ArtifactRuns
    """
    frames = []
    for ci, cell in enumerate(runs.cells):
        seed, outcome = shown_seed(runs, ci)
        out = runs.outputs[(ci, seed)]
        raw, cal = np.asarray(out.readings), np.asarray(out.calibrated)
        calibrated = np.linalg.norm(cal, axis=1)
        frames.append(pd.DataFrame({
            **cell, "seed": seed, "outcome": outcome, "reading": np.arange(len(raw)),
            "raw_x": raw[:, 0], "raw_y": raw[:, 1], "raw_z": raw[:, 2],
            "cal_x": cal[:, 0], "cal_y": cal[:, 1], "cal_z": cal[:, 2],
            "raw": np.linalg.norm(raw, axis=1), "calibrated": calibrated,
            "reference": out.reference_norm, "error": calibrated - out.reference_norm,
        }))
    return pd.concat(frames, ignore_index=True)


#: the table builder of each artifact kind (:data:`magexp.artifacts.plots.KINDS` names the drawing)
BUILDERS = {"convergence": convergence_table, "field": field_table, "sphere": field_table, "final": final_table,
            "sweep": final_table, "parameters": parameters_table, "trace": trace_table, "heatmap": benchmark_table,
            "speed": benchmark_table, "estimates": estimates_table, "tuning": tuning_table,
            "recording": recording_table, "recording_spread": spread_table}


def tabulate(runs) -> pd.DataFrame:
    """The table behind the figure of ``runs.spec``: its kind's builder in :data:`BUILDERS`.

    Parameters
    ----------
    runs : ArtifactRuns
    """
    return BUILDERS[runs.spec.kind](runs)
