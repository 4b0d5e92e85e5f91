"""ArduPilot DataFlash (``.bin``) logs: magnetometer, gyroscope, attitude, GPS position and date on the log's clock.

Needs ``pip install 'magexp[dataflash]'`` (``pymavlink``'s ``DFReader``). ``data.format=dataflash``
(``auto`` for ``*.bin``)::

    magexp calibrate data.path=../shared/data/ardupilot_test.bin

Messages read (``instance`` k selects ``MAG``/``IMU`` of that instance: the field ``I`` in
current logs, the message ``MAG2``/``MAG3``, ``IMU2``/``IMU3`` in older ones):

============ =======================================================================================
what         messages and fields (units)
============ =======================================================================================
magnetometer ``MAG``: ``MagX/Y/Z`` (mGauss, body frame), ``OfsX/Y/Z`` (the offsets in use),
             ``MOfsX/Y/Z`` (the motor compensation in use); unit ``mG``
gyroscope    ``IMU``: ``GyrX/Y/Z`` (rad/s, body frame)
attitude     ``ATT``: ``Roll, Pitch, Yaw`` (degrees; ``Z-Y-X`` Euler angles, body -> NED),
             interpolated at the readings (:func:`magexp.core.logfiles.attitude_at`)
position     ``GPS``: ``Lat, Lng`` (degrees), ``Alt`` (m above sea level), fixes with ``Status >= 3``;
             the date from ``GWk`` and ``GMS`` (GPS week and milliseconds; the leap seconds are
             ignored: the date is what the field model needs)
calibration  ``PARM``: ``COMPASS_OFS*``, ``COMPASS_DIA*``, ``COMPASS_ODI*``, ``COMPASS_SCALE*``
             (the last value logged before the first reading)
time         ``TimeUS`` (microseconds since boot), in seconds from the log's first ``TimeUS``
============ =======================================================================================

**Already corrected.** ``MAG`` logs the field *after* ArduPilot's correction
(``AP_Compass_Backend::correct_field``: the sample is first rotated into the body frame by
``rotate_field``, then)

.. math:: B = M\\,(s\\,(r + \\mathrm{OFS})) + \\mathrm{MOFS},

``M`` symmetric with ``COMPASS_DIA_X/Y/Z`` on its diagonal and ``COMPASS_ODI_X/Y/Z`` (``xy, xz, yz``)
off it (identity when all ``DIA`` are zero), ``s = COMPASS_SCALE`` when within ArduPilot's
``[0.85, 1.4]`` (``Compass::have_scale_factor``; else 1), ``MOFS`` the motor compensation (added
after ``M`` in current ArduPilot; before it up to 3.x, the same when it is zero, as in most
logs). The reader undoes it: ``r = (M⁻¹ (B − MOFS)) / s − OFS``, the body-frame field ArduPilot's
calibration parameters apply to. ``OFS`` is the ``PARM`` value where it agrees with the logged
``OfsX/Y/Z`` (rounded to 1 mGauss), else the logged value of that reading (offsets learnt in
flight, ``COMPASS_LEARN``). Binary records are decoded by the ``FMT`` layouts as numpy views
(``np.frombuffer``), every message type at once.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import io
import os
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

from magexp.core.logfiles import (check_count, euler_quaternions, log_recording, log_unit, matrix_text,
                                       navigation_angles, need, place)
from magexp.errors import MagexpError
from magexp.core.recording import Recording

NAME = "dataflash"
PRIORITY = 20
SUFFIXES = (".bin",)
UNIT = "mG (milligauss), fixed by the format"
EXTRA = "dataflash"
BINARY = True
READ_MEMORY = 32

#: ``struct`` codes of DataFlash fields -> numpy dtypes (little-endian, packed)
DTYPES = {"b": "i1", "B": "u1", "h": "<i2", "H": "<u2", "i": "<i4", "I": "<u4", "q": "<i8", "Q": "<u8",
          "f": "<f4", "d": "<f8", "e": "<f2", "4s": "S4", "16s": "S16", "64s": "S64"}
#: ``COMPASS_SCALE`` is applied only within ``[COMPASS_MIN_SCALE_FACTOR, COMPASS_MAX_SCALE_FACTOR]``
SCALE_RANGE = (0.85, 1.4)
#: the two bytes that start every DataFlash message
HEADER = "0xA3 0x95"
#: the first complaint of pymavlink's indexer about a byte that starts no message (it prints one per byte)
BAD_HEADER = re.compile(rb"bad header 0x[0-9a-f]+(?: 0x[0-9a-f]+)? at (\d+)")
#: the GPS epoch (GPS week 0)
GPS_EPOCH = _dt.datetime(1980, 1, 6, tzinfo=_dt.timezone.utc)


def _dtype(fmt) -> np.dtype:
    """The numpy dtype of a DataFlash message format ``fmt`` (its ``msg_struct``): decoded by a fixed layout."""
    codes, k = [], 1  # msg_struct is "<" then the codes; a count prefixes the strings ("16s")
    text = fmt.msg_struct
    while k < len(text):
        j = k
        while text[j].isdigit():
            j += 1
        codes.append(text[k:j + 1])
        k = j + 1
    return np.dtype([(col, DTYPES[code]) for col, code in zip(fmt.columns, codes)])


def table(reader, name: str) -> dict | None:
    """Every ``name`` message (``MAG``, ``ATT``, ...) of the log read by pymavlink's ``reader`` as ``{column: array}``, multipliers applied; None if it has none."""
    ids = [t for t, f in reader.formats.items() if f.name == name]
    offsets = np.asarray(reader.offsets[ids[0]] if ids else [], np.int64)  # offsets: a list by type id
    if offsets.size == 0:
        return None
    fmt = reader.formats[ids[0]]
    dtype = _dtype(fmt)
    buffer = np.frombuffer(reader.data_map, np.uint8)
    offsets = offsets[offsets + 3 + dtype.itemsize <= buffer.size]
    records = buffer[(offsets + 3)[:, None] + np.arange(dtype.itemsize)].copy().view(dtype).ravel()
    out = {}
    for col, mult in zip(fmt.columns, fmt.msg_mults):
        values = records[col]
        if mult is not None and values.dtype.kind in "iuf":
            values = values / (1 / mult) if 0 < mult < 1 else values * mult  # as pymavlink's DFMessage
        out[col] = values
    return out


