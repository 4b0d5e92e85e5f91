"""Calibrate a recording or an array of readings, and say how good the calibration is.

Command line (its own primary config, ``conf/calibrate.yaml``)::

    magexp calibrate data.path=mine.csv [data.unit=uT] [estimator=lm] [out=folder] [KEY=VALUE ...]

Python::

    import magexp
    cal = magexp.calibrate(readings, unit="uT", estimator="ellipsoid")   # (N, 3) array or DataFrame
    cal.w, cal.offset, cal.report                                         # B = W (reading - offset)

Flow (the same as a simulated run, with a recording instead of a scenario)::

    recording (magexp.core.recordings) ──► dataset: readings, reference total, attitudes (if any)
    dataset + objective (scalar | vector) + search box from the data ──► problem
    estimator.fit(problem, rng=...) ──► W, o ──► canonical form, quality (magexp.core.identifiability), k-fold

Reference total field, first found of: ``data.reference_total`` (command line), the ``total``
column, ``# reference_total:``, the norm of ``# field:``, the ``field.model`` (``igrf`` or ``wmm``) total
at ``field.latitude``, ``field.longitude``, ``field.altitude_km``, ``field.date``, each taken from
the log's GPS when not given (:mod:`magexp.core.field_model`; ``igrf.*``: the older names of these
keys with ``field.model=igrf``); a raw-count recording is then calibrated to the model's total in nT. With none, the reference is *estimated*: the fit uses ``R0``, the radius of
the sphere fitted to the raw readings (:func:`centroid_radius`), as the radius, then ``W`` is rescaled so that
the mean calibrated magnitude equals ``R0``. The shape of the calibration (and the spread
std/mean) does not depend on this choice; the absolute scale does, and the output says so.

Search box of swarm estimators (:func:`search_box`), derived from the data: each offset
within the range of the readings, ``[min, max]`` over all three axes; matrix entries scaled
by ``s = reference / R0``: diagonal in ``[0.5 s, 1.5 s]``, off-diagonal in ``[-0.5 s, 0.5 s]``
(``1 / s`` instead of ``s`` for the vector objective, whose parameters are ``S = W^-1``: Yuan 2018).

Degenerate data (identical readings, a plane, one attitude, too few distinct directions) and an
estimator reporting failure raise one :class:`~magexp.errors.MagexpError` line that says why and
what to record instead (:mod:`magexp.calibration.checks`); the command then writes nothing.

Held-out check (:func:`heldout`): the readings' directions about the centre of the sphere fitted to them
are cut into six regions, one about each half-axis ``±v_k`` of their principal axes
(:func:`magexp.core.identifiability.direction_regions`); each region holding at least :data:`MIN_READINGS`
readings is calibrated by the fit on the others, and ``heldout_spread`` is the spread of the pooled
held-out magnitudes. Every region is thus tested on attitudes outside its fit (contiguous time blocks,
the earlier folds, lie in the plane of the rest on a turn about one axis and passed a calibration that
made the sensor's other recordings worse than raw). A region holding less than ``gate.min_region`` of
the readings was never tested: the gate refuses the calibration (:func:`magexp.calibration.checks.gate`).
"""

from __future__ import annotations

import os
import re
import sys
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from omegaconf import OmegaConf

from magexp.calibration import models as models_
from magexp.calibration.export import (TARGETS as EXPORT_TARGETS, check_counts_nt, check_max_rotation,
                                      options_of as export_options_of,
                                      render as render_export)
from magexp.calibration.onboard import onboard_of, saying_onboard, says_onboard
from magexp.calibration.checks import check_fit, check_optimum, check_readings, gate, gate_thresholds, refuse
from magexp.calibration.write import check_out, read_parameters, save_parameters, summary, table, write
from magexp.core.dataset import Dataset
from magexp.problems import kernels
from magexp.core.geometry import preintegrate
from magexp.core.identifiability import canonical, coverage, direction_regions, identifiability, spread
from magexp.core.field_model import check_given, check_model, field_of_recording, place_of
from magexp.core.recordings import (MAG_COLUMNS, UNITS, Recording, check_unique, check_unit, load_recording,
                                    resolve)
from magexp.core.seeding import run_generators
from magexp.errors import LARGEST, MagexpError, check_positive_int, exit_code
from magexp.estimators.base import check_applies
from magexp.estimators.reduced import UPPER, expand
from magexp.estimators.result import FitResult
from magexp.paths import CONF
from magexp.problems import make_problem, problem_class
from magexp.run.budget import check_calibration, check_recording_file
from magexp.run.compose import GROUPS, check_choice, compose_config, options, target_class
from magexp.run.outputs import print_table
from magexp.run.guard import (check_destination, check_folds, check_hydra_keys, check_override_targets,
                              check_override_values, readings_array)
from magexp.run.runner import build
from magexp.scenarios.search import SearchBox, centroid_radius, fit_sphere, search_box

#: Objectives a recording can be calibrated with.
OBJECTIVES = ("scalar", "vector")
#: Fewest readings accepted: the 12 parameters of ``W`` and ``o`` (a scalar fit identifies 9).
MIN_READINGS = 12
#: Calibration models (:mod:`magexp.calibration.models`): ``sphere``, ``diagonal``, ``full``, ``gyro`` and ``auto``.
MODELS = models_.MODELS
#: How each objective's ``W`` is reported.
FORMS = {"scalar": "symmetric positive-definite polar factor (W = Q P, reported P = (W^T W)^(1/2)): a total-field "
                   "fit cannot see a rotation of W",
         "vector": "as fitted (the vector objective determines the rotation)",
         "sphere": "s I (model=sphere: offset and one scale only)",
         "diagonal": "diag(w1, w2, w3) (model=diagonal: offset and one scale per axis)",
         "gyro": "as fitted (model=gyro: the gyro-aided fit determines the rotation into the gyroscope's axes)"}
