"""PX4 ULog (``.ulg``) logs: magnetometer, gyroscope, attitude, GPS position and date on the log's clock.

Needs ``pip install 'magexp[ulog]'`` (``pyulog``). ``data.format=ulog`` (``auto`` for ``*.ulg``)::

    magexp calibrate data.path=../shared/data/px4_sample.ulg

Topics read (the first present, in this order):

================== ==================================================================================
what               topics and fields (units)
================== ==================================================================================
magnetometer       the one with most samples of ``vehicle_magnetometer.magnetometer_ga[0..2]``,
                   ``sensor_combined.magnetometer_ga[0..2]`` (older logs; a reading only where
                   ``timestamp + magnetometer_timestamp_relative`` changes) and ``sensor_mag.x/y/z`` of
                   the prime magnetometer (``CAL_MAG_PRIME``, else ``vehicle_magnetometer.device_id``);
                   gauss -> unit ``G``
gyroscope          ``sensor_combined.gyro_rad[0..2]`` (rad/s, body frame), else
                   ``vehicle_angular_velocity.xyz[0..2]``
attitude           ``vehicle_attitude.q[0..3]`` (``w, x, y, z``, body FRD -> NED), interpolated at the
                   readings (:func:`magexp.core.logfiles.attitude_at`)
position, date     ``vehicle_gps_position`` or ``sensor_gps``: ``lat``/``lon`` (1e-7 degrees) or
                   ``latitude_deg``/``longitude_deg``; ``alt`` (mm) or ``altitude_msl_m``; the fixes
                   with ``fix_type >= 3``; the date from ``time_utc_usec``
time               ``timestamp`` (microseconds since boot), in seconds from the log's start
================== ==================================================================================

**Already corrected.** PX4 publishes ``vehicle_magnetometer`` and ``sensor_combined``'s
magnetometer *after* its onboard calibration ``CAL_MAGn_*`` (``n`` the calibration slot whose
``CAL_MAGn_ID`` is the magnetometer's device id, ``CAL_MAG_PRIME`` in older logs), and ``sensor_mag``
too up to PX4 1.11 (the drivers applied offsets and scales; the sensors module rotated). In every
version (``Magnetometer::Correct`` from 1.12 on, ``src/lib/sensor_calibration/Magnetometer.hpp``;
the drivers and ``VotedSensorsUpdate`` before)

.. math:: B = R\\,S\\,(r - \\mathrm{OFF}),

gauss, ``S`` symmetric with ``CAL_MAGn_XSCALE/YSCALE/ZSCALE`` on its diagonal and
``CAL_MAGn_XODIAG/YODIAG/ZODIAG`` (``xy, xz, yz``; 1.12 on, else 0) off it, ``R`` the rotation to the
body frame: ``get_rot_matrix(CAL_MAGn_ROT)`` for an external magnetometer, the board's
``Euler(SENS_BOARD_X/Y/Z_OFF) · get_rot_matrix(SENS_BOARD_ROT)`` for an internal one
(:func:`onboard_rotation`; ``sensor_mag`` before 1.12 was not yet rotated: ``R = I``). The reader
undoes it with the parameters the log holds, ``r = S⁻¹ Rᵀ B + OFF``: the readings are in the frame
the offsets apply in, so that a new calibration can replace them (:mod:`magexp.calibration.export`,
whose ``px4`` target takes ``R`` back out of a vector calibration's ``W``). ``sensor_mag`` from 1.12 on
is raw and read as it is.

Parameters that change while the magnetometer is logged, or a slot that cannot be found, are
refused in one line; ``undo=False`` keeps the readings as logged (``meta['corrected']`` says so).
Power compensation ``CAL_MAGn_COMP`` (``CAL_MAG_COMP_TYP > 0``) is not undone (``meta`` says so).
"""

from __future__ import annotations

import datetime as _dt
from pathlib import Path

import numpy as np

from magexp.core.logfiles import (check_count, euler_quaternions, log_recording, log_unit, matrix_text,
                                       navigation_angles, need, place)
