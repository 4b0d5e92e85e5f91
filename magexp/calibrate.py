"""Calibrate a user's recording with any estimator: ``python -m magexp task=calibrate data.path=...``.

Flow (the same as a simulated run, with a recording instead of a scenario)::

    recording (magexp.recordings) ──► dataset: readings, reference total, attitudes (if any)
    dataset + objective (scalar | vector) + search box from the data ──► problem
    estimator.fit(problem, rng=...) ──► W, o ──► calibrated readings B = W (r - o), spread metrics

Reference total field, first found of: ``data.reference_total`` (command line), the ``total``
column, ``# reference_total:``, the norm of ``# field:``. With none, the reference is
*estimated*: the fit uses ``R0``, the mean distance of the raw readings from their centroid,
as the radius, then ``W`` is rescaled so that the mean calibrated magnitude equals ``R0``.
The shape of the calibration (and the spread std/mean) does not depend on this choice; the
absolute scale does, and the output says so.

Search box of swarm estimators (:func:`search_box`), derived from the data: each offset
within the range of the readings, ``[min, max]`` over all three axes; matrix entries scaled
by ``s = reference / R0``: diagonal in ``[0.5 s, 1.5 s]``, off-diagonal in ``[-0.5 s, 0.5 s]``
(``1 / s`` instead of ``s`` for the vector objective, whose parameters are ``S = W^-1``: Yuan 2018).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from magexp.dataset import Dataset
from magexp.errors import MagexpError
from magexp.estimators.result import FitResult
from magexp.recordings import Recording
from magexp.scenarios.search import SearchBox

#: Objectives a recording can be calibrated with.
OBJECTIVES = ("scalar", "vector")
#: Fewest readings accepted: the 12 parameters of ``W`` and ``o`` (a scalar fit identifies 9).
MIN_READINGS = 12


@dataclass
class Reference:
    """The reference total field of a calibration.

    Attributes
    ----------
    total : (N,) reference total per reading (in the recording's unit).
    source : where it comes from (``data.reference_total``, ``total column``, ...).
    estimated : True when no reference was given and the scale was fixed from the data.
    """

    total: np.ndarray
    source: str
    estimated: bool = False

    def describe(self) -> str:
        mean = float(np.mean(self.total))
        if self.estimated:
            return (f"none given: estimated as the mean calibrated magnitude, scale fixed to the mean distance "
                    f"of the raw readings from their centroid, {mean:.6g}")
        return f"{mean:.6g} from {self.source}"


@dataclass
class Calibration:
    """A fitted calibration ``B = W (reading - offset)`` of a recording, and how good it is."""

    recording: Recording
    estimator: str
    objective: str
    w: np.ndarray
    offset: np.ndarray
    reference: Reference
    search: SearchBox
    fit: FitResult
    calibrated: np.ndarray
    metrics: dict = field(default_factory=dict)

    @property
    def unit(self) -> str:
        return self.recording.unit


def centroid_radius(readings: np.ndarray) -> float:
    """Mean distance of ``readings`` from their centroid (the radius of a sphere-like cloud)."""
    return float(np.linalg.norm(readings - readings.mean(axis=0), axis=1).mean())


def reference_of(rec: Recording, override=None) -> Reference:
    """The reference total field of ``rec`` (see the module docstring for the order)."""
    n = rec.n
    if override is not None:
        try:
            value = float(override)
        except (TypeError, ValueError):
            value = float("nan")
        if not (np.isfinite(value) and value > 0):
            raise MagexpError(f"data.reference_total={override!r} is not allowed: it must be a number > 0")
        return Reference(np.full(n, value), "data.reference_total")
    if rec.total is not None:
        return Reference(np.asarray(rec.total, float), "the total column")
    if rec.reference_total is not None:
        return Reference(np.full(n, rec.reference_total), "'# reference_total:'")
    if rec.field is not None:
        return Reference(np.full(n, float(np.linalg.norm(rec.field))), "the norm of '# field:'")
    return Reference(np.full(n, centroid_radius(rec.readings)), "estimated", estimated=True)


def attitude_of(rec: Recording) -> np.ndarray | None:
    """Navigation -> sensor rotations ``(N, 3, 3)`` from the angles or the gyro rates, or None."""
    if rec.angles is not None:
        from magexp.scenarios.ship import ship_attitude

        return ship_attitude(*rec.angles.T)
    if rec.gyro is not None:
        from magexp.scenarios.motion import integrate_rates

        return np.transpose(integrate_rates(rec.gyro[:-1], rec.sample_time), (0, 2, 1))
    return None


def search_box(readings: np.ndarray, reference: float, *, forward: bool = False) -> SearchBox:
    """The parameter box of swarm estimators, derived from the data (module docstring).

    ``forward``: the matrix parameters are ``S = W^-1`` (the vector problem's parameterisation,
    which the ``ekf`` state uses), so their scale is ``1 / s``.
    """
    lo, hi = float(readings.min()), float(readings.max())
    if hi <= lo:
        hi = lo + 1.0
    s = reference / (centroid_radius(readings) or 1.0)
    s = 1.0 / s if forward else s
    return SearchBox(diag=(0.5 * s, 1.5 * s), offdiag=(-0.5 * s, 0.5 * s), offset=(lo, hi))


def recording_dataset(rec: Recording, reference: Reference, objective: str) -> Dataset:
    """The :class:`Dataset` of ``rec`` for ``objective`` (attitudes and field for ``vector``)."""
    if objective not in OBJECTIVES:
        raise MagexpError(f"objective={objective!r} is not allowed for task=calibrate: choose one of "
                          f"{', '.join(OBJECTIVES)}")
    attitude, field_nav = None, None
    if objective == "vector":
        attitude = attitude_of(rec)
        if attitude is None or rec.field is None:
            raise MagexpError(f"objective='vector' is not allowed for {rec.path.name}: it needs attitudes "
                              "(heading, roll, trim or gx, gy, gz columns) and a '# field:' line; use objective=scalar")
        field_nav = np.broadcast_to(rec.field, (rec.n, 3)).copy()
    return Dataset(readings=rec.readings, reference_norm=reference.total, field_nav=field_nav, attitude=attitude,
                   unit=rec.unit, meta={"recording": str(rec.path), **rec.meta})


def check_size(rec: Recording) -> None:
    """At least :data:`MIN_READINGS` readings."""
    if rec.n < MIN_READINGS:
        raise MagexpError(f"{rec.path.name}: {rec.n} readings is not allowed: a calibration needs at least "
                          f"{MIN_READINGS} (the 12 parameters of W and the offset)")


def check_applies(estimator, objective: str) -> None:
    """Fail in one line unless ``estimator`` applies to the ``objective`` problem
    (:func:`magexp.estimators.base.applies_to`), naming the estimators that do."""
    from magexp.cli_checks import options, target_class
    from magexp.estimators.base import applies_to
    from magexp.problems import problem_class

    problem = problem_class(objective)
    ok, reason = applies_to(estimator, problem)
    if ok:
        return
    fits = [n for n in options("estimator") if applies_to(target_class("estimator", n), problem)[0]]
    raise MagexpError(f"estimator={estimator.name!r} is not allowed for objective {objective!r}: choose one of "
                      f"{', '.join(fits)} ({reason})")


def spread(magnitudes: np.ndarray) -> float:
    """Relative spread ``std / mean`` of total-field magnitudes."""
    return float(np.std(magnitudes) / np.mean(magnitudes))


def quality(raw: np.ndarray, calibrated: np.ndarray, reference: np.ndarray) -> dict:
    """Magnitude statistics before and after, and the RMS against the reference."""
    before, after = np.linalg.norm(raw, axis=1), np.linalg.norm(calibrated, axis=1)
    return {"mean_before": float(before.mean()), "std_before": float(before.std()), "spread_before": spread(before),
            "rms_before": float(np.sqrt(np.mean((before - reference) ** 2))),
            "mean_after": float(after.mean()), "std_after": float(after.std()), "spread_after": spread(after),
            "rms_after": float(np.sqrt(np.mean((after - reference) ** 2)))}


def calibrate(rec: Recording, estimator, *, objective: str = "scalar", reference_total=None,
              rng: np.random.Generator) -> Calibration:
    """Fit ``estimator`` to the recording ``rec``.

    Parameters
    ----------
    rec : a loaded :class:`~magexp.recordings.Recording`.
    estimator : any estimator object (``fit(problem, *, rng)``) that applies to ``objective``.
    objective : ``scalar`` (total field) or ``vector`` (needs attitudes and ``# field:``).
    reference_total : overrides the recording's reference total field (its unit).
    rng : the estimator's random generator.

    Returns
    -------
    Calibration
        ``W``, offset, calibrated readings, the reference used, and the metrics of :func:`quality`.
    """
    from magexp.problems import make_problem

    check_size(rec)
    check_applies(estimator, objective)
    reference = reference_of(rec, reference_total)
    dataset = recording_dataset(rec, reference, objective)
    box = search_box(rec.readings, float(np.mean(reference.total)), forward=objective == "vector")
    problem = make_problem(objective, dataset, box)  # each objective's own parameterisation
    result = estimator.fit(problem, rng=rng)
    w, o = (a[0] for a in problem.unpack(result.x))
    if not np.all(np.isfinite(w)) or not np.all(np.isfinite(o)):
        raise MagexpError(f"estimator={estimator.name!r} gave a non-finite calibration of {rec.path.name}")
    calibrated = problem.calibrate(result.x)
    if reference.estimated:  # the scale is free: the mean calibrated magnitude is the reference
        w = w * reference.total[0] / np.linalg.norm(calibrated, axis=1).mean()
        calibrated = (rec.readings - o) @ w.T
    metrics = quality(rec.readings, calibrated, reference.total)
    if objective == "vector":
        metrics["vector_rms"] = float(np.sqrt(np.mean(np.sum((problem.reference - calibrated) ** 2, axis=1))))
    return Calibration(recording=rec, estimator=estimator.name, objective=objective, w=w, offset=o,
                       reference=reference, search=box, fit=result, calibrated=calibrated, metrics=metrics)
