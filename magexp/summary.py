"""Reproduced numbers beside the paper's: the rows of ``results/summary.csv``.

A paper reports one run; magexp reproduces the distribution of runs. Each row gives, over the
seeds of a cell, the median (``value``), the quartiles, and the **interval a single run falls in**
(``lo``, ``hi``: the 2.5 % and 97.5 % quantiles). The paper's value is judged against that interval,
widened only by the paper's printing precision (half a unit of its last printed digit):

* ``reproduced``: inside, and at least half the runs succeeded (:func:`magexp.artifacts.succeeded`);
* ``differs``: outside, or a failed majority;
* ``n/a``: the paper gives no number.

Where the paper's value is itself a run of the success metric (e.g. a final RMS, or a ratio of two such
runs), it is compared with the runs of the same outcome: a successful paper run with our successful
runs, a failed one with our failed runs (``value`` stays the median over all runs). Parameter rows are taken over successful runs only (``success_rate`` counts the others).
``truth_in_interval`` says whether the true calibration's value is in the interval too: then the row
shows that the method converged to the noise floor, not more. A fixed tolerance is used only where
the paper gives no run to compare with (``reported[].tolerance`` with its ``reason``). For a single
deterministic run on recorded data (``interval: ls``), the interval is the least-squares estimate
± t(0.975, dof) standard errors instead.
"""

from __future__ import annotations

import functools

import numpy as np
import pandas as pd

from magexp.artifacts import ArtifactRuns, quantiles
from magexp.claims import matches, same  # noqa: F401  (matches: imported from here too)

COLUMNS = ["paper", "artifact", "quantity", "estimator", "setting", "truth", "paper_value", "value",
           "q25", "q75", "n_seeds", "tolerance", "verdict", "lo", "hi", "success_rate", "truth_in_interval"]
VERDICTS = ("reproduced", "differs", "n/a")
#: the interval of a single run: these quantiles over seeds
INTERVAL = (0.025, 0.975)




def interval(values, floor: float = 0.0) -> tuple[float, float]:
    """The 2.5-97.5 % quantiles of the finite ``values`` (non-negative values below ``floor`` count as it)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return (np.nan, np.nan)
    v = np.where((v >= 0) & (v < floor), floor, v)
    lo, hi = np.quantile(v, INTERVAL)
    return float(lo), float(hi)


def judge(paper: float | None, lo: float, hi: float, width: float, success_rate: float, *, floor: float = 0.0,
          tolerance=None, value: float = np.nan) -> str:
    """The verdict of one row (module docstring). ``tolerance``: a fixed
    :class:`magexp.spec.Tolerance` against ``value`` instead of the interval."""
    if paper is None or not np.isfinite(paper):
        return "n/a"
    if np.isfinite(success_rate) and success_rate < 0.5:
        return "differs"
    if tolerance is not None:
        return "reproduced" if np.isfinite(value) and tolerance.holds(value, paper) else "differs"
    p = max(paper, floor) if 0 <= paper < floor else paper
    inside = np.isfinite(lo) and lo - width <= p <= hi + width
    return "reproduced" if inside else "differs"


def cell_settings(runs: ArtifactRuns, ci: int) -> dict:
    """The ``{key: value}`` overrides of cell ``ci`` (base and grid)."""
    return dict(o.split("=", 1) for o in runs.overrides[ci])


def reported_entry(spec, quantity: str, settings: dict):
    """The paper's :class:`magexp.spec.Reported` entry of ``quantity`` for a cell (None if absent)."""
    for entry in spec.reported:
        if entry.quantity == quantity and matches(entry.match, settings):
            return entry
    return None


def reported_entries(spec) -> list[dict]:
    """The paper's numbers as plain ``{quantity, match, value}`` mappings."""
    return [{"quantity": e.quantity, "match": dict(e.match), "value": e.value} for e in spec.reported]


def reported_value(spec, quantity: str, settings: dict):
    """The paper's value of ``quantity`` for a cell and its entry (``(None, None)`` if absent)."""
    entry = reported_entry(spec, quantity, settings)
    return (None, None) if entry is None else (float(entry.value), entry)


