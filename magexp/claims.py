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
        by: paper                         # the paper's statement, evaluated (it may not hold)
        text: "F_g orders RDPSO < PSO < EKF"
        kind: ordering
        metric: fg
        cells: [{estimator: rdpso}, {estimator: pso}, {estimator: ekf}]   # best first
      - id: lm_wins
        text: "lm is the most accurate on mode 1"
        kind: winner                      # holds only where the CIs separate
        metric: offset_error / offset_bound
        stat: rms
        cells: [{estimator: lm}, {estimator: rdpso}, {estimator: ipso}]   # the winner first

``metric`` is a runs column or an expression of columns (``pandas.eval``); ``stat`` one of
:data:`STATS` over the seeds of the selected cells (pooled). Confidence intervals are 95 %
percentile bootstrap intervals over seeds (:func:`ci`, a fixed generator: the same on every
run). Claims with ``by: magexp`` are what the report states as true; ``tests/test_claims.py``
fails when one of them does not hold on the results.

Notes interpolate measured values with ``{stat:metric@key=value,key=value:format}``, e.g.
``{median:fun@estimator=ipso,scenario.noise=2:.3g}`` (:func:`interpolate`).
"""

from __future__ import annotations

import operator
import re
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from magexp.errors import MagexpError

#: a statistic over the seeds of a selection
STATS = {
    "median": lambda v, axis=None: np.median(v, axis=axis),
    "mean": lambda v, axis=None: np.mean(v, axis=axis),
    "max": lambda v, axis=None: np.max(v, axis=axis),
    "min": lambda v, axis=None: np.min(v, axis=axis),
    # RMS over seeds (of error / sqrt(tr CRB) it is 1 for an efficient estimator)
    "rms": lambda v, axis=None: np.sqrt(np.mean(np.square(v), axis=axis)),
    "lo": lambda v, axis=None: np.quantile(v, 0.025, axis=axis),
    "hi": lambda v, axis=None: np.quantile(v, 0.975, axis=axis),
    "q25": lambda v, axis=None: np.quantile(v, 0.25, axis=axis),
    "q75": lambda v, axis=None: np.quantile(v, 0.75, axis=axis),
    "n": lambda v, axis=None: np.shape(v)[-1] * np.ones(np.shape(v)[:-1]) if axis is not None else len(v),
    "success_rate": lambda v, axis=None: np.mean(v, axis=axis),  # of the 0/1 column ``succeeded``
}
OPS = {"<=": operator.le, "<": operator.lt, ">=": operator.ge, ">": operator.gt}
KINDS = ("threshold", "success", "ordering", "winner")
N_BOOT = 2000


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
    value: float | None = None
    cells: list = field(default_factory=list)
    better: str = "lower"
    # the issue-18 schema (ISSUE18_INTERFACE.md), read here and implemented by the claims engine
    section: str = ""
    role: str = "finding"
    figure: str = ""
    test: str = "auto"

    def __post_init__(self):
        checks = [("kind", self.kind, KINDS), ("by", self.by, ("magexp", "paper")), ("stat", self.stat, tuple(STATS)),
                  ("role", self.role, ("finding", "sanity")), ("test", self.test, ("auto", "fisher", "paired", "intervals")),
                  ("op", self.op, tuple(OPS)), ("better", self.better, ("lower", "higher"))]
        for key, value, allowed in checks:
            if value not in allowed:
                raise MagexpError(f"claim {self.id!r}: {key}={value!r} is not allowed: choose one of {', '.join(allowed)}")
        if self.kind in ("threshold", "success") and self.value is None:
            raise MagexpError(f"claim {self.id!r}: kind {self.kind} needs a value")
        if self.kind in ("ordering", "winner") and len(self.cells) < 2:
            raise MagexpError(f"claim {self.id!r}: kind {self.kind} needs at least two cells")


@dataclass
class Outcome:
    claim: Claim
    holds: bool
    evidence: str


def same(a, b) -> bool:
    """Two setting values are equal as numbers where both are numbers (``2`` and ``2.0``), else as text."""
    try:
        return float(a) == float(b)
    except (TypeError, ValueError):
        return str(a) == str(b)


def matches(selection: dict, settings: dict) -> bool:
    """True if every ``key: value`` of ``selection`` is among ``settings``."""
    return all(k in settings and same(settings[k], v) for k, v in selection.items())


def cell_settings(table: pd.DataFrame) -> dict[int, dict]:
    """``{cell: {key: value}}`` of a runs table: its ``setting`` pairs, estimator and objective."""
    if "cell" not in table or not len(table):
        return {}
    firsts = table.drop_duplicates("cell")  # each cell's first row: its setting is the cell's
    firsts = firsts[firsts.cell.notna()].sort_values("cell", kind="stable")
    named = [k for k in ("estimator", "objective", "scenario", "case") if k in table]
    records = firsts[[c for c in ["setting", *named] if c in table]].to_dict("records")
    out = {}
    for ci, first in zip(firsts.cell.tolist(), records):
        pairs = dict(p.split("=", 1) for p in str(first.get("setting", "") or "").split(";") if "=" in p)
        for key in named:
            if key not in pairs:
                pairs[key] = first[key]
        out[int(ci)] = pairs
    return out


def _restrict(table: pd.DataFrame, where: dict) -> tuple[pd.DataFrame, dict]:
    """Apply the row filters of ``where`` and return the rest (the cell settings to match):
    ``seeds: n`` keeps the first ``n`` seeds (a conclusion at n and 2n seeds), ``succeeded: 1`` the
    successful runs (any runs column that is not a setting filters rows by its value)."""
    where = dict(where)
    if "seeds" in where:
        table = table[table.seed < int(where.pop("seeds"))]
    keys = {k for s in cell_settings(table).values() for k in s}
    for key in [k for k in where if k not in keys and k in table]:
        value = where.pop(key)
        table = table[[same(v, value) for v in table[key]]]
    return table, where


def select(table: pd.DataFrame, where: dict) -> pd.DataFrame:
    """The runs of every cell whose settings include every ``key: value`` of ``where`` (after the
    row filters of :func:`_restrict`)."""
    table, where = _restrict(table, where)
    settings = cell_settings(table)
    keep = [ci for ci, s in settings.items() if matches(where, s)]
    return table[table.cell.isin(keep)]


def values(runs: pd.DataFrame, metric: str, stat: str) -> np.ndarray:
    """The per-seed values a statistic is taken over (``succeeded`` for ``success_rate``)."""
    if stat == "success_rate":
        column = runs["succeeded"] if "succeeded" in runs else pd.Series(dtype=float)
        return column.dropna().astype(float).to_numpy()
    try:
        v = runs[metric] if metric in runs else runs.eval(metric)
    except Exception as exc:
        raise MagexpError(f"metric {metric!r} is not a column or an expression of the runs' columns: {exc}") from None
    v = np.asarray(v, float)
    return v[np.isfinite(v)]


def statistic(v: np.ndarray, stat: str) -> float:
    return float(STATS[stat](v)) if len(v) else float("nan")


def ci(v: np.ndarray, stat: str, level: float = 0.95) -> tuple[float, float]:
    """Percentile bootstrap interval of ``stat`` over the seeds ``v`` (fixed generator)."""
    if len(v) < 2:
        return (float("nan"), float("nan"))
    rng = np.random.default_rng(0)
    idx = rng.integers(0, len(v), size=(N_BOOT, len(v)))
    boot = np.asarray(STATS[stat](v[idx], axis=1), float)
    a = (1 - level) / 2
    return float(np.quantile(boot, a)), float(np.quantile(boot, 1 - a))


def _name(where: dict) -> str:
    return ", ".join(f"{k}={v}" for k, v in where.items()) or "all cells"


def _describe(where: dict, v: np.ndarray, stat: str) -> tuple[float, tuple, str]:
    s, (lo, hi) = statistic(v, stat), ci(v, stat)
    return s, (lo, hi), f"{_name(where)}: {stat} {s:.4g} [95 % CI {lo:.4g}, {hi:.4g}] (n={len(v)})"


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
        table, where = _restrict(table, claim.where)
        cells = cell_settings(table)
        chosen = [ci for ci, s in cells.items() if matches(where, s)]
        if not chosen:
            return Outcome(claim, False, f"no runs match {_name(claim.where)}")
        parts, ok = [], True
        for ci in chosen:
            v = values(table[table.cell == ci], claim.metric, stat)
            s, _, text = _describe({k: cells[ci][k] for k in cells[ci] if k not in where} or where, v, stat)
            ok &= bool(np.isfinite(s) and OPS[claim.op](s, float(claim.value)))
            parts.append(text)
        return Outcome(claim, ok, f"required {stat} {claim.op} {claim.value:g}; " + "; ".join(parts))
    stats, cis, parts = [], [], []
    for where in claim.cells:
        v = values(select(table, where), claim.metric, stat)
        s, interval, text = _describe(where, v, stat)
        stats.append(s), cis.append(interval), parts.append(text)
    sign = 1 if claim.better == "lower" else -1
    if any(not np.isfinite(s) for s in stats):
        return Outcome(claim, False, "; ".join(parts) + " (a selection has no runs)")
    if claim.kind == "ordering":
        ok = all(sign * a < sign * b for a, b in zip(stats, stats[1:]))
        return Outcome(claim, ok, f"{'ascending' if sign > 0 else 'descending'} {stat} of {claim.metric}: " + "; ".join(parts))
    (wlo, whi), others = cis[0], cis[1:]
    ok = all((whi < lo) if sign > 0 else (wlo > hi) for lo, hi in others)
    return Outcome(claim, ok, f"winner only where the 95 % CIs separate; {stat} of {claim.metric}: " + "; ".join(parts))


_FIELD = re.compile(r"\{(\w+):([^@{}]+)@([^:{}]*)(?::([^{}]+))?\}")


def interpolate(text: str, table: pd.DataFrame) -> str:
    """Replace every ``{stat:metric@key=value,...:format}`` of ``text`` by its value on ``table``."""

    def one(m: re.Match) -> str:
        stat, metric, where_text, fmt = m.group(1), m.group(2).strip(), m.group(3), m.group(4) or ".3g"
        if stat not in STATS:
            raise MagexpError(f"note field {m.group(0)!r}: stat {stat!r} is not allowed: choose one of {', '.join(STATS)}")
        where = dict(p.split("=", 1) for p in where_text.split(",") if "=" in p)
        try:
            v = values(select(table, where), metric, stat)
        except MagexpError:
            return f"[no column {metric!r} in the runs]"
        s = statistic(v, stat)
        return format(s, fmt) if np.isfinite(s) else "n/a"

    return _FIELD.sub(one, text)
