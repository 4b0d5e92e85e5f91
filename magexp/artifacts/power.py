"""Sample sizes fixed before the data: the seeds a comparison's cells get so that its test detects the
smallest effect worth detecting (the claim's ``effect:``) with 80 % power at the level it is judged at.

Nothing here reads a run: the seeds follow from the artifact and ``paper.yaml`` alone, before any run, and
no rule adds seeds by looking at a result (optional stopping inflates the error rates the tests promise).

**Level.** A comparison of a Holm family of ``m`` comparisons (:func:`magexp.artifacts.families.claim_families`)
is planned at the family's strictest step, ``level = ALPHA / m`` (:func:`claim_levels`); a sanity check
or an exploratory claim, judged alone, at ``ALPHA``. Planned at the strictest step, the power holds whatever
rank the comparison takes in its family.

**Power, by the test the claim is judged with** (:func:`comparison_test`), every cell at ``n`` seeds:

* Fisher's exact one-sided test (success rates; a mean of a 0/1 metric, whose permutation test is Fisher's
  test): ``effect: {rise, baseline}``, exact enumeration over both binomials,
  ``power(n) = sum_{k1, k2} Bin(k1; n, baseline + rise) Bin(k2; n, baseline) 1[p(k1, k2) < level]``
  (:func:`magexp.artifacts.significance.fisher_power`);
* the paired Wilcoxon signed-rank test: ``effect: {ratio, spread}``, simulated: :data:`N_SIM` data sets of
  per-seed values ``a = exp(spread z_a)``, ``b = ratio exp(spread z_b)`` (lognormal, the medians in the
  declared ratio, ``z ~ N(0, 1)`` from ``numpy.random.default_rng(SIM_SEED)``), ``power(n)`` the fraction
  whose one-sided p of ``a - b`` is below ``level``. The two sides are drawn independently: the plan takes
  no credit for the pairing (same readings), which only narrows the differences;
* the unpaired permutation test of the claim's ``stat``: the same data sets (:data:`N_SIM_PERM` of them),
  each tested with ``n_perm = min(N_PERM, ceil(2 / level) - 1)`` relabellings (one fixed set, drawn once),
  fewer than the report's :data:`~magexp.artifacts.significance.N_PERM`: its p can still fall below
  ``level`` (``1 / (n_perm + 1) <= level / 2``), on a coarser grid, so the simulated test rejects less
  often than the report's and the plan errs towards more seeds, never fewer.

* a trend's one-sided bootstrap test (:mod:`magexp.artifacts.trends`): ``effect: {slope, spread}``,
  simulated: :data:`N_SIM` data sets of per-seed values ``y_ij = slope x_j + spread z_ij`` at the grid's
  axis values ``x_j`` (logs of both with ``log: true``; ``z ~ N(0, 1)``, seed ``i`` of every data set drawn
  before seed ``i + 1``, so a data set of ``n`` seeds extends that of ``n - 1``), each judged as the claim is:
  ``stat`` per axis value, :data:`~magexp.artifacts.trends.N_BOOT` bootstrap resamples of each value's
  seeds (one fixed set of resamples for every data set, drawn independently per axis value), the
  least-squares slopes and their p (:func:`magexp.artifacts.trends.p_values`); ``power(n)`` the fraction of
  data sets whose p is below ``level`` (:func:`trend_power`). A median of a resample is read off the data
  set's sorted values at the resample's sorted middle indices, no sort per resample. One cell per axis value is
  assumed: cells that share a value pool their seeds, which only adds to the power.

**Seeds** (:func:`required_seeds`, :func:`trend_seeds`): the smallest ``n >= seeds`` with ``power(n) >= POWER``, found by
bisection between the artifact's ``seeds`` and its cap ``max_seeds`` (the simulations draw one set of
values for every ``n``: common random numbers keep ``power(n)`` monotone; the exact Fisher power is
then scanned over the ten ``n`` below the bisection's answer, where its saw-tooth could reach the target
first). When even the cap does not reach :data:`POWER`, the cells get the cap and the claim's evidence says
the power reached. Each answer is computed once per process (``functools.cache``).

:mod:`magexp.artifacts.sample_sizes` gives each cell its planned seeds; ``python -m
magexp.artifacts.sample_sizes`` prints, per paper, each comparison's effect, level, seeds and power.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from magexp.artifacts import trends
from magexp.artifacts.comparisons import ALONE, ESTIMATOR_SIDE
from magexp.artifacts.significance import ALPHA, N_PERM, POWER, effect_kind, effect_words, fisher_power
from magexp.artifacts.tables import STATS

#: simulated data sets of the Wilcoxon power
N_SIM = 400
#: simulated data sets of the permutation test's power (each tested with up to N_PERM relabellings)
N_SIM_PERM = 400
#: the generator seed of the simulations (fixed: the plan is the same on every machine)
SIM_SEED = 20240639
#: the claim kinds tested in a Holm family (each has a p-value)
TESTED = ("ordering", "winner", "trend")


def comparison_test(claim) -> str:
    """The test a comparison claim will be judged with, read from the claim alone: ``fisher`` for a
    success rate, ``unpaired`` or ``paired`` where the claim says so; under ``test: auto``, ``paired``
    when its cells differ only in method keys (``estimator``, ``estimator.*``, ``objective``: the same
    readings), else ``unpaired`` (:func:`magexp.artifacts.comparisons.compare`).
    """
    if claim.stat == "success_rate":
        return "fisher"
    if claim.test != "auto":
        return claim.test
    data_side = [{k: v for k, v in c.items() if k not in ESTIMATOR_SIDE and not k.startswith("estimator.")}
                 for c in claim.cells]
    return "paired" if all(d == data_side[0] for d in data_side) else "unpaired"


def _draws(n_sim: int, n: int) -> np.ndarray:
    """Standard normal draws ``(2, n_sim, n)`` of the simulations (:data:`SIM_SEED`)."""
    return np.random.default_rng(SIM_SEED).standard_normal((2, n_sim, n))


def wilcoxon_power(n: int, ratio: float, spread: float, level: float, n_sim: int = N_SIM) -> float:
    """Simulated power of the one-sided paired Wilcoxon signed-rank test
    (:func:`magexp.artifacts.significance.wilcoxon_less`'s test) at ``level`` with ``n`` seeds per cell
    (module docstring).
    """
    from scipy.stats import wilcoxon  # lazy: see magexp.artifacts.significance.wilcoxon_less

    z = _draws(n_sim, n)
    d = np.exp(spread * z[0]) - ratio * np.exp(spread * z[1])
    return float(np.mean(wilcoxon(d, alternative="less", axis=1).pvalue < level))


def permutation_power(n: int, ratio: float, spread: float, level: float, stat: str = "median",
                      n_sim: int = N_SIM_PERM) -> float:
    """Simulated power of the one-sided permutation test of ``stat``
    (:func:`magexp.artifacts.significance.permutation_less`) at ``level`` with ``n`` seeds per cell, each
    data set tested with ``min(N_PERM, ceil(2 / level) - 1)`` relabellings (module docstring).
    """
    n_perm = min(N_PERM, math.ceil(2 / level) - 1)
    z = _draws(n_sim, n)
    pooled = np.concatenate([np.exp(spread * z[0]), ratio * np.exp(spread * z[1])], axis=1)
    relabel = np.random.default_rng(SIM_SEED + 1).permuted(np.tile(np.arange(2 * n), (n_perm, 1)), axis=1)
    f = STATS[stat]
    observed = np.asarray(f(pooled[:, :n], axis=1)) - np.asarray(f(pooled[:, n:], axis=1))
    null = _median_null if stat == "median" else _any_null
    hits = np.sum(null(pooled, relabel, f) <= observed[:, None], axis=1)
    return float(np.mean((1 + hits) / (n_perm + 1) < level))


def _median_null(pooled: np.ndarray, relabel: np.ndarray, f) -> np.ndarray:
    """The relabelled differences of medians ``(n_sim, n_perm)``: the relabellings index each data set's
    sorted values (a set of relabellings independent of the data is as valid on them), so a half's median
    is the sorted values at the middle of its sorted indices: four gathers, no median per relabelling."""
    n = pooled.shape[1] // 2
    ordered = np.sort(pooled, axis=1)
    half = [np.sort(relabel[:, :n], axis=1), np.sort(relabel[:, n:], axis=1)]
    mid = [(h[:, (n - 1) // 2], h[:, n // 2]) for h in half]
    med = [(ordered[:, lo] + ordered[:, hi]) / 2 for lo, hi in mid]
    return med[0] - med[1]


def _any_null(pooled: np.ndarray, relabel: np.ndarray, f) -> np.ndarray:
    """The relabelled differences of the statistic ``f`` ``(n_sim, n_perm)``, in chunks of data sets."""
    n = pooled.shape[1] // 2
    chunk = max(1, 4_000_000 // relabel.size)
    out = np.empty((pooled.shape[0], relabel.shape[0]))
    for s in range(0, pooled.shape[0], chunk):
        x = pooled[s:s + chunk][:, relabel]  # (chunk, n_perm, 2n)
        out[s:s + chunk] = np.asarray(f(x[..., :n], axis=2)) - np.asarray(f(x[..., n:], axis=2))
    return out


def power_at(n: int, test: str, effect: tuple, level: float, stat: str = "median") -> float:
    """The power of ``test`` at ``level`` with ``n`` seeds per cell against ``effect`` (the items of a
    claim's ``effect:``): :func:`~magexp.artifacts.significance.fisher_power`, :func:`wilcoxon_power` or
    :func:`permutation_power`.
    """
    e = dict(effect)
    if "rise" in e:
        return float(fisher_power(n, n, e["baseline"] + e["rise"], e["baseline"], level)[0])
    if test == "paired":
        return wilcoxon_power(n, e["ratio"], e["spread"], level)
    return permutation_power(n, e["ratio"], e["spread"], level, stat)


def _smallest(power, start: int, cap: int, scan: bool = False) -> tuple[int, float]:
    """The smallest ``n`` in ``[start, cap]`` whose ``power(n)`` is at least :data:`POWER` and that power, by
    bisection (``scan``: then over the ten ``n`` below, for a saw-tooth power); ``(cap, power(cap))`` when the
    cap does not reach it."""
    if power(cap) < POWER:
        return cap, power(cap)
    lo, hi = start, cap  # power(hi) >= POWER; below lo nothing is asked
    if power(lo) >= POWER:
        return lo, power(lo)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if power(mid) >= POWER else (mid, hi)
    if scan:
        hi = next((n for n in range(max(start, hi - 10), hi) if power(n) >= POWER), hi)
    return hi, power(hi)


@functools.cache
def required_seeds(test: str, effect: tuple, level: float, start: int, cap: int,
                   stat: str = "median") -> tuple[int, float]:
    """The smallest ``n`` in ``[start, cap]`` whose :func:`power_at` is at least :data:`POWER`, and that
    power; ``(cap, power at cap)`` when the cap does not reach it (module docstring: bisection, the exact
    Fisher power scanned below it).
    """
    power = functools.cache(lambda n: power_at(n, test, effect, level, stat))
    return _smallest(power, start, cap, scan="rise" in dict(effect))


def _resample_stat(y: np.ndarray, idx: np.ndarray, stat: str) -> np.ndarray:
    """``stat`` of every bootstrap resample ``idx`` ``(J, B, n)`` of each data set's values ``y``
    ``(n_sim, J, n)``: ``(n_sim, J, B)`` (a median off the sorted values at the sorted middle indices)."""
    rows = np.arange(y.shape[1])[:, None]
    if stat == "median":
        ordered, order = np.sort(y, axis=-1), np.sort(idx, axis=-1)
        n = y.shape[-1]
        return (ordered[:, rows, order[..., (n - 1) // 2]] + ordered[:, rows, order[..., n // 2]]) / 2
    f, out = STATS[stat], np.empty(y.shape[:2] + idx.shape[1:2])
    chunk = max(1, 4_000_000 // idx.size)
    for s in range(0, y.shape[0], chunk):
        out[s:s + chunk] = f(y[s:s + chunk][:, rows[..., None], idx], axis=-1)
    return out


def trend_power(n: int, xs: tuple, stat: str, between: tuple, sign: str, slope: float, spread: float,
                level: float, n_sim: int = N_SIM) -> float:
    """Simulated power of a trend's one-sided bootstrap test at ``level`` with ``n`` seeds per axis value
    against a true ``slope`` with per-seed ``spread`` around the line, the points at ``xs`` (logs with
    ``log: true``, :func:`magexp.artifacts.trends.axis_values`) (module docstring).
    """
    x = np.asarray(xs, float)
    z = np.random.default_rng(SIM_SEED).standard_normal((n, n_sim, len(x))).transpose(1, 2, 0)
    idx = np.random.default_rng(SIM_SEED + 2).integers(0, n, size=(len(x), trends.N_BOOT, n))
    boot = _resample_stat(slope * x[None, :, None] + spread * z, idx, stat)
    xc = x - x.mean()
    slopes = np.einsum("sjb,j->sb", boot, xc) / (xc @ xc)
    p, _ = trends.p_values(between, sign, slopes)
    return float(np.mean(p < level))


@functools.cache
def trend_seeds(xs: tuple, stat: str, between: tuple, sign: str, effect: tuple, level: float, start: int,
                cap: int) -> tuple[int, float]:
    """The smallest ``n`` in ``[max(start, MIN_SEEDS), cap]`` whose :func:`trend_power` is at least
    :data:`POWER`, and that power (``(cap, power at cap)`` when the cap does not reach it)."""
    e = dict(effect)
    power = functools.cache(lambda n: trend_power(n, xs, stat, between, sign, e["slope"], e["spread"], level))
    return _smallest(power, max(start, trends.MIN_SEEDS), max(cap, trends.MIN_SEEDS))


@dataclass(frozen=True)
class ClaimPlan:
    """The sample size of one comparison: its ``test``, ``effect`` (and its ``words``), ``family`` of
    ``m`` comparisons and ``level``, the ``seeds`` its cells get (at least the artifact's, at most its
    cap), the ``power`` they reach, and whether the cap bound (``capped``)."""

    key: str
    test: str
    effect: dict
    words: str
    family: str
    m: int
    level: float
    seeds: int
    power: float
    capped: bool


def claim_levels(specs: list, family: dict[str, str]) -> dict[str, tuple[str, int, float]]:
    """``{"<artifact>.<claim id>": (family, m, level)}`` of every comparison and trend claim of a paper: its
    Holm family, the number ``m`` of tested claims in it and the strictest step ``ALPHA / m`` (``ALPHA``
    alone).
    """
    comparisons = [f"{s.name}.{c.id}" for s in specs for c in s.claims if c.kind in TESTED]
    sizes = {name: sum(family[k] == name for k in comparisons) for name in set(family.values())}
    out = {}
    for key in comparisons:
        m = 1 if family[key] in ALONE else sizes[family[key]]
        out[key] = (family[key], m, ALPHA / m)
    return out


def claim_plans(specs: list, family: dict[str, str]) -> dict[str, ClaimPlan]:
    """The :class:`ClaimPlan` of every comparison or trend claim of a paper that declares an ``effect:``."""
    levels = claim_levels(specs, family)
    out = {}
    for spec in specs:
        cap = max(int(spec.max_seeds), int(spec.seeds))
        for c in spec.claims:
            key = f"{spec.name}.{c.id}"
            if key not in levels or not c.effect:
                continue
            name, m, level = levels[key]
            effect = tuple(sorted(c.effect.items()))
            if c.kind == "trend":
                test, words = "bootstrap", trends.effect_words(c.effect)
                n, reached = trend_seeds(trends.axis_values(c, spec.grid), c.stat, tuple(c.between), c.sign, effect,
                                         level, int(spec.seeds), cap)
            else:
                test, words = ("fisher" if effect_kind(c.stat) == "rates" else comparison_test(c)), effect_words(c.effect)
                n, reached = required_seeds(test, effect, level, int(spec.seeds), cap, c.stat)
            out[key] = ClaimPlan(key, test, dict(c.effect), words, name, m, level, n, reached, reached < POWER)
    return out
