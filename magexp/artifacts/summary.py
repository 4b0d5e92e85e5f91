"""Reproduced numbers beside the paper's: the rows of ``results/summary.csv``.

A paper reports one run; magexp reproduces the distribution of runs. Each row gives, over the
seeds of a cell, the median (``value``), the quartiles, and the **interval a single run falls in**
(``lo``, ``hi``: the 2.5 % and 97.5 % quantiles over **all** seeds). Where the paper's run has an
outcome, it is compared with our runs of the same outcome, whose interval is ``lo_same``-``hi_same``:

* a paper value of the success metric (a final RMS, a ratio of two such runs) is classified as a
  successful or a failed run by the artifact's success rule, and compared with our successful or
  our failed runs;
* a parameter row (``mode: parameters``) is compared with our successful runs (the paper published
  a calibration that worked); ``value`` is then their median (``success_rate`` counts the others).

Elsewhere ``lo_same``/``hi_same`` are empty and the paper's value is judged against ``lo``-``hi``.
What the verdict used is written beside it: ``judged_runs`` (``all seeds``, ``successful seeds``,
``failed seeds``, ``least-squares t-interval`` or ``fixed tolerance``), ``judged_n`` (how many
runs), ``judged_value`` (their median) and ``judged_lo``-``judged_hi`` (their interval). The
judged interval is widened only by the paper's printing precision (half a unit of its last printed
digit). ``verdict``, one rule applied in this order (:func:`judge`, then :func:`uninformative`):

1. ``n/a``: the paper gives no number; ``not compared``: the artifact says why its number is not
   comparable (``reported[].compared: false``: e.g. an absolute F_g, a row that repeats another's);
2. ``differs``: the paper's value is outside the judged interval (or its fixed tolerance);
3. ``differs``: inside, but fewer than half of our runs succeeded (a failed majority);
4. ``uninformative``: inside, but the interval cannot exclude values far from the paper's
   (:func:`uninformative`): not counted as reproduced;
5. ``reproduced``: inside and informative.

``scale`` is the scale of the row's block (:func:`paper_scale`: the RMS of the paper's values of
the quantities sharing the row's block, e.g. S's nine entries of the same cell; a quantity alone in
its block: its own magnitude) and ``rel_difference`` ``|judged_value - paper_value| / scale``: how
far the paper's number is from ours on that scale.

``label`` names the row for a reader (:mod:`magexp.artifacts.row_labels`); ``reason`` says in a
line why the verdict is what it is. ``truth_in_interval`` says whether the true calibration's value
is in the interval too: then the row shows that the method converged to the noise floor, not more.
A paper's value that is a statistic over its own trials (``reported[].statistic`` and ``trials``) is judged
against the interval of that statistic over as many runs like ours (:mod:`magexp.artifacts.monte_carlo`),
not against the spread of single runs; ``judged_runs`` says so. A fixed tolerance is used only where the paper gives no run to compare with
(``reported[].tolerance`` with its ``reason``). For a single deterministic run on recorded data
(``interval: ls``), the interval is the least-squares estimate ± t(0.975, dof) standard errors
(:mod:`magexp.artifacts.least_squares`).
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from magexp.artifacts import monte_carlo
from magexp.artifacts.censoring import censor_row, censored_mask
from magexp.artifacts.least_squares import f_test, least_squares_interval
from magexp.artifacts.plan import ArtifactRuns
from magexp.artifacts.row_labels import label_of
from magexp.artifacts.tables import (cell_overrides, cell_runs, first_output, matches, median,
                                     outcomes, parameter_values, reported_entry, row_numbers, successful_medians)
from magexp.core.outcomes import failed_majority, success_threshold
from magexp.run.compose import estimator_label

COLUMNS = ["paper", "artifact", "quantity", "estimator", "setting", "truth", "paper_value", "value",
           "q25", "q75", "n_seeds", "tolerance", "verdict", "lo", "hi", "success_rate", "truth_in_interval",
           "label", "reason", "lo_same", "hi_same", "judged_runs", "judged_n", "judged_value", "judged_lo",
           "judged_hi", "scale", "rel_difference"]
VERDICTS = ("reproduced", "differs", "uninformative", "not compared", "n/a")
#: verdicts of rows that are not compared numbers
NOT_COMPARED = ("not compared", "n/a")
#: a parameter's interval spanning at least this fraction of its search range is uninformative
SEARCH_FRACTION = 0.5
#: a parameter's interval wider than this fraction of its block's scale (the RMS of the medians of the
#: parameters sharing its name's letters: S's nine entries, b's three components) is uninformative
BLOCK_FRACTION = 0.15


def judge(paper: float | None, lo: float, hi: float, width: float, success_rate: float, *, floor: float = 0.0,
          tolerance=None, value: float = np.nan) -> str:
    """The verdict of one row before the informativeness rules (module docstring, steps 1-3): inside
    or outside first (:func:`inside`), then a failed majority. ``tolerance``: a fixed
    :class:`magexp.artifacts.spec.Tolerance` against ``value`` instead of the interval.
    """
    if paper is None or not np.isfinite(paper):
        return "n/a"
    if not inside(paper, lo, hi, width, floor=floor, tolerance=tolerance, value=value):
        return "differs"
    return "differs" if failed_majority(success_rate) else "reproduced"


def inside(paper: float, lo: float, hi: float, width: float, *, floor: float = 0.0, tolerance=None,
           value: float = np.nan) -> bool:
    """Whether the paper's value lies in ``lo``-``hi`` widened by ``width`` (a value below the
    round-off ``floor`` counts as it), or within a fixed ``tolerance`` of ``value``.
    """
    if tolerance is not None:
        return bool(np.isfinite(value) and tolerance.holds(value, paper))
    p = max(paper, floor) if 0 <= paper < floor else paper
    return bool(np.isfinite(lo) and lo - width <= p <= hi + width)


def reported_entries(spec) -> list[dict]:
    """The paper's numbers as plain ``{quantity, match, value}`` mappings."""
    return [{"quantity": e.quantity, "match": dict(e.match), "value": e.value} for e in spec.reported]


