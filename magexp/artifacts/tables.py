"""Tables: every aggregation of an artifact's runs, apart from the figures drawn from them.

An artifact's runs (:class:`magexp.artifacts.plan.ArtifactRuns`: one row per (cell, seed), and each
run's stored output) become here

* the table behind its figure (:func:`magexp.artifacts.kinds.tabulate`, each kind's ``table``): medians
  and quartiles over seeds, success fractions, intervals. :mod:`magexp.artifacts.plots` only draws it,
  from the CSV alone;
* the numbers of a summary row (:func:`row_numbers`) of the runs handed (the runs CSV as written:
  :mod:`magexp.artifacts.stored`): the verdicts of :mod:`magexp.artifacts.summary` are judged on them.

One interval helper, :func:`interval`: the central ``level`` interval of the values themselves (where a
single run falls: ``level=0.95``; the quartiles: ``level=0.5``), or, with ``stat``, of that statistic's
percentile bootstrap over them (a fixed generator: the same on every run). :func:`quartiles` and
:func:`median` are read off it.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from magexp.core.metrics import rms

#: a statistic over the seeds of a selection (claims, note fields, bootstrap intervals)
STATS = {
    "median": lambda v, axis=None: np.median(v, axis=axis),
    "mean": lambda v, axis=None: np.mean(v, axis=axis),
    "max": lambda v, axis=None: np.max(v, axis=axis),
    "min": lambda v, axis=None: np.min(v, axis=axis),
    # RMS over seeds (of error / sqrt(tr CRB) it is 1 for an efficient estimator)
    "rms": lambda v, axis=None: rms(v, axis=axis),
    "lo": lambda v, axis=None: np.quantile(v, 0.025, axis=axis),
    "hi": lambda v, axis=None: np.quantile(v, 0.975, axis=axis),
    "q25": lambda v, axis=None: np.quantile(v, 0.25, axis=axis),
    "q75": lambda v, axis=None: np.quantile(v, 0.75, axis=axis),
    "n": lambda v, axis=None: np.shape(v)[-1] * np.ones(np.shape(v)[:-1]) if axis is not None else len(v),
    "success_rate": lambda v, axis=None: np.mean(v, axis=axis),  # of the 0/1 column ``succeeded``
}
#: bootstrap resamples of :func:`interval` with ``stat``
N_BOOT = 2000


# -- the one interval helper and what is read off it ---------------------------------------------

def finite(values) -> np.ndarray:
    """The finite ``values`` as floats."""
    v = np.asarray(values, float)
    return v[np.isfinite(v)]


def interval(values, level: float = 0.95, *, stat: str | None = None, floor: float = 0.0,
             axis: int | None = None) -> tuple:
    """``(lo, hi)``, the central ``level`` interval (0.95: where a single run falls; 0.5: the quartiles): with
    ``stat=None`` of the finite ``values`` themselves (NaN for none); with a name of :data:`STATS` the percentile
    bootstrap interval of that statistic (:data:`N_BOOT` resamples from a fixed generator; NaN for fewer than two
    values). A non-negative value below ``floor`` (the round-off floor) counts as it; ``axis``: quantiles of an
    array along it, e.g. per step over seeds (arrays returned).
    """
    tail = round((1 - level) / 2, 12)
    if axis is not None:
        lo, hi = np.quantile(np.asarray(values, float), [tail, 1 - tail], axis=axis)
        return lo, hi
    if stat is not None:
        v = np.asarray(values, float)
        if len(v) < 2:
            return (np.nan, np.nan)
        idx = np.random.default_rng(0).integers(0, len(v), size=(N_BOOT, len(v)))
        v = np.asarray(STATS[stat](v[idx], axis=1), float)
    else:
        v = finite(values)
        if v.size == 0:
            return (np.nan, np.nan)
        v = np.where((v >= 0) & (v < floor), floor, v)
    lo, hi = np.quantile(v, [tail, 1 - tail])
    return float(lo), float(hi)


def quartiles(values, axis: int | None = None) -> tuple:
    """Median, 25 % and 75 % quantiles of the finite ``values`` (NaN for none; ``axis``: of an array
    along it, :func:`interval` at ``level=0.5``).
    """
    if axis is not None:
        return (np.quantile(np.asarray(values, float), 0.5, axis=axis), *interval(values, 0.5, axis=axis))
    v = finite(values)
    if v.size == 0:
        return (np.nan, np.nan, np.nan)
    return (float(np.quantile(v, 0.5)), *interval(v, 0.5))


def median(values) -> float:
    """The median of the finite ``values`` (NaN for none)."""
    return quartiles(values)[0]


def fraction(outcomes) -> float:
    """The fraction of the judged runs that succeeded: the mean of the finite 0/1 (or boolean)
    ``outcomes`` (NaN: not judged; NaN if none is).
    """
    v = finite(np.asarray(outcomes, float))
    return float(v.mean()) if v.size else np.nan


# -- runs columns and selections ------------------------------------------------------------------

def same(a, b) -> bool:
    """Two setting values are equal as numbers where both are numbers (``2`` and ``2.0``), else as text."""
    try:
        return float(a) == float(b)
    except (TypeError, ValueError):
        return str(a) == str(b)


def matches(selection: dict, settings: dict) -> bool:
    """True if every ``key: value`` of ``selection`` is among ``settings``."""
    return all(k in settings and same(settings[k], v) for k, v in selection.items())


def statistic(v: np.ndarray, stat: str) -> float:
    """``stat`` (:data:`STATS`) of the values ``v`` (NaN for none)."""
    return float(STATS[stat](v)) if len(v) else float("nan")


def cell_runs(runs, ci: int, by_seed: bool = False) -> pd.DataFrame:
    """The rows of cell ``ci`` of ``runs.table`` (``by_seed``: sorted by seed)."""
    sub = runs.table[runs.table.cell == ci]
    return sub.sort_values("seed") if by_seed else sub


def outcomes(sub: pd.DataFrame) -> np.ndarray:
    """The ``succeeded`` column of a cell's rows (all NaN without one: not judged)."""
    return sub["succeeded"].to_numpy(float) if "succeeded" in sub else np.full(len(sub), np.nan)


