"""ROS 1 bags (``.bag``), ROS 2 bags (a folder with ``metadata.yaml``, or its ``.db3``/``.mcap`` file) and MCAP files.

Needs ``pip install 'magexp[ros]'`` (``rosbags``). ``data.format=rosbag`` (``auto`` for ``*.bag``,
``*.mcap``, ``*.db3`` and a ROS 2 bag folder)::

    magexp calibrate data.path=flight.mcap

Messages read (by type; with several topics of a type, the one with most messages, or ``topic``):

=============================== ====================================================================
type                            fields (units)
=============================== ====================================================================
``sensor_msgs/msg/MagneticField`` ``magnetic_field.x/y/z`` (tesla, REP-145: the sensor's frame),
                                  read as µT (unit ``uT``, ×1e6)
``sensor_msgs/msg/Imu``           ``angular_velocity`` (rad/s) -> the gyroscope stream;
                                  ``orientation`` (``x, y, z, w``, body -> ENU, REP-103) -> the
                                  attitude, converted to NED; unused when ``orientation_covariance[0]
                                  == -1`` (no orientation, by the message's definition)
``sensor_msgs/msg/NavSatFix``     ``latitude, longitude`` (degrees), ``altitude`` (m, WGS84) of the
                                  fixes with ``status.status >= 0``; the date from their stamps
=============================== ====================================================================

Time: ``header.stamp`` (the sensor's time; the bag's receive time where the stamp is zero), in
seconds from the earliest message read.

**Already corrected.** ``sensor_msgs/MagneticField`` carries no record of a calibration: what a
driver published is read as the raw reading (``meta['corrected']`` says so); a driver that
publishes calibrated values should be recorded with its calibration switched off.

Safety: messages are decoded with the message definitions built into rosbags (``ROS2_HUMBLE``
for CDR, ``ROS1_NOETIC`` for ROS 1), never with the definitions a bag carries (rosbags generates
code from those), and only the three types above.
"""

from __future__ import annotations

import datetime as _dt
import functools
from pathlib import Path

import numpy as np

from magexp.core.readers import check_count, log_recording, log_unit, navigation_angles, need, place
from magexp.errors import MagexpError
from magexp.recordings import Recording

MAG, IMU, FIX = "sensor_msgs/msg/MagneticField", "sensor_msgs/msg/Imu", "sensor_msgs/msg/NavSatFix"
#: tesla -> µT
TESLA_TO_UT = 1e6


def is_bag(path: Path) -> bool:
    """A ROS bag by its name: ``*.bag``, ``*.mcap``, ``*.db3``, or a folder holding ``metadata.yaml``."""
    path = Path(path)
    return path.suffix in (".bag", ".mcap", ".db3") or (path.is_dir() and (path / "metadata.yaml").is_file())


@functools.lru_cache(maxsize=2)
def typestore(ros1: bool):
    """rosbags' built-in message definitions (ROS 1 Noetic or ROS 2 Humble); built once a process
    (0.2-0.3 s each, measured)."""
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)


def _open(path: Path):
    """``(reader, deserialize)`` of the bag at ``path`` (a ROS 2 storage file inside a bag folder opens the folder)."""
    need("rosbags", f"{path.name} (a ROS bag)")
    from rosbags.rosbag1 import Reader as Reader1
    from rosbags.rosbag2 import Reader as Reader2

    if path.suffix == ".bag":
        return Reader1(path), typestore(True).deserialize_ros1
    folder = path.parent if path.is_file() and (path.parent / "metadata.yaml").is_file() else path
    return Reader2(folder), typestore(False).deserialize_cdr


def _stamp(msg, received: int) -> float:
    sec, nsec = int(msg.header.stamp.sec), int(msg.header.stamp.nanosec)
    return sec + nsec * 1e-9 if (sec or nsec) else received * 1e-9


def _pick(connections, msgtype: str, topic: str | None, name: str):
    """The connections of the chosen topic of ``msgtype`` (the one with most messages), [] if none."""
    of_type = [c for c in connections if c.msgtype == msgtype]
    if topic is not None:
        of_type = [c for c in of_type if c.topic == topic]
        if not of_type and msgtype == MAG:
            raise MagexpError(f"topic={topic!r} is not allowed for {name}: it holds no {msgtype} messages")
    counts: dict[str, int] = {}
    for c in of_type:
        counts[c.topic] = counts.get(c.topic, 0) + c.msgcount
    best = max(counts, key=counts.get) if counts else None
    return [c for c in of_type if c.topic == best]