def uninformative(paper: float, lo: float, hi: float, *, kind: str = "value", search_range: float | None = None,
                  block_scale: float | None = None, mixed_outcome: bool = False, median: float = np.nan) -> str:
    """Why an interval that holds the paper's value cannot exclude values far from it ('' if it can).

    The rule, in order (``kind``: ``value``, ``parameter`` or ``ratio``):

    1. a ratio (``ratios:``) whose paper value is matched only by ratios with a failed run on one
       side (``mixed_outcome``): it measures the size of a failure, not the accuracy of a method;
    2. a parameter whose interval spans at least :data:`SEARCH_FRACTION` of its search range
       (``search_range``: upper - lower of the box): the runs do not identify it;
    3. a parameter whose interval is wider than :data:`BLOCK_FRACTION` of its block's scale
       (``block_scale``: the RMS of the medians of S's entries, of b's components, ...): it cannot
       tell the entry from values that change the calibration by that much (entries near zero are
       judged on the block's scale, not on their own);
    4. any other row whose interval is wider than the magnitude of the paper's value.
    """
    width = hi - lo
    if not np.isfinite(width):
        return ""
    if kind == "ratio" and mixed_outcome:
        return (f"the paper's ratio is matched only by ratios with a failed run on one side ({lo:.3g}-{hi:.3g}); "
                f"our median ratio is {median:.3g}")
    if kind == "parameter":
        if search_range is not None and np.isfinite(search_range) and search_range > 0 \
                and width >= SEARCH_FRACTION * search_range:
            return f"the interval spans {width / search_range:.0%} of the search range: not identified by the runs"
        if block_scale is not None and np.isfinite(block_scale) and block_scale > 0 and width > BLOCK_FRACTION * block_scale:
            return (f"the interval ({lo:.3g} to {hi:.3g}) is {width / block_scale:.0%} of its block's scale "
                    f"({block_scale:.3g}): not pinned down")
        return ""
    if width > abs(paper):
        return f"the interval ({lo:.3g} to {hi:.3g}) is wider than the paper's value itself"
    return ""