#: the ``MAG`` fields the reader needs (ArduPilot 3.3 on: ``TimeUS``; older logs' ``TimeMS`` is not read)
MAG_FIELDS = ("TimeUS", "MagX", "MagY", "MagZ", "OfsX", "OfsY", "OfsZ")


def _with(rows: dict | None, fields) -> dict | None:
    """``rows`` if it holds a message and every one of ``fields``, else None."""
    return rows if rows is not None and all(f in rows for f in fields) and len(rows[fields[0]]) else None


def _instance(reader, name: str, instance: int) -> dict | None:
    """The messages of ``instance``: field ``I`` when present, else ``<name><k+1>`` for ``k > 0``."""
    rows = table(reader, name)
    if rows is not None and "I" in rows:
        keep = rows["I"] == instance
        return {k: v[keep] for k, v in rows.items()} if np.any(keep) else None
    return rows if instance == 0 else table(reader, f"{name}{instance + 1}")


def parameters(reader, before_us: float) -> dict:
    """``{name: value}`` of the log's ``PARM`` messages up to ``before_us`` (µs), the last value of each: the calibration in use at the first reading."""
    rows = table(reader, "PARM")
    if rows is None:
        return {}
    keep = rows["TimeUS"] <= before_us
    names = [n.split(b"\0")[0].decode("ascii", "replace") for n in rows["Name"][keep]]
    return dict(zip(names, rows["Value"][keep].astype(float).tolist()))


def correction(params: dict, instance: int) -> tuple[np.ndarray, float, np.ndarray]:
    """``(M, s, OFS)`` of compass ``instance`` (0: ``COMPASS_*``, k: ``COMPASS_*<k+1>``) from the log's ``params`` (module
    docstring); ``s`` is 1 outside :data:`SCALE_RANGE`, as ArduPilot applies it.
    """
    suffix = "" if instance == 0 else str(instance + 1)
    p = lambda key, axis, default: float(params.get(f"COMPASS_{key}{suffix}_{axis}", default))  # noqa: E731
    dia = [p("DIA", a, 1.0) for a in "XYZ"]
    if not any(dia):
        dia = [1.0, 1.0, 1.0]
    odi = [p("ODI", a, 0.0) for a in "XYZ"]
    m = np.array([[dia[0], odi[0], odi[1]], [odi[0], dia[1], odi[2]], [odi[1], odi[2], dia[2]]])
    scale = float(params.get(f"COMPASS_SCALE{suffix}", 1.0))
    scale = scale if SCALE_RANGE[0] <= scale <= SCALE_RANGE[1] else 1.0
    return m, scale, np.array([p("OFS", a, 0.0) for a in "XYZ"])