def successful(sub: pd.DataFrame) -> pd.DataFrame:
    """The runs of ``sub`` that succeeded (all of them where none is judged: no truth)."""
    if "succeeded" in sub and sub.succeeded.notna().any():
        return sub[sub.succeeded == 1]
    return sub


def cell_overrides(runs, ci: int) -> dict:
    """The ``{key: value}`` overrides of cell ``ci`` (base and grid), as requested: what a paper's
    ``reported[].match`` is matched against.
    """
    return dict(o.split("=", 1) for o in runs.overrides[ci])


def reported_entry(spec, quantity: str, settings: dict):
    """The paper's :class:`magexp.artifacts.spec.Reported` entry of ``quantity`` for a cell (None if absent)."""
    return next((e for e in spec.reported if e.quantity == quantity and matches(e.match, settings)), None)


def reported_value(spec, quantity: str, settings: dict):
    """The paper's value of ``quantity`` for a cell and its entry (``(None, None)`` if absent)."""
    entry = reported_entry(spec, quantity, settings)
    return (None, None) if entry is None else (float(entry.value), entry)


def first_output(runs, ci: int):
    """The stored output of cell ``ci``'s first seed: its parameter names, true vector, search box
    and linear design summary (what a run stores for the summary; nothing is simulated again).
    """
    return runs.outputs[min(k for k in runs.outputs if k[0] == ci)]


def parameter_values(runs, ci: int) -> tuple[list[str], np.ndarray, np.ndarray | None]:
    """Parameter names, estimates ``(seeds, p)`` and the true vector of cell ``ci``."""
    outs = [runs.outputs[k] for k in sorted(runs.outputs) if k[0] == ci]
    return list(outs[0].parameter_names), np.array([o.x for o in outs]), getattr(outs[0], "truth_x", None)


