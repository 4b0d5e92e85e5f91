"""Export a calibration where users put it: ArduPilot and PX4 parameter files, a ROS parameter file, a C header.

magexp's calibration is ``B = W (r − o)`` in the recording's unit (:mod:`magexp.calibration.fit`):
``r`` a raw reading, ``o`` the offset, ``B`` the calibrated field. Each target holds it in its
own convention and unit:

``ardupilot`` (a ``.param`` file, mGauss)
    ``B = M (s (r + OFS))`` (``AP_Compass_Backend::correct_field``): ``M`` symmetric with
    ``COMPASS_DIA_X/Y/Z`` on its diagonal and ``COMPASS_ODI_X/Y/Z`` = ``M_xy, M_xz, M_yz`` off it,
    ``s = COMPASS_SCALE``, ``r`` the body-frame raw field; holds a symmetric ``S`` only.
``px4`` (a QGroundControl ``.params`` file, gauss)
    ``B = R S (r − OFF)`` (``Magnetometer::Correct``, ``src/lib/sensor_calibration/Magnetometer.hpp``):
    ``S`` symmetric with ``CAL_MAGn_XSCALE/YSCALE/ZSCALE`` on its diagonal and
    ``CAL_MAGn_XODIAG/YODIAG/ZODIAG`` = ``S_xy, S_xz, S_yz`` off it, ``R`` the board or
    ``CAL_MAGn_ROT`` rotation (kept as set); holds a symmetric ``S`` only.
``ros`` (a ROS 2 parameter YAML, ``<node>: ros__parameters: magnetometer_calibration:``, tesla)
    ``B = W (r − o)``, ``matrix`` the full ``W`` row-major, ``offset`` 3 numbers (tesla, the unit
    of ``sensor_msgs/MagneticField``).
``c`` (a C header, the recording's units)
    ``B = W (r − o)``: ``static const float`` arrays ``<NAME>_OFFSET[3]``, ``<NAME>_MATRIX[3][3]``
    and ``<name>_apply(raw, out)``.

**Units, the symmetric matrix and the orientation** are the firmware's side of a calibration,
:mod:`magexp.calibration.firmware` (:func:`~magexp.calibration.firmware.to_firmware`).

**ArduPilot's scale.** ``COMPASS_SCALE`` is written as 1 (ArduPilot applies a scale only within
``[0.85, 1.4]``; the whole of ``S`` sits in ``DIA/ODI``, exact for any scale), and written
explicitly so that an earlier value on the vehicle does not rescale the new calibration. ArduPilot's
own calibrator accepts diagonals within ``[0.2, 5]``, off-diagonals within ``[-1, 1]`` and offsets
up to ``COMPASS_OFFS_MAX`` (default 1800 mGauss, a pre-arm check): values outside are reported in
:attr:`Export.warnings` and in the file's comments.

Values are written with Python's shortest round-trip ``repr`` (``%.9g`` in the C header's float
literals): the firmware rounds them to float32 when it loads them.
"""

from __future__ import annotations

import inspect
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from magexp.calibration.heading import export_line, heldout_note
from magexp.calibration.firmware import (MAX_ROTATION_DEG, STANDARD_ROTATIONS, Correction, check_counts_nt,
                                         check_max_rotation, euler_321, to_firmware)
from magexp.calibration.folder import check_file, file_path, recording_files
from magexp.core.atomic import write_text
from magexp.errors import MagexpError
from magexp.run.folders import check_destination

#: the export targets
TARGETS = ("ardupilot", "px4", "ros", "c")
#: each target's unit (``None``: the recording's own)
TARGET_UNITS = {"ardupilot": "mG", "px4": "G", "ros": "T", "c": None}
#: the file name each target is written to by default
FILE_NAMES = {"ardupilot": "magexp_compass.param", "px4": "magexp_mag.params", "ros": "magexp_mag_calibration.yaml",
              "c": "magexp_mag_calibration.h"}