def _row(spec, quantity, estimator, setting, truth, values, settings, *, ok=None, parameters: bool = False,
         extra_setting: str = "", aggregate: str = "median", success_threshold: float | None = None, ls=None) -> dict:
    """One summary row. ``ok``: per-value success (1/0/NaN); ``parameters``: statistics over the
    successful runs only; ``success_threshold``: a paper value at or below it is a successful run, and
    is compared with the interval of our successful runs (else of our failed ones);
    ``ls``: ``(estimate, half width)`` of a least-squares interval (recorded data, one run)."""
    v = np.asarray(values, float)
    ok = np.full(v.shape, np.nan) if ok is None else np.asarray(ok, float)
    judged = np.isfinite(ok)
    success_rate = float(ok[judged].mean()) if judged.any() else np.nan
    entry = reported_entry(spec, quantity, settings)
    paper = None if entry is None else float(entry.value)
    floor = float(spec.floor)
    basis = v
    if parameters and judged.any():
        basis = v[ok == 1]
    if aggregate == "mean":  # fractions: the mean of 0/1 outcomes, no quantiles
        med, q25, q75 = float(np.nanmean(v)), np.nan, np.nan
    else:
        med, q25, q75 = quantiles(basis)
    if success_threshold is not None and paper is not None and judged.any():
        same = v[ok == (1 if paper <= success_threshold else 0)]  # the paper's run classified by our rule
        basis = same if same.size else v
    lo, hi = interval(basis, floor)
    if ls is not None:
        lo, hi = ls[0] - ls[1], ls[0] + ls[1]
    width = entry.half_unit() if entry is not None else 0.0
    tol = None if entry is None else (entry.tolerance or spec.tolerance)
    verdict = judge(paper, lo, hi, width, success_rate, floor=floor, tolerance=tol, value=med)
    in_interval = np.nan
    if truth is not None and np.isfinite(lo):
        t = max(truth, floor) if 0 <= truth < floor else truth
        in_interval = bool(lo - width <= t <= hi + width)
    if entry is None:
        tol_text = ""
    elif tol is not None:
        tol_text = tol.text()
    else:
        tol_text = ("ls t-interval" if ls is not None else "95 % of runs") + (f" ± {width:.2g}" if width else "")
    return {
        "paper": spec.paper, "artifact": spec.name, "quantity": quantity, "estimator": estimator,
        "setting": setting + extra_setting, "truth": truth, "paper_value": paper, "value": med,
        "q25": q25, "q75": q75, "n_seeds": int(np.isfinite(v).sum()), "tolerance": tol_text, "verdict": verdict,
        "lo": lo, "hi": hi, "success_rate": success_rate, "truth_in_interval": in_interval,
    }


def parameter_values(runs: ArtifactRuns, ci: int) -> tuple[list[str], np.ndarray, np.ndarray | None]:
    """Parameter names, estimates ``(seeds, p)`` and the true vector of cell ``ci``."""
    outs = [runs.outputs[k] for k in sorted(runs.outputs) if k[0] == ci]
    truth = getattr(outs[0], "truth_x", None)
    return list(outs[0].parameter_names), np.array([o.x for o in outs]), truth


def _cell_ok(runs: ArtifactRuns, ci: int) -> np.ndarray:
    sub = runs.table[runs.table.cell == ci].sort_values("seed")
    return sub["succeeded"].to_numpy(float) if "succeeded" in sub else np.full(len(sub), np.nan)


def _parameter_rows(runs: ArtifactRuns, item) -> list[dict]:
    """``mode: parameters``: one row per (cell, parameter), statistics over the successful runs;
    ``only`` (optional) restricts to those estimators."""
    rows = []
    for ci in range(len(runs.cells)):
        sub = runs.table[runs.table.cell == ci]
        if item.only and sub.estimator.iloc[0] not in item.only:
            continue
        names, values, truth = parameter_values(runs, ci)
        ok = _cell_ok(runs, ci)
        for k, name in enumerate(names):
            rows.append(_row(runs.spec, name, sub.estimator.iloc[0], sub.setting.iloc[0],
                             None if truth is None else float(truth[k]), values[:, k], cell_settings(runs, ci),
                             ok=ok, parameters=True))
    return rows


