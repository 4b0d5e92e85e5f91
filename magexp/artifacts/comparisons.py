"""The test that decides a comparison claim (``kind: ordering | winner``) and Holm's adjustment within its
family (:mod:`magexp.artifacts.claims` says what a claim is; :mod:`magexp.artifacts.significance` holds the
statistics themselves).

:func:`compare` tests one pair of sides by the claim's ``test:`` (Fisher's exact test of success counts, the
Wilcoxon signed-rank test of paired per-seed differences, or a permutation test); :func:`combined` joins the
pairs of one claim; :func:`decide` turns p-values into a verdict; :func:`adjust` applies Holm's rule within
each family of a paper.

Each comparison carries its ``p`` (of the claimed direction; for several pairs the largest: every
pair must hold), the smallest ``p_min`` its test can give at its n (a signed-rank test of n
non-zero differences: ``2^-n``; Fisher's: the most extreme table of its margins), and, where it
detects no difference, ``detectable``: the smallest difference it would detect with :data:`POWER`
probability at the level Holm's rule judged it at, with its own test (Fisher's by exact enumeration,
:func:`~magexp.artifacts.significance.detect_rise`; the signed-rank test's "not computable (k of n ties)"
where its scale is degenerate, :func:`~magexp.artifacts.significance.detect_paired`;
:func:`~magexp.artifacts.significance.detect_unpaired`), beside the ``observed`` effect in its units.
Within a paper the ``p`` of its comparison claims (sanity checks apart) are adjusted by Holm's step-down
rule (:func:`~magexp.artifacts.significance.holm`, :func:`adjust`): a comparison :data:`HOLDS` when its
``p_adjusted`` is below :data:`ALPHA`, is :data:`CONTRADICTED` when the converse's is, :data:`UNDECIDED`
when ``p_min`` is not below :data:`ALPHA` (the test cannot reach it at this n, whatever the data), else
:data:`NO_DIFFERENCE`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pandas as pd

from magexp.artifacts.selection import cell_settings, column, select, values
from magexp.artifacts.significance import (ALPHA, POWER, detect_paired, detect_rise, detect_unpaired, fisher_greater,
                                          holm, permutation_less, wilcoxon_less)
from magexp.artifacts.tables import statistic
from magexp.errors import MagexpError

#: the verdicts of a comparison; the first is the only one that counts as holding
HOLDS, CONTRADICTED, NO_DIFFERENCE = "holds", "contradicted", "no difference detected"
UNDECIDED = "cannot be decided"
#: cell keys that choose the method, not the readings: cells that differ only in these share their data
ESTIMATOR_SIDE = ("estimator", "objective")
#: families whose comparisons are judged alone, each at its own p (never in a Holm family)
ALONE = ("sanity", "exploratory")


def _paired(table: pd.DataFrame, a: dict, b: dict, metric: str) -> tuple[np.ndarray, np.ndarray] | None:
    """Per-seed values of ``metric`` of the single cells ``a`` and ``b`` matched on seed, when they
    share their seeds and differ only in :data:`ESTIMATOR_SIDE` keys (then a seed is the same
    readings for both); else None."""
    ta, tb = select(table, a), select(table, b)
    if ta.cell.nunique() != 1 or tb.cell.nunique() != 1 or ta.cell.iloc[0] == tb.cell.iloc[0]:
        return None
    settings = cell_settings(table)
    sa, sb = settings[int(ta.cell.iloc[0])], settings[int(tb.cell.iloc[0])]
    data_side = lambda s: {k: v for k, v in s.items() if k not in ESTIMATOR_SIDE and not k.startswith("estimator.")}
    if data_side(sa) != data_side(sb) or set(ta.seed) != set(tb.seed):
        return None
    va = pd.Series(column(ta, metric), index=ta.seed)
    vb = pd.Series(column(tb, metric), index=tb.seed).reindex(va.index)
    return va.to_numpy(float), vb.to_numpy(float)


@dataclass(frozen=True)
class Test:
    """One pair's test: the one-sided p of the claim (``p_hold``) and of its converse (``p_contra``),
    the smallest p the test can give at its n (``p_min``), the pair's smallest sample ``n``, the
    observed effect in the claimed direction (``observed``: a success-rate rise, a per-seed shift, a
    difference of the statistic), a text, and ``detect``: ``level -> (detectable, words)``, the
    difference it would detect with :data:`POWER` at that level (in the units of ``observed``)."""

    name: str
    p_hold: float
    p_contra: float
    p_min: float
    n: int
    observed: float
    text: str
    detect: object


def decide(p: float, p_contra: float, p_min: float, alpha: float = ALPHA) -> str:
    """The outcome of a comparison from its p-values (module docstring): :data:`UNDECIDED` when even
    the smallest attainable p is not below ``alpha``.
    """
    if not p_min < alpha:
        return UNDECIDED
    if p < alpha:
        return HOLDS
    return CONTRADICTED if p_contra < alpha else NO_DIFFERENCE


def compare(claim, table: pd.DataFrame, better: dict, worse: dict, stats: tuple, cis: tuple) -> Test:
    """The test of "the cells ``better`` beat the cells ``worse``" by the claim's ``test``."""
    test, pair = _test_of(claim, table, better, worse)
    if test == "fisher":
        return _fisher_test(claim, table, better, worse)
    if test == "paired":
        return _paired_test(claim, pair or _paired(table, better, worse, claim.metric))
    return _unpaired_test(claim, table, better, worse, cis)


