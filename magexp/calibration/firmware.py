"""The firmware's side of a calibration: its units, its symmetric matrix and its orientation.

magexp's calibration is ``B = W (r − o)`` in the recording's unit. ArduPilot and PX4 hold it in
their own unit, as a symmetric matrix, with the sensor's rotation in a parameter of its own;
:func:`to_firmware` gives the :class:`Correction` each renderer of :mod:`magexp.calibration.export`
writes.

**Units.** The raw readings the firmware sees are the recording's readings times
``k_in`` (firmware unit per recording unit, from :data:`magexp.core.recordings.UNITS`), and its
calibrated field is ``B`` times ``k_out`` (the field's unit, the recording's unless
``field_unit`` says otherwise: a raw-count recording calibrated to a field model's total in nT).
A reading in ``counts`` has no factor: ``counts_nt`` gives the nanotesla per count of the
firmware's driver. Then ``B_fw = (k_out / k_in) W (r_fw − k_in o)``: the matrix is scaled by
``k_out / k_in``, the offset by ``k_in`` (:func:`to_firmware`).

**Symmetrising W (ArduPilot, PX4).** Their matrix is symmetric. magexp's ``W`` is factored by the
polar decomposition ``W = R S`` (``W = U Σ Vᵀ``: ``R = U Vᵀ`` a rotation, ``S = V Σ Vᵀ`` symmetric
positive definite) and the firmware gets ``S``; its calibrated field is then ``Rᵀ B``: magexp's
field turned by ``Rᵀ``. A total-field (scalar) calibration cannot see ``R`` at all (magexp reports
``W`` as ``S``: ``R = I``); a vector (attitude-aided) calibration finds ``R``, the misalignment
between the magnetometer and the attitude's body frame, which belongs in the firmware's
orientation parameter (``COMPASS_ORIENT``, ``CAL_MAGn_ROT``), not in the matrix (for PX4, whose
``R`` is known from a log, ``px4(..., rotation=R)`` takes it out of ``W`` first). The export
refuses, in one line, an ``R`` turning by more than ``max_rotation_deg`` (default
:data:`MAX_ROTATION_DEG`, a documented default: 1° of heading error is what a good compass
calibration is expected to leave) and a ``W`` with a negative determinant (a mirrored axis).

**Orientation (the gyro-aided model).** Where ``R`` is determined (``model=gyro`` on readings in the
magnetometer's own axes, ``orient=True``), it is written as the firmware's orientation parameter when
it lies within ``max_rotation_deg`` of one of the firmware's standard rotations ``R_n``
(:data:`STANDARD_ROTATIONS`: the enum both ArduPilot's ``AP_Math/rotations.h`` and PX4's
``src/lib/conversion/rotation.h`` number 0-40, ``R_n = R_z(yaw) R_y(pitch) R_x(roll)``, the rotation from
the sensor's axes to the body's): ``W = R_n (R_n^T W)`` and ``R_n^T W`` is symmetrised as above, its own
rotation (the residual, at most ``max_rotation_deg``) left out. PX4 applies the rotation last,
``B = R_n S (r − OFF)``: ``CAL_MAGn_ROT = n``, ``S`` and ``OFF`` in the sensor's axes. ArduPilot
applies it first, ``B = M (R_n r + OFS)``: ``COMPASS_ORIENT = n``, ``M = R_n S R_n^T``,
``OFS = −R_n o``. Both firmwares use that parameter for an external magnetometer only (an internal
one follows the board's orientation); the file says so. Farther than ``max_rotation_deg`` from every
standard rotation, ArduPilot takes ``R`` itself as its custom rotation (``COMPASS_ORIENT=101``,
``CUST_ROT_ENABLE=1``, ``CUST_ROT1_ROLL``/``_PITCH``/``_YAW`` its Euler angles, ``R = R_z(yaw) R_y(pitch) R_x(roll)``:
:func:`euler_321`; ArduPilot 4.2 or later), and nothing is left out; PX4's ``CAL_MAGn_ROT`` holds only the
standard rotations, so its export refuses in one line naming ``max_rotation_deg=`` with the residual, which
would be left out.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from magexp.core.geometry import rot_x, rot_y, rot_z, rotation_angle
from magexp.core.recording import RAW_UNITS, UNITS
from magexp.errors import MagexpError

#: the largest rotation ``R`` of ``W = R S`` a symmetric-only target accepts (degrees; a config value)
MAX_ROTATION_DEG = 1.0
#: the firmware's standard sensor rotations: enum value -> (roll, pitch, yaw) in degrees, as both ArduPilot
#: (``AP_Math/rotations.h``, ``COMPASS_ORIENT``) and PX4 (``src/lib/conversion/rotation.h``, ``CAL_MAGn_ROT``)
#: number them; 38 (roll 90, pitch 68, yaw 293: one board's mounting) is left out, and the two firmwares'
#: lists part after 40
STANDARD_ROTATIONS = {
    0: (0, 0, 0), 1: (0, 0, 45), 2: (0, 0, 90), 3: (0, 0, 135), 4: (0, 0, 180), 5: (0, 0, 225), 6: (0, 0, 270),
    7: (0, 0, 315), 8: (180, 0, 0), 9: (180, 0, 45), 10: (180, 0, 90), 11: (180, 0, 135), 12: (0, 180, 0),
    13: (180, 0, 225), 14: (180, 0, 270), 15: (180, 0, 315), 16: (90, 0, 0), 17: (90, 0, 45), 18: (90, 0, 90),
    19: (90, 0, 135), 20: (270, 0, 0), 21: (270, 0, 45), 22: (270, 0, 90), 23: (270, 0, 135), 24: (0, 90, 0),
    25: (0, 270, 0), 26: (0, 180, 90), 27: (0, 180, 270), 28: (90, 90, 0), 29: (180, 90, 0), 30: (270, 90, 0),
    31: (90, 180, 0), 32: (270, 180, 0), 33: (90, 270, 0), 34: (180, 270, 0), 35: (270, 270, 0),
    36: (90, 180, 90), 37: (90, 0, 270), 39: (0, 315, 0), 40: (90, 315, 0)}
#: ArduPilot's ``ROTATION_CUSTOM_1`` (``COMPASS_ORIENT=101``): the rotation of ``CUST_ROT1_ROLL``, ``_PITCH``,
#: ``_YAW`` (ArduPilot 4.2 and later, ``CUST_ROT_ENABLE=1``; ``AP_CustomRotations``), any rotation
CUSTOM_ORIENTATION = 101


@dataclass(frozen=True)
class Correction:
    """A calibration in a target's unit: ``B = matrix (r − offset)``; ``rotation`` the ``R`` of
    ``W = R S`` taken out of a symmetrised matrix (identity otherwise)."""

    matrix: np.ndarray
    offset: np.ndarray
    unit: str
    field_unit: str
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    orientation: int | None = None
    field_scale: float = 1.0  # k_out: the target's field unit per the calibration's (module docstring)
    custom: np.ndarray | None = None

    @property
    def rotation_deg(self) -> float:
        """The angle of :attr:`rotation` in degrees (0 when nothing was taken out)."""
        return float(np.rad2deg(rotation_angle(self.rotation)))

    @property
    def orientation_matrix(self) -> np.ndarray:
        """``R_n`` of :attr:`orientation`, the :attr:`custom` rotation, or the identity when none is exported."""
        if self.custom is not None:
            return self.custom
        return np.eye(3) if self.orientation is None else standard_rotation(self.orientation)




def polar(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(R, S)`` with ``W = R S``, ``R`` orthogonal, ``S`` symmetric positive semi-definite (SVD)."""
    u, sigma, vt = np.linalg.svd(np.asarray(w, float))
    s = vt.T @ np.diag(sigma) @ vt
    return u @ vt, (s + s.T) / 2