def undo_correction(mag: dict, params: dict, instance: int) -> tuple[np.ndarray, dict]:
    """``(r, meta)``: the raw body-frame field ``r = (M⁻¹ (B − MOFS)) / s − OFS`` (mGauss, module docstring) of the
    ``MAG`` messages ``mag``, and what was undone as ``meta`` text.
    """
    b = np.column_stack([mag[f"Mag{a}"] for a in "XYZ"]).astype(float)
    motor = np.column_stack([mag.get(f"MOfs{a}", np.zeros(len(b))) for a in "XYZ"]).astype(float)
    m, scale, ofs = correction(params, instance)
    logged = np.column_stack([mag[f"Ofs{a}"] for a in "XYZ"]).astype(float)
    agree = np.all(np.abs(logged - np.round(ofs)) <= 1, axis=1, keepdims=True)
    offsets = np.where(agree, ofs, logged)
    raw = np.linalg.solve(m, (b - motor).T).T / scale - offsets
    meta = {"corrected": "undone: ArduPilot B = M (s (r + OFS)) + MOFS, r = M^-1 (B - MOFS) / s - OFS (body frame)",
            "onboard_offset_mG": ", ".join(f"{v!r}" for v in ofs.tolist()), "onboard_scale": repr(scale),
            "onboard_matrix": matrix_text(m)}
    if not np.all(agree):
        meta["offsets"] = f"{int(np.sum(~agree))} readings use their logged OfsX/Y/Z (offsets changed in the log)"
    return raw, meta


def _gps(gps: dict | None) -> dict:
    """The log's place and date from its ``GPS`` messages with a 3D fix (:func:`magexp.core.logfiles.place`), {} without."""
    if gps is None:
        return {}
    fix = np.asarray(gps.get("Status", np.full(len(gps["Lat"]), 3))) >= 3
    when = None
    if "GWk" in gps and np.any(gps["GWk"][fix] > 0):
        k = int(np.flatnonzero(fix & (gps["GWk"] > 0))[0])
        when = GPS_EPOCH + _dt.timedelta(weeks=int(gps["GWk"][k]), milliseconds=int(gps["GMS"][k]))
    return place(gps["Lat"][fix], gps["Lng"][fix], gps["Alt"][fix], when)


@contextlib.contextmanager
def _silenced():
    """Everything written to standard output and error while the log is indexed, kept in a scratch
    file (deleted on close) instead: pymavlink's indexer, compiled code, prints one line per damaged
    byte (19,474 for 20 kB of random bytes) on the file descriptors themselves, its Python code
    on ``sys.stdout``. Yields the scratch file, read back by :func:`_check_headers`."""
    with tempfile.TemporaryFile() as sink, contextlib.redirect_stdout(io.StringIO()), \
            contextlib.redirect_stderr(io.StringIO()):
        for stream in (sys.__stdout__, sys.__stderr__):
            if stream is not None:
                stream.flush()
        saved = [os.dup(1), os.dup(2)]
        try:
            os.dup2(sink.fileno(), 1)
            os.dup2(sink.fileno(), 2)
            yield sink
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)


def _close(reader) -> None:
    """Close the file and the memory map of a refused log's ``reader`` (pymavlink has no ``close``); a map
    still viewed by an array stays open (closed with the reader when it is collected)."""
    for part in ("data_map", "filehandle"):
        with contextlib.suppress(AttributeError, BufferError, ValueError):
            getattr(reader, part).close()


def _check_headers(sink, name: str) -> None:
    """Refuse a log in which the indexer met a byte that starts no message (``sink``: its output, of
    :func:`_silenced`): at byte 0 the file is no DataFlash log, further on it is damaged (a flipped
    bit, a torn write), and messages were skipped. Says where, not what: the offset alone."""
    sink.seek(0)
    found = BAD_HEADER.search(sink.read(4096))
    if found is None:
        return
    at = int(found.group(1))
    if at == 0:
        raise MagexpError(f"data.path={name!r} is not allowed: it is no DataFlash log (byte 0 does not start a "
                          f"message {HEADER}); give an ArduPilot .bin log or set data.format")
    raise MagexpError(f"data.path={name!r} is not allowed: the DataFlash log is damaged at byte {at} (no message "
                      f"{HEADER} starts there, messages were skipped); give an undamaged copy of the log")


def _open(df, path: Path, name: str):
    """pymavlink's reader (module ``df``) of the log at ``path``, its indexer silenced; a file that is no
    log, or a damaged one, refused in one line (:func:`_check_headers`)."""
    with _silenced() as sink:
        try:
            reader = df.DFReader_binary(str(path), zero_time_base=False)
        except Exception as exc:  # pymavlink raises bare exceptions of many kinds on a damaged file
            reader = exc
        try:
            _check_headers(sink, name)
        except MagexpError:
            _close(reader)
            raise
    if isinstance(reader, Exception):
        raise MagexpError(f"{name}: not a readable DataFlash log ({type(reader).__name__})")
    return reader


