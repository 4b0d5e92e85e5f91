"""Claims: every qualitative statement of the report as a condition on an artifact's runs.

A claim sits in the artifact YAML next to the runs it is about::

    claims:
      - id: ipso_converges
        text: "IPSO reaches the optimum the truth gives on at least 90 % of seeds at every noise level"
        kind: success                     # threshold | success | ordering | winner | trend
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

``metric`` is a runs column or an expression of columns (``pandas.eval``; a dotted config key written as it
is, :func:`~magexp.artifacts.selection.expression`), checked before any run (:mod:`magexp.artifacts.spec_check`); ``stat`` one of
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

A **trend** (``kind: trend``: the slope of ``metric``, or of its log against the log of ``axis``, over every
cell of a grid ``axis``, judged against ``between: [lo, hi]`` or ``sign``) is decided by a one-sided bootstrap
test over seeds, Holm-adjusted in its family beside the comparisons: :mod:`magexp.artifacts.trends` states the
statistic, the test and the rule.

Each comparison is decided by :mod:`magexp.artifacts.comparisons` (its ``p``, ``p_min``,
``detectable`` and Holm's adjustment within its family).

Notes interpolate measured values with ``{stat:metric@key=value,key=value:format}``, e.g.
``{median:fun@estimator=ipso,scenario.noise=2:.3g}`` (:func:`interpolate`); a field whose
selection matches no cell fails the build with one line naming it; one whose cells exist but whose
row filter (``succeeded=0``, ``seeds=10``) leaves no value prints :data:`NO_RUNS`, never ``n/a``.
"""

from __future__ import annotations

import operator
import re
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from magexp.artifacts.censoring import censored_mask, censored_statistic, censored_text
from magexp.artifacts.comparisons import HOLDS, NO_DIFFERENCE, UNDECIDED, combined, compare, decide
from magexp.artifacts.schema import Bool, Float, typed
from magexp.artifacts.selection import cell_settings, restrict, select, values
from magexp.artifacts.significance import effect_error
from magexp.artifacts.tables import STATS, interval, matches
from magexp.artifacts import trends
from magexp.errors import MagexpError

OPS = {"<=": operator.le, "<": operator.lt, ">=": operator.ge, ">": operator.gt}
#: the words of an operator and of a statistic in a claim's short evidence
OP_WORDS = {"<=": "at most", "<": "below", ">=": "at least", ">": "above"}
STAT_WORDS = {"success_rate": "success rate", "max": "largest", "min": "smallest"}
KINDS = ("threshold", "success", "ordering", "winner", "trend")
#: ``finding``: counted; ``sanity``: true by construction, a check of the code; ``exploratory``: a setting
#: chosen because its runs resemble the paper's numbers, shown but never counted nor tested in a family
ROLES = ("finding", "sanity", "exploratory")
TESTS = ("auto", "fisher", "paired", "unpaired", "intervals")
#: the outcome of a threshold or a success rate that does not hold (a comparison's verdicts, :data:`HOLDS`
#: the only one that counts as holding: :mod:`magexp.artifacts.comparisons`)
FAILS = "does not hold"


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
    axis: str = ""  # a trend's grid key (magexp.artifacts.trends), with log, between or sign
    log: Bool = False
    between: list[Float] = field(default_factory=list)
    sign: str = ""

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
        """An ``effect:`` only on a comparison, with the keys of its statistic (:func:`effect_error`), or on a
        trend (:func:`magexp.artifacts.trends.effect_error`)."""
        if not self.effect:
            return
        why = (effect_error(self.effect, self.stat) if self.kind in ("ordering", "winner")
               else trends.effect_error(self) if self.kind == "trend" else "only a comparison or a trend has one")
        if why:
            raise MagexpError(f"claim {self.id!r}: effect={self.effect} is not allowed: {why}")


@dataclass
class Outcome:
    """A claim's outcome (``result``: :data:`HOLDS`, :data:`FAILS`, or a comparison's other verdicts of
    :mod:`magexp.artifacts.comparisons`) with its evidence: ``short`` (the numbers) and
    ``evidence`` (all of them). A comparison also has ``p`` (its claimed direction), ``p_contra``
    (the converse), ``p_min`` (the smallest its test can give), ``n`` (its smallest sample; of a
    threshold: the fewest runs of a selected cell),
    ``detectable`` (module docstring) and, once :func:`~magexp.artifacts.comparisons.adjust` has seen its family, ``family`` (its name,
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
    detect: object = None  # level -> (detectable, its words): the deciding pair's (comparisons.Test.detect)
    detectable_words: str = ""
    rule: object = None  # (p, p_contra, p_min) -> verdict: a trend's (trends.decide); None: a comparison's

    def __post_init__(self):
        self.result = self.result or (HOLDS if self.holds else FAILS)
        self.short = self.short or self.evidence

    @property
    def undetected(self) -> bool:
        """Whether its test decided nothing though it could: no difference detected, or a trend that cannot be
        decided at its level (then ``detectable`` says what it could have seen)."""
        return self.result == NO_DIFFERENCE or self.result == UNDECIDED and self.p_min < self.level

    @property
    def is_comparison(self) -> bool:
        """Whether the outcome is a comparison's (it has a p-value)."""
        return bool(np.isfinite(self.p))