def _row(spec, quantity, estimator, setting, truth, values, settings, *, ok=None, parameters: bool = False,
         extra_setting: str = "", aggregate: str = "median", success_threshold: float | None = None, ls=None,
         label: str = "", search_range: float | None = None, block_scale: float | None = None,
         ratio: bool = False) -> dict:
    """One summary row (module docstring). ``ok``: per-value success (1/0/NaN); ``parameters``:
    compared with the successful runs; ``success_threshold``: a paper value at or below it is a
    successful run, and is compared with our successful runs (else with our failed ones);
    ``ls``: ``(estimate, half width)`` of a least-squares interval (recorded data, one run);
    ``search_range``, ``block_scale``, ``ratio``: what :func:`uninformative` needs."""
    v = np.asarray(values, float)
    entry = reported_entry(spec, quantity, settings)
    paper = None if entry is None else float(entry.value)
    floor = float(spec.floor)
    n = row_numbers(v, ok, paper, parameters=parameters, success_threshold=success_threshold, aggregate=aggregate,
                    floor=floor, ls=ls)
    n.update(monte_carlo.judged(v, entry))  # a statistic over the paper's trials: its interval
    success_rate, med, jlo, jhi, outcome = n["success_rate"], n["value"], n["jlo"], n["jhi"], n["outcome"]
    width = entry.half_unit() if entry is not None else 0.0
    tol = None if entry is None else (entry.tolerance or spec.tolerance)
    judged = _judged(n["judged"], med, aggregate, ls, tol, outcome, entry)
    verdict = judge(paper, jlo, jhi, width, success_rate, floor=floor, tolerance=tol, value=med)
    within = paper is not None and inside(paper, jlo, jhi, width, floor=floor, tolerance=tol, value=med)
    against = _against(entry, outcome, ls is not None)
    reason = _reason(verdict, paper, jlo, jhi, success_rate, tol, med, against, within)
    kind = "ratio" if ratio else "parameter" if parameters else "value"
    verdict, reason = _informative(verdict, reason, entry, tol, lambda: uninformative(
        paper, jlo, jhi, kind=kind, search_range=search_range, block_scale=block_scale, median=med,
        mixed_outcome=ratio and outcome == "failed"))
    scale, rel = _difference(spec, quantity, settings, paper, judged["judged_value"])
    reason += f"; off by {relative(rel)} ({scale:.4g})" if verdict == "differs" and np.isfinite(rel) else ""
    return {
        "paper": spec.paper, "artifact": spec.name, "quantity": quantity, "estimator": estimator,
        "setting": setting + extra_setting, "truth": truth, "paper_value": paper, "value": med,
        "q25": n["q25"], "q75": n["q75"], "n_seeds": int(np.isfinite(v).sum()),
        "tolerance": _tolerance_text(entry, tol, ls, width), "verdict": verdict, "lo": n["lo"], "hi": n["hi"],
        "success_rate": success_rate, "truth_in_interval": _truth_inside(truth, n["lo"], jlo, jhi, width, floor),
        "label": label or quantity, "reason": reason, "lo_same": n["lo_same"], "hi_same": n["hi_same"],
        **judged, "judged_lo": jlo, "judged_hi": jhi, "scale": scale, "rel_difference": rel,
    }


def relative(x: float) -> str:
    """A difference on its block's scale: a percentage with two significant digits below 10 times the
    scale (``0.0003`` -> ``0.03 % of its scale``), else a multiple (``38 times its scale``).
    """
    if not np.isfinite(x):
        return "n/a"
    if x >= 10:
        return f"{x:.2g} times its scale"
    return f"{100 * x:{'.0f' if x >= 1 else '.2g'}} % of its scale"


def _judged(runs: np.ndarray, med: float, aggregate: str, ls, tol, outcome: str, entry=None) -> dict:
    """``judged_runs``, ``judged_n`` and ``judged_value`` of a row: which runs the verdict used, how
    many, and their median (the least-squares estimate of an ``ls`` row, the row's value for a fixed
    tolerance or an ``aggregate: mean`` row; a paper's statistic over trials: ours,
    :func:`magexp.artifacts.monte_carlo.columns`)."""
    finite = runs[np.isfinite(runs)]
    if entry is not None and entry.statistic is not None:
        return monte_carlo.columns(runs, entry)
    if ls is not None:
        return {"judged_runs": "least-squares t-interval", "judged_n": 1, "judged_value": float(ls[0])}
    which = f"{outcome} seeds" if outcome else "all seeds"
    if tol is not None:
        which = f"fixed tolerance, {which}"
    centre = med if tol is not None or aggregate == "mean" or not finite.size else median(finite)
    return {"judged_runs": which, "judged_n": int(finite.size), "judged_value": centre}


