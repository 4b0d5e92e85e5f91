"""Trend claims: how a metric changes along a grid axis, as a least-squares slope with a bootstrap interval.

A trend claim sits in ``claims:`` beside the other kinds (:mod:`magexp.artifacts.claims`)::

    - id: offset_falls
      text: "the offset error falls as 1/sqrt(N)"
      kind: trend
      metric: offset_error
      axis: scenario.n_readings        # a key of the artifact's grid, numeric values
      where: {estimator: ellipsoid}    # the cells along the axis (cells sharing an axis value are pooled)
      log: true                        # the slope of log metric against log axis: an exponent
      between: [-0.6, -0.4]            # or sign: negative (positive)
      stat: median                     # per axis value, over its seeds (default)

**The statistic.** At each axis value ``x_j`` (the cells ``where`` selects with that value, their seeds
pooled) ``y_j`` is ``stat`` of the metric over its seeds (of ``log metric`` with ``log: true``, where ``x_j``
is ``log x_j`` too); the slope is the ordinary least-squares slope through the points, every axis value
weighing alike::

    b = sum_j (x_j - mean x) (y_j - mean y) / sum_j (x_j - mean x)^2

All cells of the axis enter, never its two ends alone. Why the per-value statistic rather than every run:
with ``stat: median`` a failed run's outlier moves no point, the median of ``log metric`` is the log of the
median (the exponent is that of the medians the figure draws), and the slope does not depend on how many
seeds each value has. The other reading, least squares over every run, is one spec value away: with the
same seeds at every value, ``stat: mean`` gives exactly it (the per-value means carry the all-runs fit).

**Its interval** (:func:`fit`): a percentile bootstrap over seeds, :data:`N_BOOT` resamples, each drawing
every axis value's seeds with replacement (as many as it has) and fitting again; the 2.5 and 97.5 %
quantiles of the slopes. The draws come from ``numpy.random.default_rng(TREND_SEED)``, axis values in
ascending order: the same interval on every run, to the bit.

**The test** (:func:`p_values`): the claim's one-sided bootstrap p, the share of the ``B = N_BOOT`` bootstrap
slopes ``s*`` on the wrong side, ``(1 + #{s* >= 0}) / (B + 1)`` for ``sign: negative`` (``<= 0`` for
``positive``) and, for ``between: [lo, hi]``, the larger of the two one-sided p (an intersection-union test:
the slope is above ``lo`` and below ``hi``), ``max((1 + #{s* <= lo}), (1 + #{s* >= hi})) / (B + 1)``. Its
converse (the slope lies on the other side, or outside the range) has ``p_contra``: ``(1 + #{s* <= 0}) /
(B + 1)`` for a sign, and for a range twice the smaller of ``(1 + #{s* >= lo}) / (B + 1)`` (below ``lo``) and
``(1 + #{s* <= hi}) / (B + 1)`` (above ``hi``), one test per side. The smallest p is ``1 / (B + 1)``.

**The verdict** (:func:`decide`): a trend is tested in its paper's Holm family beside the comparisons
(:mod:`magexp.artifacts.families`, :func:`magexp.artifacts.comparisons.adjust`): it ``holds`` when its
Holm-adjusted p is below :data:`~magexp.artifacts.significance.ALPHA`, ``does not hold`` when its converse's
is, and ``cannot be decided`` otherwise. Alone (``m = 1``) it holds when at least 95 % of the bootstrap
slopes lie inside the range (on the side of the sign): the one-sided 95 % bound, or the 90 % interval inside
``[lo, hi]``; the evidence prints the 95 % interval as a description. An axis value with fewer than
:data:`MIN_SEEDS` seeds gives no p and makes the claim ``cannot be decided``: the whole range of ``n`` seeds
covers their median with probability ``1 - 2^(1-n)`` (0.5 at 2 seeds, 0.94 at 5), so below 5 no resampling of
a value's seeds gives a 95 % interval. What could have been seen (:func:`detect`): the distance beyond a
boundary at which a true slope is caught with 80 % power at the level Holm's rule judged it at,
``(z(1 - level) + z(0.8)) se``, ``se`` the standard deviation of the bootstrap slopes.

**Seeds** (:mod:`magexp.artifacts.power`): a trend that declares the slope it expects, ``effect: {slope: s,
spread: sd}`` (``s`` inside the range or on the side of the sign; ``sd`` the standard deviation of a seed's
value, of its log with ``log: true``, around the line), gets the seeds at which this test detects it with 80
% power at its family's strictest Holm level, found by simulation before any run (:func:`magexp.artifacts.power.trend_power`); without
one its cells get the artifact's ``seeds`` and its evidence says what they resolve.

**On the figure** (:func:`band`): the fitted line and the pointwise 2.5-97.5 % band of the bootstrap lines,
drawn by the kinds that plot a metric against a grid axis (``final``, ``sweep``) for the trends whose
``metric`` is a panel's and whose ``axis`` is ``plot.x``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.special import ndtri

from magexp.artifacts.comparisons import HOLDS, UNDECIDED
from magexp.artifacts.selection import restrict, values
from magexp.artifacts.significance import ALPHA, POWER
from magexp.artifacts.tables import STATS, matches
from magexp.errors import MagexpError

#: bootstrap resamples of a trend's interval
N_BOOT = 2000
#: the generator seed of the bootstrap (fixed: the same interval on every run)
TREND_SEED = 20260444
#: the fewest seeds per axis value at which a trend can be decided (module docstring)
MIN_SEEDS = 5
SIGNS = ("negative", "positive")
#: the statistics a trend's points may be (``n`` is no measurement of the metric)
TREND_STATS = tuple(s for s in STATS if s != "n")
#: the verdict of a trend whose interval lies outside its range (:data:`magexp.artifacts.claims.FAILS`, which
#: imports this module)
FAILS = "does not hold"
#: x positions of the drawn line (geometric on a log fit)
BAND_POINTS = 25


@dataclass(frozen=True)
class Fit:
    """A trend's fit: the axis values ``x`` and points ``y`` (logs with ``log``), the seeds ``n`` at each,
    the ``slope`` and ``intercept``, the bootstrap ``boot`` ``(N_BOOT, 2)`` of both, and ``why`` no
    interval is given ('' when one is)."""

    x: np.ndarray
    y: np.ndarray
    n: np.ndarray
    slope: float
    intercept: float
    boot: np.ndarray
    why: str = ""

    @property
    def ci(self) -> tuple[float, float]:
        """The 95 % percentile interval of the slope (NaN when there is none)."""
        if self.why:
            return float("nan"), float("nan")
        lo, hi = np.quantile(self.boot[:, 0], [0.025, 0.975])
        return float(lo), float(hi)


def spec_error(claim, grid: dict) -> str:
    """Why ``claim``'s trend keys are not allowed against the artifact's ``grid`` ('' when they are): a
    trend needs an ``axis`` among the grid's keys with two numeric values or more (positive with ``log``)
    and exactly one of ``between: [lo, hi]`` (``lo < hi``) or ``sign``; another kind has none of them.
    """
    if claim.kind != "trend":
        given = [k for k in ("axis", "between", "sign") if getattr(claim, k)] + (["log"] if claim.log else [])
        return f"{given[0]}={getattr(claim, given[0])!r} is not allowed: only a trend claim has one" if given else ""
    if claim.axis not in grid:
        return f"axis={claim.axis!r} is not allowed: choose a key of the grid ({', '.join(grid) or 'none'})"
    try:
        xs = sorted({float(v) for v in grid[claim.axis]})
    except (TypeError, ValueError):
        return f"axis={claim.axis!r} is not allowed: its grid values {grid[claim.axis]} are not all numbers"
    if len(xs) < 2 or claim.log and xs[0] <= 0:
        return (f"axis={claim.axis!r} is not allowed: a slope needs two values or more"
                + (", all positive with log: true" if claim.log else "") + f" (the grid has {grid[claim.axis]})")
    return _range_error(claim)


def _range_error(claim) -> str:
    """Why a trend's ``between``/``sign``/``stat`` are not allowed ('' when they are)."""
    if bool(claim.between) == bool(claim.sign):
        return "give exactly one of between: [lo, hi] or sign: negative|positive"
    if claim.sign and claim.sign not in SIGNS:
        return f"sign={claim.sign!r} is not allowed: choose one of {', '.join(SIGNS)}"
    if claim.between and not (len(claim.between) == 2 and claim.between[0] < claim.between[1]):
        return f"between={list(claim.between)} is not allowed: give [lo, hi] with lo < hi"
    if claim.stat not in TREND_STATS:
        return f"stat={claim.stat!r} is not allowed for a trend: choose one of {', '.join(TREND_STATS)}"
    return ""