#: The estimator of ``model=gyro`` (:mod:`magexp.calibration.models`): Levenberg-Marquardt from the gyro-aided
#: problem's two-stage start, whatever ``estimator`` is, its Jacobian from one stacked evaluation
#: (:func:`magexp.estimators.lm.stacked_jacobian`); at most 200 residual evaluations at a tolerance of
#: 1e-10 (documented defaults: a good recording converges well within them; one whose gyroscope does not
#: carry the attitude, e.g. a saturated one, stops there instead of running 2000 evaluations per fold).
GYRO_ESTIMATOR = {"name": "lm", "max_nfev": 200, "tol": 1e-10, "jacobian": "stacked"}


def gyro_estimator():
    """The estimator of ``model=gyro``: ``conf/estimator/lm.yaml``'s class with :data:`GYRO_ESTIMATOR`."""
    return target_class("estimator", "lm")(**GYRO_ESTIMATOR)
#: ``model=gyro`` fits at most this many readings, evenly spaced in time (the gyroscope integrated between
#: them), as the ``real_hmc5883l_*`` scenarios do (``n_readings: 300``): a documented default that bounds
#: the work of its 17-parameter fit (each held-out fold and the final fit) whatever the recording's length.
GYRO_READINGS = 300


@dataclass
class Reference:
    """The reference total field of a calibration.

    Attributes
    ----------
    total : (N,) reference total per reading (in the recording's unit).
    source : where it comes from (``data.reference_total``, ``total column``, ``IGRF-14 at ...``).
    estimated : True when no reference was given and the scale was fixed from the data.
    unit : the reference's unit when it differs from the recording's (a raw-count recording
        calibrated to a field model's total in nT); None: the recording's.
    record : the field model, generation and inputs it came from, or None.
    """

    total: np.ndarray
    source: str
    estimated: bool = False
    unit: str | None = None  # the reference's unit when it is not the recording's (counts calibrated to nT)
    record: dict | None = None  # a field model's name, generation and inputs (:meth:`ReferenceField.record`)

    def describe(self) -> str:
        mean = float(np.mean(self.total))
        if self.estimated:
            return (f"none given: estimated as the mean calibrated magnitude, scale fixed to the radius of the "
                    f"sphere fitted to the raw readings, {mean:.6g}")
        return f"{mean:.6g} from {self.source}"


@dataclass
class Calibration:
    """A fitted calibration ``B = W (reading - offset)`` of a recording, and how good it is.

    ``w`` is in the canonical form of :data:`FORMS` (``report["w_form"]``); ``metrics`` holds the
    spreads before, after and held out; ``report`` the standard errors, conditioning, the
    undetermined combinations, the direction coverage (:mod:`magexp.core.identifiability`), the
    acceptance gate's outcome and the model selection. A calibration read back by :meth:`load`
    has no recording (``recording`` None): it applies, exports and summarises, but has no
    readings to plot.
    """

    recording: Recording | None
    estimator: str
    objective: str
    w: np.ndarray
    offset: np.ndarray
    reference: Reference
    search: SearchBox | None
    fit: FitResult | None
    calibrated: np.ndarray
    metrics: dict = field(default_factory=dict)
    report: dict = field(default_factory=dict)
    seed: int = 0
    config: dict = field(default_factory=dict)  # the settings it was made with (the command's config, the call's)
    saved: dict | None = None  # the JSON it was loaded from (:meth:`load`)

    @property
    def unit(self) -> str:
        """Unit of the raw readings."""
        return self.recording.unit if self.recording is not None else self.saved["unit"]

    @property
    def field_unit(self) -> str:
        """Unit of the calibrated field (the recording's, or the field model's nT for raw counts)."""
        return self.reference.unit or self.unit

    @property
    def name(self) -> str:
        return self.recording.name if self.recording is not None else Path(self.saved["recording"]).name

    @property
    def model(self) -> str:
        return self.report.get("model", "full")

    def apply(self, readings) -> np.ndarray:
        """``B = W (r - o)`` of raw ``readings`` (``(N, 3)`` or ``(3,)``, the recording's unit)."""
        r = readings_array(readings)
        if r.shape[-1:] != (3,) or r.ndim > 2:
            raise MagexpError(f"readings of shape {r.shape} are not allowed: give (N, 3) or (3,) raw readings")
        return (r - self.offset) @ self.w.T

    def save(self, path, *, overwrite: bool = False) -> Path:
        """Write ``calibration.json`` content (versioned, with provenance) to ``path``; an existing
        file is refused in one line unless ``overwrite``. :meth:`load` reads it back exactly."""
        return save_parameters(self, path, overwrite=overwrite)

    @classmethod
    def load(cls, path) -> "Calibration":
        """A :class:`Calibration` from a ``calibration.json`` (:meth:`save`, ``magexp calibrate``)."""
        data = read_parameters(path)
        ref = data["reference"]
        reference = Reference(np.array([ref["total"]]), ref["source"], ref["estimated"], ref.get("unit"),
                              ref.get("field_model"))
        quality = data.get("quality", {})
        return cls(recording=None, estimator=data["estimator"], objective=data["objective"],
                   w=np.array(data["W"], float), offset=np.array(data["offset"], float), reference=reference,
                   search=None, fit=None, calibrated=np.zeros((0, 3)), metrics=data.get("metrics", {}),
                   report=quality, seed=data.get("seed", 0), config=data.get("config", {}), saved=data)

    def __repr__(self) -> str:
        m = self.metrics
        held = f", held out {100 * m['heldout_spread']:.3g} %" if "heldout_spread" in m else ""
        gate = self.report.get("gate") or {}
        state = "" if not gate else (", gate passed" if gate.get("passed") else ", gate FAILED (accepted)")
        return (f"<Calibration {self.name}: {self.model} model by {self.estimator}, spread "
                f"{100 * m.get('spread_before', float('nan')):.3g} % -> {100 * m.get('spread_after', float('nan')):.3g} %"
                f"{held}{state}; B = W (r - o), r in {self.unit}, B in {self.field_unit}>")

    def summary(self) -> str:
        """The printed summary of ``magexp calibrate`` (the key numbers, one per line)."""
        return table(summary(self))

    def plot(self):
        """The before/after figure (:mod:`magexp.calibration.figure`); returns the matplotlib Figure."""
        if self.recording is None:
            raise MagexpError("plot() is not allowed for a loaded calibration: it has no readings; calibrate the "
                              "recording again, or plot cal.apply(readings) yourself")
        from magexp.calibration.write import figure  # lazy: matplotlib only when a figure is drawn

        return figure(self)

    def export(self, target: str, path=None, **options) -> Path:
        """Write ``target``'s file (``ardupilot``, ``px4``, ``ros``, ``c``: :mod:`magexp.calibration.export`)."""
        from magexp.calibration.export import export  # lazy: yaml and the targets only when exporting

        return export(self, target, path, **options)