def read_dataflash(path: Path, *, unit=None, mag_axes=None, gyro_axes=None, instance: int = 0,
                   undo: bool = True) -> Recording:
    """The :class:`~magexp.core.recording.Recording` of an ArduPilot DataFlash ``.bin`` log, the onboard correction undone.

    The readings are the raw body-frame field ``r = (M⁻¹ (B − MOFS)) / s − OFS`` of the logged ``MAG`` field ``B``
    (the inverse of ArduPilot's ``AP_Compass_Backend::correct_field``, module docstring), in mGauss, with the
    attitude of ``ATT``, the gyroscope of ``IMU`` and the GPS place and date.

    Parameters
    ----------
    path, unit, mag_axes, gyro_axes
        As ``read`` of every format (:mod:`magexp.core.readers`): ``path`` the ``.bin`` file; ``unit`` None or
        ``mG`` (DataFlash ``MAG`` is in mGauss).
    instance : int
        The compass and IMU instance (0: the first).
    undo : bool
        Undo the onboard correction (default); False keeps ``MagX/Y/Z`` as logged.

    Returns
    -------
    Recording
        The readings (mGauss) at their times (s from the log's first ``TimeUS``), the attitude angles, the
        gyroscope stream, the GPS place and date and the undone correction in ``meta``; the readings as logged
        in the columns :data:`magexp.core.logfiles.LOGGED`.

    Raises
    ------
    MagexpError
        One line when pymavlink is missing, ``unit`` is not ``mG``, the file is no DataFlash log or is damaged,
        it has no ``MAG`` message of ``instance``, or more readings than the ``readings`` limit.

    References
    ----------
    ArduPilot, ``libraries/AP_Compass/AP_Compass_Backend.cpp`` (``correct_field``) and ``AP_Compass.cpp``
    (``have_scale_factor``).
    """
    name = Path(path).name
    df = need("pymavlink.DFReader", f"{name} (an ArduPilot DataFlash log)")
    log_unit(unit, "mG", name, "DataFlash MAG")
    reader = _open(df, path, name)
    mag = _with(_instance(reader, "MAG", instance), MAG_FIELDS)
    if mag is None or len(mag["TimeUS"]) == 0:
        del mag
        _close(reader)
        raise MagexpError(f"{name}: no MAG messages of compass instance {instance} with {', '.join(MAG_FIELDS)}: "
                          "nothing to calibrate")
    check_count(len(mag["TimeUS"]), f"data.path={name!r}")
    att = _with(table(reader, "ATT"), ("TimeUS", "Roll", "Pitch", "Yaw"))
    imu = _with(_instance(reader, "IMU", instance), ("TimeUS", "GyrX", "GyrY", "GyrZ"))
    gps = _with(table(reader, "GPS"), ("Lat", "Lng", "Alt"))
    t_mag = mag["TimeUS"].astype(np.int64)
    t0 = min(int(rows["TimeUS"].min()) for rows in (mag, att, imu, gps) if rows is not None and "TimeUS" in rows)
    clock = lambda rows: (rows["TimeUS"].astype(np.int64) - t0) / 1e6  # noqa: E731
    meta = {"format": "dataflash", "source": "MAG" if instance == 0 else f"MAG instance {instance}"}
    logged = np.column_stack([mag[f"Mag{a}"] for a in "XYZ"]).astype(float)
    if undo:
        raw, undone = undo_correction(mag, parameters(reader, float(t_mag.min())), instance)
        meta.update(undone)
    else:
        raw = logged
        meta["corrected"] = "kept as logged (undo=False)"
    times = clock(mag)
    angles, gyro = None, None
    if att is not None:
        quats = euler_quaternions(*(np.deg2rad(att[k].astype(float)) for k in ("Roll", "Pitch", "Yaw")))
        angles = navigation_angles(clock(att), quats, times)
        meta["attitude"] = "ATT Roll, Pitch, Yaw (body -> NED)"
    if imu is not None:
        gyro = clock(imu), np.column_stack([imu[f"Gyr{a}"] for a in "XYZ"]).astype(float)
    meta.update(_gps(gps))
    return log_recording(Path(path), readings=raw, unit="mG", times=times, angles=angles, gyro=gyro, meta=meta,
                         mag_axes=mag_axes, gyro_axes=gyro_axes, logged=logged if undo else None)


#: the format's reader, by the name every format module gives it
read = read_dataflash