def _difference(spec, quantity: str, settings: dict, paper, judged_value: float) -> tuple[float, float]:
    """``(scale, rel_difference)`` of a row (:func:`paper_scale`; NaN without a paper value)."""
    if paper is None:
        return np.nan, np.nan
    scale = paper_scale(spec, quantity, settings)
    return scale, (abs(judged_value - paper) / scale if scale > 0 else np.nan)


def paper_scale(spec, quantity: str, settings: dict) -> float:
    """The scale a row's difference is read on: the RMS of the paper's values of the quantities of
    the row's block (:func:`block_of`: ``S11``..``S33`` -> ``S``) reported for the same cell; a
    quantity alone in its block (a final RMS, an F_g) has its own magnitude.
    """
    block = block_of(quantity)
    paper = [float(e.value) for e in spec.reported if block_of(e.quantity) == block and matches(e.match, settings)]
    return float(np.sqrt(np.mean(np.square(paper)))) if paper else np.nan


def _informative(verdict: str, reason: str, entry, tol, why) -> tuple[str, str]:
    """Steps 1 and 4 of the rule (module docstring): an entry marked ``compared: false`` is not
    compared (its reason says why); a ``reproduced`` row (inside, a successful majority) whose entry
    says ``informative: false`` is uninformative for its own reason, and one without a fixed
    tolerance when ``why()`` (:func:`uninformative`) gives a reason. Rows outside keep ``differs``."""
    if verdict != "n/a" and entry is not None and not entry.compared:
        return "not compared", str(entry.reason).strip()
    if verdict != "reproduced":
        return verdict, reason
    if entry is not None and not entry.informative:
        return "uninformative", str(entry.reason).strip()
    if tol is None:
        text = why()
        if text:
            return "uninformative", text
    return verdict, reason


def _truth_inside(truth, lo: float, jlo: float, jhi: float, width: float, floor: float):
    """Whether the true value lies in the compared interval widened by the printing precision
    ``width`` (NaN without a truth or an interval; a truth below the round-off ``floor`` counts as it)."""
    if truth is None or not np.isfinite(lo):
        return np.nan
    t = max(truth, floor) if 0 <= truth < floor else truth
    return bool(jlo - width <= t <= jhi + width)


def _tolerance_text(entry, tol, ls, width: float) -> str:
    """The ``tolerance`` column: how the paper's value was compared ('' when the paper gives none)."""
    if entry is None:
        return ""
    if tol is not None:
        return tol.text()
    if entry.statistic is not None:
        return f"95 % of {monte_carlo.words(entry).removeprefix('our ')}" + (f" ± {width:.2g}" if width else "")
    return ("ls t-interval" if ls is not None else "95 % of runs") + (f" ± {width:.2g}" if width else "")


def _against(entry, outcome: str, ls: bool) -> str:
    """What a row's interval is of, in its reason: the least-squares t-interval, our runs (of the paper
    run's outcome), or our statistic over the paper's trials (:mod:`magexp.artifacts.monte_carlo`)."""
    if entry is not None and entry.statistic is not None:
        return monte_carlo.words(entry)
    return "the least-squares t-interval" if ls else f"our {outcome} runs" if outcome else "our runs"


def _reason(verdict: str, paper, lo: float, hi: float, success_rate: float, tol, med: float, against: str,
            within: bool) -> str:
    """A short line: why ``verdict`` (numbers from the row; ``against``: what the interval is of,
    :func:`_against`; ``within``: :func:`inside`)."""
    if verdict == "n/a":
        return ""
    if tol is not None:
        where = f"median {med:.4g} vs paper {paper:.4g} ({tol.text()})"
    else:
        where = f"paper {paper:.4g} {'inside' if within else 'outside'} {against} ({lo:.4g} to {hi:.4g})"
    if within and failed_majority(success_rate):
        return f"our runs succeed on {success_rate:.0%} of seeds (a failed majority); {where}"
    return where


def block_of(name: str) -> str:
    """The block a parameter belongs to: its name's leading letters (``S13`` -> ``S``, ``Bp1`` -> ``Bp``)."""
    m = re.match(r"^[A-Za-z_]*[A-Za-z]", name)
    return m.group(0) if m else name


