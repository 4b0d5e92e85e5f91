"""One CSV with named, unit-bearing columns ``Time (s)``, ``Gyroscope X (deg/s)``, ``Magnetometer X (uT)``,
... (the x-io Fusion file). A magnetometer slower than the row rate repeats its value: only the rows where
it changes are readings (at their row times); the gyroscope stream keeps every row.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from magexp.core.geometry import axis_map
from magexp.core.textfiles import GYRO_UNITS, check_unique, numeric_table, read_lines, same_unit, to_rad_s
from magexp.core.recording import Recording, check_unit
from magexp.errors import MagexpError

NAME = "named-columns"
PRIORITY = 70
SUFFIXES = ()
UNIT = "the magnetometer columns' names (`Magnetometer X (uT)`)"
EXTRA = None
BINARY = False
READ_MEMORY = 80
#: a ``named-columns`` column: ``<Sensor> <X|Y|Z> (<unit>)``
NAMED = re.compile(r"^\s*(\w+)\s+([xyz])\s*\((.+)\)\s*$", re.IGNORECASE)


def sniff(head: list[str]) -> bool:
    """The first line's last comma-separated cell is a ``<Sensor> X (<unit>)`` column."""
    first = head[0].strip()
    return bool(NAMED.match(first.split(",")[-1] if "," in first else ""))


def read(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """The readings where the magnetometer updated, at their times, and the gyroscope stream."""
    lines = read_lines(path)
    header = [h.strip() for h in lines[0].split(",")]
    check_unique([h.lower() for h in header], path.name)
    groups = _named_groups(header)
    time_col = next((j for j, h in enumerate(header) if h.lower().startswith("time")), None)
    mag = groups.get("magnetometer", {})
    if time_col is None or sorted(mag) != ["x", "y", "z"]:
        raise MagexpError(f"{path.name}: columns must include 'Time (s)' and 'Magnetometer X/Y/Z (<unit>)'")
    table = numeric_table(lines[1:], path.name, 2, len(header))
    mag_unit = check_unit({mag[a][1] for a in "xyz"}.pop(), f"{path.name}: magnetometer unit")
    same_unit(unit, mag_unit, path.name)
    values = table[:, [mag[a][0] for a in "xyz"]]
    fresh = np.concatenate([[True], np.any(np.diff(values, axis=0) != 0, axis=1)])
    rec = Recording(readings=values[fresh] @ axis_map(mag_axes, "data.mag_axes").T, angles=None, field=None,
                    unit=mag_unit, meta={"format": "named-columns", "rows": str(len(table))},
                    times=table[fresh, time_col], path=path,
                    columns={h: table[fresh, j] for j, h in enumerate(header)})
    gyro = groups.get("gyroscope", {})
    if sorted(gyro) == ["x", "y", "z"]:
        rates = _named_rates(table, gyro, path.name)
        rec.gyro_stream = (table[:, time_col], rates @ axis_map(gyro_axes, "data.gyro_axes").T)
    return rec


def _named_groups(header: list[str]) -> dict[str, dict[str, tuple[int, str]]]:
    """``{sensor: {axis: (column, unit)}}`` of the ``<Sensor> <X|Y|Z> (<unit>)`` columns of ``header``."""
    groups: dict[str, dict[str, tuple[int, str]]] = {}
    for j, h in enumerate(header):
        m = NAMED.match(h)
        if m:
            groups.setdefault(m.group(1).lower(), {})[m.group(2).lower()] = (j, m.group(3).strip())
    return groups


def _named_rates(table: np.ndarray, gyro: dict[str, tuple[int, str]], name: str) -> np.ndarray:
    """The gyroscope columns ``gyro`` (:func:`_named_groups`) of ``table`` in rad/s."""
    rate_unit = {gyro[a][1] for a in "xyz"}.pop()
    if rate_unit not in GYRO_UNITS:
        raise MagexpError(f"{name}: gyroscope unit {rate_unit!r} is not allowed: choose one of "
                          f"{', '.join(GYRO_UNITS)}")
    return to_rad_s(table[:, [gyro[a][0] for a in "xyz"]], rate_unit)