def least_squares_interval(runs: ArtifactRuns, ci: int, level: float = 0.95) -> dict:
    """``{parameter: (estimate, half width)}`` of the least-squares fit of a linear ship model
    (Yan & Zhou 2022, eq 1: per axis ``B_i = [A_i Be, 1] [K_i, Bp_i]^T``, 4 parameters).

    Per axis ``s^2 = RSS / (N - 4)`` and ``Cov = s^2 (C^T C)^{-1}``; the half width is
    ``t(1 - (1 - level)/2, N - 4)`` standard errors (12 readings: 8 degrees of freedom), the quantile
    from ``scipy.special.stdtrit`` (what ``scipy.stats.t.ppf`` evaluates, without importing
    ``scipy.stats``).
    """
    from scipy.special import stdtrit

    c, y, names = _design_of(runs, ci)
    n, p = c.shape
    coef, *_ = np.linalg.lstsq(c, y, rcond=None)  # (4, 3): column a = axis a's [K_a1, K_a2, K_a3, Bp_a]
    rss = np.sum((y - c @ coef) ** 2, axis=0)
    dof = n - p
    cov = np.linalg.inv(c.T @ c)
    se = np.sqrt(np.outer(np.diag(cov), rss / dof))  # (4, 3)
    t = stdtrit(dof, 0.5 + level / 2)
    out = {}
    for a in range(3):
        for j in range(3):
            out[names[3 * a + j]] = (float(coef[j, a]), float(t * se[j, a]))
        out[names[9 + a]] = (float(coef[3, a]), float(t * se[3, a]))
    return out


def f_test(runs: ArtifactRuns, ci: int, theta: np.ndarray) -> list[dict]:
    """Per axis, the F-test of the hypothesis that ``theta`` (e.g. the paper's K, Bp) is the true
    parameter of the linear model: ``F = (b - b_ls)^T C^T C (b - b_ls) / p / s^2 ~ F(p, N - p)``; the
    p-value from ``scipy.special.fdtrc`` (what ``scipy.stats.f.sf`` evaluates)."""
    from scipy.special import fdtrc

    c, y, _ = _design_of(runs, ci)
    n, p = c.shape
    coef, *_ = np.linalg.lstsq(c, y, rcond=None)
    k, bp = np.asarray(theta[:9], float).reshape(3, 3), np.asarray(theta[9:], float)
    out = []
    for a in range(3):
        d = np.append(k[a], bp[a]) - coef[:, a]
        s2 = np.sum((y[:, a] - c @ coef[:, a]) ** 2) / (n - p)
        f = float(d @ c.T @ c @ d / p / s2)
        out.append({"axis": a + 1, "F": f, "dof": (p, n - p), "p_value": float(fdtrc(p, n - p, f))})
    return out


def _ftest_rows(runs: ArtifactRuns, item) -> list[dict]:
    """``mode: ftest``: per cell (of ``only``) and axis, the p-value of :func:`f_test` of its estimate."""
    rows = []
    for ci in range(len(runs.cells)):
        sub = runs.table[runs.table.cell == ci]
        if item.only and sub.estimator.iloc[0] not in item.only:
            continue
        theta = runs.outputs[(ci, int(sub.seed.min()))].x
        for test in f_test(runs, ci, theta):
            rows.append(_row(runs.spec, f"{item.quantity}_axis{test['axis']}", sub.estimator.iloc[0],
                             sub.setting.iloc[0] + f";F={test['F']:.4g};dof={test['dof'][0]},{test['dof'][1]}",
                             None, [test["p_value"]], cell_settings(runs, ci)))
    return rows


def _design_of(runs: ArtifactRuns, ci: int) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """``(C, y, parameter names)`` of the linear problem of cell ``ci``'s first seed
    (``problem.design()``, :func:`_design`): built once per cell and seed, however many summary rows
    and tests read it (the mock-up's interval rows and F-tests share one)."""
    return _design(tuple(runs.overrides[ci]), int(runs.table[runs.table.cell == ci].seed.min()))


