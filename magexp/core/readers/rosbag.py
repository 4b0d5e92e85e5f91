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

Safety and speed: a message is decoded by the fixed layout of its type (:data:`LAYOUTS`, ROS 2
Humble and ROS 1 Noetic definitions), every message of a topic at once by numpy gathers
(:class:`Messages`), never with the message definitions a bag carries (rosbags would generate
code from those); a message whose length does not fit the layout is refused in one line.
"""

from __future__ import annotations

import datetime as _dt
from pathlib import Path

import numpy as np

from magexp.core.datafiles import BAG_MARKER
from magexp.core.logfiles import check_count, log_recording, log_unit, navigation_angles, need, place
from magexp.errors import MagexpError
from magexp.core.recording import Recording

NAME = "rosbag"
PRIORITY = 30
SUFFIXES = (".bag", ".mcap", ".db3")
UNIT = "uT (read from tesla), fixed by the format"
EXTRA = "ros"
BINARY = True
READ_MEMORY = 32


def claims(path: Path) -> bool:
    """A folder holding ``metadata.yaml`` (a ROS 2 bag)."""
    return path.is_dir() and (path / BAG_MARKER).is_file()


MAG, IMU, FIX = "sensor_msgs/msg/MagneticField", "sensor_msgs/msg/Imu", "sensor_msgs/msg/NavSatFix"
#: tesla -> µT
TESLA_TO_UT = 1e6


#: each type's fields after its header, in order, as ``(name, dtype, count)`` (``None``: read past);
#: the whole message, so that a message of another layout is caught by its length
LAYOUTS = {
    MAG: (("field", "<f8", 3), (None, "<f8", 9)),
    IMU: (("orientation", "<f8", 4), ("orientation_covariance", "<f8", 9), ("angular_velocity", "<f8", 3),
          (None, "<f8", 9), (None, "<f8", 3), (None, "<f8", 9)),
    FIX: (("status", "i1", 1), (None, "<u2", 1), ("position", "<f8", 3), (None, "<f8", 9), (None, "u1", 1)),
}
#: the CDR encapsulation of little-endian plain CDR (ROS 2's serialisation)
CDR_LE = (0, 1)


class LayoutError(ValueError):
    """A message shorter or longer than its type's layout."""