def block_scales(names: list[str], medians: np.ndarray) -> dict[str, float]:
    """``{block: RMS of its parameters' medians}`` (:func:`block_of`)."""
    groups: dict[str, list] = {}
    for name, m in zip(names, medians):
        groups.setdefault(block_of(name), []).append(m)
    return {b: float(np.sqrt(np.nanmean(np.square(v)))) if np.isfinite(v).any() else np.nan
            for b, v in ((b, np.asarray(v, float)) for b, v in groups.items())}


def _cell_ok(runs: ArtifactRuns, ci: int) -> np.ndarray:
    """The per-seed outcomes (1/0/NaN) of cell ``ci``."""
    return outcomes(cell_runs(runs, ci, by_seed=True))


def _parameter_rows(runs: ArtifactRuns, item) -> list[dict]:
    """``mode: parameters``: one row per (cell, parameter), compared with the successful runs;
    ``only`` (optional) restricts to those estimators."""
    rows = []
    for ci in range(len(runs.cells)):
        sub = runs.table[runs.table.cell == ci]
        if item.only and sub.estimator.iloc[0] not in item.only:
            continue
        names, values, truth = parameter_values(runs, ci)
        ok = _cell_ok(runs, ci)
        scales = block_scales(names, successful_medians(values, ok))
        ranges = search_ranges(runs, ci)
        for k, name in enumerate(names):
            rows.append(_row(runs.spec, name, sub.estimator.iloc[0], sub.setting.iloc[0],
                             None if truth is None else float(truth[k]), values[:, k], cell_overrides(runs, ci),
                             ok=ok, parameters=True, label=label_of(runs.spec, runs.cells, ci, name, sub.estimator.iloc[0]),
                             search_range=ranges.get(name), block_scale=scales[block_of(name)]))
    return rows


def search_ranges(runs: ArtifactRuns, ci: int) -> dict[str, float]:
    """``{parameter: upper - lower}`` of cell ``ci``'s search box, as its first run stored it (empty
    where it stored none).
    """
    out = first_output(runs, ci)
    lower, upper = getattr(out, "lower", None), getattr(out, "upper", None)
    if lower is None or upper is None:
        return {}
    return {n: float(u - lo) for n, lo, u in zip(out.parameter_names, lower, upper)}


def _ftest_rows(runs: ArtifactRuns, item) -> list[dict]:
    """``mode: ftest``: per cell (of ``only``) and axis, the p-value of :func:`f_test` of its estimate."""
    rows = []
    for ci in range(len(runs.cells)):
        sub = runs.table[runs.table.cell == ci]
        if item.only and sub.estimator.iloc[0] not in item.only:
            continue
        theta = runs.outputs[(ci, int(sub.seed.min()))].x
        for test in f_test(runs, ci, theta):
            quantity = f"{item.quantity}_axis{test['axis']}"
            rows.append(_row(runs.spec, quantity, sub.estimator.iloc[0],
                             sub.setting.iloc[0] + f";F={test['F']:.4g};dof={test['dof'][0]},{test['dof'][1]}",
                             None, [test["p_value"]], cell_overrides(runs, ci),
                             label=label_of(runs.spec, runs.cells, ci, quantity, sub.estimator.iloc[0])))
    return rows


def summarise(runs: ArtifactRuns) -> pd.DataFrame:
    """One row per (summarised quantity, cell) and per ratio group, from ``runs`` as handed (a reproduction: as stored).
    """
    rows = []
    for item in runs.spec.summarise:
        rows += _item_rows(runs, item)
    for item in runs.spec.ratios:
        rows += _ratio_rows(runs, item)
    return pd.DataFrame(rows, columns=COLUMNS)


def _item_rows(runs: ArtifactRuns, item) -> list[dict]:
    """The rows of one ``summarise:`` entry (:class:`magexp.artifacts.spec.Summarise`), by its ``mode``."""
    if item.mode == "parameters":
        return _parameter_rows(runs, item)
    if item.mode == "ftest":
        return _ftest_rows(runs, item)
    return _value_rows(runs, item)


def _value_rows(runs: ArtifactRuns, item) -> list[dict]:
    """``mode: value``: one row per cell whose runs hold ``metric``."""
    rows = []
    for ci in range(len(runs.cells)):
        sub = runs.table[runs.table.cell == ci].sort_values("seed")
        if item.metric in sub and not (sub[item.metric].isna() & ~censored_mask(sub, item.metric)).all():
            rows.append(_value_row(runs, item, ci, sub))
    return rows


