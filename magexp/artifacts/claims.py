"""Claims: every qualitative statement of the report as a condition on an artifact's runs.

A claim sits in the artifact YAML next to the runs it is about::

    claims:
      - id: ipso_converges
        text: "IPSO reaches the optimum the truth gives on at least 90 % of seeds at every noise level"
        kind: success                     # threshold | success | ordering | winner
        where: {estimator: ipso}          # every selected cell must satisfy it
        op: ">="
        value: 0.9
      - id: table7_order
        by: paper                         # the paper's own statement, evaluated (it may not hold)...
        section: "Sec. 5, Table 7"        # ...with where the paper says it (required for by: paper)
        text: "F_g orders RDPSO < PSO < EKF"
        kind: ordering
        metric: fg
        cells: [{estimator: rdpso}, {estimator: pso}, {estimator: ekf}]   # best first
      - id: lm_at_optimum
        role: sanity                      # holds by construction: a check of the code, never counted
        ...

``metric`` is a runs column or an expression of columns (``pandas.eval``); ``stat`` one of
:data:`STATS` over the seeds of the selected cells (pooled). Confidence intervals are 95 %
percentile bootstrap intervals over seeds (a fixed generator: the same on every
run, :func:`magexp.artifacts.tables.interval`). ``role: finding`` (default) claims with ``by: magexp``
are what the report states as true;
``tests/test_claims.py`` fails when one of them does not hold on the results. ``figure``: the
artifact whose figure shows the claim (default: its own).

**Comparisons** (``kind: ordering``: each cell better than the next; ``kind: winner``: the first
better than every other) hold only when a test separates the two sides (``test:``):

* ``fisher``: one-sided Fisher's exact test on the success counts (``stat: success_rate``);
* ``paired``: one-sided Wilcoxon signed-rank test on the per-seed differences of ``metric``,
  where the two cells share their seeds and scenario (same seed and scenario: the same readings);
* ``unpaired``: one-sided permutation test of the difference of ``stat`` between the two cells'
  per-seed values (:data:`~magexp.artifacts.significance.N_PERM` relabellings from a fixed generator; ``intervals``, its old name,
  is read as it: two bootstrap intervals that do not overlap are no test);
* ``auto`` (default): ``fisher`` for success rates, ``paired`` where the cells differ only in
  estimator-side keys (``estimator``, ``estimator.*``, ``objective``) and have the same seeds,
  ``unpaired`` otherwise.

Each comparison carries its ``p`` (of the claimed direction; for several pairs the largest: every
pair must hold), the smallest ``p_min`` its test can give at its n (a signed-rank test of n
non-zero differences: ``2^-n``; Fisher's: the most extreme table of its margins), and, where it
detects no difference, ``detectable``: the smallest difference it would detect with
:data:`POWER` probability at the level Holm's rule judged it at, with its own test (Fisher's by exact
enumeration, :func:`~magexp.artifacts.significance.detect_rise`; the signed-rank test's "not computable
(k of n ties)" where its scale is degenerate, :func:`~magexp.artifacts.significance.detect_paired`;
:func:`~magexp.artifacts.significance.detect_unpaired`), beside the ``observed`` effect in its units. Within a paper the ``p`` of its comparison claims (sanity checks
apart) are adjusted by Holm's step-down rule (:func:`holm`, :func:`adjust`): a comparison
``holds`` when its ``p_adjusted`` is below :data:`ALPHA`, is ``contradicted`` when the converse's
is, ``cannot be decided`` when ``p_min`` is not below :data:`ALPHA` (the test cannot reach it at
this n, whatever the data), else ``no difference detected``; a threshold's or a success rate's
outcome is ``holds`` or ``does not hold``.

Notes interpolate measured values with ``{stat:metric@key=value,key=value:format}``, e.g.
``{median:fun@estimator=ipso,scenario.noise=2:.3g}`` (:func:`interpolate`); a field whose
selection matches no cell fails the build with one line naming it; one whose cells exist but whose
row filter (``succeeded=0``, ``seeds=10``) leaves no value prints :data:`NO_RUNS`, never ``n/a``.
"""

from __future__ import annotations