#: each target's orientation parameter (``{n}``: ArduPilot's compass suffix, PX4's slot)
ORIENTATION_KEYS = {"ardupilot": "COMPASS_ORIENT{n}", "px4": "CAL_MAG{n}_ROT"}
#: ArduPilot's calibrator's accepted ranges (``CompassCalibrator``) and ``COMPASS_OFFS_MAX``'s default (mGauss)
ARDUPILOT_DIAGONAL, ARDUPILOT_OFFDIAGONAL, ARDUPILOT_OFFSET_MAX = (0.2, 5.0), (-1.0, 1.0), 1800.0
#: MAVLink's ``MAV_PARAM_TYPE_REAL32`` and ``MAV_PARAM_TYPE_INT32``, the type column of a QGroundControl ``.params`` file
REAL32, INT32 = 9, 6


@dataclass(frozen=True)
class Export:
    """A rendered export: its ``target``, file ``text``, the ``values`` written (name -> number
    for the parameter targets) and ``warnings`` (values outside the firmware's accepted ranges)."""

    target: str
    text: str
    values: dict
    warnings: tuple = ()



def _comments(notes: dict | None, convention: str, correction: Correction, marker: str, site=None) -> list[str]:
    """The file's head comment lines: the convention, the orientation and rotation, the heading error (with a
    ``site``: :func:`magexp.calibration.heading.export_line`), the notes."""
    lines = [f"{marker} magexp magnetometer calibration", f"{marker} {convention}"]
    if correction.orientation is not None:
        roll, pitch, yaw = (STANDARD_ROTATIONS.get(correction.orientation) or
                            tuple(float(f"{a:.6g}") for a in euler_321(correction.custom)))
        kind = "custom: CUST_ROT1_* of ArduPilot 4.2 or later, " if correction.custom is not None else ""
        lines.append(f"{marker} orientation {correction.orientation} ({kind}roll {roll}, pitch {pitch}, yaw {yaw} deg) from the "
                     "gyro-aided fit: the magnetometer's axes as recorded to the gyroscope's; the firmware applies it to "
                     "an external magnetometer only (an internal one follows the board orientation)")
    if correction.rotation_deg > 0:
        lines.append(f"{marker} W = R S (polar decomposition): S exported, R turns by "
                     f"{correction.rotation_deg:.3g} deg (the firmware's field is R^T times magexp's)")
    heading = export_line(correction, *(site or (None, None)))
    lines += [f"{marker} {heading}"] if heading else []
    for key, value in (notes or {}).items():
        text = " ".join(str(value).split())  # one line
        lines.append(f"{marker} {key}: {text}")
    return lines


