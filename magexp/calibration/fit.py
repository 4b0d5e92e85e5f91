"""The pipeline of a calibration: read → fit → checks → outputs (:func:`calibrate_recording`), and say how
good the calibration is. The API (:func:`magexp.calibration.api.calibrate`) and the command
(:mod:`magexp.calibration.command`, ``magexp calibrate``) both run it; its stages: the inputs
(:mod:`magexp.calibration.inputs`), the fit and the held-out regions (here), the quality
(:mod:`magexp.calibration.quality`), the refusals (:mod:`magexp.calibration.checks`), the outputs
(:mod:`magexp.calibration.write`).

Flow (the same as a simulated run, with a recording instead of a scenario)::

    recording (magexp.core.recordings) ──► dataset (magexp.core.recording.recording_dataset): readings, reference, attitudes
    dataset + objective (scalar | vector) + search box from the data ──► problem
    estimator.fit(problem, rng=...) ──► W, o ──► canonical form, quality (magexp.core.identifiability), k-fold

Reference total field, first found of: ``data.reference_total`` (command line), the ``total``
column, ``# reference_total:``, the norm of ``# field:``, the ``field.model`` (``igrf`` or ``wmm``) total
at ``field.latitude``, ``field.longitude``, ``field.altitude_km``, ``field.date``, each taken from
the log's GPS when not given (:mod:`magexp.core.field_model`; ``igrf.*``: the older names of these
keys with ``field.model=igrf``); a raw-count recording is then calibrated to the model's total in nT. With none, the reference is *estimated*: the fit uses ``R0``, the radius of
the sphere fitted to the raw readings (:func:`~magexp.scenarios.search.centroid_radius`), as the radius, then ``W`` is rescaled so that
the mean calibrated magnitude equals ``R0``. The shape of the calibration (and the spread
std/mean) does not depend on this choice; the absolute scale does, and the output says so.

Search box (:func:`magexp.calibration.model_fit.search_box_of`). The scalar ``model=full`` fit of an iterative estimator (the swarms, the
black-box baselines) searches a box centred on the closed-form ellipsoid fit of the same readings, ``W``
within :data:`~magexp.calibration.box.MATRIX_MARGIN` times its largest eigenvalue and the offset within
:data:`~magexp.calibration.box.OFFSET_MARGIN` times its shortest semi-axis
(:func:`magexp.calibration.box.calibration_box`): it holds the optimum whatever the unit, the offset or the
anisotropy, where the readings' range box below clipped it, and it keeps the swarms out of the scalar
objective's valley of far offsets. Where the closed form fails, the box is the readings' range, and the
box's record says so. Every other fit (a closed form, the vector objectives) has the readings' range box
(:func:`magexp.scenarios.search.search_box`): each offset within the range of the readings, ``[min, max]``
over all three axes; matrix entries scaled by ``s = reference / R0``: diagonal in ``[0.5 s, 1.5 s]``,
off-diagonal in ``[-0.5 s, 0.5 s]`` (``1 / s`` instead of ``s`` for the vector objective, whose parameters
are ``S = W^-1``: Yuan 2018). Each held-out fold derives its box from its own fitted readings.

Degenerate data (identical readings, a plane, one attitude, too few distinct directions) and an
estimator reporting failure raise one :class:`~magexp.errors.MagexpError` line that says why and
what to record instead (:mod:`magexp.calibration.checks`); the command then writes nothing.

Held-out check (:func:`heldout`, its designs in :mod:`magexp.calibration.holdout`): the readings' directions
about the centre of the sphere fitted to them are cut into six regions, one about each half-axis ``±v_k`` of
their principal axes (:func:`magexp.core.identifiability.direction_regions`); where each occupied region holds at
least :data:`~magexp.calibration.checks.MIN_READINGS` readings, each is calibrated by the fit on the others, and ``heldout_spread`` is the
spread of the pooled held-out magnitudes. Every region is thus tested on attitudes outside its fit (contiguous
time blocks, the earlier folds, lie in the plane of the rest on a turn about one axis and passed a calibration that
made the sensor's other recordings worse than raw). Where a region is too small to be a fold (a couple of dozen
static shots), each reading is calibrated by the fit on the readings more than
:data:`~magexp.calibration.holdout.EXCLUSION_DEG` from its direction (a gap as large as a region). A region
holding less than ``gate.min_region`` of the readings was never tested: the gate refuses the calibration
(:func:`magexp.calibration.checks.gate`).
"""

from __future__ import annotations

import os

import numpy as np

from magexp.calibration import holdout, models as models_
from magexp.calibration.checks import (check_fit, check_optimum, check_readings, estimator_name, gate, gate_thresholds,
                                      is_broken_estimator, refuse)