def reference_of(rec: Recording, override=None) -> Reference:
    """The reference total field of ``rec`` (see the module docstring for the order)."""
    n = rec.n
    if override is not None:
        try:
            value = float("nan") if isinstance(override, bool) else float(override)
        except (TypeError, ValueError):
            value = float("nan")
        if not (np.isfinite(value) and 0 < value <= LARGEST):
            raise MagexpError(f"data.reference_total={override!r} is not allowed: it must be a number > 0 and "
                              f"<= {LARGEST:g}")
        return Reference(np.full(n, value), "data.reference_total")
    if rec.total is not None:
        return Reference(np.asarray(rec.total, float), "the total column")
    if rec.reference_total is not None:
        return Reference(np.full(n, rec.reference_total), "'# reference_total:'")
    if rec.field is not None:
        return Reference(np.full(n, float(np.linalg.norm(rec.field))), "the norm of '# field:'")
    return Reference(np.full(n, centroid_radius(rec.readings)), "estimated", estimated=True)


def attitude_of(rec: Recording) -> np.ndarray | None:
    """Navigation -> sensor rotations ``(N, 3, 3)`` (:meth:`Recording.attitude`), or None."""
    return rec.attitude()


def recording_dataset(rec: Recording, reference: Reference, objective: str) -> Dataset:
    """The :class:`Dataset` of ``rec`` for ``objective`` (attitudes and field for ``vector``)."""
    if objective not in OBJECTIVES:
        raise MagexpError(f"objective={objective!r} is not allowed for magexp calibrate: choose one of "
                          f"{', '.join(OBJECTIVES)}")
    attitude, field_nav = None, None
    if objective == "vector":
        attitude = attitude_of(rec)
        if attitude is None or rec.field is None:
            raise MagexpError(f"objective='vector' is not allowed for {rec.name}: it needs attitudes "
                              "(heading, roll, trim or gx, gy, gz columns) and a '# field:' line; use objective=scalar")
        field_nav = np.broadcast_to(rec.field, (rec.n, 3)).copy()
    return Dataset(readings=rec.readings, reference_norm=reference.total, field_nav=field_nav, attitude=attitude,
                   unit=rec.unit, meta={"recording": str(rec.path), **rec.meta})


def gyro_dataset(rec: Recording, reference: Reference) -> Dataset:
    """The :class:`Dataset` of ``model=gyro`` (:class:`~magexp.problems.gyro.GyroAidedCalibration`): the
    readings (at most :data:`GYRO_READINGS`, evenly spaced), the reference total (the field's magnitude ``F``)
    and the gyroscope's rotation increments between their times (:func:`magexp.core.geometry.preintegrate`)."""
    stream, times = rec.gyro_rates(), rec.reading_times()
    if stream is None or times is None:
        models_.check_model("gyro", "scalar", gyro=False)
    keep = np.unique(np.round(np.linspace(0, rec.n - 1, min(rec.n, GYRO_READINGS))).astype(int))
    return Dataset(readings=rec.readings[keep], reference_norm=reference.total[keep], unit=rec.unit,
                   meta={"recording": str(rec.path), **rec.meta},
                   extra={"preintegration": preintegrate(*stream, times[keep])})


def check_size(rec: Recording) -> None:
    """At least :data:`MIN_READINGS` readings."""
    if rec.n < MIN_READINGS:
        raise MagexpError(f"{rec.name}: {rec.n} readings is not allowed: a calibration needs at least "
                          f"{MIN_READINGS} (the 12 parameters of W and the offset)")


#: readings whose mean step from one to the next is below this fraction of their radius are a time series
#: (:func:`noise_of`): the noise of neighbours is the sensor's; a shuffled set's steps are about 1.3 radii
SERIES_STEP = 0.25


def noise_of(raw: np.ndarray, calibrated: np.ndarray) -> float:
    """The readings' own noise in the calibrated magnitude: the RMS of its second differences over
    ``sqrt(6)`` (white noise of variance ``σ²`` has second differences of variance ``6 σ²``; a
    calibration error varies slowly with the attitude and cancels there). 0 when the readings are not
    a time series (their mean step over :data:`SERIES_STEP` of the raw radius), where neighbours are
    not close in time. The gate's RMS check discounts it (:func:`magexp.calibration.checks.gate`): a
    noisy sensor (the QMC5883L log: 6.04 % of 6.27 %) is not a bad calibration."""
    if len(raw) < 3 or np.linalg.norm(np.diff(raw, axis=0), axis=1).mean() > SERIES_STEP * centroid_radius(raw):
        return 0.0
    return float(np.sqrt(np.mean(np.diff(np.linalg.norm(calibrated, axis=1), 2) ** 2) / 6))


def quality(raw: np.ndarray, calibrated: np.ndarray, reference: np.ndarray) -> dict:
    """Magnitude statistics before and after, the RMS against the reference and the readings' noise (:func:`noise_of`)."""
    before, after = np.linalg.norm(raw, axis=1), np.linalg.norm(calibrated, axis=1)
    return {"mean_before": float(before.mean()), "std_before": float(before.std()), "spread_before": spread(before),
            "rms_before": float(np.sqrt(np.mean((before - reference) ** 2))),
            "mean_after": float(after.mean()), "std_after": float(after.std()), "spread_after": spread(after),
            "rms_after": float(np.sqrt(np.mean((after - reference) ** 2))), "noise_after": noise_of(raw, calibrated)}