def ardupilot(w, offset, unit: str, *, field_unit=None, counts_nt=None, instance: int = 0,
              max_rotation_deg: float = MAX_ROTATION_DEG, orient: bool = False, notes: dict | None = None,
              site=None) -> Export:
    """ArduPilot parameters (a Mission Planner / MAVProxy ``.param`` file, ``NAME,VALUE`` lines).

    Convention (``AP_Compass_Backend::correct_field``): ``B = M (s (r + OFS))``, mGauss, ``r`` the
    body-frame raw field (after ``COMPASS_ORIENT``). From ``B = S' (r − o')`` (:func:`to_firmware`,
    mGauss): ``COMPASS_OFS = −o'``, ``M = S'``, ``COMPASS_SCALE = 1``. ``instance`` 0, 1, 2 (as the
    log's ``MAG`` instance, :func:`magexp.core.readers.dataflash.read_dataflash`): the names
    ``COMPASS_OFS_X``, ``COMPASS_OFS2_X``, ``COMPASS_OFS3_X`` (``DIA``, ``ODI``, ``SCALE`` alike).
    ``orient``: ``W``'s rotation was determined (:func:`to_firmware`); its standard rotation ``R_n`` is
    written as ``COMPASS_ORIENT`` (applied before the offsets): ``M = R_n S' R_n^T``, ``OFS = −R_n o'``; farther than
    ``max_rotation_deg`` from every standard one, ``R`` itself as the custom rotation (``COMPASS_ORIENT=101``,
    ``CUST_ROT_ENABLE=1``, ``CUST_ROT1_ROLL``/``_PITCH``/``_YAW``; :data:`~magexp.calibration.firmware.CUSTOM_ORIENTATION`).
    """
    if instance not in (0, 1, 2):
        raise MagexpError(f"instance={instance!r} is not allowed for ardupilot: choose 0, 1 or 2 (the compass)")
    c = to_firmware(w, offset, unit, TARGET_UNITS["ardupilot"], field_unit=field_unit, counts_nt=counts_nt, symmetric=True,
                    max_rotation_deg=max_rotation_deg, orient=orient, custom=True)
    n = "" if instance == 0 else str(instance + 1)
    turn = c.orientation_matrix
    m, ofs = turn @ c.matrix @ turn.T, -(turn @ c.offset)
    values = {**{f"COMPASS_OFS{n}_{a}": float(ofs[i]) for i, a in enumerate("XYZ")},
              **{f"COMPASS_DIA{n}_{a}": float(m[i, i]) for i, a in enumerate("XYZ")},
              **{f"COMPASS_ODI{n}_{a}": float(v) for a, v in zip("XYZ", (m[0, 1], m[0, 2], m[1, 2]))},
              f"COMPASS_SCALE{n}": 1.0}
    if c.orientation is not None:
        values[ORIENTATION_KEYS["ardupilot"].format(n=n)] = c.orientation
    if c.custom is not None:  # AP_CustomRotations: Matrix3::from_euler(roll, pitch, yaw), shared by the board's sensors
        values["CUST_ROT_ENABLE"] = 1
        values.update({f"CUST_ROT1_{k}": v for k, v in zip(("ROLL", "PITCH", "YAW"), euler_321(c.custom))})
    warnings = _ardupilot_warnings(values, ofs)
    head = _comments(notes, "ArduPilot: B = M (COMPASS_SCALE (raw + COMPASS_OFS)), M = [[DIA_X, ODI_X, ODI_Y], "
                            "[ODI_X, DIA_Y, ODI_Z], [ODI_Y, ODI_Z, DIA_Z]]; mGauss, body frame", c, "#", site)
    head += [f"# WARNING: {text}" for text in warnings]
    text = "\n".join(head + [f"{k},{v!r}" for k, v in values.items()]) + "\n"
    return Export("ardupilot", text, values, tuple(warnings))


def _ardupilot_warnings(values: dict, ofs: np.ndarray) -> list[str]:
    """The values of an ArduPilot export outside its calibrator's ranges (:func:`ardupilot`)."""
    warnings = []
    for key, value in values.items():
        if "_DIA" in key and not ARDUPILOT_DIAGONAL[0] <= value <= ARDUPILOT_DIAGONAL[1]:
            warnings.append(f"{key}={value:.6g} is outside ArduPilot's calibrator range {list(ARDUPILOT_DIAGONAL)}")
        if "_ODI" in key and not ARDUPILOT_OFFDIAGONAL[0] <= value <= ARDUPILOT_OFFDIAGONAL[1]:
            warnings.append(f"{key}={value:.6g} is outside ArduPilot's calibrator range {list(ARDUPILOT_OFFDIAGONAL)}")
    if np.max(np.abs(ofs)) > ARDUPILOT_OFFSET_MAX:
        warnings.append(f"an offset of {np.max(np.abs(ofs)):.6g} mGauss exceeds COMPASS_OFFS_MAX's default "
                        f"{ARDUPILOT_OFFSET_MAX:g} (a pre-arm check)")
    return warnings