from magexp.calibration.onboard import onboard_of, saying_onboard, says_onboard
from magexp.calibration.inputs import OBJECTIVES, Reference, check_size, recording_dataset, reference_of
from magexp.calibration.export import firmware_correction
from magexp.calibration.heading import heading_of, worst_left
from magexp.calibration.model_fit import GYRO_ESTIMATOR, fit_model, fold_fit
from magexp.calibration.quality import gyro_extras, quality, report_of
from magexp.calibration.result import Calibration
from magexp.core.dataset import Dataset
from magexp.core.field_model import gps_field
from magexp.core.ellipsoid import fit_sphere
from magexp.core.identifiability import coverage, direction_regions, spread
from magexp.core.recording import UNITS, Recording
from magexp.errors import MagexpError
from magexp.estimators.base import check_applies
from magexp.estimators.result import FitResult
from magexp.problems import problem_class
from magexp.run.budget import check_calibration
from magexp.run.compose import options, target_class
from magexp.run.named import estimator_named
from magexp.scenarios.search import centroid_radius

#: Calibration models (:mod:`magexp.calibration.models`): ``sphere``, ``diagonal``, ``full``, ``gyro`` and ``auto``.
MODELS = models_.MODELS


def select_model(rec: Recording, estimator, objective: str, reference: Reference, folds: int, rng,
                 margin: float) -> tuple[str, dict, dict]:
    """``model=auto`` (:func:`magexp.calibration.models.select`): ``(model, record, held-out of each fitted
    candidate)``. ``gyro`` is dropped before any fit where it cannot succeed (no gyroscope, or a saturated one:
    :func:`magexp.calibration.models.gyro_unusable`), and the record says why."""
    unusable = models_.gyro_unusable(rec.gyro_rates())
    held = {}

    def measure(m, beat):  # only gyro's folds stop once it cannot win: the others' records are checked and reported
        held[m] = heldout(rec, estimator, objective, reference, folds, rng, m,
                         beat=beat if m in models_.NEEDS_GYRO else None)
        return held[m].get("heldout_spread", float("nan")), held[m].get("heldout_stopped", False)

    try:
        model, selection = models_.select(measure, objective, models_.check_margin(margin), gyro=not unusable,
                                          dropped={"gyro": unusable} if unusable and objective == "scalar" else {},
                                          bounded=True)
    except MagexpError:
        failures = [r.get("heldout_failure") for r in held.values()]
        if held and all(failures):  # no candidate held out: the simplest one's cause is the recording's
            raise MagexpError(f"{rec.name}: model=auto: no model could be tested on readings it was not fitted to, "
                              f"nothing written: {failures[0]}") from None
        raise
    return model, selection, held


def check_gyro(rec: Recording, model: str) -> None:
    """Refuse ``model=gyro`` in one line, before any fit, where it cannot succeed
    (:func:`magexp.calibration.models.gyro_unusable`: a saturated gyroscope); other models pass."""
    why = models_.gyro_unusable(rec.gyro_rates()) if model == "gyro" else None
    if why:
        raise MagexpError(f"{rec.name}: model='gyro' cannot succeed, nothing fitted: {why}: choose model=full, "
                          "or record turning more slowly")


def check_converged(rec: Recording, estimator, objective: str, model: str, result: FitResult, calibrated: np.ndarray,
                    reference: Reference, dataset: Dataset) -> None:
    """An iterative estimator's successful ``model=full`` scalar fit must reach the closed-form optimum
    (:func:`magexp.calibration.checks.check_optimum`); other fits are not checked."""
    if not (result.success and model == "full" and objective == "scalar" and getattr(estimator, "iterative", True)):
        return
    check_optimum(rec.name, estimator, spread(np.linalg.norm(calibrated, axis=1)),
                  closed_form_spread(rec, reference, dataset))


def measured_heldout(rec: Recording, estimator, objective: str, reference: Reference, folds: int, rng, model: str,
                     held: dict, *, checks: bool) -> dict:
    """The held-out record of ``model`` (:func:`heldout`; ``held``: those ``model=auto`` measured already), after,
    with ``checks``, the held-out spread of ``model=full`` has been checked against the closed-form optimum
    (:func:`check_heldout_converged`)."""
    record = held.get(model) or heldout(rec, estimator, objective, reference, folds, rng, model)
    if checks:
        check_heldout_converged(rec, estimator, objective, held.get("full") or {model: record}.get("full", {}),
                                reference, folds, rng)
    return record