def _fit(rec: Recording, estimator, objective: str, reference: Reference, rng, model: str = "full",
         dataset: Dataset | None = None) -> tuple:
    """``(W, o, calibrated, problem, result, box)`` of one fit (W canonical for a scalar objective);
    ``dataset``: the recording's :func:`recording_dataset`, when the caller has it already. ``problem``
    is the objective's, in its own parameterisation (the sphere model's residuals are the scalar
    problem's at ``W = s I``)."""
    if model == "gyro":  # its own problem and estimator (magexp.calibration.models)
        objective, dataset, estimator = "gyro", gyro_dataset(rec, reference), gyro_estimator()
    dataset = recording_dataset(rec, reference, objective) if dataset is None else dataset
    box = search_box(rec.readings, float(np.mean(reference.total)), forward=objective != "scalar")
    problem = make_problem(objective, dataset, box)  # each objective's own parameterisation
    if model in models_.CLOSED_FORM:
        w, o, calibrated, result = _closed_form(rec, model, reference)
        return w, o, calibrated, problem, result, box
    result = estimator.fit(problem, rng=rng)
    w, o = (a[0] for a in problem.unpack(result.x))
    if not np.all(np.isfinite(w)) or not np.all(np.isfinite(o)):
        raise MagexpError(f"{rec.name}: estimator={estimator.name!r} gave a non-finite calibration, nothing written: "
                          "try estimator=ellipsoid or estimator=lm")
    if objective == "scalar":
        w = canonical(w)
    calibrated = (rec.readings - o) @ w.T
    if reference.estimated:  # the scale is free: the mean calibrated magnitude is the reference
        w = w * reference.total[0] / np.linalg.norm(calibrated, axis=1).mean()
        calibrated = (rec.readings - o) @ w.T
    return w, o, calibrated, problem, result, box


