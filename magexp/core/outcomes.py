"""The outcome of a run: when it succeeded, when a cell's runs mostly did, when an estimate sits on a
face of the search box, and the round-off floor below which a value is noise of the arithmetic.

This module is the one home of these definitions; every reader imports them from here (the runs
table's ``succeeded`` column, :mod:`magexp.artifacts.plan`; the verdicts, :mod:`magexp.artifacts.summary`;
the swarm's ``on_boundary`` count, :mod:`magexp.estimators.swarm`; the figures and the report).

**Success is judged against the optimum the data allow, never by the optimiser.** A run *succeeded*
when its objective is within a factor of the objective of the true calibration on the same readings
(:func:`succeeded`); on a recording without a truth, within that factor of the best value any
estimator reached on it (``success: {reference: best}``, :data:`magexp.artifacts.plan.BEST`). The
optimiser's own flag (scipy's ``OptimizeResult.success``) says only that its stopping test was met,
and is stored apart as ``optimizer_flag``: a swarm always meets its iteration budget, so the flag
was True for a real-data RDPSO run ending at ``F_g`` = 39.4 where the best fit reaches 2.59
(``results/real/real_table7_runs.csv``). It imports only numpy.
"""

from __future__ import annotations

import numpy as np

#: A run succeeds when ``metric <= SUCCESS_FACTOR * reference + ROUNDOFF_FLOOR`` (the default of an
#: artifact's ``success:``, :class:`magexp.artifacts.spec.Success`). 1.1: a run within 10 % of the
#: true calibration's objective on the same readings has found the optimum's basin, within the
#: spread of the noise; a run stuck on the box's face or in another basin ends far above it.
SUCCESS_FACTOR = 1.1
#: The round-off floor of the objectives (nT or mG): a noise-free fit reaches 1e-11 to 1e-13 in double
#: precision, so values below 1e-9 are arithmetic, not data. Added to every threshold (a truth at 0
#: is reached by a run at round-off), and the value results files write and compare below it.
ROUNDOFF_FLOOR = 1.0e-9
#: A run has *reached the floor* (the ``converged`` column, and ``nfev_to_floor``: the evaluations
#: until then) when its objective is within 1 % of the true calibration's: a stricter level than
#: success, that measures how far along a successful run got rather than whether it found the basin.
REACHED_FACTOR = 1.01
#: A cell's runs failed in majority when fewer than this fraction of them succeeded: a paper value
#: inside such a cell's interval is matched by failures, and a figure draws the cell as failed. A
#: rate of exactly one half is not a failed majority.
MAJORITY = 0.5
#: A coordinate is on a face of the search box when ``|x - face| <= FACE_TOL (high - low)``: a swarm
#: that clips to the box leaves a coordinate that crossed a face exactly on it, 1e-9 of the width
#: allows for the round-off of the clip's arithmetic and nothing more.
FACE_TOL = 1.0e-9


def success_threshold(reference, factor: float = SUCCESS_FACTOR, floor: float = ROUNDOFF_FLOOR):
    """The largest objective of a successful run."""
    out = factor * np.asarray(reference, float) + floor
    return float(out) if out.ndim == 0 else out


def succeeded(metric, reference, factor: float = SUCCESS_FACTOR, floor: float = ROUNDOFF_FLOOR) -> np.ndarray:
    """Per run, whether it succeeded (``metric <= factor * reference + floor``): 1.0, 0.0 (a NaN metric fails),
    or NaN where the reference is unknown (the run is not judged)."""
    metric, reference = np.asarray(metric, float), np.asarray(reference, float)
    with np.errstate(invalid="ignore"):
        ok = (metric <= success_threshold(reference, factor, floor)).astype(float)
    return np.where(np.isnan(reference), np.nan, ok)


def reach_level(truth_fun: float) -> float:
    """The objective at which a run has reached the floor: ``REACHED_FACTOR * truth_fun + ROUNDOFF_FLOOR``
    (:data:`REACHED_FACTOR`), with ``truth_fun`` the true calibration's objective on the same readings.
    """
    return REACHED_FACTOR * float(truth_fun) + ROUNDOFF_FLOOR


def failed_majority(success_rate):
    """Whether fewer than half of a cell's judged runs succeeded (``success_rate < MAJORITY``)."""
    with np.errstate(invalid="ignore"):
        out = np.asarray(success_rate, float) < MAJORITY
    return bool(out) if out.ndim == 0 else out


def succeeded_majority(success_rate):
    """Whether at least half of a cell's judged runs succeeded (``success_rate >= MAJORITY``; False
    where the rate is NaN: nothing judged has not succeeded either). Same shapes as :func:`failed_majority`.
    """
    with np.errstate(invalid="ignore"):
        out = np.asarray(success_rate, float) >= MAJORITY
    return bool(out) if out.ndim == 0 else out


def on_face(x, low, high) -> np.ndarray:
    """Which coordinates of ``x`` sit on a face of the box ``[low, high]``: within :data:`FACE_TOL` of its width,
    or equal to an infinite face."""
    x, low, high = (np.asarray(a, float) for a in (x, low, high))
    with np.errstate(invalid="ignore"):
        atol = FACE_TOL * (high - low)
        return (np.abs(x - low) <= atol) | (np.abs(x - high) <= atol) | (x == low) | (x == high)


def recording_succeeded(optimizer_flag, spread_before, spread_after) -> np.ndarray:
    """Per run on a recording judged by no reference: the optimiser met its stopping test and the
    calibration narrowed the spread of the total field (``spread_after < spread_before``). The
    fallback of a benchmark of recordings whose artifact has no ``success: {reference: best}``: a
    calibration must not widen the spread it fits.
    """
    with np.errstate(invalid="ignore"):
        narrowed = np.asarray(spread_after, float) < np.asarray(spread_before, float)
    return np.asarray(optimizer_flag, bool) & narrowed