def standard_rotation(index: int) -> np.ndarray:
    """The rotation matrix of a firmware's standard rotation."""
    roll, pitch, yaw = np.radians(STANDARD_ROTATIONS[index])
    return rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)


def euler_321(rotation: np.ndarray) -> tuple[float, float, float]:
    """``(roll, pitch, yaw)`` in degrees with ``rotation = R_z(yaw) R_y(pitch) R_x(roll)`` (ArduPilot's
    ``Matrix3::from_euler``, the order of its ``CUST_ROTn_*``; pitch in [-90, 90])."""
    r = np.asarray(rotation, float)
    return (float(np.degrees(np.arctan2(r[2, 1], r[2, 2]))), float(np.degrees(-np.arcsin(np.clip(r[2, 0], -1, 1)))),
            float(np.degrees(np.arctan2(r[1, 0], r[0, 0]))))


def nearest_orientation(rotation: np.ndarray) -> tuple[int, float]:
    """The standard rotation nearest to ``rotation`` and the angle left between them."""
    indices = list(STANDARD_ROTATIONS)
    angles = np.rad2deg(rotation_angle(np.stack([standard_rotation(i).T @ rotation for i in indices])))
    best = int(np.argmin(angles))
    return indices[best], float(angles[best])


def _number(value) -> float:
    """``value`` as a float (NaN for anything that is not a number, a bool included)."""
    return float(value) if isinstance(value, (int, float, np.number)) and not isinstance(value, bool) else float("nan")


def check_counts_nt(counts_nt) -> float:
    """``counts_nt`` (nT per count) as a float, else one line."""
    value = _number(counts_nt)
    if not (np.isfinite(value) and value > 0):
        raise MagexpError(f"counts_nt={counts_nt!r} is not allowed: it must be a number > 0 (nT per count)")
    return value