import functools
import operator
import re
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from magexp.artifacts.censoring import censored_mask, censored_statistic, censored_text, with_censored
from magexp.artifacts.schema import Float, typed
from magexp.artifacts.significance import (ALPHA, POWER, detect_paired, detect_rise, detect_unpaired, effect_error,
                                          fisher_greater, holm, permutation_less, wilcoxon_less)
from magexp.artifacts.tables import STATS, interval, matches, same, statistic
from magexp.errors import MagexpError

OPS = {"<=": operator.le, "<": operator.lt, ">=": operator.ge, ">": operator.gt}
#: the words of an operator and of a statistic in a claim's short evidence
OP_WORDS = {"<=": "at most", "<": "below", ">=": "at least", ">": "above"}
STAT_WORDS = {"success_rate": "success rate", "max": "largest", "min": "smallest"}
KINDS = ("threshold", "success", "ordering", "winner")
#: ``finding``: counted; ``sanity``: true by construction, a check of the code; ``exploratory``: a setting
#: chosen because its runs resemble the paper's numbers, shown but never counted nor tested in a family
ROLES = ("finding", "sanity", "exploratory")
TESTS = ("auto", "fisher", "paired", "unpaired", "intervals")
#: outcomes of a claim; the first is the only one that counts as holding
HOLDS, FAILS, CONTRADICTED, NO_DIFFERENCE = "holds", "does not hold", "contradicted", "no difference detected"
UNDECIDED = "cannot be decided"
#: cell keys that choose the method, not the readings: cells that differ only in these share their data
ESTIMATOR_SIDE = ("estimator", "objective")


@typed
@dataclass(frozen=True)
class Claim:
    """A statement and the condition on the runs that makes it true (see the module docstring)."""

    id: str
    text: str
    kind: str
    by: str = "magexp"
    metric: str = "fun"
    stat: str = "median"
    where: dict = field(default_factory=dict)
    op: str = "<="
    value: Float | None = None
    cells: list = field(default_factory=list)
    better: str = "lower"
    section: str = ""
    role: str = "finding"
    figure: str = ""
    test: str = "auto"
    effect: dict = field(default_factory=dict)

    def __post_init__(self):
        checks = [("kind", self.kind, KINDS), ("by", self.by, ("magexp", "paper")), ("stat", self.stat, tuple(STATS)),
                  ("op", self.op, tuple(OPS)), ("better", self.better, ("lower", "higher")),
                  ("role", self.role, ROLES), ("test", self.test, TESTS)]
        for key, value, allowed in checks:
            if value not in allowed:
                raise MagexpError(f"claim {self.id!r}: {key}={value!r} is not allowed: choose one of {', '.join(allowed)}")
        if self.kind in ("threshold", "success") and self.value is None:
            raise MagexpError(f"claim {self.id!r}: kind {self.kind} needs a value")
        if self.kind in ("ordering", "winner") and len(self.cells) < 2:
            raise MagexpError(f"claim {self.id!r}: kind {self.kind} needs at least two cells")
        if self.by == "paper" and not str(self.section).strip():
            raise MagexpError(f"claim {self.id!r}: by: paper needs a section (where the paper says it)")
        if self.test == "fisher" and self.stat != "success_rate":
            raise MagexpError(f"claim {self.id!r}: test: fisher compares success counts: it needs stat: success_rate")
        self._check_effect()
        if self.test == "intervals":  # the old name: overlapping intervals are no test, a permutation test is
            object.__setattr__(self, "test", "unpaired")

    def _check_effect(self) -> None:
        """An ``effect:`` only on a comparison, with the keys of its statistic (:func:`effect_error`)."""
        if not self.effect:
            return
        why = effect_error(self.effect, self.stat) if self.kind in ("ordering", "winner") else "only a comparison has one"
        if why:
            raise MagexpError(f"claim {self.id!r}: effect={self.effect} is not allowed: {why}")