def effect_error(claim) -> str:
    """Why a trend's ``effect:`` is not allowed ('' when it is, or when it has none): ``{slope, spread}``,
    numbers, ``spread > 0`` and ``slope`` strictly inside ``between`` (on the side of ``sign``): the slope the
    seeds are planned to show holds the claim."""
    e = claim.effect
    if not e:
        return ""
    if set(e) != {"slope", "spread"} or not all(isinstance(v, (int, float)) for v in e.values()):
        return "give exactly {slope: number, spread: number} for a trend"
    if not e["spread"] > 0:
        return "spread > 0 (the standard deviation of a seed's value around the line)"
    lo, hi = claim.between or ((-np.inf, 0.0) if claim.sign == "negative" else (0.0, np.inf))
    if not lo < e["slope"] < hi:
        return f"its slope {e['slope']:g} must lie {required(claim)} (strictly): a slope outside plans no power to hold"
    return ""


def effect_words(effect: dict) -> str:
    """A trend's ``effect:`` in words: "a slope of -0.5 (spread 0.3 per seed around the line)"."""
    return f"a slope of {effect['slope']:g} (spread {effect['spread']:g} per seed around the line)"


def axis_values(claim, grid: dict) -> tuple[float, ...]:
    """The axis values a trend's points will sit at, as its fit takes them (logs with ``log``), ascending:
    the grid's values of its ``axis`` (what the seeds are planned for before any run)."""
    xs = sorted({float(v) for v in grid[claim.axis]})
    return tuple(float(v) for v in (np.log(xs) if claim.log else xs))