@functools.lru_cache(maxsize=64)
def _design(overrides: tuple[str, ...], seed: int) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The design of :func:`_problem_of` (read-only arrays: one copy is shared by every caller);
    :func:`summarise` empties this cache when it returns (a data file edited later is read again)."""
    problem = _problem_of(overrides, seed)
    c, y = (np.array(a, float) for a in problem.design())
    c.setflags(write=False), y.setflags(write=False)
    return c, y, list(problem.parameter_names())


def _problem_of(overrides, seed: int):
    """The problem of a cell's run ``seed``, rebuilt from the cell's overrides (deterministic data)."""
    from magexp.artifacts import compose_config
    from magexp.problems import make_problem
    from magexp.runner import build
    from magexp.seeding import run_generators, scenario_stream

    cfg = compose_config(list(overrides))
    scenario = build(cfg.scenario, "scenario")
    dataset = scenario.generate(rng=run_generators(seed, stream=scenario_stream(cfg.scenario))[0])
    objective = cfg.get("objective") or scenario.objective
    return make_problem(objective, dataset, scenario.search, **getattr(scenario, "problem_options", {}))


def summarise(runs: ArtifactRuns) -> pd.DataFrame:
    """One row per (summarised quantity, cell) and per ratio group."""
    try:
        return _summarise(runs)
    finally:
        _design.cache_clear()


def _summarise(runs: ArtifactRuns) -> pd.DataFrame:
    spec, table = runs.spec, runs.table
    rows = []
    for item in spec.summarise:
        if item.mode == "parameters":
            rows += _parameter_rows(runs, item)
            continue
        if item.mode == "ftest":
            rows += _ftest_rows(runs, item)
            continue
        metric = item.metric
        truth_metric = item.truth_metric or f"truth_{metric}"
        for ci in range(len(runs.cells)):
            sub = table[table.cell == ci].sort_values("seed")
            if metric not in sub or sub[metric].isna().all():
                continue
            truth = float(np.median(sub[truth_metric])) if truth_metric in sub and sub[truth_metric].notna().all() else None
            ls = None
            if item.interval == "ls" and item.quantity in (names := least_squares_interval(runs, ci)):
                ls = names[item.quantity]
            rows.append(_row(spec, item.quantity, sub.estimator.iloc[0], sub.setting.iloc[0], truth,
                             sub[metric].astype(float).to_numpy(), cell_settings(runs, ci), ok=_cell_ok(runs, ci),
                             aggregate=item.aggregate, ls=ls, success_threshold=None if truth is None or
                             metric != spec.success.metric else spec.success.factor * truth + spec.success.floor))
    for item in spec.ratios:
        num_sel, den_sel, metric = item.numerator, item.denominator, item.metric
        for ci in range(len(runs.cells)):
            settings = cell_settings(runs, ci)
            if not matches(den_sel, settings):
                continue
            partner = {**settings, **num_sel}
            nj = [cj for cj in range(len(runs.cells)) if cell_settings(runs, cj) == partner]
            if not nj:
                continue
            den = table[table.cell == ci].set_index("seed")
            num = table[table.cell == nj[0]].set_index("seed")
            ratio = (num[metric].astype(float) / den[metric].astype(float)).dropna()
            both = (num["succeeded"] * den["succeeded"]).reindex(ratio.index) if "succeeded" in den else None
            sub = table[table.cell == ci]
            ref = ",".join(f"{k}={v}" for k, v in num_sel.items())
            # a ratio of two successful runs is within the success factor of 1
            threshold = spec.success.factor if item.metric == spec.success.metric else None
            rows.append(_row(spec, item.quantity, sub.estimator.iloc[0], sub.setting.iloc[0], None, ratio.to_numpy(),
                             settings, extra_setting=f";reference={ref}", success_threshold=threshold,
                             ok=None if both is None else both.to_numpy(float)))
    return pd.DataFrame(rows, columns=COLUMNS)
