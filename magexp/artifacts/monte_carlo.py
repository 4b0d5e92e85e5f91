"""A paper's Monte-Carlo value: a statistic over the paper's own trials, judged against the interval of that
statistic, not against the spread of single runs.

A ``reported:`` entry says so with ``statistic`` and ``trials``::

    reported:
      - {quantity: offset_error, match: {scenario.n_readings: 200}, value: 1.84, statistic: median, trials: 1000}

Use it when the paper prints a median (or a mean) over many of its own runs ("median over 1,000 Monte-Carlo
trials"); a number from one run, or one whose trials the paper does not say, stays a single run. Judged as
one run, such a value lies inside the wide interval of single runs and is ``uninformative``; judged as
a statistic, it is compared with where that statistic falls.

**The interval** (:func:`interval`): where the paper's ``statistic`` over ``trials`` runs would fall if its
runs were distributed like ours, as far as our ``n`` runs tell it. Two-stage bootstrap, :data:`N_BOOT`
times: resample our ``n`` runs (the uncertainty of our own distribution), then draw ``trials`` runs from that
resample (the paper's sampling), and take the statistic; the interval is the 2.5 and 97.5 % quantiles.
The first stage matters: with ``trials`` far above ``n`` (1,000 against 30), the second alone would give an
interval as narrow as 1,000 runs allow while our median over 30 is itself uncertain, and a paper's value
would ``differ`` from ours by our own sampling error. The draws come from
``numpy.random.default_rng(MC_SEED)``: the same interval on every run. The runs are all of the cell's
finite runs (the paper's statistic is over all its trials, successful or not); the verdict rule is then
that of :mod:`magexp.artifacts.summary` on this interval (widened by the paper's printing precision; a
failed majority ``differs``; an interval wider than the paper's value is ``uninformative``).
"""

from __future__ import annotations

import numpy as np

from magexp.artifacts.tables import STATS, finite

#: the statistics a paper's Monte-Carlo value may be
STATISTICS = ("median", "mean")
#: bootstrap resamples of :func:`interval`
N_BOOT = 2000
#: the generator seed of :func:`interval` (fixed: the same interval on every run)
MC_SEED = 20260445
#: the most draws held in memory at once (resamples are taken in chunks of this many values)
CHUNK = 4_000_000


def interval(values, statistic: str, trials: int, n_boot: int = N_BOOT) -> tuple[float, float]:
    """The 95 % interval of ``statistic`` over ``trials`` runs distributed like the finite ``values``
    (module docstring: a two-stage bootstrap); NaN for fewer than two values.

    Parameters
    ----------
    values : array_like
        Our per-seed values of the cell.
    statistic : str
        One of :data:`STATISTICS`.
    trials : int
        The paper's number of trials (at least 1).
    n_boot : int
        Bootstrap resamples.

    Returns
    -------
    tuple of float
        ``(lo, hi)``: the 2.5 and 97.5 % quantiles of the statistic.
    """
    v = finite(values)
    if v.size < 2:
        return float("nan"), float("nan")
    rng = np.random.default_rng(MC_SEED)
    rows = max(1, CHUNK // max(trials, v.size))
    stats = []
    for start in range(0, n_boot, rows):
        k = min(rows, n_boot - start)
        ours = rng.integers(0, v.size, size=(k, v.size))  # our runs, resampled
        theirs = rng.integers(0, v.size, size=(k, int(trials)))  # the paper's trials, drawn from each resample
        stats.append(STATS[statistic](v[np.take_along_axis(ours, theirs, axis=1)], axis=1))
    lo, hi = np.quantile(np.concatenate(stats), [0.025, 0.975])
    return float(lo), float(hi)


def judged(values, entry) -> dict:
    """The judged numbers of a summary row whose paper entry is a statistic over trials: ``jlo``, ``jhi``
    (:func:`interval`), the runs judged (all finite values) and no outcome; empty for any other entry."""
    if entry is None or entry.statistic is None:
        return {}
    lo, hi = interval(values, entry.statistic, entry.trials)
    return {"jlo": lo, "jhi": hi, "judged": finite(values), "outcome": ""}


def columns(values, entry) -> dict:
    """``judged_runs``, ``judged_n`` and ``judged_value`` of such a row: what the interval is of, how many
    runs it is drawn from and our statistic over them."""
    v = finite(values)
    return {"judged_runs": f"{entry.statistic} of {entry.trials} trials (bootstrap), all seeds",
            "judged_n": int(v.size), "judged_value": float(STATS[entry.statistic](v)) if v.size else np.nan}


def words(entry) -> str:
    """What the interval is, as a row's reason and ``tolerance`` name it."""
    return f"our {entry.statistic} of {entry.trials} trials"