def select_model(rec: Recording, estimator, objective: str, reference: Reference, folds: int, rng,
                 margin: float) -> tuple[str, dict, dict]:
    """``model=auto`` (:func:`magexp.calibration.models.select`): ``(model, record, held-out of each fitted
    candidate)``. ``gyro`` is dropped before any fit where it cannot succeed (no gyroscope, or a saturated one:
    :func:`magexp.calibration.models.gyro_unusable`), and the record says why."""
    unusable = models_.gyro_unusable(rec.gyro_rates())
    held = {m: heldout(rec, estimator, objective, reference, folds, rng, m)
            for m in models_.candidates(objective, gyro=not unusable)}
    model, selection = models_.select(lambda m: held[m].get("heldout_spread", float("nan")), objective,
                                      models_.check_margin(margin), gyro=not unusable,
                                      dropped={"gyro": unusable} if unusable and objective == "scalar" else {})
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
    regions (:func:`magexp.calibration.checks.check_optimum`): a swarm that fails on the folds is named, not the data."""
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
        _, _, calibrated, _, result, _ = _fit(rec, estimator_named("ellipsoid"), "scalar", reference, None, "full",
                                              dataset)
    except MagexpError:
        return None
    return spread(np.linalg.norm(calibrated, axis=1)) if result.success else None


def _closed_form(rec: Recording, model: str, reference: Reference) -> tuple:
    """``(W, o, calibrated, result)`` of a closed-form model (:data:`magexp.calibration.models.CLOSED_FORM`)."""
    radius = float(np.mean(reference.total))
    fitted = models_.CLOSED_FORM[model](rec.readings, radius)
    if fitted is None:
        raise MagexpError(f"{rec.name}: model={model!r}: the readings do not lie on an axis-aligned ellipsoid, "
                          "nothing written: try model=sphere, or record more orientations")
    w, centre = fitted
    result = FitResult(x=np.concatenate([w.ravel(), centre]), fun=float("nan"), nit=1, nfev=1,
                       history=np.zeros(1), history_nfev=np.ones(1), success=True,
                       message=f"closed-form {model} fit (no estimator)")
    calibrated = (rec.readings - centre) @ w.T
    if reference.estimated and model != "sphere":  # the scale is free: the mean calibrated magnitude is the reference
        w = w * reference.total[0] / np.linalg.norm(calibrated, axis=1).mean()
        calibrated = (rec.readings - centre) @ w.T
    return w, centre, calibrated, result


def regions(readings: np.ndarray) -> tuple[np.ndarray, dict]:
    """``(labels, record)``: the region of directions of each reading
    (:func:`magexp.core.identifiability.direction_regions` about the centre of the sphere fitted to them)
    and ``{direction_regions: fraction of the readings in each, region_axes: each region's half-axis}``
    (what the gate's ``min_region`` check reads)."""
    labels, axes = direction_regions(readings - fit_sphere(readings)[0])
    fractions = np.bincount(labels, minlength=6) / len(readings)
    return labels, {"direction_regions": fractions.tolist(), "region_axes": axes.tolist()}


def heldout(rec: Recording, estimator, objective: str, reference: Reference, folds: int, rng,
            model: str = "full") -> dict:
    """Spread of each region of directions calibrated by the fit on the others (module docstring): the
    regions of :func:`regions` holding at least :data:`MIN_READINGS` readings are held out one at a time
    (a smaller one's readings stay in every fit). ``folds`` < 2: no check. NaN when fewer than two
    regions can be held out or a fold cannot be fitted."""
    if folds < 2:
        return {}
    labels, _ = regions(rec.readings)
    counts = np.bincount(labels, minlength=6)
    tested = [k for k in range(6) if counts[k] >= MIN_READINGS]
    if len(tested) < 2:
        return {"heldout_spread": float("nan"), "heldout_folds": len(tested)}
    pooled, per_fold = [], []
    for k in tested:
        keep = np.flatnonzero(labels != k)
        train = rec.subset(keep)
        ref = Reference(reference.total[keep], reference.source, reference.estimated)
        try:
            w, o, _, _, result, _ = _fit(train, estimator, objective, ref, rng, model)
        except MagexpError:
            result = None
        if result is None or not result.success:  # a fold the model cannot fit: the model is not supported
            return {"heldout_spread": float("nan"), "heldout_folds": len(tested)}
        mags = np.linalg.norm((rec.readings[labels == k] - o) @ w.T, axis=1)
        pooled.append(mags)
        per_fold.append(spread(mags))
    return {"heldout_spread": spread(np.concatenate(pooled)), "heldout_spread_max_fold": float(np.max(per_fold)),
            "heldout_folds": len(tested)}


def report_of(objective: str, w, o, problem, model: str = "full", extra=()) -> dict:
    """Standard errors, conditioning, undetermined combinations (:func:`magexp.core.identifiability.identifiability`)
    of the reported parameters, over the residuals of the fit's own ``problem``
    (:meth:`~magexp.problems.base.CalibrationProblem.residual_stack`): ``[s, o]`` (``W = s I``) for the
    sphere model, the 6 upper entries of the symmetric ``W`` and ``o`` for the scalar objective,
    ``[vec W, o]`` for the vector one, ``[vec W, o]`` and ``extra`` (the field direction and gyro bias
    of the fit) for the gyro-aided model."""
    if model == "sphere":
        theta = np.concatenate([[w[0, 0]], o])
        names = ["s", "o1", "o2", "o3"]
        to_problem = lambda t: problem.pack(t[0] * np.eye(3), t[1:])  # noqa: E731
    elif model == "diagonal":
        theta = np.concatenate([np.diag(w), o])
        names = ["W11", "W22", "W33", "o1", "o2", "o3"]
        to_problem = lambda t: problem.pack(np.diag(t[:3]), t[3:])  # noqa: E731
    elif objective == "scalar":
        theta = np.concatenate([w.ravel()[UPPER], o])  # the 6 upper entries of the symmetric W, then o
        names = [f"W{k // 3 + 1}{k % 3 + 1}" for k in UPPER] + ["o1", "o2", "o3"]
        to_problem = lambda t: problem.pack(expand(t)[0, :9].reshape(3, 3), t[6:])  # noqa: E731
    else:
        theta = np.concatenate([w.ravel(), o, extra])
        names = ([f"W{i + 1}{j + 1}" for i in range(3) for j in range(3)] + ["o1", "o2", "o3"]
                 + problem.parameter_names()[12:])
        to_problem = lambda t: np.concatenate([problem.pack(t[:9].reshape(3, 3), t[9:12]), t[12:]])  # noqa: E731
    out = identifiability(lambda thetas: problem.residual_stack(thetas, of=to_problem), theta, names)
    se = out["standard_errors"]
    if model == "sphere":
        out["W_standard_errors"] = (np.eye(3) * se["s"]).tolist()
    elif model == "diagonal":
        out["W_standard_errors"] = np.diag([se["W11"], se["W22"], se["W33"]]).tolist()
    else:
        out["W_standard_errors"] = [[se[f"W{min(i, j) + 1}{max(i, j) + 1}"] if objective == "scalar"
                                     else se[f"W{i + 1}{j + 1}"] for j in range(3)] for i in range(3)]
    out["offset_standard_errors"] = [se["o1"], se["o2"], se["o3"]]
    out["w_form"] = FORMS[model if model in FORMS else objective]
    out["model"] = model
    return out


@says_onboard
def calibrate_recording(rec: Recording, estimator, *, objective: str = "scalar", reference_total=None,
                        folds: int = 6, rng: np.random.Generator, checks: bool = True,
                        model: str = "full", accept: bool = False, gate_overrides=None,
                        auto_margin: float = models_.MARGIN) -> Calibration:
    """Fit ``estimator`` to the recording ``rec``, measure how good the fit is and gate it.

    Parameters
    ----------
    rec : a loaded :class:`~magexp.core.recordings.Recording`.
    estimator : any estimator object (``fit(problem, *, rng)``) that applies to ``objective``.
    objective : ``scalar`` (total field) or ``vector`` (needs attitudes and ``# field:``).
    reference_total : overrides the recording's reference total field (its unit), a number or a
        :class:`Reference` (with its source).
    folds : the held-out check: 0 or 1 none; 2 or more, by regions of directions (:func:`heldout`).
    rng : the estimator's random generator.
    checks : refuse degenerate data, failed fits and calibrations failing the acceptance gate
        (:mod:`magexp.calibration.checks`); False measures them anyway.
    model : ``sphere``, ``diagonal``, ``full`` or ``auto`` (:mod:`magexp.calibration.models`;
        all but ``full`` need the scalar objective).
    accept : keep a calibration that fails the acceptance gate, its failures recorded in
        ``report["gate"]``.
    gate_overrides : ``gate.*`` thresholds (:func:`magexp.calibration.checks.gate_thresholds`).
    auto_margin : the parsimony margin of ``model=auto``.

    Returns
    -------
    Calibration
        ``W`` (canonical form), offset, calibrated readings, the reference used, the spread
        metrics, the quality report, the gate's outcome and (``auto``) the model selection.

    Raises
    ------
    MagexpError
        One line: bad input, degenerate data, a failed fit, or (unless ``accept``) every failed check of the gate.
    """
    check_size(rec)
    checks, accept = check_flag(checks, "checks"), check_flag(accept, "accept")
    models_.check_margin(auto_margin)
    folds = check_folds(folds)
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
    w, o, calibrated, problem, result, box = _fit(rec, estimator, objective, reference, rng, model, dataset)
    cover = coverage(rec.readings - o)  # the raw directions about the fitted centre: what the recording covered
    name = (f"{model} fit" if model in models_.CLOSED_FORM
            else GYRO_ESTIMATOR["name"] if model == "gyro" else estimator.name)
    if checks:
        check_converged(rec, estimator, objective, model, result, calibrated, reference, dataset)
        check_fit(rec.name, name, bool(result.success), result.message, cover,
                  coverage(rec.readings - fit_sphere(rec.readings)[0]))
    metrics = {**quality(rec.readings, calibrated, reference.total), **cover, **regions(rec.readings)[1]}
    if objective == "vector":
        metrics["vector_rms"] = float(np.sqrt(np.mean(np.sum((problem.reference - calibrated) ** 2, axis=1))))
    metrics.update(measured_heldout(rec, estimator, objective, reference, folds, rng, model, held, checks=checks))
    report = {**report_of(problem.objective, w, o, problem, model, extra=result.x[12:]),
              **gyro_extras(model, problem, result), **onboard_of(rec, metrics.get("heldout_spread"))}
    if selection is not None:
        report["model_selection"] = selection
    report["gate"] = gate_of(rec, w, metrics, reference, thresholds, checks=checks, accept=accept)
    return Calibration(recording=rec, estimator=name, objective=problem.objective, w=w, offset=o,
                       reference=reference, search=box, fit=result, calibrated=calibrated, metrics=metrics,
                       report=report)


@contextmanager
def numpy_kernels(on: bool):
    """Within the block, numpy computes the residuals (``MAGEXP_NUMBA=0``) when ``on`` and the user
    set no ``MAGEXP_NUMBA``; afterwards the process is as it was. A closed-form fit evaluates a few
    residual vectors, which numpy computes in milliseconds: loading the compiled kernels for them
    costs 0.75 s (numba import and cache load; cProfile, QMC5883L recording). Restoring matters when
    the command runs inside a longer process (a notebook, the tests): it once left numba off there."""
    if not on or "MAGEXP_NUMBA" in os.environ:
        yield
        return
    os.environ["MAGEXP_NUMBA"] = "0"
    kernels.compiled.cache_clear()
    try:
        yield
    finally:
        del os.environ["MAGEXP_NUMBA"]
        kernels.compiled.cache_clear()


def gyro_extras(model: str, problem, result) -> dict:
    """What the gyro-aided model reports beside ``W`` and ``o`` (nothing for the others): the field
    direction (rad) and the gyroscope's bias (deg/s) it fitted, and ``vector_rms``, the RMS of
    ``R_jᵀ h - W (r_j - o)`` over the readings the fit used (against the field the gyroscope carries to
    each reading; the recording's unit)."""
    if model != "gyro":
        return {}
    x = result.x
    residual = problem.residual_swarm(x[None])[0]
    return {"field_azimuth": float(x[12]), "field_elevation": float(x[13]),
            "gyro_bias_deg_s": [float(v) for v in x[14:17]],
            "vector_rms": float(np.sqrt(np.mean(np.sum(residual**2, axis=1))))}


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
            "thresholds": {k: list(v) if isinstance(v, tuple) else v for k, v in thresholds.items()}}


# -- the Python API --------------------------------------------------------------------------------
def frame_readings(frame) -> np.ndarray:
    """The ``(N, 3)`` readings of a DataFrame: its ``bx, by, bz`` (or ``mx, my, mz``, ``x, y, z``:
    :data:`~magexp.core.recordings.MAG_COLUMNS`) columns, else its three numeric columns."""
    cols = [str(c).strip().lower() for c in frame.columns]
    check_unique(cols, "readings")
    pick = next((names for names in MAG_COLUMNS if all(n in cols for n in names)), None)
    chosen = frame.iloc[:, [cols.index(n) for n in pick]] if pick else frame.select_dtypes("number")
    if chosen.shape[1] != 3:
        raise MagexpError(f"readings with columns {list(frame.columns)} are not allowed: give bx, by, bz "
                          "(or x, y, z), or exactly three numeric columns")
    return chosen.to_numpy(float)


def as_recording(readings, *, unit: str | None = None) -> Recording:
    """A :class:`Recording` from an ``(N, 3)`` array, a DataFrame (columns ``bx, by, bz`` or
    ``x, y, z``, else its three numeric columns), a path or a Recording."""
    if isinstance(readings, Recording):
        return readings
    if isinstance(readings, (str, Path)):
        return load_recording(readings, unit=unit)
    pandas = sys.modules.get("pandas")  # a DataFrame exists only if pandas is loaded: not importing it saves
    if pandas is not None and isinstance(readings, pandas.DataFrame):  # 240 ms (-X importtime) per calibration
        readings = frame_readings(readings)
    values = readings_array(readings)
    if values.ndim != 2 or values.shape[1] != 3:
        raise MagexpError(f"readings of shape {values.shape} are not allowed: give an (N, 3) array")
    if not np.all(np.isfinite(values)):
        raise MagexpError("readings with NaN or infinite values are not allowed: every value must be finite")
    if unit is None:
        raise MagexpError("unit=None is not allowed: name the unit of the readings (nT, uT, mG, G, T or counts)")
    return Recording(readings=values, angles=None, field=None, unit=check_unit(unit, "unit"),
                     meta={"format": "array", "name": "readings"})


def estimator_named(name: str, **overrides):
    """The estimator of ``conf/estimator/<name>.yaml`` (composed: :func:`magexp.run.compose.compose_config`)
    with ``overrides``."""
    check_choice("estimator", name)
    node = compose_config([f"estimator={name}"], config_name="calibrate").estimator
    unknown = [key for key in overrides if key not in node]
    if unknown:
        options = ", ".join(str(k) for k in node if not str(k).startswith("_") and k != "name")
        raise MagexpError(f"{unknown[0]}={overrides[unknown[0]]!r} is not allowed: estimator {name!r} has no option "
                          f"{unknown[0]!r} (options: {options})")
    return build(OmegaConf.merge(node, overrides), f"estimator {name!r}")


def calibrate(readings, *, unit: str | None = None, estimator="ellipsoid", objective: str = "scalar",
              reference_total=None, folds: int = 6, seed: int = 0, checks: bool = True, model: str = "auto",
              accept: bool = False, gate=None, auto_margin: float = models_.MARGIN,
              **estimator_options) -> Calibration:
    """Calibrate readings from a notebook: ``magexp.calibrate(readings, unit="uT", estimator="lm")``.

    Parameters
    ----------
    readings : ``(N, 3)`` array, DataFrame (``bx, by, bz`` / ``x, y, z`` columns), a recording's path,
        or a :class:`~magexp.core.recordings.Recording`.
    unit : unit of an array or DataFrame (``nT, uT, mG, G, T, counts``).
    estimator : a name of ``conf/estimator/*.yaml`` (``ellipsoid``, ``lm``, ``ipso``, ...) or an estimator object.
    objective, reference_total, folds, checks, model, accept, auto_margin : as :func:`calibrate_recording`.
    gate : ``gate.*`` thresholds overriding :data:`magexp.calibration.checks.GATE` (a dict).
    seed : the estimator's random generator derives from it (:func:`magexp.core.seeding.run_generators`).
    estimator_options : overrides of the estimator config (e.g. ``n_iterations=200``).

    Returns
    -------
    Calibration
        ``.w`` (canonical form), ``.offset``, ``.calibrated``, ``.metrics`` (spread before, after,
        held out; coverage), ``.report`` (standard errors, conditioning, undetermined combinations).

    Raises
    ------
    MagexpError
        One line for degenerate data, a failed estimator or bad input.
    """
    rec = as_recording(readings, unit=unit)
    if not isinstance(estimator, str) and not callable(getattr(estimator, "fit", None)):
        raise MagexpError(f"estimator={estimator!r} is not allowed: give an estimator's name ("
                          f"{', '.join(options('estimator'))}) or an object with a fit(problem, rng=...) method")
    est = estimator_named(estimator, **estimator_options) if isinstance(estimator, str) else estimator
    seed = check_positive_int(seed, "seed", minimum=0)
    _, rng = run_generators(seed)
    cal = calibrate_recording(rec, est, objective=objective, reference_total=reference_total, folds=folds,
                              rng=rng, checks=checks, model=model, accept=accept, gate_overrides=gate,
                              auto_margin=auto_margin)
    cal.seed = seed
    cal.config = {"readings": str(readings) if isinstance(readings, (str, Path)) else type(readings).__name__,
                  "unit": unit, "estimator": est.name if hasattr(est, "name") else str(estimator),
                  "objective": objective, "reference_total": None if reference_total is None else
                  float(np.mean(cal.reference.total)), "folds": folds, "seed": seed, "checks": checks, "model": model,
                  "accept": accept, "gate": dict(gate or {}), "auto_margin": auto_margin, **estimator_options}
    return cal


# -- the command -----------------------------------------------------------------------------------
def calibrate_config(argv: list[str]):
    """The config of ``conf/calibrate.yaml`` with the ``KEY=VALUE`` overrides ``argv``, composed as every
    command's config is (:func:`magexp.run.compose.compose_config`)."""
    bad = [a for a in argv if "=" not in a]
    if bad:
        raise MagexpError(f"argument {bad[0]!r} is not allowed: magexp calibrate takes KEY=VALUE overrides "
                          "(e.g. data.path=mine.csv data.unit=uT estimator=lm)")
    check_hydra_keys(argv)
    check_override_targets(argv)  # no code from an override, before the recording is read
    argv = check_override_values(argv)
    for arg in argv:
        if arg.partition("=")[0] in GROUPS:
            check_choice(*arg.split("=", 1))
    return compose_config(argv, config_name="calibrate")


def field_keys(cfg) -> dict:
    """``field.*`` of ``cfg``, with the older ``igrf.*`` keys as aliases (``field.model=igrf``)."""
    place = {k: v for k, v in dict(cfg.get("field") or {}).items()}
    old = {k: v for k, v in dict(cfg.get("igrf") or {}).items() if v is not None and k != "altitude_km"}
    if old:
        if place.get("latitude") is not None:
            raise MagexpError(f"igrf.latitude={old.get('latitude')!r} is not allowed with field.latitude: igrf.* is "
                              "the older name of field.* (with field.model=igrf), give field.* only")
        place.update(dict(cfg.igrf), model="igrf")
    check_model(place.get("model"))  # a bad model named even when no place asks for one
    check_given({**dict(cfg.get("igrf") or {}), "model": "igrf"}, "igrf")
    check_given(place)
    return place


def reference_from_field(cfg, rec: Recording) -> Reference | None:
    """The field model's total where and when ``rec`` was recorded (:mod:`magexp.core.field_model`):
    ``field.latitude/longitude/altitude_km/date`` (each, if not given, from the log's GPS), or None
    when neither the command line nor the log gives a place. In the recording's unit; a raw-count
    recording is calibrated to the model's total in nT (``W`` then maps counts to nT)."""
    place = field_keys(cfg)
    if place.get("latitude") is None and not {"latitude", "date"} <= set(place_of(rec)):
        return None
    ref = field_of_recording(rec, model=place.get("model") or "igrf", latitude=place.get("latitude"),
                             longitude=place.get("longitude"), altitude_km=place.get("altitude_km"),
                             date=place.get("date"), prefix="field")
    unit = rec.unit if rec.unit in UNITS else "nT"
    inputs = ref.record()
    where = f"{ref.generation} at {inputs['latitude']:g}, {inputs['longitude']:g}, {inputs['date']}"
    return Reference(np.full(rec.n, ref.total / UNITS[unit]), where, unit=None if unit == rec.unit else unit,
                     record=inputs)


def run(cfg) -> Calibration:
    """Load, calibrate, check and write as ``cfg`` says; print the summary."""
    data = cfg.data
    check_options(cfg)
    rec = recording_of(cfg)
    out = cfg.get("out")
    out_dir = Path(f"calibration_{rec.path.stem}") if out is None else Path(str(out))
    check_destination(out_dir if out is None else out, "out")
    overwrite, draw = flag(cfg, "overwrite"), flag(cfg, "figure")
    target, options = export_of(cfg, rec)
    check_out(out_dir, overwrite=overwrite, export=target)
    estimator = build(cfg.estimator, f"estimator {cfg.estimator.get('name')!r}")
    seed = check_positive_int(cfg.seed, "seed", minimum=0)
    _, est_rng = run_generators(seed)
    reference = data.get("reference_total")
    if reference is None:
        reference = reference_from_field(cfg, rec)
    with numpy_kernels(not getattr(estimator, "iterative", True)):
        cal = calibrate_recording(rec, estimator, objective=cfg.objective, reference_total=reference,
                                  folds=cfg.folds, rng=est_rng, model=cfg.model, accept=flag(cfg, "accept"),
                                  gate_overrides=cfg.get("gate"), auto_margin=cfg.get("auto_margin", models_.MARGIN))
    cal.seed, cal.config = seed, OmegaConf.to_container(cfg, resolve=True)
    paths = write(cal, out_dir, draw=draw, overwrite=overwrite, export=target, export_options=options)
    print(table({**summary(cal), "written to": ", ".join(str(p) for p in paths.values())
                 + (" (replacing the earlier calibration's files: overwrite=true)" if overwrite else "")
                 + ("" if draw else "; no figure (figure=true draws it)")}))
    return cal


def check_options(cfg) -> None:
    """The keys that a run may not use checked before anything is read: every given ``field.*`` and
    ``igrf.*`` value (used only when a place is known, and not at all beside ``data.reference_total``),
    ``counts_nt`` and ``max_rotation_deg`` (used only by some exports), ``auto_margin`` (only by
    ``model=auto``): a bad value is refused in one line, not ignored."""
    field_keys(cfg)
    if cfg.get("counts_nt") is not None:
        check_counts_nt(cfg.counts_nt)
    if cfg.get("max_rotation_deg") is not None:
        check_max_rotation(cfg.max_rotation_deg)
    models_.check_margin(cfg.get("auto_margin", models_.MARGIN))


def recording_of(cfg) -> Recording:
    """The recording ``data.*`` names (its size checked before it is read; ``instance``: a DataFlash log's compass)."""
    data = cfg.data
    if data.get("path") is None or not str(data.path).strip():
        raise MagexpError(f"data.path={data.get('path')!r} is not allowed: give data.path=<recording file>")
    check_recording_file(resolve(data.path))  # its size within the readings limit, before it is read
    instance = cfg.get("instance")
    instance = None if instance is None else check_positive_int(instance, "instance", minimum=0)
    return load_recording(data.path, unit=data.get("unit"), format=data.get("format") or "auto",
                          mag_axes=data.get("mag_axes"), gyro_axes=data.get("gyro_axes"), instance=instance)


def export_of(cfg, rec: Recording) -> tuple[str | None, dict | None]:
    """``(target, options)`` of ``export=<target>`` (``(None, None)`` without one), checked before the fit:
    the target's name, and its options on an identity calibration (``counts_nt`` for raw counts, the
    rotation limit, the slot: :func:`export_options`)."""
    target = cfg.get("export")
    if target is None:
        return None, None
    if str(target) not in EXPORT_TARGETS:
        raise MagexpError(f"export={target!r} is not allowed: choose one of {', '.join(EXPORT_TARGETS)} (or null)")
    options = export_options(cfg, str(target), rec)
    render_export(str(target), np.eye(3), np.zeros(3), rec.unit, **options)
    return str(target), options


def export_options(cfg, target: str, rec: Recording) -> dict:
    """The options of ``export=<target>`` from the command line (those the target takes,
    :func:`magexp.calibration.export.options_of`): ``counts_nt``, ``max_rotation_deg`` and ``instance``, the
    parameter slot (null: a ULog's calibration slot, else 0; a DataFlash log's instance is the one read)."""
    slot = cfg.get("instance")
    given = {"counts_nt": cfg.get("counts_nt"), "max_rotation_deg": cfg.get("max_rotation_deg"),
             "instance": int(rec.meta.get("calibration_slot", 0)) if slot is None else slot}
    return {k: v for k, v in given.items() if v is not None and k in export_options_of(target)}


def flag(cfg, key: str) -> bool:
    """A true/false key of ``cfg`` (default false), else one line."""
    return check_flag(cfg.get(key, False), key)


def check_flag(value, key: str) -> bool:
    """``value`` if it is a bool (``"yes"``, ``1`` or ``"no"`` are not: a string is always true), else one line."""
    if not isinstance(value, (bool, np.bool_)):
        raise MagexpError(f"{key}={value!r} is not allowed: give {key}=true or {key}=false")
    return bool(value)


_KEY_LINE = re.compile(r"^(?P<indent> *)(?P<key>[A-Za-z_]\w*):\s*(?P<value>[^#]*?)\s*(#\s*(?P<text>.*))?$")


def help_text(path: Path = CONF / "calibrate.yaml") -> str:
    """``magexp calibrate --help``: every key of ``conf/calibrate.yaml`` (dotted), its default and the
    sentence its comment gives (the one home of both), then the estimators to choose from."""
    rows, parents, last = [], [], None
    for line in path.read_text().splitlines():
        match = _KEY_LINE.match(line)
        if match is None:
            comment = line.strip()
            if last is not None and comment.startswith("#") and line.startswith("   "):
                last[2] += " " + comment.lstrip("# ")  # a comment continued on the next line
            continue
        depth = len(match["indent"]) // 2
        parents[depth:] = [match["key"]]
        if match["key"] == "defaults" or not match["value"] and not match["text"]:
            last = None
            continue
        last = [".".join(parents), match["value"] or "(group)", match["text"] or ""]
        rows.append(last)
    width = max(len(k) for k, *_ in rows)
    lines = ["magexp calibrate KEY=VALUE ...: calibrate a recording (docs/calibrate.md)", "",
             "e.g. magexp calibrate data.path=mine.csv data.unit=uT", "",
             f"{'key':<{width}}  default: meaning"]
    lines += [f"{k:<{width}}  {v}: {t}" for k, v, t in rows]
    lines += ["", f"estimator: one of {', '.join(options('estimator'))} (conf/estimator/*.yaml; "
              "estimator.<option>=... sets its options)"]
    return "\n".join(lines)


def command(argv: list[str]) -> None:
    """``magexp calibrate KEY=VALUE ...``: compose, check, calibrate, write; errors are raised (the
    one error path, :func:`magexp.errors.guarded`, turns them into one line and an exit code).
    ``--help`` (``-h``) prints :func:`help_text`."""
    if any(a in ("--help", "-h") for a in argv):
        print(help_text())
        return
    run(calibrate_config(argv))


def main(argv: list[str] | None = None) -> int:
    """``python -m magexp.calibration.fit KEY=VALUE ...`` (= ``magexp calibrate``): 0 on success; one
    line on stderr and exit 2 on bad input or degenerate data (nothing written), 3 on a bug."""
    return exit_code(command, sys.argv[1:] if argv is None else list(argv))


if __name__ == "__main__":
    sys.exit(main())