def _value_row(runs: ArtifactRuns, item, ci: int, sub: pd.DataFrame) -> dict:
    """The row of ``item`` for cell ``ci`` (``sub``: its runs by seed). A run of a metric that
    decides success is compared with our runs of the same outcome as the paper's value."""
    spec, metric = runs.spec, item.metric
    truth = _cell_truth(sub, item.truth_metric or f"truth_{metric}")
    ls, scale = _least_squares_item(runs, item, ci)
    threshold = (None if truth is None or metric != spec.success.metric
                 else success_threshold(truth, spec.success.factor, spec.success.floor))
    return censor_row(_row(spec, item.quantity, sub.estimator.iloc[0], sub.setting.iloc[0], truth,
                           sub[metric].astype(float).to_numpy(), cell_overrides(runs, ci), ok=_cell_ok(runs, ci),
                           aggregate=item.aggregate, ls=ls, success_threshold=threshold,
                           label=label_of(spec, runs.cells, ci, item.quantity, sub.estimator.iloc[0]),
                           parameters=scale is not None, block_scale=scale), sub, metric)  # censored: never observed-only


def _cell_truth(sub: pd.DataFrame, column: str) -> float | None:
    """The median of the true value ``column`` over a cell's runs (None unless every run has it)."""
    return median(sub[column]) if column in sub and sub[column].notna().all() else None


def _least_squares_item(runs: ArtifactRuns, item, ci: int) -> tuple:
    """``interval: ls``: the least-squares ``(estimate, half width)`` of the item's parameter in cell
    ``ci`` and its block's scale (it is judged on that scale); ``(None, None)`` otherwise."""
    if item.interval != "ls" or item.quantity not in (fits := least_squares_interval(runs, ci)):
        return None, None
    scale = block_scales(list(fits), np.array([e for e, _ in fits.values()]))[block_of(item.quantity)]
    return fits[item.quantity], scale


def _ratio_rows(runs: ArtifactRuns, item) -> list[dict]:
    """One row per denominator cell of a ``ratios:`` entry (:class:`magexp.artifacts.spec.Ratio`)
    that has a numerator cell."""
    rows = []
    for ci in range(len(runs.cells)):
        settings = cell_overrides(runs, ci)
        nj = _numerator_cell(runs, item, settings)
        if nj is not None:
            rows.append(_ratio_row(runs, item, ci, nj, settings))
    return rows


def _numerator_cell(runs: ArtifactRuns, item, settings: dict) -> int | None:
    """The cell whose settings are ``settings`` with the numerator's selection applied (None if
    ``settings`` do not match the denominator's selection or no cell has them)."""
    if not matches(item.denominator, settings):
        return None
    partner = {**settings, **item.numerator}
    return next((cj for cj in range(len(runs.cells)) if cell_overrides(runs, cj) == partner), None)


def _ratio_row(runs: ArtifactRuns, item, ci: int, nj: int, settings: dict) -> dict:
    """The row of the per-seed ratio of ``metric`` of cell ``nj`` over cell ``ci``; a ratio of two
    successful runs is within the success factor of 1 (``success_threshold``)."""
    spec, table, metric, num_sel = runs.spec, runs.table, item.metric, item.numerator
    den = table[table.cell == ci].set_index("seed")
    num = table[table.cell == nj].set_index("seed")
    ratio = (num[metric].astype(float) / den[metric].astype(float)).dropna()
    both = (num["succeeded"] * den["succeeded"]).reindex(ratio.index) if "succeeded" in den else None
    sub = table[table.cell == ci]
    ref = ",".join(f"{k}={v}" for k, v in num_sel.items())
    threshold = spec.success.factor if item.metric == spec.success.metric else None
    over = "/".join(estimator_label(str(e)) for e in (num_sel.get("estimator"), sub.estimator.iloc[0]) if e)
    return _row(spec, item.quantity, sub.estimator.iloc[0], sub.setting.iloc[0], None, ratio.to_numpy(),
                settings, extra_setting=f";reference={ref}", success_threshold=threshold,
                ok=None if both is None else both.to_numpy(float), ratio=True,
                label=label_of(spec, runs.cells, ci, item.quantity, sub.estimator.iloc[0], prefix=over))
