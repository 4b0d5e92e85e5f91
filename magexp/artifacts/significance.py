"""The significance tests of a comparison claim, the difference each could detect, and Holm's correction.

One-sided tests of "the first side is better": Fisher's exact test of two success counts
(:func:`fisher_greater`), the Wilcoxon signed-rank test of paired differences (:func:`wilcoxon_less`), a
permutation test of a statistic of two independent samples (:func:`permutation_less`); the smallest
difference each detects with :data:`POWER` (``detectable_*``); Holm's step-down adjustment (:func:`holm`).
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

    Parameters
    ----------
    k1, n1 : int
        Successes and runs of the group claimed better.
    k2, n2 : int
        Successes and runs of the other group.

    Returns
    -------
    float
        The one-sided p-value.
    """
    total, succ = n1 + n2, k1 + k2
    denom = math.comb(total, n1)
    hi = min(n1, succ)
    return float(sum(math.comb(succ, x) * math.comb(total - succ, n1 - x) for x in range(k1, hi + 1)) / denom)


def wilcoxon_less(d: np.ndarray) -> float:
    """One-sided p-value of the Wilcoxon signed-rank test that the paired differences ``d`` lie
    below zero (zero differences dropped; 1 when none is left).

    Parameters
    ----------
    d : numpy.ndarray
        The paired differences.

    Returns
    -------
    float
        The one-sided p-value.
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

    Parameters
    ----------
    alpha : float
        The one-sided level.
    power : float
        The probability of detection.

    Returns
    -------
    float
        The distance in standard errors.
    """
    return float(ndtri(1 - alpha) + ndtri(power))


def detectable_paired(d: np.ndarray) -> float:
    """The shift of the paired differences ``d`` a one-sided Wilcoxon signed-rank test detects with
    :data:`POWER`: the normal approximation ``(z(1-alpha) + z(power)) s / sqrt(n)``, divided by the
    square root of the test's asymptotic relative efficiency against the t-test (3/pi). ``s`` is the
    robust scale ``1.4826 MAD(d)`` (the standard deviation of normal differences): a rank test does
    not see how far a failed run's difference lies, so its tails do not inflate ``s``.

    Parameters
    ----------
    d : numpy.ndarray
        The paired differences (non-finite ones dropped).

    Returns
    -------
    float
        The detectable shift (NaN for fewer than two differences).
    """
    d = np.asarray(d, float)
    d = d[np.isfinite(d)]
    if d.size < 2:
        return float("nan")
    scale = 1.4826 * float(np.median(np.abs(d - np.median(d))))
    return z_power() * scale / math.sqrt(d.size) / math.sqrt(3 / math.pi)


def detectable_unpaired(ci_a: tuple, ci_b: tuple) -> float:
    """The difference of a statistic between two independent samples the permutation test detects
    with :data:`POWER`: ``(z(1-alpha) + z(power)) sqrt(se_a^2 + se_b^2)``, each standard error read
    off its 95 % bootstrap interval (``(hi - lo) / (2 z(0.975))``).

    Parameters
    ----------
    ci_a, ci_b : tuple of float
        The two statistics' 95 % bootstrap intervals.

    Returns
    -------
    float
        The detectable difference (NaN where an interval is not finite).
    """
    z = float(ndtri(0.975))
    se = [(hi - lo) / (2 * z) for lo, hi in (ci_a, ci_b)]
    return z_power() * math.sqrt(se[0] ** 2 + se[1] ** 2) if all(np.isfinite(se)) else float("nan")


def detectable_rates(p0: float, n1: int, n2: int) -> float:
    """The rise of a success rate above ``p0`` (the rate of the side claimed worse, ``n2`` runs)
    that a one-sided test of ``n1`` against ``n2`` runs detects with :data:`POWER`, by the arcsine
    approximation: ``2 asin(sqrt(p1)) - 2 asin(sqrt(p0)) = (z(1-alpha) + z(power)) sqrt(1/n1 + 1/n2)``
    (Cohen's h); ``1 - p0`` when no rate up to 1 reaches that power (then nothing is detectable).

    Parameters
    ----------
    p0 : float
        The success rate of the side claimed worse.
    n1, n2 : int
        The runs of the side claimed better and of the other.

    Returns
    -------
    float
        The detectable rise (NaN without runs).
    """
    if min(n1, n2) < 1 or not np.isfinite(p0):
        return float("nan")
    phi = math.asin(math.sqrt(p0)) + z_power() * math.sqrt(1 / n1 + 1 / n2) / 2
    return (math.sin(phi) ** 2 if phi < math.pi / 2 else 1.0) - p0


def permutation_less(a: np.ndarray, b: np.ndarray, stat: str) -> tuple[float, float, float]:
    """One-sided permutation p-values that ``stat`` of ``a`` lies below that of ``b`` and of the
    converse, and the smallest p the test can give: :data:`N_PERM` random relabellings of the pooled
    values (a fixed generator: the same on every run), ``p = (1 + #{relabelled difference at or
    beyond the observed}) / (N_PERM + 1)`` (Phipson & Smyth 2010), at least ``1 / C(n, n_a)``.

    Parameters
    ----------
    a, b : numpy.ndarray
        The two samples.
    stat : str
        The statistic (a key of :data:`magexp.artifacts.tables.STATS`).

    Returns
    -------
    tuple of float
        ``(p that stat(a) < stat(b), p of the converse, the smallest p attainable)``.
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

    Parameters
    ----------
    p : list of float
        The raw p-values of one family.

    Returns
    -------
    list of float
        The adjusted p-values, in the same order.
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
