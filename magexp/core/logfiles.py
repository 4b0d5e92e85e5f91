"""What the readers of the flight and robot logs users have share (PX4 ULog, ArduPilot DataFlash, ROS 1/2 bags, MCAP).

Each reader returns a :class:`magexp.core.recording.Recording` (the structure every other magexp
recording uses) with, on one clock:

* ``readings``: the magnetometer, *before* the firmware's onboard calibration (undone where the
  log says which calibration was applied; see each module), in the frame in which that
  firmware's calibration parameters apply, so that a calibration fitted to them can be exported
  back (:mod:`magexp.calibration.export`);
* ``times``: seconds from the start of the log (the log's own clock: microseconds since boot for
  ULog and DataFlash, the header stamps for ROS);
* ``angles``: the logged attitude at each reading (interpolated on the rotation group,
  :func:`attitude_at`), as the ``heading, roll, trim`` of :func:`magexp.core.geometry.ship_attitude`
  whose matrix is exactly the logged navigation -> body rotation (:func:`angles_from_attitude`);
  the navigation frame is **NED** for every format (a ROS ENU orientation is converted);
* ``gyro_stream``: the gyroscope's ``(times, rates rad/s)`` at its own times;
* ``columns`` :data:`LOGGED`: the readings as logged (after the onboard calibration), where it was undone;
* ``meta``: the position and date of the log (``latitude``, ``longitude`` in degrees,
  ``altitude_km``, ``date`` ISO, from its GPS), the source topics, what was undone, the firmware.
  :func:`magexp.core.field_model.place_of` reads the position back.

Modules: :mod:`~magexp.core.readers.ulog` (``pip install 'magexp[ulog]'``, pyulog),
:mod:`~magexp.core.readers.dataflash` (``magexp[dataflash]``, pymavlink),
:mod:`~magexp.core.readers.rosbag` (``magexp[ros]``, rosbags). A missing package is one
:class:`~magexp.errors.MagexpError` line naming the ``pip install`` to run. Nothing read can run
code: binary records are decoded by fixed layouts (numpy views), ROS messages only with the
message definitions built into rosbags (never the definitions a bag carries).

A reader does not judge whether a log can support a calibration: a log with too few readings
or one attitude loads, and :func:`magexp.calibration.fit.calibrate_recording` refuses it in one line.
"""

from __future__ import annotations

import datetime as _dt
import importlib

import numpy as np

from magexp.core.limits import refuse_over
from magexp.errors import MagexpError
from magexp.core.geometry import axis_map, quat_to_matrix
from magexp.core.recording import Recording

#: the ``pip install`` extra of each optional package a reader needs
EXTRAS = {"pyulog": "ulog", "pymavlink": "dataflash", "rosbags": "ros"}

#: NED coordinates -> ENU coordinates (a symmetric permutation with a sign: its own inverse)
NED_TO_ENU = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def need(module: str, what: str):
    """The module ``module``, or one line naming the ``pip install 'magexp[<extra>]'`` (:data:`EXTRAS`) that ``what`` (``a ULog``) needs."""
    try:
        return importlib.import_module(module)
    except ImportError:
        package = module.split(".")[0]
        raise MagexpError(f"reading {what} needs the optional package {package}: run "
                          f"pip install 'magexp[{EXTRAS[package]}]'") from None


def log_unit(unit, fixed: str, name: str, what: str) -> str:
    """``fixed``, the unit a log format defines; one line naming the log ``name`` and ``what`` is in it if ``unit`` (``data.unit``) names another."""
    if unit is not None and unit != fixed:
        raise MagexpError(f"data.unit={unit!r} is not allowed for {name}: {what} is in {fixed} (leave data.unit "
                          "unset)")
    return fixed


def angles_from_attitude(a: np.ndarray) -> np.ndarray:
    """``(N, 3)`` ``[heading, roll, trim]`` (radians, Yan & Zhou 2022 eq 2) of navigation -> sensor rotations ``a``,
    with ``ship_attitude(*angles.T) == a``.

    :func:`magexp.core.geometry.ship_attitude` is ``A = R_y(t) R_x(-r) R_z(-h)`` (active rotations); its middle row
    is ``[cos r' sin h', cos r' cos h', -sin r']`` and its last column ``[sin t cos r', -sin r', cos t cos r']``
    (``r' = -r``, ``h' = -h``), so

    .. math:: r = \\arcsin A_{12},\\quad h = -\\operatorname{atan2}(A_{10}, A_{11}),\\quad
              t = \\operatorname{atan2}(A_{02}, A_{22}).

    Exact whenever ``|A_12| < 1`` (``|A_12| = 1``: the body's y axis along the navigation z axis).
    """
    a = np.asarray(a, float)
    roll = np.arcsin(np.clip(a[..., 1, 2], -1.0, 1.0))
    heading = -np.arctan2(a[..., 1, 0], a[..., 1, 1])
    trim = np.arctan2(a[..., 0, 2], a[..., 2, 2])
    return np.stack([heading, roll, trim], axis=-1)


def _unit_quaternions(q: np.ndarray) -> np.ndarray:
    """``q`` normalised to unit quaternions; one line for a zero or non-finite one."""
    q = np.asarray(q, float)
    norm = np.linalg.norm(q, axis=1, keepdims=True)
    if not np.all(norm > 0) or not np.all(np.isfinite(q)):
        raise MagexpError("an attitude quaternion is zero or not finite: the log's attitude is unusable")
    return q / norm