@dataclass
class Outcome:
    """A claim's outcome (``result``: :data:`HOLDS`, :data:`FAILS`, :data:`CONTRADICTED`,
    :data:`NO_DIFFERENCE` or :data:`UNDECIDED`) with its evidence: ``short`` (the numbers) and
    ``evidence`` (all of them). A comparison also has ``p`` (its claimed direction), ``p_contra``
    (the converse), ``p_min`` (the smallest its test can give), ``n`` (its smallest sample; of a
    threshold: the fewest runs of a selected cell),
    ``detectable`` (module docstring) and, once :func:`adjust` has seen its family, ``family`` (its name,
:mod:`magexp.artifacts.families`), ``family_size``, ``p_adjusted`` and ``level``: the raw-p level Holm's
rule judged it at, at which ``detectable`` (and ``detectable_words``) is then computed with its own test;
``observed``: the deciding pair's effect in the units of ``detectable`` (positive: the claimed direction)."""

    claim: Claim
    holds: bool
    evidence: str
    result: str = ""
    short: str = ""
    p: float = float("nan")
    p_contra: float = float("nan")
    p_min: float = float("nan")
    n: int = 0
    detectable: float = float("nan")
    p_adjusted: float = float("nan")
    test: str = ""
    family: str = ""
    family_size: int = 0
    level: float = float("nan")
    observed: float = float("nan")
    detect: object = None  # level -> (detectable, its words): the deciding pair's (Test.detect)
    detectable_words: str = ""

    def __post_init__(self):
        self.result = self.result or (HOLDS if self.holds else FAILS)
        self.short = self.short or self.evidence

    @property
    def is_comparison(self) -> bool:
        return bool(np.isfinite(self.p))


def cell_settings(table: pd.DataFrame) -> dict[int, dict]:
    """``{cell: {key: value}}`` of a runs table: its ``setting`` pairs, estimator and objective."""
    if "cell" not in table or not len(table):
        return {}
    cell = table["cell"].to_numpy()
    rows = np.flatnonzero(pd.notna(cell))
    cells, first = np.unique(cell[rows], return_index=True)  # each cell's first row: its setting is the cell's
    named = [k for k in ("estimator", "objective", "scenario", "case") if k in table]
    columns = {c: table[c].to_numpy()[rows[first]].tolist() for c in ["setting", *named] if c in table}
    records = [dict(zip(columns, values)) for values in zip(*columns.values())] if columns else [{}] * len(cells)
    out = {}
    for ci, first in zip(cells.tolist(), records):
        pairs = dict(p.split("=", 1) for p in str(first.get("setting", "") or "").split(";") if "=" in p)
        for key in named:
            if key not in pairs:
                pairs[key] = first[key]
        out[int(ci)] = pairs
    return out


def _restrict(table: pd.DataFrame, where: dict) -> tuple[pd.DataFrame, dict, dict]:
    """Apply the row filters of ``where``; return the rows, the rest of ``where`` (the cell settings
    to match) and the cells' settings (:func:`cell_settings`, the same for any of a cell's rows):
    ``seeds: n`` keeps the first ``n`` seeds (a conclusion at n and 2n seeds), ``succeeded: 1`` the
    successful runs (any runs column that is not a setting filters rows by its value)."""
    where = dict(where)
    if "seeds" in where:
        table = table[table.seed < int(where.pop("seeds"))]
    settings = cell_settings(table)
    keys = {k for s in settings.values() for k in s}
    for key in [k for k in where if k not in keys and k in table]:
        value = where.pop(key)
        table = table[[same(v, value) for v in table[key]]]
    return table, where, settings


def select(table: pd.DataFrame, where: dict) -> pd.DataFrame:
    """The runs of every cell whose settings include every ``key: value`` of ``where`` (after the
    row filters of :func:`_restrict`)."""
    table, where, settings = _restrict(table, where)
    keep = [ci for ci, s in settings.items() if matches(where, s)]
    return table[table.cell.isin(keep)]


def values(runs: pd.DataFrame, metric: str, stat: str) -> np.ndarray:
    """The per-seed values a statistic is taken over (``succeeded`` for ``success_rate``); a censored
    value (:mod:`magexp.artifacts.censoring`) is ``+inf``, never dropped."""
    if stat == "success_rate":
        column = runs["succeeded"] if "succeeded" in runs else pd.Series(dtype=float)
        return column.dropna().astype(float).to_numpy()
    frame = with_censored(runs)
    try:
        v = frame[metric] if metric in frame else frame.eval(metric)
    except Exception as exc:
        raise MagexpError(f"metric {metric!r} is not a column or an expression of the runs' columns: {exc}") from None
    v = np.asarray(v, float)
    return v[np.isfinite(v) | censored_mask(runs, metric)]


def _name(where: dict) -> str:
    return ", ".join(f"{k}={v}" for k, v in where.items()) or "all cells"