def px4(w, offset, unit: str, *, field_unit=None, counts_nt=None, instance: int = 0, rotation=None,
        max_rotation_deg: float = MAX_ROTATION_DEG, orient: bool = False, notes: dict | None = None,
        site=None) -> Export:
    """PX4 parameters (a QGroundControl ``.params`` file: ``vehicle component name value type``).

    Convention (``Magnetometer::Correct``): ``B = R S (r − OFF)``, gauss; ``S`` from ``SCALE`` and
    ``ODIAG``, ``R`` the board or ``CAL_MAGn_ROT`` rotation (kept: set it as before). From
    ``Rᵀ B = S' (r − o')`` (:func:`to_firmware` of ``Rᵀ W``, gauss): ``OFF = o'``, ``S = S'``.
    ``rotation``: that ``R`` when ``W`` maps the readings into the body frame (a vector calibration
    of a ULog's readings: its ``meta['onboard_rotation']``); None: the identity (a
    total-field calibration, or readings in the body frame). ``instance``: the slot ``n`` of
    ``CAL_MAGn_*`` (0-3; keep its ``CAL_MAGn_ID``). ``orient`` (without ``rotation``): ``W``'s rotation
    was determined (:func:`to_firmware`); its standard rotation is written as ``CAL_MAGn_ROT``."""
    if instance not in (0, 1, 2, 3):
        raise MagexpError(f"instance={instance!r} is not allowed for px4: choose 0, 1, 2 or 3 (CAL_MAGn)")
    if rotation is not None:
        rotation = np.asarray(rotation, float)
        if rotation.shape != (3, 3) or not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-6):
            raise MagexpError("rotation is not allowed: it must be a 3 x 3 rotation matrix (PX4's R)")
        w, orient = rotation.T @ np.asarray(w, float), False
    c = to_firmware(w, offset, unit, TARGET_UNITS["px4"], field_unit=field_unit, counts_nt=counts_nt, symmetric=True,
                    max_rotation_deg=max_rotation_deg, orient=orient)
    n, m = instance, c.matrix
    values = {**{f"CAL_MAG{n}_{a}OFF": float(c.offset[i]) for i, a in enumerate("XYZ")},
              **{f"CAL_MAG{n}_{a}SCALE": float(m[i, i]) for i, a in enumerate("XYZ")},
              **{f"CAL_MAG{n}_{a}ODIAG": float(v) for a, v in zip("XYZ", (m[0, 1], m[0, 2], m[1, 2]))}}
    if c.orientation is not None:
        values[ORIENTATION_KEYS["px4"].format(n=n)] = c.orientation
    head = _comments(notes, "PX4: B = R S (raw - CAL_MAGn_OFF), S = [[XSCALE, XODIAG, YODIAG], [XODIAG, YSCALE, "
                            "ZODIAG], [YODIAG, ZODIAG, ZSCALE]]; gauss; keep CAL_MAGn_ID"
                            + ("" if c.orientation is not None else " and CAL_MAGn_ROT"), c, "#", site)
    head.append("# Vehicle-Id Component-Id Name Value Type")
    text = "\n".join(head + [f"1\t1\t{k}\t{v!r}\t{INT32 if isinstance(v, int) else REAL32}"
                             for k, v in values.items()]) + "\n"
    return Export("px4", text, values)


def ros(w, offset, unit: str, *, field_unit=None, counts_nt=None, node: str = "/**",
        namespace: str = "magnetometer_calibration", notes: dict | None = None, site=None) -> Export:
    """A ROS 2 parameter file: ``<node>: ros__parameters: <namespace>: {convention, unit, offset,
    matrix}``; ``B = W (r − o)`` in tesla (``sensor_msgs/MagneticField``'s unit), ``matrix`` the
    full ``W`` row-major (9 numbers), ``offset`` 3 numbers."""
    c = to_firmware(w, offset, unit, TARGET_UNITS["ros"], field_unit=field_unit, counts_nt=counts_nt)
    values = {"convention": "B = W (r - o), W row-major", "unit": "T",
              "offset": [float(v) for v in c.offset], "matrix": [float(v) for v in c.matrix.ravel()]}
    head = _comments(notes, "ROS: B = W (r - o), tesla (sensor_msgs/MagneticField), matrix row-major", c, "#", site)
    body = yaml.safe_dump({node: {"ros__parameters": {namespace: values}}}, sort_keys=False, width=200)
    return Export("ros", "\n".join(head) + "\n" + body, values)