# -- the numbers of a summary row -----------------------------------------------------------------

def compared_runs(v: np.ndarray, ok: np.ndarray, paper, *, parameters: bool, success_threshold):
    """``(basis, same, outcome)``: the values whose quartiles a row reports (``basis``), those the
    paper's value is compared with (``same``; None: all of ``v``) and which runs they are (``outcome``,
    "successful", "failed" or ""). A parameter is read from the successful runs; with a
    ``success_threshold`` the paper's run is classified by our success rule and compared with our
    runs of the same outcome (with all of them if we have none).
    """
    judged = np.isfinite(ok).any()
    basis, same_, outcome = v, None, ""
    if parameters and judged:
        basis = same_ = v[ok == 1]
        outcome = "successful"
    if success_threshold is not None and paper is not None and judged:
        succeeded = paper <= success_threshold  # the paper's run classified by our rule
        chosen = v[ok == (1 if succeeded else 0)]
        same_, outcome = (chosen, "successful" if succeeded else "failed") if chosen.size else (None, "")
    return basis, same_, outcome


def row_numbers(v, ok, paper, *, parameters: bool = False, success_threshold=None, aggregate: str = "median",
                floor: float = 0.0, ls=None) -> dict:
    """The unrounded numbers of a summary row over a cell's per-seed values ``v`` and outcomes ``ok``:
    ``success_rate``; ``value``, ``q25``, ``q75`` (:func:`quartiles` of the compared basis, or for
    ``aggregate: mean`` the mean of 0/1 outcomes); ``lo``, ``hi`` (:func:`interval` of all runs, or
    the least-squares ``ls = (estimate, half width)``), ``lo_same``, ``hi_same`` (of the runs of the
    paper's outcome), the judged ``jlo``, ``jhi``, ``judged`` runs and ``outcome``.
    """
    v = np.asarray(v, float)
    ok = np.full(v.shape, np.nan) if ok is None else np.asarray(ok, float)
    basis, same_, outcome = compared_runs(v, ok, paper, parameters=parameters, success_threshold=success_threshold)
    med, q25, q75 = (float(np.nanmean(v)), np.nan, np.nan) if aggregate == "mean" else quartiles(basis)
    lo, hi = interval(v, floor=floor)
    lo_same, hi_same = interval(same_, floor=floor) if same_ is not None else (np.nan, np.nan)
    if ls is not None:
        lo, hi = ls[0] - ls[1], ls[0] + ls[1]
    jlo, jhi = (lo_same, hi_same) if same_ is not None else (lo, hi)
    return {"success_rate": fraction(ok), "value": med, "q25": q25, "q75": q75, "lo": lo, "hi": hi,
            "lo_same": lo_same, "hi_same": hi_same, "jlo": jlo, "jhi": jhi, "outcome": outcome,
            "judged": v if same_ is None else same_}


def successful_medians(values: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """Per parameter, the median over the successful seeds (every seed where none succeeded or
    none is judged).
    """
    kept = values[ok == 1] if np.isfinite(ok).any() and (ok == 1).any() else values
    return np.nanmedian(kept, axis=0) if len(kept) else np.full(values.shape[1], np.nan)


def scenario_label(scenario: str) -> str:
    """A scenario's name, readable in a legend or on a tick: without its paper's prefix, the rotation
    mode or experiment numbered apart (``yuan2018_mode1`` -> ``mode 1``), and a recording without
    ``real_`` and its sensor (``real_hmc5883l_rotate_ccw_around_x`` -> ``rotate ccw around x``).
    """
    name = str(scenario)
    if name.startswith("real_"):
        name = name.removeprefix("real_").removeprefix("hmc5883l_")
    elif (paper := re.match(r"[a-z]+\d{4}_", name)) is not None:
        name = re.sub(r"(?<=[a-z])(?=\d{1,2}$)", " ", name[paper.end():])  # not a sensor's model number
    return name.replace("_", " ")