def check_heldout_converged(rec: Recording, estimator, objective: str, full: dict, reference: Reference,
                            folds: int, rng) -> None:
    """An iterative estimator's held-out spread of ``model=full`` (``full``: :func:`heldout`'s record of that
    model, the candidate's under ``model=auto``; empty for another model) must be within
    :data:`~magexp.calibration.checks.OPTIMUM_FACTOR` of the closed-form ellipsoid fit's, measured on the same
    regions (:func:`magexp.calibration.checks.check_optimum`): a swarm that fails on the folds is named, not the data.
    """
    value = full.get("heldout_spread")
    if value is None or objective != "scalar" or not getattr(estimator, "iterative", True):
        return
    closed = heldout(rec, estimator_named("ellipsoid"), "scalar", reference, folds, rng, "full").get("heldout_spread")
    check_optimum(rec.name, estimator, value, closed, what="held-out spread")


def closed_form_spread(rec: Recording, reference: Reference, dataset: Dataset) -> float | None:
    """The spread of the closed-form ellipsoid fit (``estimator=ellipsoid``, ``model=full``) of ``rec``, or
    None where it is not an ellipsoid: the optimum an iterative estimator must reach
    (:func:`magexp.calibration.checks.check_optimum`). Milliseconds beside any iterative fit."""
    try:
        _, _, calibrated, _, result, _ = fit_model(rec, estimator_named("ellipsoid"), "scalar", reference, None, "full",
                                              dataset)
    except MagexpError:
        return None
    return spread(np.linalg.norm(calibrated, axis=1)) if result.success else None


def regions(readings: np.ndarray) -> tuple[np.ndarray, dict]:
    """``(labels, record)``: the region of directions of each reading
    (:func:`magexp.core.identifiability.direction_regions` about the centre of the sphere fitted to them)
    and ``{direction_regions: fraction of the readings in each, region_axes: each region's half-axis}``
    (what the gate's ``min_region`` check reads)."""
    labels, axes = direction_regions(readings - fit_sphere(readings)[0])
    fractions = np.bincount(labels, minlength=6) / len(readings)
    return labels, {"direction_regions": fractions.tolist(), "region_axes": axes.tolist()}


def heldout(rec: Recording, estimator, objective: str, reference: Reference, folds: int, rng,
            model: str = "full", beat: float | None = None) -> dict:
    """Spread of readings calibrated by fits that have not seen their directions (module docstring): by regions of
    directions, or, where a region is too small to be a fold (a few static shots), each reading by the fit
    without its neighbours in direction (:mod:`magexp.calibration.holdout`). ``folds`` < 2: no check. NaN, with
    ``heldout_failure`` saying why, when a fold cannot be fitted (or, gyro-aided, collapsed:
    :func:`magexp.calibration.models.collapsed`); stopped early once it cannot pool below ``beat``."""
    if folds < 2:
        return {"heldout_design": "none", "heldout_folds": folds}

    def fit_on(keep):
        train = rec.subset(keep)
        ref = Reference(reference.total[keep], reference.source, reference.estimated)
        try:
            w, o, result = fold_fit(train, estimator, objective, ref, rng, model)
        except MagexpError as exc:
            if is_broken_estimator(exc):  # a broken estimator, not a fold the model cannot fit
                raise
            return None
        if not result.success or (model == "gyro" and models_.collapsed(train.readings, o)):
            return None  # a fold the model cannot fit: the model is not supported
        return w, o

    return holdout.measure(rec.readings, regions(rec.readings)[0], fit_on, model,
                           stop=lambda pooled, total, n: models_.stopped(pooled, total, beat, n))