def _describe(where: dict, v: np.ndarray, stat: str) -> tuple[float, tuple, str]:
    """The statistic, its CI and a text; a CI over fewer than two values is not printed (n says it);
    a censored statistic is ``inf``, printed as censored, with no CI."""
    s = censored_statistic(v, stat)
    if np.isposinf(v).any():
        value = "censored" if np.isposinf(s) else f"{s:.4g}"
        return s, (np.nan, np.nan), f"{_name(where)}: {stat} {value} ({int(np.isposinf(v).sum())} of n={len(v)} censored)"
    lo, hi = interval(v, stat=stat)
    shown = f" [95 % CI {lo:.4g}, {hi:.4g}]" if np.isfinite(lo) and np.isfinite(hi) else ""
    return s, (lo, hi), f"{_name(where)}: {stat} {s:.4g}{shown} (n={len(v)})"


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
    va = pd.Series(_column(ta, metric), index=ta.seed)
    vb = pd.Series(_column(tb, metric), index=tb.seed).reindex(va.index)
    return va.to_numpy(float), vb.to_numpy(float)


def _column(runs: pd.DataFrame, metric: str) -> np.ndarray:
    """``metric`` per run (NaN kept: pairs stay aligned)."""
    try:
        return np.asarray(runs[metric] if metric in runs else runs.eval(metric), float)
    except Exception as exc:
        raise MagexpError(f"metric {metric!r} is not a column or an expression of the runs' columns: {exc}") from None


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
    the smallest attainable p is not below ``alpha``."""
    if not p_min < alpha:
        return UNDECIDED
    if p < alpha:
        return HOLDS
    return CONTRADICTED if p_contra < alpha else NO_DIFFERENCE


def compare(claim: Claim, table: pd.DataFrame, better: dict, worse: dict, stats: tuple, cis: tuple) -> Test:
    """The test of "the cells ``better`` beat the cells ``worse``" by the claim's ``test``."""
    test, pair = _test_of(claim, table, better, worse)
    if test == "fisher":
        return _fisher_test(claim, table, better, worse)
    if test == "paired":
        return _paired_test(claim, pair or _paired(table, better, worse, claim.metric))
    return _unpaired_test(claim, table, better, worse, cis)


def _test_of(claim: Claim, table: pd.DataFrame, better: dict, worse: dict) -> tuple[str, tuple | None]:
    """The test of a comparison and the paired values ``test: auto`` found: ``fisher`` for success
    rates, ``paired`` for two single cells with the same seeds and scenario, else ``unpaired``."""
    if claim.test != "auto":
        return claim.test, None
    if claim.stat == "success_rate":
        return "fisher", None
    pair = _paired(table, better, worse, claim.metric)
    return ("paired" if pair is not None else "unpaired"), pair


def _fisher_test(claim: Claim, table: pd.DataFrame, better: dict, worse: dict) -> Test:
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


def _paired_test(claim: Claim, pair: tuple | None) -> Test:
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


def _unpaired_test(claim: Claim, table: pd.DataFrame, better: dict, worse: dict, cis: tuple) -> Test:
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


def evaluate(claim: Claim, table: pd.DataFrame) -> Outcome:
    """Whether ``claim`` holds on a runs table, with its evidence (numbers from the table); a claim
    whose metric the table lacks does not hold, and says why."""
    try:
        return _evaluate(claim, table)
    except MagexpError as exc:
        return Outcome(claim, False, f"not evaluable: {exc}")


def _evaluate(claim: Claim, table: pd.DataFrame) -> Outcome:
    stat = "success_rate" if claim.kind == "success" else claim.stat
    if claim.kind in ("threshold", "success"):
        return _evaluate_threshold(claim, table, stat)
    return _evaluate_comparison(claim, table, stat)