from magexp.errors import MagexpError
from magexp.core.geometry import quat_to_matrix
from magexp.core.recording import Recording

NAME = "ulog"
PRIORITY = 10
SUFFIXES = (".ulg",)
UNIT = "G (gauss), fixed by the format"
EXTRA = "ulog"
BINARY = True
READ_MEMORY = 8

#: the topics read (pyulog loads only these)
TOPICS = ("vehicle_magnetometer", "sensor_combined", "sensor_mag", "vehicle_attitude", "vehicle_angular_velocity",
          "vehicle_gps_position", "sensor_gps")
#: ``timestamp_relative`` of a sample that did not update (``uORB``'s RELATIVE_TIMESTAMP_INVALID)
RELATIVE_INVALID = 0x7FFFFFFF
#: the first PX4 release whose ``sensor_mag`` is raw (the calibration moved from the drivers to the sensors module)
NEW_CALIBRATION = (1, 12)
#: PX4's rotations (``enum Rotation``, ``src/lib/conversion/rotation.h``): roll, pitch, yaw in degrees
ROTATIONS = ((0, 0, 0), (0, 0, 45), (0, 0, 90), (0, 0, 135), (0, 0, 180), (0, 0, 225), (0, 0, 270), (0, 0, 315),
             (180, 0, 0), (180, 0, 45), (180, 0, 90), (180, 0, 135), (0, 180, 0), (180, 0, 225), (180, 0, 270),
             (180, 0, 315), (90, 0, 0), (90, 0, 45), (90, 0, 90), (90, 0, 135), (270, 0, 0), (270, 0, 45),
             (270, 0, 90), (270, 0, 135), (0, 90, 0), (0, 270, 0), (0, 180, 90), (0, 180, 270), (90, 90, 0),
             (180, 90, 0), (270, 90, 0), (90, 180, 0), (270, 180, 0), (90, 270, 0), (180, 270, 0), (270, 270, 0),
             (90, 180, 90), (90, 0, 270), (90, 68, 293), (0, 315, 0), (90, 315, 0), (270, 0, 180), (270, 0, 270),
             (0, 90, 180), (0, 9, 180), (0, 45, 0), (270, 0, 225), (270, 0, 315))


def _columns(data: dict, names: list[str]) -> np.ndarray:
    """The fields ``names`` of a ULog dataset's ``data``, stacked as float columns."""
    return np.column_stack([np.asarray(data[n], float) for n in names])


def _version(ulog) -> tuple[int, int] | None:
    """``(major, minor)`` of ``ver_sw_release`` (``0xAABBCCTT``), or None when not logged."""
    release = ulog.msg_info_dict.get("ver_sw_release")
    if not release:
        return None
    return (int(release) >> 24) & 0xFF, (int(release) >> 16) & 0xFF


def _dataset(ulog, name: str, multi_id: int = 0):
    """The dataset of topic ``name`` (instance ``multi_id``), or None when not logged."""
    return next((d for d in ulog.data_list if d.name == name and d.multi_id == multi_id), None)


def _candidates(ulog, prime: int | None) -> list[tuple[str, np.ndarray, np.ndarray, int | None]]:
    """``(topic, times µs, readings G, device id)`` of each magnetometer source in the log."""
    out = []
    vm = _dataset(ulog, "vehicle_magnetometer")
    if vm is not None:
        device = int(vm.data["device_id"][0]) if "device_id" in vm.data else prime
        out.append(("vehicle_magnetometer", vm.data["timestamp"],
                    _columns(vm.data, [f"magnetometer_ga[{i}]" for i in range(3)]), device))
        prime = device if prime is None else prime  # newer logs have no CAL_MAG_PRIME
    sc = _dataset(ulog, "sensor_combined")
    if sc is not None and "magnetometer_ga[0]" in sc.data:
        rel = np.asarray(sc.data["magnetometer_timestamp_relative"], np.int64)
        t = np.asarray(sc.data["timestamp"], np.int64) + rel
        fresh = (rel != RELATIVE_INVALID) & np.concatenate([[True], np.diff(t) != 0])
        out.append(("sensor_combined", t[fresh],
                    _columns(sc.data, [f"magnetometer_ga[{i}]" for i in range(3)])[fresh], prime))
    for d in ulog.data_list:
        if d.name == "sensor_mag" and prime is not None and int(d.data["device_id"][0]) == prime:
            out.append((f"sensor_mag[{d.multi_id}]", d.data["timestamp"], _columns(d.data, ["x", "y", "z"]), prime))
    return out