def _test_of(claim, table: pd.DataFrame, better: dict, worse: dict) -> tuple[str, tuple | None]:
    """The test of a comparison and the paired values ``test: auto`` found: ``fisher`` for success
    rates, ``paired`` for two single cells with the same seeds and scenario, else ``unpaired``."""
    if claim.test != "auto":
        return claim.test, None
    if claim.stat == "success_rate":
        return "fisher", None
    pair = _paired(table, better, worse, claim.metric)
    return ("paired" if pair is not None else "unpaired"), pair


def _fisher_test(claim, table: pd.DataFrame, better: dict, worse: dict) -> Test:
    """Fisher's exact test of the success counts; its smallest p: the most extreme table of its margins."""
    ka, kb = (values(select(table, w), claim.metric, "success_rate") for w in (better, worse))
    if claim.better == "lower":  # fewer successes is better: swap the roles
        ka, kb = kb, ka
    (a, na), (b, nb) = (int(ka.sum()), len(ka)), (int(kb.sum()), len(kb))
    p_hold, p_contra = fisher_greater(a, na, b, nb), fisher_greater(b, nb, a, na)
    top = min(na, a + b)
    p_min = fisher_greater(top, na, a + b - top, nb)
    rise = a / na - b / nb if na and nb else np.nan
    return Test("fisher", p_hold, p_contra, p_min, min(na, nb), rise,
                f"{a} of {na} vs {b} of {nb} seeds succeed, Fisher p = {p_hold:.3g}",
                functools.partial(detect_rise, b / nb if nb else np.nan, na, nb))


def _paired_test(claim, pair: tuple | None) -> Test:
    """The one-sided Wilcoxon signed-rank test of the per-seed differences of ``pair`` (the two
    cells' values on the same seeds); its smallest p: ``2^-n`` for n non-zero differences."""
    if pair is None:
        raise MagexpError(f"claim {claim.id!r}: test: paired needs two single cells with the same seeds and scenario")
    sign = 1 if claim.better == "lower" else -1
    d = sign * (pair[0] - pair[1])  # below zero: the first is better
    d = d[np.isfinite(d)]
    p_hold, p_contra = wilcoxon_less(d), wilcoxon_less(-d)
    wins, losses = int((d < 0).sum()), int((d > 0).sum())
    return Test("paired", p_hold, p_contra, 0.5 ** (wins + losses), d.size, -float(np.median(d)) if d.size else np.nan,
                f"paired Wilcoxon p = {p_hold:.3g} (first better on {wins}, worse on {losses}, "
                f"equal on {d.size - wins - losses} of {d.size} seeds)", functools.partial(detect_paired, d))