def _evaluate_threshold(claim: Claim, table: pd.DataFrame, stat: str) -> Outcome:
    """``kind: threshold | success``: ``stat`` of every selected cell against ``op value``."""
    table, where, cells = _restrict(table, claim.where)
    present = set(table.cell.unique().tolist())  # cells with rows left after the row filters
    chosen = [ci for ci, s in cells.items() if matches(where, s) and ci in present]
    if not chosen:
        return Outcome(claim, False, f"no runs match {_name(claim.where)}")
    parts, stats, ok, n = [], [], True, []
    for ci in chosen:
        v = values(table[table.cell == ci], claim.metric, stat)
        s, _, text = _describe({k: cells[ci][k] for k in cells[ci] if k not in where} or where, v, stat)
        ok &= bool(np.isfinite(s) and OPS[claim.op](s, float(claim.value)))
        parts.append(text), stats.append(s), n.append(len(v))
    evidence = f"required {stat} {claim.op} {claim.value:g}; " + "; ".join(parts)
    got = (", ".join(_short_value(s) for s in stats) if len(stats) <= 8
           else f"from {_short_value(np.nanmin(stats))} to {_short_value(np.nanmax(stats))}")
    what = STAT_WORDS.get(stat, stat) + ("" if stat == "success_rate" else f" of {claim.metric}")
    cells = f"{len(chosen)} cells, {min(n)} seeds or more each" if len(chosen) > 1 else f"{min(n)} seeds"
    return Outcome(claim, ok, evidence, short=f"{what} {got} ({cells}); required {OP_WORDS[claim.op]} "
                   f"{claim.value:g}", n=min(n))


def _evaluate_comparison(claim: Claim, table: pd.DataFrame, stat: str) -> Outcome:
    """``kind: ordering | winner``: each cell against the next (ordering) or the first against every
    other (winner), by :func:`compare`; every pair must hold (its ``p``: the largest of the pairs'),
    a pair the other way contradicts it (the converse's p: the smallest, times the number of pairs)."""
    stats, cis, parts = [], [], []
    for where in claim.cells:
        v = values(select(table, where), claim.metric, stat)
        s, bounds, text = _describe(where, v, stat)
        stats.append(s), cis.append(bounds), parts.append(text)
    if any(not np.isfinite(s) for s in stats):
        return Outcome(claim, False, "; ".join(parts) + " (a selection has no runs)")
    pairs = (list(zip(range(len(stats)), range(1, len(stats)))) if claim.kind == "ordering"
             else [(0, j) for j in range(1, len(stats))])
    tests = [compare(claim, table, claim.cells[i], claim.cells[j], (stats[i], stats[j]), (cis[i], cis[j]))
             for i, j in pairs]
    combined = _combined(tests)
    result = decide(combined["p"], combined["p_contra"], combined["p_min"])
    head = f"{stat} of {claim.metric} ({claim.better} is better): "
    what = "" if stat == "success_rate" else f"{STAT_WORDS.get(stat, stat)} {claim.metric} "
    short = "; ".join(t.text if t.name == "fisher" else f"{what}{_short_value(stats[i])} vs {_short_value(stats[j])}, {t.text}"
                      for (i, j), t in zip(pairs, tests))
    return Outcome(claim, result == HOLDS, head + "; ".join(parts) + "; one-sided tests: " + "; ".join(t.text for t in tests),
                   result=result, short=short, **combined)


def _combined(tests: list[Test]) -> dict:
    """The :class:`Outcome` fields of a claim of several pairs: every pair must hold (``p``: the
    largest), one the other way contradicts it (``p_contra``: the smallest times the number of
    pairs), the largest ``p_min``, the smallest ``n``; the deciding pair's (the largest p) test,
    observed effect and ``detectable``, at :data:`ALPHA` until :func:`adjust` knows its level."""
    deciding = max(tests, key=lambda t: t.p_hold)
    detectable, words = deciding.detect(ALPHA)
    return {"p": deciding.p_hold, "p_contra": min(1.0, len(tests) * min(t.p_contra for t in tests)),
            "p_min": max(t.p_min for t in tests), "n": min(t.n for t in tests), "detectable": detectable,
            "detectable_words": words, "test": deciding.name, "observed": deciding.observed, "detect": deciding.detect}


def adjust(outcomes: list[Outcome], families: list[str] | None = None) -> list[Outcome]:
    """Holm's correction within each family of comparisons (``families``: each outcome's family,
    :func:`magexp.artifacts.families.claim_families`; default: one family of every comparison that is not a
    sanity check). A sanity check or an exploratory claim keeps its own p. Each comparison gets its
    ``family``, ``family_size``, ``p_adjusted`` and ``level`` (``alpha / (m - rank)``, its step of Holm's
    rule); its result is decided again on ``p_adjusted`` (:func:`decide`) and its evidence names the family.

    Parameters
    ----------
    outcomes : list of Outcome
        One paper's outcomes.
    families : list of str, optional
        The family of each outcome, in order.

    Returns
    -------
    list of Outcome
        ``outcomes``, changed in place.
    """
    for o, name in zip(outcomes, families or [""] * len(outcomes)):
        o.family = name or ("sanity" if o.claim.role == "sanity" else "primary")
    groups: dict[str, list[Outcome]] = {}
    for o in (o for o in outcomes if o.is_comparison):
        groups.setdefault(o.family, []).append(o)
    for name, family in groups.items():
        _adjust_family(family, alone=name in ALONE)
    return outcomes


