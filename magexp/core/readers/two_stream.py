"""A magnetometer file ``<stem>_mag.csv`` (``t_s, mx_<unit>, ...``) and an IMU file ``<stem>_imu.csv``
(``t_s, gx_dps, ...``) with their own timestamps and rates (the HMC5883L + MPU6050 recordings); name either
file or the stem. The gyroscope is *integrated* at the magnetometer's times, not resampled: each gyro
sample is held until the next one and propagated exactly over the merged time grid.

The integration: :meth:`magexp.core.recording.Recording.attitude`. For the HMC5883L + MPU6050 files the data decide the
gyroscope's axes: a gyro-aided fit (:mod:`magexp.problems.gyro`) with the gyroscope as recorded leaves
about 2 % of the field as vector residual, with its x axis flipped (``-x,y,z``, the authors' note on the
gyroscope alone) over 50 %: the magnetometer's unstated x convention evidently matches the gyroscope's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from magexp.core.datafiles import TWO_STREAM
from magexp.core.geometry import axis_map
from magexp.core.textfiles import RATE_SUFFIX, UNIT_SUFFIX, check_unique, numeric_table, read_lines, same_unit, to_rad_s
from magexp.core.recording import Recording
from magexp.errors import MagexpError, excerpt

NAME = "two-stream"
PRIORITY = 40
SUFFIXES = ()
UNIT = "the magnetometer columns' suffix (`mx_uT`)"
EXTRA = None
BINARY = False
READ_MEMORY = 80


def claims(path: Path) -> bool:
    """A name ending in ``_mag.csv`` or ``_imu.csv``, or a stem whose ``<stem>_mag.csv`` exists."""
    return str(path).endswith(TWO_STREAM) or (not path.is_file() and Path(f"{path}{TWO_STREAM[0]}").is_file())


def read(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """The readings at the magnetometer's times, and the gyroscope stream at its own."""
    stem = str(path)
    for tail in TWO_STREAM:
        stem = stem[: -len(tail)] if stem.endswith(tail) else stem
    mag_path, imu_path = (Path(stem + tail) for tail in TWO_STREAM)
    for p in (mag_path, imu_path):
        if not p.is_file():
            raise MagexpError(f"recording {str(p)!r} does not exist: a two-stream recording needs both "
                              f"{mag_path.name} and {imu_path.name}")
    t_mag, mag, mag_unit = _stream(mag_path, "m", UNIT_SUFFIX)
    t_imu, gyro, rate_unit = _stream(imu_path, "g", RATE_SUFFIX)
    same_unit(unit, mag_unit, mag_path.name)
    rates = to_rad_s(gyro, rate_unit) @ axis_map(gyro_axes, "data.gyro_axes").T
    return Recording(readings=mag @ axis_map(mag_axes, "data.mag_axes").T, angles=None, field=None,
                     unit=mag_unit, meta={"format": "two-stream", "gyro_axes": str(gyro_axes)},
                     times=t_mag, gyro_stream=(t_imu, rates), path=mag_path)


def _stream(path: Path, prefix: str, suffixes: dict) -> tuple[np.ndarray, np.ndarray, str]:
    """``(times, xyz, unit)`` of a ``t_s, <p>x_<u>, <p>y_<u>, <p>z_<u>[, ...]`` CSV."""
    lines = read_lines(path)
    header = [h.strip().lower() for h in lines[0].split(",")] if lines else []
    check_unique(header, path.name)
    cols = [next((c for c in header if c.startswith(f"{prefix}{a}_")), None) for a in "xyz"]
    if not header or header[0] != "t_s" or None in cols:
        raise MagexpError(f"{path.name}: header {excerpt(','.join(header))} is not allowed: it must start with t_s and "
                          f"name {prefix}x_<unit>, {prefix}y_<unit>, {prefix}z_<unit>")
    units = {c.split("_", 1)[1] for c in cols}
    if len(units) != 1 or next(iter(units)) not in suffixes:
        raise MagexpError(f"{path.name}: unit suffix {'/'.join(sorted(units))!r} is not allowed: choose one of "
                          f"{', '.join(suffixes)}")
    table = numeric_table(lines[1:], path.name, 2, len(header))
    t = table[:, 0]
    if np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0)) + 3
        raise MagexpError(f"{path.name} line {k}: t_s={t[k - 2]:g} is not allowed: times must increase")
    return t, table[:, [header.index(c) for c in cols]], suffixes[next(iter(units))]