class Messages:
    """The serialised messages ``raws`` of one type, decoded field by field for all of them at once (numpy gathers):
    ROS 2's CDR (``cdr``: a 4-byte encapsulation header, then each value aligned to its size from the body's
    start) or ROS 1's packed serialisation.
    """

    def __init__(self, raws: list[bytes], *, cdr: bool):
        lengths = np.fromiter(map(len, raws), np.int64, len(raws))
        self.buf = np.frombuffer(b"".join(raws), np.uint8)
        first = np.concatenate([[0], np.cumsum(lengths)[:-1]])
        self.cdr, self.end = cdr, first + lengths
        self.start = first + (4 if cdr else 0)
        if cdr and len(raws) and (np.any(lengths < 4) or np.any(self.buf[first] != CDR_LE[0])
                                  or np.any(self.buf[first + 1] != CDR_LE[1])):
            raise LayoutError("not little-endian CDR")
        self.pos = np.zeros(len(raws), np.int64)  # from each body's start

    def read(self, dtype, count: int = 1) -> np.ndarray:
        """The next ``count`` values of the little-endian ``dtype`` of every message, ``(n, count)``, each aligned to its size under CDR; :class:`LayoutError` if a message is too short."""
        dt = np.dtype(dtype)
        if self.cdr:
            self.pos = -(-self.pos // dt.itemsize) * dt.itemsize
        at = self.start + self.pos
        if np.any(at + dt.itemsize * count > self.end):
            raise LayoutError("shorter than its type")
        self.pos = self.pos + dt.itemsize * count
        return self.buf[at[:, None] + np.arange(dt.itemsize * count)].view(dt)

    def skip_string(self) -> None:
        """Step over a CDR string field (its length, then its bytes) of every message."""
        n = self.read("<u4")[:, 0].astype(np.int64)
        if np.any(self.start + self.pos + n > self.end):
            raise LayoutError("a string longer than the message")
        self.pos = self.pos + n

    def header(self) -> tuple[np.ndarray, np.ndarray]:
        """``(sec, nanosec)`` of every message's ``std_msgs/Header`` (ROS 1: ``seq`` first, read past; ``frame_id`` skipped)."""
        if not self.cdr:
            self.read("<u4")
        sec, nsec = self.read("<i4")[:, 0], self.read("<u4")[:, 0]
        self.skip_string()  # frame_id
        return sec, nsec

    def finish(self) -> None:
        """Every byte read; CDR may pad the end to a multiple of 4 bytes (the DDS serialised payload)."""
        left = self.end - (self.start + self.pos)
        pad = -self.pos % 4 if self.cdr else 0
        if np.any((left != 0) & (left != pad)):
            raise LayoutError("longer than its type")


def _open(path: Path):
    """``(reader, cdr)`` of the bag at ``path`` (a ROS 2 storage file inside a bag folder opens the folder)."""
    need("rosbags", f"{path.name} (a ROS bag)")
    from rosbags.rosbag1 import Reader as Reader1
    from rosbags.rosbag2 import Reader as Reader2

    if path.suffix == ".bag":
        return Reader1(path), False
    folder = path.parent if path.is_file() and (path.parent / BAG_MARKER).is_file() else path
    return Reader2(folder), True


def decode(raws: list[bytes], received: np.ndarray, msgtype: str, *, cdr: bool) -> tuple[np.ndarray, dict]:
    """``(times s, {field: (n, k) array})`` of the serialised ``msgtype`` messages ``raws`` (:data:`LAYOUTS`; ``cdr``
    as in :class:`Messages`); a time is the header stamp, else (zero) the bag's receive time ``received`` (ns).
    """
    rows = Messages(raws, cdr=cdr)
    sec, nsec = rows.header()
    fields = {}
    for field, dtype, count in LAYOUTS[msgtype]:
        values = rows.read(dtype, count)
        if field is not None:
            fields[field] = values.astype(float)
    rows.finish()
    stamped = (sec != 0) | (nsec != 0)
    return np.where(stamped, sec + nsec * 1e-9, np.asarray(received, float) * 1e-9), fields


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


def _messages(reader, connections, msgtype: str, cdr: bool, name: str) -> tuple[np.ndarray, dict]:
    """:func:`decode` of every message of ``connections``, one line naming the topic if one does
    not have ``msgtype``'s layout."""
    received, raws = [], []
    for _, stamp, raw in reader.messages(connections=connections):
        received.append(stamp)
        raws.append(bytes(raw))
    try:
        return decode(raws, np.asarray(received, np.int64), msgtype, cdr=cdr)
    except LayoutError as exc:
        raise MagexpError(f"{name}: topic {connections[0].topic}: a message is {exc}, not a {msgtype} as magexp "
                          "reads it (ROS 2 Humble / ROS 1 Noetic definition)") from None


def read_rosbag(path: Path, *, unit=None, mag_axes=None, gyro_axes=None, topic: str | None = None) -> Recording:
    """The :class:`~magexp.core.recording.Recording` of a ROS 1/2 bag or MCAP file.

    The ``sensor_msgs/MagneticField`` readings (tesla, REP-145) read as µT, with the attitude and angular
    rate of ``sensor_msgs/Imu`` (body -> ENU, REP-103, converted to NED) and the place and date of
    ``sensor_msgs/NavSatFix`` (module docstring). No calibration is undone: the message records none.

    Parameters
    ----------
    path, unit, mag_axes, gyro_axes
        As ``read`` of every format (:mod:`magexp.core.readers`): ``path`` the ``.bag`` / ``.mcap`` / ``.db3``
        file, or a ROS 2 bag folder; ``unit`` None or ``uT`` (the tesla of ``MagneticField`` are read as µT).
    topic : str, optional
        The ``MagneticField`` topic (None: the one with most messages).

    Returns
    -------
    Recording
        The readings (µT) at their times (s from the earliest message read), the orientation's angles and the
        angular rate of the ``Imu`` messages where there are some, the GPS place and date in ``meta``.

    Raises
    ------
    MagexpError
        One line when rosbags is missing, ``unit`` is not ``uT``, the bag is unreadable, ``topic`` or the bag
        holds no ``MagneticField`` messages, a message does not fit its type's layout, or the bag holds more
        readings than the ``readings`` limit.

    References
    ----------
    ROS REP-103 (Standard Units of Measure and Coordinate Conventions) and REP-145 (Conventions for IMU
    Sensor Drivers).
    """
    path = Path(path)
    name = path.name
    log_unit(unit, "uT", name, "MagneticField, read from tesla,")
    reader, cdr = _open(path)
    from rosbags.rosbag1 import ReaderError as Error1
    from rosbags.rosbag2 import ReaderError as Error2

    try:
        with reader:
            mags = _pick(reader.connections, MAG, topic, name)
            if not mags:
                raise MagexpError(f"{name}: no {MAG} messages: nothing to calibrate")
            check_count(sum(c.msgcount for c in mags), f"data.path={name!r}")
            t_mag, mag = _messages(reader, mags, MAG, cdr, name)
            imus = _pick(reader.connections, IMU, None, name)
            imu = _messages(reader, imus, IMU, cdr, name) if imus else None
            fixes = _pick(reader.connections, FIX, None, name)
            fix = _messages(reader, fixes, FIX, cdr, name) if fixes else None
    except (Error1, Error2, KeyError, ValueError) as exc:
        if isinstance(exc, MagexpError):
            raise
        raise MagexpError(f"{name}: not a readable ROS bag ({type(exc).__name__}: "
                          f"{str(exc).splitlines()[0] if str(exc) else 'no detail'})") from None
    t0 = min(float(t.min()) for t in (t_mag, *(s[0] for s in (imu, fix) if s is not None)) if t.size)
    times = t_mag - t0
    meta = {"format": "rosbag", "source": mags[0].topic, "corrected": "as published (MagneticField records no "
            "calibration)", "clock_origin_s": repr(t0)}
    angles, gyro = _imu_streams(imu, imus, t0, times, meta)
    if fix is not None and len(fix[0]):
        ok = fix[1]["status"][:, 0] >= 0
        when = _dt.datetime.fromtimestamp(float(np.median(fix[0][ok])), _dt.timezone.utc) if np.any(ok) else None
        meta.update(place(*fix[1]["position"][ok].T, when))
    return log_recording(path, readings=mag["field"] * TESLA_TO_UT, unit="uT", times=times, angles=angles, gyro=gyro,
                         meta=meta, mag_axes=mag_axes, gyro_axes=gyro_axes)


def _imu_streams(imu, imus, t0: float, times: np.ndarray, meta: dict):
    """``(angles, gyro)`` of the bag's ``Imu`` messages: the orientation where it is given (body to ENU,
    converted to NED, at the magnetometer's ``times``; noted in ``meta``) and the angular rate on the
    common clock (origin ``t0``); ``(None, None)`` without ``Imu`` messages."""
    if imu is None or not len(imu[0]):
        return None, None
    angles = None
    has_orientation = imu[1]["orientation_covariance"][:, 0] != -1
    if np.any(has_orientation):
        xyzw = imu[1]["orientation"][has_orientation]
        angles = navigation_angles(imu[0][has_orientation] - t0, xyzw[:, [3, 0, 1, 2]], times, enu=True)
        meta["attitude"] = f"{imus[0].topic} orientation (body -> ENU, converted to NED)"
    return angles, (imu[0] - t0, imu[1]["angular_velocity"])


#: the format's reader, by the name every format module gives it
read = read_rosbag
