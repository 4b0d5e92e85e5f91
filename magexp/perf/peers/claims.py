"""The claims of the section "magexp beside MAGYC", computed from the bench's long rows (``peers.csv``).

The bench's rows are not a paper's runs table (:mod:`magexp.artifacts.claims` reads those, one column per setting),
so its claims are computed here, with the same vocabulary and tests:

* a comparison of two cells (``better`` against ``worse``, lower is better) :data:`HOLDS` when the one-sided
  Wilcoxon signed-rank test of their paired differences (:func:`magexp.artifacts.claims.wilcoxon_less`; pairs:
  the same seed, or the same half of a recording) separates them at :data:`ALPHA`, or their 95 % bootstrap
  intervals of the median (:func:`magexp.artifacts.claims.ci`) do not overlap; :data:`CONTRADICTED` when one of
  the two separates them the other way; else :data:`NO_DIFFERENCE`;
* a winner (the lowest median) holds when its comparison with every other method holds; else the section names
  the methods it is not separated from.

On MAGYC's synthetic data a method's accuracy in one run is its worse error, ``max(soft-iron error, hard-iron
error / field)`` (:data:`ERROR`): the quantity the bench's success rule bounds (both within 0.05). On a
recording the pairs are its two halves: two pairs cannot reach ``ALPHA`` in a signed-rank test, so there only
the intervals (the two halves' range) can separate two methods.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from magexp.artifacts.claims import ALPHA, CONTRADICTED, HOLDS, NO_DIFFERENCE, ci, wilcoxon_less

#: the combined error of a simulated run (module docstring)
ERROR = "worse_error"
#: the methods a winner is chosen among: every one but the bounds and the raw readings
NOT_METHODS = ("none", "bound")


def frame_of(rows) -> pd.DataFrame:
    """The long rows as a frame with float values and, per simulated run, the combined :data:`ERROR`."""
    frame = pd.DataFrame(list(rows)).astype({"value": float, "seed": str, "axis_map": str})
    frame["axis_map"] = frame.axis_map.replace("nan", "")
    key = ["kind", "dataset", "seed", "fit_on", "axis_map", "side", "method"]
    parts = frame[frame.metric.isin(("soft_iron_error", "hard_iron_error"))]
    worse = parts.groupby(key, sort=False).value.agg(lambda v: v.max() if len(v) == 2 else np.nan).reset_index()
    return pd.concat([frame, worse.assign(metric=ERROR)], ignore_index=True)


def values(frame: pd.DataFrame, metric: str, **where) -> pd.Series:
    """The finite values of ``metric`` in the cell ``where``, indexed by their pair key (seed, part)."""
    sel = frame[frame.metric == metric]
    for k, v in where.items():
        sel = sel[sel[k].isin(v) if isinstance(v, tuple) else sel[k] == v]
    sel = sel[np.isfinite(sel.value)]
    return pd.Series(sel.value.to_numpy(), index=pd.MultiIndex.from_arrays([sel.seed, sel.fit_on]))


def _median_ci(v: pd.Series) -> tuple[float, float, float]:
    lo, hi = ci(v.to_numpy(), "median") if len(v) > 1 else (np.nan, np.nan)
    return float(np.median(v)) if len(v) else np.nan, lo, hi


def said(v: pd.Series, scale: float = 1.0, unit: str = "") -> str:
    """``median [lo, hi]`` of ``v`` (3 significant digits)."""
    m, lo, hi = (x * scale for x in _median_ci(v))
    return f"{m:.3g}{unit}" + (f" [{lo:.3g}, {hi:.3g}]" if np.isfinite(lo) else "")


def compare(better: pd.Series, worse: pd.Series) -> tuple[str, str]:
    """The outcome of "``better`` is lower than ``worse``" and its test (module docstring)."""
    if not len(better) or not len(worse):
        return NO_DIFFERENCE, "a side has no values"
    d = (better - worse).dropna()
    p_hold, p_contra = (wilcoxon_less(d), wilcoxon_less(-d)) if len(d) > 2 else (1.0, 1.0)
    _, alo, ahi = _median_ci(better)
    _, blo, bhi = _median_ci(worse)
    if p_hold < ALPHA or ahi < blo:
        return HOLDS, f"paired p = {p_hold:.2g}, n = {len(d)}" if p_hold < ALPHA else "intervals separate"
    if p_contra < ALPHA or bhi < alo:
        return CONTRADICTED, f"paired p = {p_contra:.2g} the other way" if p_contra < ALPHA else "intervals separate"
    if len(d) <= 2:
        return NO_DIFFERENCE, f"intervals overlap ({len(d)} pairs: too few for the paired test)"
    return NO_DIFFERENCE, f"paired p = {min(p_hold, p_contra):.2g}, n = {len(d)}; intervals overlap"


def winner(frame: pd.DataFrame, metric: str, methods: list[str], **where) -> tuple[str, str, list[str]]:
    """``(best method, outcome, methods not separated from it)`` of the lowest median of ``metric``."""
    cells = {m: values(frame, metric, method=m, **where) for m in methods}
    cells = {m: v for m, v in cells.items() if len(v)}
    best = min(cells, key=lambda m: np.median(cells[m]))
    tied = [m for m, v in cells.items() if m != best and compare(cells[best], v)[0] != HOLDS]
    return best, HOLDS if not tied else NO_DIFFERENCE, tied