def _slot(params: dict, device: int | None, name: str) -> int:
    """The ``CAL_MAGn`` slot calibrating the magnetometer ``device``, else one line naming what to do."""
    slots = [n for n in range(4) if device is not None and params.get(f"CAL_MAG{n}_ID") == device]
    if not slots:
        raise MagexpError(f"{name}: the magnetometer (device id {'unknown' if device is None else device}) has no CAL_MAGn_ID in the log's parameters: "
                          "its onboard calibration cannot be undone; log sensor_mag (raw from PX4 1.12 on), or keep "
                          "the corrected readings with magexp.core.readers.ulog.read_ulog(path, undo=False)")
    return slots[0]


def _calibration(params: dict, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``(S, OFF)`` of slot ``n``: ``S`` symmetric from ``SCALE`` and ``ODIAG`` (0 when not logged)."""
    p = lambda key, default: float(params.get(f"CAL_MAG{n}_{key}", default))  # noqa: E731
    d = [p(f"{a}SCALE", 1.0) for a in "XYZ"]
    o = [p(f"{a}ODIAG", 0.0) for a in "XYZ"]
    s = np.array([[d[0], o[0], o[1]], [o[0], d[1], o[2]], [o[1], o[2], d[2]]])
    return s, np.array([p(f"{a}OFF", 0.0) for a in "XYZ"])


def _changed(ulog, n: int, t0: float, t1: float) -> str | None:
    """The first ``CAL_MAGn_*`` change logged within ``[t0, t1]`` (µs), as text, or None."""
    keys = {f"CAL_MAG{n}_{k}" for k in ("XOFF", "YOFF", "ZOFF", "XSCALE", "YSCALE", "ZSCALE", "XODIAG",
                                         "YODIAG", "ZODIAG", "ROT")}
    hit = next(((t, k) for t, k, _ in ulog.changed_parameters if k in keys and t0 <= t <= t1), None)
    return None if hit is None else f"{hit[1]} changes at {(hit[0] - ulog.start_timestamp) / 1e6:.3f} s"


def rotation_matrix(enum: int) -> np.ndarray:
    """PX4's ``get_rot_matrix(enum)`` (``src/lib/conversion/rotation.cpp``): the board -> body matrix
    ``R_z(yaw) R_y(pitch) R_x(roll)`` of :data:`ROTATIONS` ``[enum]``; one line for an unknown ``enum``.
    """
    if not 0 <= enum < len(ROTATIONS):
        raise MagexpError(f"rotation {enum} is not allowed: PX4's rotations are 0 to {len(ROTATIONS) - 1}")
    return quat_to_matrix(euler_quaternions(*np.deg2rad(np.array(ROTATIONS[enum], float)[:, None])))[0]


def onboard_rotation(params: dict, n: int) -> np.ndarray:
    """``R`` of ``B = R S (r − OFF)`` for slot ``n``: ``get_rot_matrix(CAL_MAGn_ROT)`` for an external magnetometer
    (``ROT >= 0``), else the board's ``Euler(SENS_BOARD_X/Y/Z_OFF) · get_rot_matrix(SENS_BOARD_ROT)`` (``GetBoardRotation``).
    """
    rot = int(params.get(f"CAL_MAG{n}_ROT", -1))
    if rot >= 0:
        return rotation_matrix(rot)
    level = np.deg2rad([float(params.get(f"SENS_BOARD_{a}_OFF", 0.0)) for a in "XYZ"])
    return quat_to_matrix(euler_quaternions(*level[:, None]))[0] @ rotation_matrix(int(params.get("SENS_BOARD_ROT", 0)))


def undo_calibration(ulog, topic: str, device: int | None, readings: np.ndarray, times_us: np.ndarray,
                     name: str) -> tuple[np.ndarray, dict]:
    """``(r, meta)``: the ``readings`` ``B`` (gauss) of ``topic`` before PX4's onboard calibration, ``r = S⁻¹ Rᵀ B + OFF``
    (module docstring), and what was undone; one line if ``device`` has no ``CAL_MAGn_ID`` or its calibration
    changes within ``times_us``. ``sensor_mag`` is raw from PX4 1.12 on (nothing undone) and unrotated before.
    """
    version = _version(ulog)
    new = version is not None and version >= NEW_CALIBRATION
    if topic.startswith("sensor_mag") and new:
        return readings, {"corrected": "no: sensor_mag is raw from PX4 1.12 on"}
    params = ulog.initial_parameters
    n = _slot(params, device, name)
    changed = _changed(ulog, n, float(times_us.min()), float(times_us.max()))
    if changed:
        raise MagexpError(f"{name}: the onboard calibration {changed}, while the magnetometer is logged: it cannot "
                          "be undone with one set of parameters (log a calibration with fixed parameters)")
    s, off = _calibration(params, n)
    rotation = np.eye(3) if topic.startswith("sensor_mag") else onboard_rotation(params, n)  # < 1.12: not rotated
    meta = {"calibration_slot": str(n), "onboard_offset_G": ", ".join(f"{v!r}" for v in off.tolist()),
            "onboard_scale": matrix_text(s), "onboard_rotation": matrix_text(rotation),
            "corrected": "undone: PX4 B = R S (r - OFF), r = S^-1 R^T B + OFF (the frame the offsets apply in)"}
    if float(params.get("CAL_MAG_COMP_TYP", 0)) > 0:
        meta["power_compensation"] = "CAL_MAG_COMP_TYP > 0: the power compensation is not undone"
    return np.linalg.solve(s, (readings @ rotation).T).T + off, meta


def _gps(ulog) -> dict:
    """The log's place and date from its GPS topic (:func:`magexp.core.logfiles.place`), {} without."""
    d = _dataset(ulog, "vehicle_gps_position") or _dataset(ulog, "sensor_gps")
    if d is None:
        return {}
    data = d.data
    fix = np.asarray(data.get("fix_type", np.full(len(data["timestamp"]), 3))) >= 3
    if "lat" in data:
        lat, lon = np.asarray(data["lat"], float) * 1e-7, np.asarray(data["lon"], float) * 1e-7
    else:
        lat, lon = np.asarray(data["latitude_deg"], float), np.asarray(data["longitude_deg"], float)
    alt = np.asarray(data["alt"], float) / 1e3 if "alt" in data else np.asarray(data.get("altitude_msl_m", 0.0 * lat))
    utc = np.asarray(data.get("time_utc_usec", np.zeros(len(lat))), np.int64)[fix]
    when = _dt.datetime.fromtimestamp(int(np.median(utc[utc > 0])) / 1e6, _dt.timezone.utc) if np.any(utc > 0) else None
    return place(lat[fix], lon[fix], alt[fix], when)


def _gyro(ulog, t0: int) -> tuple | None:
    """``(times s, rates rad/s)`` of the gyroscope from ``t0`` (µs), or None when not logged."""
    sc = _dataset(ulog, "sensor_combined")
    if sc is not None and "gyro_rad[0]" in sc.data:
        return (np.asarray(sc.data["timestamp"], np.int64) - t0) / 1e6, _columns(sc.data, [f"gyro_rad[{i}]" for i in range(3)])
    av = _dataset(ulog, "vehicle_angular_velocity")
    if av is not None:
        return (np.asarray(av.data["timestamp"], np.int64) - t0) / 1e6, _columns(av.data, [f"xyz[{i}]" for i in range(3)])
    return None


def read_ulog(path: Path, *, unit=None, mag_axes=None, gyro_axes=None, undo: bool = True) -> Recording:
    """The :class:`~magexp.core.recording.Recording` of a PX4 ULog file, the onboard calibration undone.

    The readings are the field ``r = S⁻¹ Rᵀ B + OFF`` before PX4's calibration ``B = R S (r − OFF)``
    (``Magnetometer::Correct``, module docstring), in the frame its offsets apply in, with the attitude of
    ``vehicle_attitude``, the gyroscope and the GPS place and date.

    Parameters
    ----------
    path, unit, mag_axes, gyro_axes
        As ``read`` of every format (:mod:`magexp.core.readers`): ``path`` the ``.ulg`` file; ``unit`` None or
        ``G`` (ULog magnetometer topics are in gauss).
    undo : bool
        Undo the onboard calibration (default); False keeps the readings as logged.

    Returns
    -------
    Recording
        The readings (gauss) at their times (s from the log's start), the attitude angles, the gyroscope
        stream, the GPS place and date, and the undone calibration in ``meta`` (``onboard_rotation``: the
        firmware's ``R``, :func:`magexp.core.logfiles.matrix_text`).

    Raises
    ------
    MagexpError
        One line when pyulog is missing, ``unit`` is not ``G``, the file is no readable ULog, it has no
        magnetometer topic or more readings than the ``readings`` limit, or the calibration cannot be undone
        (no ``CAL_MAGn_ID`` for the device, parameters changed while logging).

    References
    ----------
    PX4, ``src/lib/sensor_calibration/Magnetometer.hpp`` (``Magnetometer::Correct``) and
    ``src/lib/conversion/rotation.cpp`` (``get_rot_matrix``).
    """
    name = Path(path).name
    core = need("pyulog.core", f"{name} (a PX4 ULog)")
    log_unit(unit, "G", name, "a ULog's magnetometer")
    try:
        ulog = core.ULog(str(path), list(TOPICS))
    except (core.ULogException, ValueError, IndexError, KeyError, UnicodeDecodeError) as exc:
        raise MagexpError(f"{name}: not a readable ULog file ({type(exc).__name__}: "
                          f"{str(exc).splitlines()[0] if str(exc) else 'no detail'})") from None
    prime = ulog.initial_parameters.get("CAL_MAG_PRIME")
    sources = _candidates(ulog, None if prime is None else int(prime))
    if not sources:
        raise MagexpError(f"{name}: no magnetometer topic (vehicle_magnetometer, sensor_combined.magnetometer_ga, "
                          "sensor_mag) in the log: nothing to calibrate")
    topic, times_us, readings, device = max(sources, key=lambda s: len(s[1]))
    check_count(len(readings), f"data.path={name!r}")
    meta = {"format": "ulog", "source": topic, "firmware": ".".join(map(str, _version(ulog) or ("< 1.12 (not logged)",))),
            "hardware": str(ulog.msg_info_dict.get("ver_hw", "")), "device_id": str(device)}
    logged = readings
    if undo:
        readings, undone = undo_calibration(ulog, topic, device, readings, np.asarray(times_us, float), name)
        meta.update(undone)
    else:
        meta["corrected"] = "kept as logged (undo=False)"
    t0 = int(ulog.start_timestamp)
    times = (np.asarray(times_us, np.int64) - t0) / 1e6
    att = _dataset(ulog, "vehicle_attitude")
    angles = None
    if att is not None:
        angles = navigation_angles((np.asarray(att.data["timestamp"], np.int64) - t0) / 1e6,
                                   _columns(att.data, [f"q[{i}]" for i in range(4)]), times)
        meta["attitude"] = "vehicle_attitude (body FRD -> NED)"
    meta.update(_gps(ulog))
    return log_recording(Path(path), readings=readings, unit="G", times=times, angles=angles, gyro=_gyro(ulog, t0),
                         meta=meta, mag_axes=mag_axes, gyro_axes=gyro_axes,
                         logged=logged if meta["corrected"].startswith("undone") else None)


#: the format's reader, by the name every format module gives it
read = read_ulog