def attitude_at(times: np.ndarray, quats: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Body -> NED rotations ``(len(at), 3, 3)`` at the times ``at``: the logged body -> NED quaternions ``[w, x, y, z]``
    at ``times`` slerped between neighbouring samples (held outside them); one line for a zero or non-finite one.
    """
    q = _unit_quaternions(quats)
    times = np.asarray(times, float)
    order = np.argsort(times, kind="stable")
    times, q = times[order], q[order]
    k = np.clip(np.searchsorted(times, at, side="right") - 1, 0, len(times) - 1)
    k1 = np.minimum(k + 1, len(times) - 1)
    span = times[k1] - times[k]
    u = np.where(span > 0, np.clip((at - times[k]) / np.where(span > 0, span, 1.0), 0.0, 1.0), 0.0)[:, None]
    q0, q1 = q[k], q[k1]
    dot = np.sum(q0 * q1, axis=1, keepdims=True)
    q1 = np.where(dot < 0, -q1, q1)  # the shorter arc
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    small = theta < 1e-6
    s = np.where(small, 1.0, np.sin(theta))
    w0 = np.where(small, 1.0 - u, np.sin((1.0 - u) * theta) / s)
    w1 = np.where(small, u, np.sin(u * theta) / s)
    return quat_to_matrix(_unit_quaternions(w0 * q0 + w1 * q1))


def euler_quaternions(roll, pitch, yaw) -> np.ndarray:
    """Unit quaternions ``[w, x, y, z]`` of the aerospace Z-Y-X Euler angles (radians): body -> NED ``R_z(yaw) R_y(pitch) R_x(roll)``."""
    cr, sr = np.cos(np.asarray(roll, float) / 2), np.sin(np.asarray(roll, float) / 2)
    cp, sp = np.cos(np.asarray(pitch, float) / 2), np.sin(np.asarray(pitch, float) / 2)
    cy, sy = np.cos(np.asarray(yaw, float) / 2), np.sin(np.asarray(yaw, float) / 2)
    return np.column_stack([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy])


def navigation_angles(times: np.ndarray, quats: np.ndarray, at: np.ndarray, *, enu: bool = False) -> np.ndarray:
    """``[heading, roll, trim]`` (:func:`angles_from_attitude`) at ``at`` of body -> navigation quaternions ``quats``
    at ``times``; ``enu``: they rotate into ENU (ROS, REP-103), converted to NED (``A_ned = A_enu C``, :data:`NED_TO_ENU`).
    """
    to_body = np.transpose(attitude_at(times, quats, at), (0, 2, 1))
    return angles_from_attitude(to_body @ NED_TO_ENU if enu else to_body)


def place(latitude, longitude, altitude_m, when: _dt.datetime | None) -> dict:
    """``meta`` of the log's place and date: the median of the valid fixes (degrees, altitude m -> km, a non-finite
    one 0), their count and the ISO date of ``when``; {} without a fix.
    """
    latitude, longitude, altitude_m = (np.asarray(v, float) for v in (latitude, longitude, altitude_m))
    ok = np.isfinite(latitude) & np.isfinite(longitude) & (np.abs(latitude) <= 90) & (np.abs(longitude) <= 360)
    if not np.any(ok):
        return {}
    out = {"latitude": repr(float(np.median(latitude[ok]))), "longitude": repr(float(np.median(longitude[ok]))),
           "altitude_km": repr(float(np.median(np.where(np.isfinite(altitude_m[ok]), altitude_m[ok], 0.0))) / 1e3),
           "gps_fixes": str(int(np.sum(ok)))}
    if when is not None:
        out["date"] = when.date().isoformat()
    return out


#: the columns of a log's readings as logged, after the onboard calibration its reader undid (:func:`log_recording`)
LOGGED = ("logged_bx", "logged_by", "logged_bz")


def log_recording(path, *, readings: np.ndarray, unit: str, times: np.ndarray, angles: np.ndarray | None,
                  gyro: tuple | None, meta: dict, mag_axes=None, gyro_axes=None, logged: np.ndarray | None = None):
    """The :class:`~magexp.core.recording.Recording` of a log, sorted by ``times`` (s), ``meta['nav_frame'] = 'NED'``:
    readings and ``gyro`` ``(times, rad/s)`` mapped by ``mag_axes``/``gyro_axes``; ``logged``: the readings as logged,
    before the reader undid the onboard calibration (columns :data:`LOGGED`), or None.
    """
    order = np.argsort(times, kind="stable")
    axes = axis_map(mag_axes, "data.mag_axes").T
    columns = {} if logged is None else dict(zip(LOGGED, (np.asarray(logged, float)[order] @ axes).T))
    rec = Recording(readings=np.asarray(readings, float)[order] @ axes,
                    angles=None if angles is None else np.asarray(angles)[order], field=None, unit=unit,
                    meta={"nav_frame": "NED", **meta}, times=np.asarray(times, float)[order], path=path,
                    columns=columns)
    if gyro is not None and len(gyro[0]) >= 2:
        g_order = np.argsort(gyro[0], kind="stable")
        rec.gyro_stream = (np.asarray(gyro[0], float)[g_order],
                           np.asarray(gyro[1], float)[g_order] @ axis_map(gyro_axes, "data.gyro_axes").T)
    return rec


def matrix_text(m: np.ndarray) -> str:
    """A 3 x 3 matrix as ``meta`` text: rows separated by ``;``, values by ``,`` (``repr``, so it reads back exactly)."""
    return "; ".join(", ".join(f"{v!r}" for v in np.asarray(row, float).tolist()) for row in m)


def check_count(count: int, subject: str) -> None:
    """Refuse, before decoding, a log whose ``count`` magnetometer readings pass the ``readings`` limit (:func:`magexp.core.limits.refuse_over`)."""
    refuse_over(count, "readings", subject, "its magnetometer messages hold")