def _adjust_family(family: list[Outcome], alone: bool) -> None:
    """Holm's rule over one family's comparisons (each at its own p when ``alone``), in place."""
    m = 1 if alone else len(family)
    p_adj = [o.p for o in family] if alone else holm([o.p for o in family])
    p_con = [o.p_contra for o in family] if alone else holm([o.p_contra for o in family])
    rank = {id(o): r for r, o in enumerate(sorted(family, key=lambda o: o.p))}
    for o, p, pc in zip(family, p_adj, p_con):
        o.family_size, o.p_adjusted, o.level = m, p, ALPHA / (1 if alone else m - rank[id(o)])
        if o.detect is not None:
            o.detectable, o.detectable_words = o.detect(o.level)
        o.result = decide(p, pc, o.p_min)
        o.holds = o.result == HOLDS
        note = _adjusted_note(o, m)
        o.short, o.evidence = f"{o.short}; {note}", f"{o.evidence}; {note}"


#: families whose comparisons are judged alone, each at its own p (never in a Holm family)
ALONE = ("sanity", "exploratory")


def _adjusted_note(o: Outcome, m: int) -> str:
    """What the evidence of a comparison adds once its family is known: the adjusted p, and what it
    could detect (no difference) or why it cannot decide."""
    note = f"{o.p_adjusted:.3g} after Holm over {m} {o.family} tests" if m > 1 else f"p = {o.p:.3g}"
    if o.result == UNDECIDED:
        return f"{note}; cannot be decided at n = {o.n}: its smallest p is {o.p_min:.3g}"
    if o.result == NO_DIFFERENCE and o.detectable_words:
        return (f"{note}; detectable at {POWER:.0%} power at its level {o.level:.3g}: {o.detectable_words} "
                f"(observed: {_short_value(o.observed)})")
    return note


def _short_value(v: float) -> str:
    return f"{v:.3g}"


#: what a note field prints when its cells exist but its row filter (``succeeded``, ``seeds``) leaves no
#: value (an exploration with few seeds); tests fail on it in the canonical results
NO_RUNS = "(no runs)"


def _setting_keys(table: pd.DataFrame) -> set:
    return {k for s in cell_settings(table).values() for k in s}


_FIELD = re.compile(r"\{(\w+):([^@{}]+)@([^:{}]*)(?::([^{}]+))?\}")


def interpolate(text: str, table: pd.DataFrame) -> str:
    """Replace every ``{stat:metric@key=value,...:format}`` of ``text`` by its value on ``table``."""
    settings = _setting_keys(table) if _FIELD.search(text) else set()  # the row filters are no setting

    def one(m: re.Match) -> str:
        stat, metric, where_text, fmt = m.group(1), m.group(2).strip(), m.group(3), m.group(4) or ".3g"
        if stat not in STATS:
            raise MagexpError(f"note field {m.group(0)!r}: stat {stat!r} is not allowed: choose one of {', '.join(STATS)}")
        where = dict(p.split("=", 1) for p in where_text.split(",") if "=" in p)
        if not len(select(table, {k: v for k, v in where.items() if k in settings or k not in table})):
            raise MagexpError(f"note field {m.group(0)!r}: its selection matches no cell of the runs: fix it")
        try:
            v = values(select(table, where), metric, stat)
        except MagexpError:
            raise MagexpError(f"note field {m.group(0)!r}: {metric!r} is not a column or an expression of the runs' columns") from None
        s = censored_statistic(v, stat)
        if np.isposinf(s) and censored_mask(select(table, where), metric).any():
            return censored_text(select(table, where), metric)  # never a median of the observed values alone
        return format(s, fmt) if np.isfinite(s) else NO_RUNS

    return _FIELD.sub(one, text)
