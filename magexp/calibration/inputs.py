"""What a calibration is fitted to: the reference total field of a recording (:class:`Reference`,
:func:`reference_of`) and its
:class:`~magexp.core.dataset.Dataset` for the objective or the gyro-aided model (:func:`recording_dataset`,
:func:`gyro_dataset`: the one path from a recording to a Dataset, :func:`magexp.core.recording.recording_dataset`,
which the recorded scenarios take too). The first stage of the pipeline (:mod:`magexp.calibration.fit`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from magexp.calibration import models as models_
from magexp.calibration.checks import MIN_READINGS
from magexp.core.dataset import Dataset
from magexp.core.recording import Recording, evenly_spaced, recording_dataset as dataset_of
from magexp.errors import LARGEST, MagexpError
from magexp.scenarios.search import centroid_radius

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
    record: dict | None = None  # a field model's name, generation and inputs (:meth:`magexp.core.field_model.ReferenceField.record`)

    def describe(self) -> str:
        """The reference in one line, as the summary prints it."""
        mean = float(np.mean(self.total))
        if self.estimated:
            return (f"none given: estimated as the mean calibrated magnitude, scale fixed to the radius of the "
                    f"sphere fitted to the raw readings, {mean:.6g}")
        return f"{mean:.6g} from {self.source}"



#: Objectives a recording can be calibrated with.
OBJECTIVES = ("scalar", "vector")

#: ``model=gyro`` fits at most this many readings, evenly spaced in time (the gyroscope integrated between
#: them), as the ``real_hmc5883l_*`` scenarios do (``n_readings: 300``): a documented default that bounds
#: the work of its 17-parameter fit (each held-out fold and the final fit) whatever the recording's length.
GYRO_READINGS = 300


def check_reference_total(override) -> float:
    """``data.reference_total`` as a float, or one line unless it is a number > 0 and <= LARGEST."""
    try:
        value = float("nan") if isinstance(override, bool) else float(override)
    except (TypeError, ValueError):
        value = float("nan")
    if not (np.isfinite(value) and 0 < value <= LARGEST):
        raise MagexpError(f"data.reference_total={override!r} is not allowed: it must be a number > 0 and "
                          f"<= {LARGEST:g}")
    return value


def reference_of(rec: Recording, override=None) -> Reference:
    """The reference total field of ``rec`` (see the module docstring for the order)."""
    n = rec.n
    if override is not None:
        return Reference(np.full(n, check_reference_total(override)), "data.reference_total")
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
    """The :class:`Dataset` of ``rec`` for ``objective`` (attitudes and field for ``vector``): the one path
    from a recording to a Dataset, :func:`magexp.core.recording.recording_dataset`, which the scenarios take too."""
    if objective not in OBJECTIVES:
        raise MagexpError(f"objective={objective!r} is not allowed for magexp calibrate: choose one of "
                          f"{', '.join(OBJECTIVES)}")
    return dataset_of(rec, reference.total, objective)


def gyro_dataset(rec: Recording, reference: Reference) -> Dataset:
    """The :class:`Dataset` of ``model=gyro`` (:class:`~magexp.problems.gyro.GyroAidedCalibration`): the
    readings (at most :data:`GYRO_READINGS`, evenly spaced), the reference total (the field's magnitude ``F``)
    and the gyroscope's rotation increments between their times (:func:`magexp.core.geometry.preintegrate`)."""
    if rec.gyro_rates() is None or rec.reading_times() is None:
        models_.check_model("gyro", "scalar", gyro=False)
    return dataset_of(rec, reference.total, "gyro", keep=evenly_spaced(rec.n, GYRO_READINGS))


def check_size(rec: Recording) -> None:
    """At least :data:`MIN_READINGS` readings."""
    if rec.n < MIN_READINGS:
        raise MagexpError(f"{rec.name}: {rec.n} readings is not allowed: a calibration needs at least "
                          f"{MIN_READINGS} (the 12 parameters of W and the offset)")


def readings_array(readings):
    """``readings`` as a float array, or one line: complex numbers and masked arrays are refused
    (their imaginary part and their mask would be dropped silently), as is anything that is not
    numbers."""
    if np.ma.isMaskedArray(readings):
        raise MagexpError("masked readings are not allowed: a masked array's hidden values would be used; give "
                          "only the valid readings (readings[~readings.mask.any(axis=1)].data)")
    if readings is None or isinstance(readings, (bytes, dict, set)):
        raise MagexpError(f"readings of type {type(readings).__name__} are not allowed: give an (N, 3) array, "
                          "a DataFrame or a recording's path")
    try:
        raw = np.asarray(readings)
    except (TypeError, ValueError) as exc:
        raise MagexpError(f"readings are not allowed: they are not an array of numbers ({str(exc)[:80]})") from None
    if np.iscomplexobj(raw):
        raise MagexpError("complex readings are not allowed: a magnetometer reading is real; give the real (N, 3) "
                          "array")
    if raw.dtype.kind not in "biuf":
        try:
            raw = raw.astype(float)
        except (TypeError, ValueError):
            raise MagexpError(f"readings of type {raw.dtype} are not allowed: every value must be a number") from None
        if np.iscomplexobj(raw):
            raise MagexpError("complex readings are not allowed: a magnetometer reading is real")
    values = raw.astype(float)
    if values.size and not np.all(np.abs(values[np.isfinite(values)]) <= LARGEST):
        raise MagexpError(f"readings larger than {LARGEST:g} in magnitude are not allowed")
    return values