_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def c_header(w, offset, unit: str, *, field_unit=None, name: str = "MAG_CAL", notes: dict | None = None,
             site=None) -> Export:
    """A C header: ``static const float <NAME>_OFFSET[3]``, ``<NAME>_MATRIX[3][3]`` (row-major) and
    ``static inline void <name>_apply(const float raw[3], float out[3])`` computing ``out = W (raw − o)``,
    in the recording's units (the raw unit in, ``field_unit`` out), float32 literals (``%.9g``)."""
    if not _IDENTIFIER.match(str(name)):
        raise MagexpError(f"name={name!r} is not allowed: it must be a C identifier (letters, digits, _)")
    c = to_firmware(w, offset, unit, TARGET_UNITS["c"], field_unit=field_unit)
    up, low = str(name).upper(), str(name).lower()
    lit = lambda v: f"{v:.9g}f" if "." in f"{v:.9g}" or "e" in f"{v:.9g}" else f"{v:.9g}.0f"  # noqa: E731
    head = _comments(notes, f"B = W (r - o): r raw ({c.unit}), o offset ({c.unit}), B calibrated ({c.field_unit}); "
                            "W row-major: B[i] = sum_j W[i][j] (r[j] - o[j])", c, " *", site)
    rows = ",\n    ".join("{" + ", ".join(lit(v) for v in row) + "}" for row in c.matrix)
    text = "\n".join([
        "/*", *head, " */", f"#ifndef {up}_H", f"#define {up}_H", "",
        f"static const float {up}_OFFSET[3] = {{{', '.join(lit(v) for v in c.offset)}}};",
        f"static const float {up}_MATRIX[3][3] = {{\n    {rows}\n}};", "",
        f"static inline void {low}_apply(const float raw[3], float out[3])", "{",
        "    int i, j;",
        "    for (i = 0; i < 3; ++i) {",
        "        out[i] = 0.0f;",
        "        for (j = 0; j < 3; ++j) {",
        f"            out[i] += {up}_MATRIX[i][j] * (raw[j] - {up}_OFFSET[j]);",
        "        }", "    }", "}", "", f"#endif /* {up}_H */", ""])
    return Export("c", text, {"offset": c.offset.tolist(), "matrix": c.matrix.tolist()})


#: each target's renderer
RENDERERS = {"ardupilot": ardupilot, "px4": px4, "ros": ros, "c": c_header}


def options_of(target: str) -> tuple[str, ...]:
    """The keyword options ``target``'s renderer takes (:data:`RENDERERS`), e.g. ``counts_nt``, ``instance``."""
    if target not in RENDERERS:
        raise MagexpError(f"export={target!r} is not allowed: choose one of {', '.join(TARGETS)}")
    return tuple(p.name for p in inspect.signature(RENDERERS[target]).parameters.values() if p.kind == p.KEYWORD_ONLY)


