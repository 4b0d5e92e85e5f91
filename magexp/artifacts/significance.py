"""The significance tests of a comparison claim, the difference each could detect, and Holm's correction.

One-sided tests of "the first side is better": Fisher's exact test of two success counts
(:func:`fisher_greater`), the Wilcoxon signed-rank test of paired differences (:func:`wilcoxon_less`), a
permutation test of a statistic of two independent samples (:func:`permutation_less`); the smallest
difference each detects with :data:`POWER` at a level (``detect_*``: Fisher's by exact enumeration,
:func:`fisher_power`; the rank and permutation tests by their normal approximations); Holm's step-down
adjustment (:func:`holm`); the vocabulary of a comparison's ``effect:`` (:func:`effect_error`).

Exact power of Fisher's one-sided test of ``n1`` runs at rate ``p1`` against ``n2`` at ``p0``, at a level:
``sum_{k1, k2} Bin(k1; n1, p1) Bin(k2; n2, p0) 1[P(X >= k1) < level]``, ``X ~ Hypergeom(n1 + n2, k1 + k2, n1)``.
The normal approximations: a paired shift ``(z(1 - level) + z(power)) 1.4826 MAD(d) / sqrt(n) / sqrt(3/pi)``;
an unpaired difference ``(z(1 - level) + z(power)) sqrt(se_a^2 + se_b^2)``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtri

from magexp.artifacts.tables import STATS, statistic

#: significance level of every comparison test
ALPHA = 0.05
#: power at which ``detectable`` is the smallest difference a comparison would detect
POWER = 0.8
#: relabellings of the permutation test (``unpaired``): its smallest p is ``1 / (N_PERM + 1)``
N_PERM = 4000


def fisher_greater(k1: int, n1: int, k2: int, n2: int) -> float:
    """One-sided p-value of Fisher's exact test that the success probability of the first group
    (``k1`` of ``n1``) exceeds the second's (``k2`` of ``n2``): the hypergeometric upper tail
    ``P(X >= k1)``, ``X ~ Hypergeom(n1 + n2, k1 + k2, n1)`` (what ``scipy.stats.fisher_exact(...,
    alternative="greater")`` gives).
    """
    total, succ = n1 + n2, k1 + k2
    denom = math.comb(total, n1)
    hi = min(n1, succ)
    return float(sum(math.comb(succ, x) * math.comb(total - succ, n1 - x) for x in range(k1, hi + 1)) / denom)


def wilcoxon_less(d: np.ndarray) -> float:
    """One-sided p-value of the Wilcoxon signed-rank test that the paired differences ``d`` lie
    below zero (zero differences dropped; 1 when none is left).
    """
    d = np.asarray(d, float)
    d = d[np.isfinite(d) & (d != 0)]
    if d.size == 0:
        return 1.0
    # lazy: scipy.stats is the largest import of magexp.artifacts; without it ``import
    # magexp.artifacts.reproduce`` takes 0.61 of the CPU time (farm-bench, paired, median of 5), which
    # a refused command, ``--help`` and every reader of an artifact's spec would pay for nothing
    from scipy.stats import wilcoxon

    return float(wilcoxon(d, alternative="less").pvalue)


def z_power(alpha: float = ALPHA, power: float = POWER) -> float:
    """``z(1 - alpha) + z(power)``: the distance, in standard errors, a one-sided test at ``alpha``
    needs to detect a difference with probability ``power``.
    """
    return float(ndtri(1 - alpha) + ndtri(power))


def detectable_paired(d: np.ndarray, alpha: float = ALPHA) -> float:
    """The shift of the paired differences ``d`` a one-sided Wilcoxon signed-rank test at ``alpha`` detects with
    :data:`POWER`: the normal approximation ``(z(1-alpha) + z(power)) s / sqrt(n)``, divided by the
    square root of the test's asymptotic relative efficiency against the t-test (3/pi). ``s`` is the
    robust scale ``1.4826 MAD(d)`` (the standard deviation of normal differences): a rank test does
    not see how far a failed run's difference lies, so its tails do not inflate ``s``.
    """
    d = np.asarray(d, float)
    d = d[np.isfinite(d)]
    if d.size < 2:
        return float("nan")
    scale = 1.4826 * float(np.median(np.abs(d - np.median(d))))
    return z_power(alpha) * scale / math.sqrt(d.size) / math.sqrt(3 / math.pi)


def detectable_unpaired(ci_a: tuple, ci_b: tuple, alpha: float = ALPHA) -> float:
    """The difference of a statistic between two independent samples the permutation test at ``alpha`` detects
    with :data:`POWER`: ``(z(1-alpha) + z(power)) sqrt(se_a^2 + se_b^2)``, each standard error read
    off its 95 % bootstrap interval (``(hi - lo) / (2 z(0.975))``).
    """
    z = float(ndtri(0.975))
    se = [(hi - lo) / (2 * z) for lo, hi in (ci_a, ci_b)]
    return z_power(alpha) * math.sqrt(se[0] ** 2 + se[1] ** 2) if all(np.isfinite(se)) else float("nan")


def permutation_less(a: np.ndarray, b: np.ndarray, stat: str) -> tuple[float, float, float]:
    """One-sided permutation p-values that ``stat`` of ``a`` lies below that of ``b`` and of the
    converse, and the smallest p the test can give: :data:`N_PERM` random relabellings of the pooled
    values (a fixed generator: the same on every run), ``p = (1 + #{relabelled difference at or
    beyond the observed}) / (N_PERM + 1)`` (Phipson & Smyth 2010), at least ``1 / C(n, n_a)``.
    """
    a, b = np.asarray(a, float), np.asarray(b, float)
    pooled, na = np.r_[a, b], len(a)
    rng = np.random.default_rng(0)
    perm = pooled[rng.permuted(np.tile(np.arange(pooled.size), (N_PERM, 1)), axis=1)]
    diff = np.asarray(STATS[stat](perm[:, :na], axis=1), float) - np.asarray(STATS[stat](perm[:, na:], axis=1), float)
    observed = statistic(a, stat) - statistic(b, stat)
    p_less = (1 + int(np.sum(diff <= observed))) / (N_PERM + 1)
    p_more = (1 + int(np.sum(diff >= observed))) / (N_PERM + 1)
    return p_less, p_more, max(1 / (N_PERM + 1), 1 / math.comb(pooled.size, na))


def holm(p: list[float]) -> list[float]:
    """Holm's step-down adjusted p-values of ``p`` (NaN stays NaN and is not counted): the i-th
    smallest of m becomes ``max over j <= i of min(1, (m - j + 1) p_(j))`` (Holm 1979).
    """
    p = np.asarray(p, float)
    out = np.full(p.shape, np.nan)
    idx = np.flatnonzero(np.isfinite(p))
    order = idx[np.argsort(p[idx], kind="stable")]
    m = len(order)
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (m - rank) * p[i]))
        out[i] = running
    return out.tolist()


# -- power at a level, by the test itself ----------------------------------------------------------------

def fisher_reject(n1: int, n2: int, level: float) -> np.ndarray:
    """The rejection region of the one-sided Fisher test at ``level``: ``R[k1, k2]`` is True where
    :func:`fisher_greater` ``(k1, n1, k2, n2) < level`` (the rule of :func:`magexp.artifacts.comparisons.decide`),
    every table of both margins at once: the hypergeometric probabilities of ``k1`` given each total
    ``t = k1 + k2``, ``C(t, k1) C(N - t, n1 - k1) / C(N, n1)`` with ``N = n1 + n2`` (log-gamma, on the
    grid), summed from ``k1`` up (no loop over tables).
    """
    from scipy.special import gammaln

    total = n1 + n2
    t, k = np.arange(total + 1)[:, None], np.arange(n1 + 1)[None, :]
    possible = (k <= t) & (n1 - k <= total - t)
    lc = lambda a, b: gammaln(a + 1) - gammaln(b + 1) - gammaln(np.maximum(a - b, 0) + 1)
    log_pmf = lc(t, k) + lc(total - t, n1 - k) - lc(total, n1)
    pmf = np.where(possible, np.exp(np.where(possible, log_pmf, 0.0)), 0.0)
    upper = np.cumsum(pmf[:, ::-1], axis=1)[:, ::-1]  # P(X >= k1 | t)
    k1, k2 = np.arange(n1 + 1)[:, None], np.arange(n2 + 1)[None, :]
    return upper[k1 + k2, k1] < level * (1 - 1e-9)


def fisher_power(n1: int, n2: int, p1, p0: float, level: float) -> np.ndarray:
    """Exact power of the one-sided Fisher test at ``level`` when the better side succeeds with
    probability ``p1`` (a scalar or an array) and the other with ``p0``:
    ``sum_{k1, k2} Bin(k1; n1, p1) Bin(k2; n2, p0) 1[p(k1, k2) < level]`` over every table
    (:func:`fisher_reject`).
    """
    from scipy.stats import binom

    reject = fisher_reject(n1, n2, level).astype(float)
    per_k1 = reject @ binom.pmf(np.arange(n2 + 1), n2, p0)  # P(reject | k1), over the worse side's counts
    p1 = np.atleast_1d(np.asarray(p1, float))
    return binom.pmf(np.arange(n1 + 1)[None, :], n1, p1[:, None]) @ per_k1


#: the grid of better-side rates :func:`detect_rise` searches (steps of 0.001 up to a rate of 1)
RISE_GRID = 1000


def detect_rise(p0: float, n1: int, n2: int, level: float) -> tuple[float, str]:
    """The smallest rise of the success rate above ``p0`` (the worse side's observed rate) that the
    one-sided Fisher test of ``n1`` against ``n2`` runs detects with :data:`POWER` at ``level``, by
    exact enumeration (:func:`fisher_power` on a grid of rates ``p0 + j (1 - p0) / RISE_GRID``; the
    power rises with the rate), and its words; NaN and "no rise up to a success rate of 1 reaches
    80 % power at this level" when even a rate of 1 does not.
    """
    if min(n1, n2) < 1 or not np.isfinite(p0) or p0 >= 1:
        return float("nan"), "no rise is possible from a success rate of 1" if p0 >= 1 else "not computable"
    rates = p0 + (1 - p0) * np.arange(1, RISE_GRID + 1) / RISE_GRID
    power = fisher_power(n1, n2, rates, p0, level)
    reached = np.flatnonzero(power >= POWER)
    if not reached.size:
        return float("nan"), f"no rise up to a success rate of 1 reaches {POWER * 100:.0f} % power at this level"
    rise = float(rates[reached[0]] - p0)
    return rise, f"a success-rate rise of {rise:.3g}"


def detect_paired(d: np.ndarray, level: float) -> tuple[float, str]:
    """:func:`detectable_paired` at ``level`` (the normal approximation of the signed-rank test) and its
    words; NaN and "not computable (k of n ties)" when the robust scale is degenerate: the MAD of the
    differences is 0 or at least half of them are tied at their median (the rank test then sees few
    differences and the scale says nothing of them).
    """
    d = np.asarray(d, float)
    d = d[np.isfinite(d)]
    if d.size < 2:
        return float("nan"), "not computable (fewer than 2 pairs)"
    ties = int(np.sum(d == np.median(d)))
    if 2 * ties >= d.size or np.median(np.abs(d - np.median(d))) == 0:
        return float("nan"), f"not computable ({ties} of {d.size} ties)"
    shift = detectable_paired(d, level)
    return shift, f"a per-seed shift of {shift:.3g}"


def detect_unpaired(ci_a: tuple, ci_b: tuple, level: float) -> tuple[float, str]:
    """:func:`detectable_unpaired` at ``level`` and its words."""
    diff = detectable_unpaired(ci_a, ci_b, level)
    return diff, f"a difference of {diff:.3g}" if np.isfinite(diff) else "not computable"


#: the keys of a comparison's ``effect:`` (the smallest effect worth detecting): a success-rate rise above
#: the worse side's planning rate (Fisher; also a mean of a 0/1 metric), or a ratio of a location
#: statistic with the planning standard deviation of the log of the metric per seed
EFFECT_KEYS = {"rates": ("rise", "baseline"), "ratio": ("ratio", "spread")}


def effect_kind(stat: str) -> str:
    """The kind of ``effect:`` a comparison of ``stat`` declares."""
    return "rates" if stat in ("success_rate", "mean") else "ratio"


def effect_error(effect: dict, stat: str) -> str:
    """Why ``effect`` is not allowed for a comparison of ``stat`` ("" when it is): ``{rise, baseline}``
    with ``0 < rise``, ``0 <= baseline`` and ``baseline + rise <= 1`` for a success rate or a mean of a
    0/1 metric; ``{ratio, spread}`` with ``ratio > 1`` and ``spread > 0`` for another statistic.
    """
    keys = EFFECT_KEYS[effect_kind(stat)]
    if set(effect) != set(keys) or not all(isinstance(effect[k], (int, float)) for k in keys):
        return f"give exactly {{{keys[0]}: number, {keys[1]}: number}} for stat {stat}"
    a, b = (float(effect[k]) for k in keys)
    if keys[0] == "rise" and not (0 < a and 0 <= b and a + b <= 1):
        return "0 < rise, 0 <= baseline and baseline + rise <= 1"
    if keys[0] == "ratio" and not (a > 1 and b > 0):
        return "ratio > 1 (the worse side's statistic over the better's) and spread > 0"
    return ""


def effect_words(effect: dict) -> str:
    """An ``effect:`` in words: "a success-rate rise of 0.15 from 0.80" or "a 1.5x ratio of medians
    (log spread 0.5 per seed)"; "" when none is declared.
    """
    if "rise" in effect:
        return f"a success-rate rise of {effect['rise']:g} from {effect['baseline']:.2f}"
    if "ratio" in effect:
        return f"a {effect['ratio']:g}x ratio (log spread {effect['spread']:g} per seed)"
    return ""