def check_max_rotation(max_rotation_deg) -> float:
    """``max_rotation_deg`` as a float in [0, 180], else one line."""
    limit = _number(max_rotation_deg)
    if not 0 <= limit <= 180:
        raise MagexpError(f"max_rotation_deg={max_rotation_deg!r} is not allowed: it must be a number of degrees in "
                          "[0, 180]")
    return limit


def _factor(unit: str, target_unit: str, counts_nt, what: str) -> float:
    """Target units per ``unit``: from :data:`UNITS`, or ``counts_nt`` for a raw unit."""
    if unit in RAW_UNITS:
        if counts_nt is None:
            raise MagexpError(f"{what} {unit!r} has no known factor to nT: give counts_nt=<nT per count of the "
                              "firmware's magnetometer driver> to export it")
        return check_counts_nt(counts_nt) / UNITS[target_unit]
    if unit not in UNITS:
        raise MagexpError(f"{what} {unit!r} is not allowed: choose one of {', '.join((*UNITS, *RAW_UNITS))}")
    return UNITS[unit] / UNITS[target_unit]


def to_firmware(w, offset, unit: str, target_unit: str | None, *, field_unit: str | None = None, counts_nt=None,
                symmetric: bool = False, max_rotation_deg: float = MAX_ROTATION_DEG, orient: bool = False,
                custom: bool = False) -> Correction:
    """magexp's ``B = W (r − o)`` in a target's unit and form: with ``symmetric``, ``W = R S`` (:func:`polar`) and
    ``S`` exported, ``R`` refused beyond ``max_rotation_deg`` unless ``orient`` (``R`` determined: the nearest
    standard rotation, or with ``custom`` ``R`` itself, becomes the sensor's orientation)."""
    w, offset = np.asarray(w, float), np.asarray(offset, float)
    if w.shape != (3, 3) or offset.shape != (3,) or not (np.all(np.isfinite(w)) and np.all(np.isfinite(offset))):
        raise MagexpError(f"a calibration with W of shape {w.shape} and offset of shape {offset.shape} is not allowed: "
                          "W must be 3 x 3 and the offset 3 numbers, all finite")
    field_unit = unit if field_unit is None else field_unit
    if target_unit is None:
        k_in = k_out = 1.0
    else:
        k_in = _factor(unit, target_unit, counts_nt, "unit")
        k_out = _factor(field_unit, target_unit, counts_nt, "field_unit")
    limit = check_max_rotation(max_rotation_deg)
    rotation, orientation, turn = np.eye(3), None, None
    if symmetric:
        w, rotation, orientation, turn = _symmetrised(w, limit, orient=orient, custom=custom)
    return Correction(matrix=(k_out / k_in) * w, offset=k_in * offset, unit=target_unit or unit,
                      field_unit=target_unit or field_unit, rotation=rotation, orientation=orientation,
                      field_scale=k_out, custom=turn)


def _symmetrised(w: np.ndarray, limit: float, *, orient: bool, custom: bool) -> tuple:
    """``(S, R left out, orientation, custom rotation or None)`` of :func:`to_firmware`'s symmetric branch."""
    if np.linalg.det(w) <= 0:
        raise MagexpError(f"W with determinant {np.linalg.det(w):.3g} is not allowed for a firmware's symmetric "
                          "matrix: it mirrors an axis; set the magnetometer's orientation in the firmware first")
    rotation, s = polar(w)
    angle = float(np.rad2deg(rotation_angle(rotation)))
    orientation, turn = None, None
    if orient:
        orientation, residual = nearest_orientation(rotation)
        if residual > limit and custom:
            orientation, turn = CUSTOM_ORIENTATION, rotation
        elif residual > limit:
            roll, pitch, yaw = STANDARD_ROTATIONS[orientation]
            raise MagexpError(f"W turns the field by {angle:.2f} deg (W = R S, R a rotation), {residual:.2f} deg "
                              f"from the nearest of the firmware's standard orientations ({orientation}: roll {roll}, "
                              f"pitch {pitch}, yaw {yaw}), over the limit {limit:g}: the heading would be off by up "
                              f"to that much (CAL_MAGn_ROT holds only the standard orientations; ArduPilot's "
                              f"COMPASS_ORIENT=101 with CUST_ROT1_* holds any); allow it with "
                              f"max_rotation_deg={np.ceil(residual * 10) / 10:g} to export orientation {orientation} and S")
        rotation, s = polar((standard_rotation(orientation) if turn is None else turn).T @ w)
    elif angle > limit:
        raise MagexpError(f"W turns the field by {angle:.2f} deg (W = R S, R a rotation): the firmware's symmetric "
                          f"matrix holds S only, so its heading would be off by up to that much; set the "
                          f"magnetometer's orientation to R in the firmware, or allow it with "
                          f"max_rotation_deg={np.ceil(angle * 10) / 10:g} to export S alone")
    return s, rotation, orientation, turn
