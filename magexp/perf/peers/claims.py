"""The claims of the section "magexp beside MAGYC", computed from the bench's long rows (``peers.csv``).

The bench's rows are not a paper's runs table (:mod:`magexp.artifacts.claims` reads those, one column per setting),
so its claims are computed here, with the same vocabulary and tests:

* a comparison of two cells (``better`` against ``worse``, lower is better) is the one-sided Wilcoxon
  signed-rank test of their paired differences (:func:`magexp.artifacts.significance.wilcoxon_less`; pairs: the same
  seed, or the same half of a recording), :func:`tested`; it :data:`HOLDS` when its p, Holm-adjusted over the
  section's comparisons (:func:`adjust`), is below :data:`ALPHA`, is :data:`CONTRADICTED` when the converse's is,
  and :data:`UNDECIDED` when the test cannot reach ``ALPHA`` at its n (n non-zero differences: ``2^-n``; two
  halves of a recording: 0.25), else :data:`NO_DIFFERENCE`. Two bootstrap intervals that do not overlap are no
  test: they decide nothing here;
* a winner (the lowest median) holds when its comparison with every other method holds (its p: the largest of
  those comparisons'); else the section names the methods it is not separated from.

On MAGYC's synthetic data a method's accuracy in one run is its worse error, ``max(soft-iron error, hard-iron
error / field)`` (:data:`ERROR`): the quantity the bench's success rule bounds (both within 0.05). On a
recording the pairs are its two halves: a signed-rank test of two pairs cannot reach ``ALPHA``, so no comparison
on a recording can be decided, and its two halves are printed as two values, never as an interval.
"""

from __future__ import annotations

import functools

import numpy as np
import pandas as pd

from magexp.artifacts.comparisons import CONTRADICTED, HOLDS, NO_DIFFERENCE, UNDECIDED, Test, decide
from magexp.artifacts.significance import ALPHA, detect_paired, holm, wilcoxon_less
from magexp.artifacts.tables import interval

#: the combined error of a simulated run (module docstring)
ERROR = "worse_error"


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
    """``(median, lo, hi)`` of ``v``: its 95 % bootstrap interval (NaN for fewer than two values)."""
    lo, hi = interval(v.to_numpy(), stat="median") if len(v) > 1 else (np.nan, np.nan)
    return float(np.median(v)) if len(v) else np.nan, lo, hi


def said(v: pd.Series, scale: float = 1.0, unit: str = "") -> str:
    """``median [lo, hi]`` of ``v`` (3 significant digits): the 95 % bootstrap interval of the median
    over seeds; two values (a recording's halves) are printed as two values, not as an interval.
    """
    if len(v) == 2:
        a, b = sorted(float(x) * scale for x in v)
        return f"{float(np.median(v)) * scale:.3g}{unit} (halves {a:.3g} and {b:.3g})"
    m, lo, hi = (x * scale for x in _median_ci(v))
    return f"{m:.3g}{unit}" + (f" [{lo:.3g}, {hi:.3g}]" if np.isfinite(lo) else "")


def tested(better: pd.Series, worse: pd.Series) -> Test:
    """The paired test of "``better`` is lower than ``worse``" (module docstring), unadjusted."""
    d = (better - worse).dropna().to_numpy(float) if len(better) and len(worse) else np.zeros(0)
    d = d[np.isfinite(d)]
    p_hold, p_contra = wilcoxon_less(d), wilcoxon_less(-d)
    nonzero = int(np.count_nonzero(d))
    return Test("paired", p_hold, p_contra, 0.5 ** nonzero if d.size else 1.0, d.size,
                -float(np.median(d)) if d.size else float("nan"), f"paired p = {p_hold:.2g}, n = {d.size}",
                functools.partial(detect_paired, d))


def compare(better: pd.Series, worse: pd.Series) -> tuple[str, str]:
    """The unadjusted outcome of "``better`` is lower than ``worse``" and its test (module docstring)."""
    if not len(better) or not len(worse):
        return NO_DIFFERENCE, "a side has no values"
    t = tested(better, worse)
    return decide(t.p_hold, t.p_contra, t.p_min), t.text


def winner_test(frame: pd.DataFrame, metric: str, methods: list[str], **where) -> tuple[str, Test, list[str]]:
    """``(best method, its test, methods not separated from it)`` of the lowest median of ``metric``: the
    test's p is the largest of the best's comparisons with every other (each must hold).
    """
    cells = {m: values(frame, metric, method=m, **where) for m in methods}
    cells = {m: v for m, v in cells.items() if len(v)}
    best = min(cells, key=lambda m: np.median(cells[m]))
    tests = {m: tested(cells[best], v) for m, v in cells.items() if m != best}
    tied = [m for m, t in tests.items() if decide(t.p_hold, t.p_contra, t.p_min) != HOLDS]
    worst = max(tests.values(), key=lambda t: t.p_hold)
    combined = Test("paired", worst.p_hold, min(t.p_contra for t in tests.values()) * len(tests),
                    max(t.p_min for t in tests.values()), min(t.n for t in tests.values()), worst.observed,
                    f"largest paired p = {worst.p_hold:.2g}, n = {worst.n}", worst.detect)
    return best, combined, tied


def winner(frame: pd.DataFrame, metric: str, methods: list[str], **where) -> tuple[str, str, list[str]]:
    """``(best method, outcome, methods not separated from it)`` of the lowest median of ``metric`` (unadjusted)."""
    best, t, tied = winner_test(frame, metric, methods, **where)
    return best, HOLDS if not tied else NO_DIFFERENCE, tied


def adjust(claims: list[dict]) -> list[dict]:
    """Holm's correction over the section's claims (each with its ``test``, :class:`Test`): ``result`` decided
    again on the adjusted p-values, the evidence saying them (and, where no difference is detected, the
    detectable shift; where the test cannot decide, its smallest p). Returns ``claims`` (changed in place).
    """
    tests = [c["test"] for c in claims]
    rank = {id(t): r for r, t in enumerate(sorted(tests, key=lambda t: t.p_hold))}
    for c, t, p, pc in zip(claims, tests, holm([t.p_hold for t in tests]), holm([t.p_contra for t in tests])):
        c["result"], c["p_adjusted"] = decide(p, pc, t.p_min), p
        note = f"{t.text}; Holm p = {p:.2g} of {len(claims)}"
        if c["result"] == UNDECIDED:
            note += f"; cannot be decided at n = {t.n}: its smallest p is {t.p_min:.2g}"
        elif c["result"] == NO_DIFFERENCE:  # at its step of Holm's rule (magexp.artifacts.comparisons.adjust)
            level = ALPHA / (len(claims) - rank[id(t)])
            note += f"; detectable at 80% power at its level {level:.2g}: {t.detect(level)[1]}"
        c["evidence"] = f"{c['evidence']}; {note}"
    return claims