def _messages(reader, connections, deserialize, msgtype: str, fields) -> tuple[np.ndarray, np.ndarray]:
    """``(times s, values (n, k))`` of the messages of ``connections``; ``fields(msg)``: the k values."""
    times, values = [], []
    for connection, received, raw in reader.messages(connections=connections):
        msg = deserialize(raw, msgtype)
        times.append(_stamp(msg, received))
        values.append(fields(msg))
    return np.asarray(times, float), np.asarray(values, float).reshape(len(times), -1)


def read_rosbag(path: Path, *, unit=None, mag_axes=None, gyro_axes=None, topic: str | None = None) -> Recording:
    """The :class:`~magexp.recordings.Recording` of a ROS 1/2 bag or MCAP file (module docstring).

    Parameters
    ----------
    path : the ``.bag`` / ``.mcap`` / ``.db3`` file, or a ROS 2 bag folder.
    unit : must be None or ``uT`` (the tesla of ``MagneticField`` are read as µT).
    mag_axes, gyro_axes : signed axis maps (:func:`magexp.geometry.axis_map`).
    topic : the ``MagneticField`` topic (None: the one with most messages).
    """
    path = Path(path)
    name = path.name
    log_unit(unit, "uT", name, "MagneticField, read from tesla,")
    reader, deserialize = _open(path)
    from rosbags.rosbag1 import ReaderError as Error1
    from rosbags.rosbag2 import ReaderError as Error2
    from rosbags.serde import SerdeError

    try:
        with reader:
            mags = _pick(reader.connections, MAG, topic, name)
            if not mags:
                raise MagexpError(f"{name}: no {MAG} messages: nothing to calibrate")
            check_count(sum(c.msgcount for c in mags), f"data.path={name!r}")
            t_mag, mag = _messages(reader, mags, deserialize, MAG, lambda m: (
                m.magnetic_field.x, m.magnetic_field.y, m.magnetic_field.z))
            imus = _pick(reader.connections, IMU, None, name)
            imu = _messages(reader, imus, deserialize, IMU, lambda m: (
                m.orientation.w, m.orientation.x, m.orientation.y, m.orientation.z, m.orientation_covariance[0],
                m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z)) if imus else None
            fixes = _pick(reader.connections, FIX, None, name)
            fix = _messages(reader, fixes, deserialize, FIX, lambda m: (
                m.latitude, m.longitude, m.altitude, m.status.status)) if fixes else None
    except (Error1, Error2, SerdeError, KeyError, ValueError) as exc:
        if isinstance(exc, MagexpError):
            raise
        raise MagexpError(f"{name}: not a readable ROS bag ({type(exc).__name__}: "
                          f"{str(exc).splitlines()[0] if str(exc) else 'no detail'})") from None
    streams = [t for t in (t_mag, None if imu is None else imu[0], None if fix is None else fix[0]) if t is not None]
    t0 = min(float(t.min()) for t in streams if t.size)
    times = t_mag - t0
    meta = {"format": "rosbag", "source": mags[0].topic, "corrected": "as published (MagneticField records no "
            "calibration)", "clock_origin_s": repr(t0)}
    angles, gyro = None, None
    if imu is not None and len(imu[0]):
        has_orientation = imu[1][:, 4] != -1
        if np.any(has_orientation):
            angles = navigation_angles(imu[0][has_orientation] - t0, imu[1][has_orientation, :4], times, enu=True)
            meta["attitude"] = f"{imus[0].topic} orientation (body -> ENU, converted to NED)"
        gyro = (imu[0] - t0, imu[1][:, 5:8])
    if fix is not None and len(fix[0]):
        ok = fix[1][:, 3] >= 0
        when = _dt.datetime.fromtimestamp(float(np.median(fix[0][ok])), _dt.timezone.utc) if np.any(ok) else None
        meta.update(place(fix[1][ok, 0], fix[1][ok, 1], fix[1][ok, 2], when))
    return log_recording(path, readings=mag * TESLA_TO_UT, unit="uT", times=times, angles=angles, gyro=gyro,
                         meta=meta, mag_axes=mag_axes, gyro_axes=gyro_axes)