def _name(where: dict) -> str:
    """The cells ``where`` selects, as evidence text names them ("all cells" for none)."""
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


class NotEvaluable(RuntimeError):
    """A claim that cannot be evaluated on its runs: a bug, never a verdict (the spec check before any run,
    :mod:`magexp.artifacts.spec_check`, refuses every claim it can tell cannot be evaluated)."""


def evaluate(claim: Claim, table: pd.DataFrame) -> Outcome:
    """Whether ``claim`` holds on a runs table, with its evidence (numbers from the table). A claim that
    cannot be evaluated (a metric the table lacks, a selection of no cell) raises :class:`NotEvaluable`:
    "not evaluable" is never a verdict."""
    try:
        return _evaluate(claim, table)
    except MagexpError as exc:
        raise NotEvaluable(f"claim {claim.id!r} cannot be evaluated on its runs ({str(exc).splitlines()[0]}): a bug, "
                           "the spec check before the run (magexp.artifacts.spec_check) should have refused it") from None


def _evaluate(claim: Claim, table: pd.DataFrame) -> Outcome:
    """The outcome of ``claim`` on ``table``: a threshold (or success rate) test, else a comparison."""
    stat = "success_rate" if claim.kind == "success" else claim.stat
    if claim.kind in ("threshold", "success"):
        return _evaluate_threshold(claim, table, stat)
    if claim.kind == "trend":
        return _evaluate_trend(claim, table)
    return _evaluate_comparison(claim, table, stat)


def _threshold_cells(claim: Claim, table: pd.DataFrame) -> tuple[pd.DataFrame, dict, dict, list]:
    """The rows after ``where``'s row filters, its settings, the cells' settings and the selected cells with
    rows left; a ``where`` that selects no cell at all raises (a spec mistake, never a verdict)."""
    table, where, cells = restrict(table, claim.where)
    present = set(table.cell.unique().tolist())  # cells with rows left after the row filters
    selected = [ci for ci, s in cells.items() if matches(where, s)]
    if not selected:
        raise MagexpError(f"where={claim.where} selects no cell")
    return table, where, cells, [ci for ci in selected if ci in present]


def _evaluate_threshold(claim: Claim, table: pd.DataFrame, stat: str) -> Outcome:
    """``kind: threshold | success``: ``stat`` of every selected cell against ``op value``."""
    table, where, cells, chosen = _threshold_cells(claim, table)
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
        _, rest, settings = restrict(table, where)
        if not any(matches(rest, s) for s in settings.values()):
            raise MagexpError(f"cells entry {where} selects no cell")
        v = values(select(table, where), claim.metric, stat)
        s, bounds, text = _describe(where, v, stat)
        stats.append(s), cis.append(bounds), parts.append(text)
    if any(not np.isfinite(s) for s in stats):
        return Outcome(claim, False, "; ".join(parts) + " (a selection has no runs)")
    pairs = (list(zip(range(len(stats)), range(1, len(stats)))) if claim.kind == "ordering"
             else [(0, j) for j in range(1, len(stats))])
    tests = [compare(claim, table, claim.cells[i], claim.cells[j], (stats[i], stats[j]), (cis[i], cis[j]))
             for i, j in pairs]
    joined = combined(tests)
    result = decide(joined["p"], joined["p_contra"], joined["p_min"])
    head = f"{stat} of {claim.metric} ({claim.better} is better): "
    what = "" if stat == "success_rate" else f"{STAT_WORDS.get(stat, stat)} {claim.metric} "
    short = "; ".join(t.text if t.name == "fisher" else f"{what}{_short_value(stats[i])} vs {_short_value(stats[j])}, {t.text}"
                      for (i, j), t in zip(pairs, tests))
    return Outcome(claim, result == HOLDS, head + "; ".join(parts) + "; one-sided tests: " + "; ".join(t.text for t in tests),
                   result=result, short=short, **joined)


def _evaluate_trend(claim: Claim, table: pd.DataFrame) -> Outcome:
    """``kind: trend``: the slope's one-sided bootstrap test against the claim's range
    (:mod:`magexp.artifacts.trends`), decided alone until its family is known; ``observed`` is the slope, ``n``
    the fewest seeds at an axis value."""
    t = trends.tested(claim, table)
    return Outcome(claim, t.result == HOLDS, t.evidence, result=t.result, short=t.short, p=t.p, p_contra=t.p_contra,
                   p_min=t.p_min, n=int(t.fit.n.min()), observed=t.fit.slope, test="bootstrap", detect=t.detect,
                   rule=trends.decide)


def _short_value(v: float) -> str:
    """``v`` to three significant digits, as evidence text prints a value."""
    return f"{v:.3g}"


#: what a note field prints when its cells exist but its row filter (``succeeded``, ``seeds``) leaves no
#: value (an exploration with few seeds); tests fail on it in the canonical results
NO_RUNS = "(no runs)"


def _setting_keys(table: pd.DataFrame) -> set:
    """Every setting name of the table's cells: the keys a claim's ``where`` may use."""
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