@says_onboard
def calibrate_recording(rec: Recording, estimator, *, objective: str = "scalar", reference_total=None,
                        folds: int = 6, rng: np.random.Generator, checks: bool = True,
                        model: str = "full", accept: bool = False, gate_overrides=None,
                        auto_margin: float = models_.MARGIN) -> Calibration:
    """Fit ``estimator`` to the recording ``rec``, measure how good the fit is and gate it."""
    check_size(rec)
    checks, accept = check_flag(checks, "checks"), check_flag(accept, "accept")
    models_.check_margin(auto_margin)
    folds = holdout.check_folds(folds)
    if objective not in OBJECTIVES:
        raise MagexpError(f"objective={objective!r} is not allowed: choose one of {', '.join(OBJECTIVES)}")
    check_calibration(rec.n, folds, estimator, problem_class(objective))  # readings, folds, memory and work within magexp.run.budget's limits
    has_gyro = rec.gyro_rates() is not None
    model = models_.check_model(model, objective, gyro=has_gyro)
    thresholds = gate_thresholds(gate_overrides)
    check_applies(estimator, problem_class(objective),
                  alternatives=lambda: {n: target_class("estimator", n) for n in options("estimator")})
    reference = reference_total if isinstance(reference_total, Reference) else reference_of(rec, reference_total)
    dataset = recording_dataset(rec, reference, objective)  # the objective's needs first (attitudes, field)
    if checks:
        check_readings(rec.readings, rec.name)
        check_gyro(rec, model)
    selection, held = None, {}
    if model == "auto" and folds < 2:  # nothing held out to choose by: the richest model, and say so
        model, selection = "full", {"chosen": "full", "why": f"full: folds={folds}, no held-out check to choose by",
                                    "margin": auto_margin, "heldout_spread": {}}
    if model == "auto":
        model, selection, held = select_model(rec, estimator, objective, reference, folds, rng, auto_margin)
    w, o, calibrated, problem, result, box = fit_model(rec, estimator, objective, reference, rng, model, dataset)
    cover = coverage(rec.readings - o)  # the raw directions about the fitted centre: what the recording covered
    name = (f"{model} fit" if model in models_.CLOSED_FORM
            else GYRO_ESTIMATOR["name"] if model == "gyro" else estimator_name(estimator))
    if checks:
        check_converged(rec, estimator, objective, model, result, calibrated, reference, dataset)
        check_fit(rec.name, "gyro fit" if model == "gyro" else name, bool(result.success), result.message, cover,
                  coverage(rec.readings - fit_sphere(rec.readings)[0]))
    metrics = {**quality(rec.readings, calibrated, reference.total), **cover, **regions(rec.readings)[1]}
    if objective == "vector":
        metrics["vector_rms"] = float(np.sqrt(np.mean(np.sum((problem.reference - calibrated) ** 2, axis=1))))
    metrics.update(measured_heldout(rec, estimator, objective, reference, folds, rng, model, held, checks=checks))
    fits = metrics.pop(holdout.FITS, [])
    report = {**report_of(problem.objective, w, o, problem, model, extra=result.x[12:]),
              **gyro_extras(model, problem, result), **onboard_of(rec, metrics.get("heldout_spread"))}
    if selection is not None:
        report["model_selection"] = selection
    cal = Calibration(recording=rec, estimator=name, objective=problem.objective, w=w, offset=o,
                      reference=reference, search=box, fit=result, calibrated=calibrated, metrics=metrics,
                      report=report, heldout_fits=fits)
    report["heading"] = heading_of(cal, firmware_correction(cal), gps=gps_field(rec))  # before the gate: gate.max_heading_deg reads it
    report["gate"] = gate_of(rec, w, {**metrics, "heading_left_deg": worst_left(report["heading"])}, reference,
                             thresholds, checks=checks, accept=accept)
    return cal


def numpy_path(compiled: bool | None, estimator) -> bool:
    """Whether a calibration by ``estimator`` takes the kernels' numpy path (:func:`magexp.problems.kernels.numpy_only`).

    A closed-form fit evaluates a few residual vectors, which numpy computes in milliseconds: loading the
    compiled kernels for them costs 0.75 s (numba import and cache load; cProfile, QMC5883L recording)."""
    if compiled is None:
        return not getattr(estimator, "iterative", True) and "MAGEXP_NUMBA" not in os.environ
    return not check_flag(compiled, "compiled")


def gate_of(rec: Recording, w, metrics: dict, reference: Reference, thresholds: dict, *, checks: bool,
            accept: bool) -> dict:
    """The acceptance gate's outcome (:func:`magexp.calibration.checks.gate`): refused in one line
    unless ``accept`` (or ``checks`` is False); ``{passed, failed, accepted_anyway, thresholds}``."""
    failed = gate(w, metrics, raw_radius=centroid_radius(rec.readings), reference=float(np.mean(reference.total)),
                  estimated=reference.estimated or reference.unit is not None, to_mg=UNITS[rec.unit] / 100.0 if rec.unit in UNITS else None,
                  thresholds=thresholds)
    if failed and checks and not accept:
        with saying_onboard(rec, metrics.get("heldout_spread")):
            refuse(rec.name, failed)
    return {"passed": not failed, "failed": failed, "accepted_anyway": bool(failed) and accept,
            "heldout": holdout.describe(metrics),
            "thresholds": {k: list(v) if isinstance(v, tuple) else v for k, v in thresholds.items()}}


def check_flag(value, key: str) -> bool:
    """``value`` if it is a bool (``"yes"``, ``1`` or ``"no"`` are not: a string is always true), else one line."""
    if not isinstance(value, (bool, np.bool_)):
        raise MagexpError(f"{key}={value!r} is not allowed: give {key}=true or {key}=false")
    return bool(value)