def _unpaired_test(claim, table: pd.DataFrame, better: dict, worse: dict, cis: tuple) -> Test:
    """The one-sided permutation test (:func:`permutation_less`) of ``stat`` of two sets of runs that
    share no readings."""
    a, b = (values(select(table, w), claim.metric, claim.stat) for w in (better, worse))
    if min(len(a), len(b)) < 1:
        raise MagexpError(f"claim {claim.id!r}: a side of the comparison has no runs")
    p_less, p_more, p_min = permutation_less(a, b, claim.stat)
    p_hold, p_contra = (p_less, p_more) if claim.better == "lower" else (p_more, p_less)
    sign = 1 if claim.better == "lower" else -1
    return Test("unpaired", p_hold, p_contra, p_min, min(len(a), len(b)),
                sign * (statistic(b, claim.stat) - statistic(a, claim.stat)),
                f"permutation p = {p_hold:.3g} (n = {len(a)}, {len(b)})", functools.partial(detect_unpaired, *cis))


def combined(tests: list[Test]) -> dict:
    """The :class:`~magexp.artifacts.claims.Outcome` fields of a claim of several pairs: every pair must hold
    (``p``: the largest), one the other way contradicts it (``p_contra``: the smallest times the number of
    pairs), the largest ``p_min``, the smallest ``n``; the deciding pair's (the largest p) test,
    observed effect and ``detectable``, at :data:`ALPHA` until :func:`adjust` knows its level.
    """
    deciding = max(tests, key=lambda t: t.p_hold)
    detectable, words = deciding.detect(ALPHA)
    return {"p": deciding.p_hold, "p_contra": min(1.0, len(tests) * min(t.p_contra for t in tests)),
            "p_min": max(t.p_min for t in tests), "n": min(t.n for t in tests), "detectable": detectable,
            "detectable_words": words, "test": deciding.name, "observed": deciding.observed, "detect": deciding.detect}


def adjust(outcomes: list, families: list[str] | None = None) -> list:
    """Holm's correction within each family of comparisons (``families``: each outcome's family,
    :func:`magexp.artifacts.families.claim_families`; default: one family of every comparison that is not a
    sanity check). A sanity check or an exploratory claim keeps its own p. Each comparison gets its
    ``family``, ``family_size``, ``p_adjusted`` and ``level`` (``alpha / (m - rank)``, its step of Holm's
    rule); its result is decided again on ``p_adjusted`` (:func:`decide`) and its evidence names the family.
    """
    for o, name in zip(outcomes, families or [""] * len(outcomes)):
        o.family = name or ("sanity" if o.claim.role == "sanity" else "primary")
    groups: dict[str, list] = {}
    for o in (o for o in outcomes if o.is_comparison):
        groups.setdefault(o.family, []).append(o)
    for name, family in groups.items():
        _adjust_family(family, alone=name in ALONE)
    return outcomes


def _adjust_family(family: list, alone: bool) -> None:
    """Holm's rule over one family's comparisons (each at its own p when ``alone``), in place."""
    m = 1 if alone else len(family)
    p_adj = [o.p for o in family] if alone else holm([o.p for o in family])
    p_con = [o.p_contra for o in family] if alone else holm([o.p_contra for o in family])
    rank = {id(o): r for r, o in enumerate(sorted(family, key=lambda o: o.p))}
    for o, p, pc in zip(family, p_adj, p_con):
        o.family_size, o.p_adjusted, o.level = m, p, ALPHA / (1 if alone else m - rank[id(o)])
        if o.detect is not None:
            o.detectable, o.detectable_words = o.detect(o.level)
        o.result = (o.rule or decide)(p, pc, o.p_min)
        o.holds = o.result == HOLDS
        note = _adjusted_note(o, m) + (f"; its converse: p = {pc:.3g}" if o.rule is not None and pc < ALPHA else "")
        o.short, o.evidence = f"{o.short}; {note}", f"{o.evidence}; {note}"


def _adjusted_note(o, m: int) -> str:
    """What the evidence of a comparison adds once its family is known: the adjusted p, and what it
    could detect (no difference) or why it cannot decide."""
    note = f"{o.p_adjusted:.3g} after Holm over {m} {o.family} tests" if m > 1 else f"p = {o.p:.3g}"
    if o.result == UNDECIDED and not o.p_min < o.level:
        return f"{note}; cannot be decided at n = {o.n}: its smallest p is {o.p_min:.3g}"
    if o.undetected and o.detectable_words:
        return (f"{note}; detectable at {POWER:.0%} power at its level {o.level:.3g}: {o.detectable_words} "
                f"(observed: {o.observed:.3g})")
    return note