def points(claim, table: pd.DataFrame) -> tuple[np.ndarray, list[np.ndarray]]:
    """The axis values (ascending) of the cells ``claim.where`` selects and each one's per-seed values of
    the metric (the cells sharing a value pooled, in the order of cell and seed: the bootstrap draws the same
    runs whatever the table's row order)."""
    table, where, settings = restrict(table.sort_values(["cell", "seed"], kind="stable"), claim.where)
    groups: dict[float, list] = {}
    for ci, s in settings.items():
        if matches(where, s) and claim.axis in s:
            groups.setdefault(float(s[claim.axis]), []).append(ci)
    if not groups:
        raise MagexpError(f"claim {claim.id!r}: no cell of the runs has {claim.axis} and matches {claim.where}")
    xs = np.array(sorted(groups))
    return xs, [values(table[table.cell.isin(groups[x])], claim.metric, claim.stat) for x in xs]


def _least_squares(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Slope and intercept of the least-squares line through ``(x, y)`` for each row of ``y``."""
    xc = x - x.mean()
    slope = (y - y.mean(axis=-1, keepdims=True)) @ xc / (xc @ xc)
    return slope, y.mean(axis=-1) - slope * x.mean()


def fit(claim, table: pd.DataFrame) -> Fit:
    """The trend of ``claim`` on a runs table: points, least-squares slope and its bootstrap over seeds
    (module docstring); ``why`` says when no interval can be given (too few seeds, a value not positive
    under ``log``, a censored point)."""
    xs, groups = points(claim, table)
    n = np.array([len(g) for g in groups])
    f = STATS[claim.stat]
    if claim.log:
        xs = np.log(xs)
        bad = sum(int((g <= 0).sum()) for g in groups)
        groups = [np.log(np.where(g > 0, g, np.nan)) for g in groups]
    y = np.array([float(f(g)) if len(g) else np.nan for g in groups])
    slope, intercept = _least_squares(xs, y) if len(xs) > 1 else (np.nan, np.nan)
    why = _no_interval(claim, xs, n, y, bad if claim.log else 0)
    if why:
        return Fit(xs, y, n, float(slope), float(intercept), np.empty((0, 2)), why)
    rng = np.random.default_rng(TREND_SEED)
    boot = np.column_stack([f(g[rng.integers(0, len(g), size=(N_BOOT, len(g)))], axis=1) for g in groups])
    b_slope, b_intercept = _least_squares(xs, boot)
    return Fit(xs, y, n, float(slope), float(intercept), np.column_stack([b_slope, b_intercept]))


def _no_interval(claim, xs: np.ndarray, n: np.ndarray, y: np.ndarray, non_positive: int) -> str:
    """Why a trend has no interval ('' when it has one): the reason a reader is given."""
    if len(xs) < 2:
        return f"one value of {claim.axis} only: a slope needs two"
    if n.min() < MIN_SEEDS:
        return (f"{int(n.min())} seeds at a value of {claim.axis}: below {MIN_SEEDS} no resampling of its seeds "
                "gives a 95 % interval")
    if non_positive:
        return f"{non_positive} values of {claim.metric} are not positive: log: true needs positive values"
    if not np.isfinite(y).all():
        return f"a point of {claim.metric} is censored or missing: no slope through it"
    return ""


def p_values(between, sign: str, slopes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The one-sided bootstrap p of a trend claiming its slope lies in ``between`` (else on the side of
    ``sign``) and of its converse, from bootstrap slopes along the last axis of ``slopes`` (module docstring:
    the test); vectorised over leading axes (the power simulations' data sets).
    """
    share = lambda wrong: (1 + np.sum(wrong, axis=-1)) / (slopes.shape[-1] + 1)
    if len(between):
        lo, hi = between
        return (np.maximum(share(slopes <= lo), share(slopes >= hi)),
                np.minimum(1.0, 2 * np.minimum(share(slopes >= lo), share(slopes <= hi))))
    below, above = share(slopes >= 0), share(slopes <= 0)
    return (below, above) if sign == "negative" else (above, below)


def decide(p: float, p_contra: float, p_min: float, alpha: float = ALPHA) -> str:
    """The verdict of a trend from its (Holm-adjusted) p-values (module docstring): :data:`UNDECIDED` when
    even its smallest p is not below ``alpha`` or neither p is."""
    if not p_min < alpha:
        return UNDECIDED
    if p < alpha:
        return HOLDS
    return FAILS if p_contra < alpha else UNDECIDED


def detect(claim, se: float, level: float) -> tuple[float, str]:
    """How far beyond a boundary a true slope must lie for the test at ``level`` to see it with
    :data:`~magexp.artifacts.significance.POWER`, ``(z(1 - level) + z(POWER)) se``, and that in words."""
    d = (float(ndtri(1 - level)) + float(ndtri(POWER))) * se
    if not claim.between:
        return d, f"a slope {d:.3g} beyond 0"
    span = claim.between[1] - claim.between[0]
    if 2 * d > span:
        return d, f"no slope: the range ({span:.3g} wide) is narrower than twice {d:.3g}, the distance from each end"
    return d, f"a slope {d:.3g} inside each end of the range"


def required(claim) -> str:
    """The claim's range in words: "between -0.6 and -0.4" or "below 0" / "above 0"."""
    if claim.between:
        return f"between {claim.between[0]:g} and {claim.between[1]:g}"
    return "below 0" if claim.sign == "negative" else "above 0"


@dataclass(frozen=True)
class TrendTest:
    """A trend's test on its runs: its ``claim`` and :class:`Fit`, the one-sided bootstrap ``p`` and ``p_contra``, the
    smallest ``p_min`` (NaN without an interval), the verdict alone (at ``ALPHA``) and the texts."""

    claim: object
    fit: Fit
    p: float
    p_contra: float
    p_min: float
    result: str
    short: str
    evidence: str

    def detect(self, level: float) -> tuple[float, str]:
        """What the test at ``level`` sees with 80 % power (:func:`detect`)."""
        return detect(self.claim, float(np.std(self.fit.boot[:, 0])), level)


def tested(claim, table: pd.DataFrame) -> TrendTest:
    """The test of ``claim`` on a runs table (module docstring): its fit, p-values, verdict alone and the
    slope, its interval, the range and the points in words (why it cannot be decided where it has no p)."""
    f = fit(claim, table)
    lo, hi = f.ci
    p, pc = p_values(claim.between, claim.sign, f.boot[:, 0]) if not f.why else (np.nan, np.nan)
    p_min = 1 / (N_BOOT + 1) if not f.why else np.nan
    of = f"log {claim.stat} of {claim.metric} against log {claim.axis}" if claim.log \
        else f"{claim.stat} of {claim.metric} against {claim.axis}"
    shown = f" [95 % CI {lo:.3g}, {hi:.3g}]" if np.isfinite(lo) and np.isfinite(hi) else ""
    short = (f"slope of {of} {f.slope:.3g}{shown} ({len(f.x)} values, {int(f.n.min())} seeds or more each); "
             f"required {required(claim)}" + (f"; cannot be decided: {f.why}" if f.why else ""))
    points_text = ", ".join(f"{x:.4g}: {y:.4g} (n={k})" for x, y, k in zip(f.x, f.y, f.n))
    evidence = f"{short}; points ({'log ' if claim.log else ''}axis: statistic): {points_text}"
    result = UNDECIDED if f.why else decide(float(p), float(pc), p_min)
    return TrendTest(claim, f, float(p), float(pc), p_min, result, short, evidence)


def band(claim, f: Fit, n_points: int = BAND_POINTS) -> pd.DataFrame:
    """The fitted line of a trend and the pointwise 2.5-97.5 % band of its bootstrap lines, at
    ``n_points`` axis positions over the axis's range, in the metric's units (columns ``x``, ``fit``,
    ``fit_lo``, ``fit_hi``; no band where there is no interval)."""
    grid = np.linspace(f.x.min(), f.x.max(), n_points)
    line = f.intercept + f.slope * grid
    if f.boot.size:
        lines = f.boot[:, 1:2] + f.boot[:, 0:1] * grid[None, :]
        lo, hi = np.quantile(lines, [0.025, 0.975], axis=0)
    else:
        lo = hi = np.full(n_points, np.nan)
    back = np.exp if claim.log else (lambda v: v)
    return pd.DataFrame({"x": back(grid), "fit": back(line), "fit_lo": back(lo), "fit_hi": back(hi)})


def figure_rows(spec, table: pd.DataFrame, x_key: str, metrics: list[str]) -> list[dict]:
    """The rows a figure of ``spec`` adds for its trend claims drawn against ``x_key`` (their ``figure``
    is this artifact, their ``metric`` one of ``metrics``): each :func:`band` point with the claim's
    ``trend`` id, ``metric`` and the settings its ``where`` names (the panel it belongs to)."""
    rows = []
    for c in spec.claims:
        if c.kind != "trend" or c.axis != x_key or c.metric not in metrics or (c.figure or spec.name) != spec.name:
            continue
        drawn = band(c, fit(c, table))
        where = {k: str(v) for k, v in c.where.items()}
        rows += [{**where, "trend": c.id, "metric": c.metric, x_key: r["x"], "fit": r["fit"], "fit_lo": r["fit_lo"],
                  "fit_hi": r["fit_hi"]} for r in drawn.to_dict("records")]
    return rows