def render(target: str, w, offset, unit: str, **options) -> Export:
    """The :class:`Export` of ``target`` (:data:`TARGETS`) for ``B = W (r − o)`` in ``unit``;
    ``options``: the target function's keywords (``field_unit``, ``counts_nt``, ``instance``,
    ``max_rotation_deg``, ``notes``, ...); ``counts_nt`` and ``max_rotation_deg`` checked even where unused
    (a unit with a factor, a target without the rotation limit): a bad value is refused, not ignored."""
    if not isinstance(target, str) or target not in RENDERERS:
        raise MagexpError(f"export={target!r} is not allowed: choose one of {', '.join(TARGETS)}")
    unknown = sorted(set(options) - set(options_of(target)))
    if unknown:
        raise MagexpError(f"{unknown[0]}={options[unknown[0]]!r} is not allowed: export={target!r} takes "
                          f"{', '.join(options_of(target))}")
    for key, check_value in (("counts_nt", check_counts_nt), ("max_rotation_deg", check_max_rotation)):
        if options.get(key) is not None:
            check_value(options[key])
    return RENDERERS[target](w, offset, unit, **options)


def orientable(cal) -> bool:
    """Whether the rotation of ``cal``'s ``W`` is the magnetometer's orientation (``orient`` of :func:`to_firmware`)."""
    from_log = "onboard_calibration" in cal.report or (cal.recording is not None and "corrected" in cal.recording.meta)
    return cal.model == "gyro" and not from_log


def firmware_correction(cal) -> Correction | str:
    """The correction a symmetric-matrix firmware (ArduPilot, PX4) would hold for ``cal``, every rotation allowed
    (the rotation it leaves out is then what ``max_rotation_deg`` must allow), or the line refusing it (a
    mirrored ``W``): what :mod:`magexp.calibration.heading` measures as exported."""
    try:
        return to_firmware(cal.w, cal.offset, cal.unit, None, symmetric=True, max_rotation_deg=180.0,
                           orient=orientable(cal))
    except MagexpError as exc:
        return str(exc)


def of_calibration(cal, target: str, **options) -> Export:
    """The :class:`Export` of ``target`` for the :class:`~magexp.calibration.result.Calibration` ``cal``:
    ``options`` as :func:`render`; ``notes`` defaults to the recording, estimator and unit, ``field_unit``
    to the calibration's. Refuses (one line) before anything is written: a caller renders first."""
    options.setdefault("field_unit", cal.field_unit)
    if "orient" in options_of(target):
        options.setdefault("orient", orientable(cal))
    record = cal.report.get("heading")
    notes = options.pop("notes", None) or {"recording": cal.name, "estimator": cal.estimator,
                                             "objective": cal.objective, "magexp unit": cal.unit,
                                             **heldout_note(record)}
    if record:  # the heading error the file's parameters leave, at the calibration's site
        options.setdefault("site", (float(np.mean(cal.reference.total)),
                                    (record["inclination_deg"], record["inclination_source"])))
    return render(target, cal.w, cal.offset, cal.unit, notes=notes, **options)


def export(cal, target: str, path: str | Path | None = None, *, overwrite: bool = False, **options) -> Path:
    """Write ``target``'s file for the :class:`~magexp.calibration.result.Calibration` ``cal`` to ``path``
    (a folder: :data:`FILE_NAMES` inside it; None: the working folder); an existing file is replaced only
    with ``overwrite`` and only if a calibration wrote it, never the recording (:func:`write`)."""
    return write(of_calibration(cal, target, **options), path, overwrite=overwrite,
                 recording=recording_files(cal.recording))


def write(out: Export, path: str | Path | None = None, *, overwrite: bool = False, recording=()) -> Path:
    """Write the rendered ``out`` to ``path`` (a folder: its default name inside; None: the working
    folder), atomically; refuse, in one line, a file that exists already unless ``overwrite``, and then one
    that no calibration wrote or that is the recording (:func:`magexp.calibration.folder.check_file`)."""
    path = Path(".") if path is None else file_path(path, "export path")
    if path.is_dir():
        path = path / FILE_NAMES[out.target]
    check_destination(path, "export path")
    check_file(path, overwrite=overwrite, recording=recording, option="export path")
    if not path.parent.is_dir():
        raise MagexpError(f"export path {str(path)!r} is not allowed: its folder {str(path.parent)!r} does not exist")
    return write_text(path, out.text)
