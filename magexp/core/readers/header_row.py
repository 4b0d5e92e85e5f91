"""A CSV whose first row names its columns: the magnetometer ``x,y,z``, ``mx,my,mz`` or ``bx,by,bz``
(first found, in that order: ``bx``, ``mx``, ``x``); optionally a time ``t`` (or ``t_s``, ``time``,
``timestamp``; seconds, increasing), a gyroscope ``gx,gy,gz`` (rad/s; ``gx_dps`` or ``gx (deg/s)``: deg/s;
it needs the time column), an accelerometer ``ax,ay,az`` and any other column (kept, unused); separated by
commas, semicolons, tabs or spaces.

A column's unit is its suffix (``mx_uT``, ``mx_G``, ``mx (uT)``), else ``data.unit``; a suffix and
``data.unit`` must agree.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from magexp.core.geometry import axis_map
from magexp.core.textfiles import (GYRO, GYRO_UNITS, RATE_SUFFIX, UNIT_SUFFIX, check_unique, numeric_table,
                                       read_lines, same_unit, to_rad_s)
from magexp.core.recording import RAW_UNITS, UNITS, Recording, check_unit
from magexp.errors import MagexpError, excerpt

NAME = "header-row"
PRIORITY = 80
SUFFIXES = ()
UNIT = "the magnetometer columns' suffix (`mx_uT`), else `data.unit`"
EXTRA = None
BINARY = False
READ_MEMORY = 80
#: the magnetometer columns a header row may name, first found used (:func:`read`; a DataFrame's too)
MAG_COLUMNS = (("bx", "by", "bz"), ("mx", "my", "mz"), ("x", "y", "z"))
#: the names of a header row's time column (seconds)
TIME_COLUMNS = ("t", "t_s", "time", "time_s", "timestamp")
#: a header row's column: a name, then optionally its unit as ``_<suffix>`` or `` (<unit>)``
_COLUMN = re.compile(r"^(?P<base>[a-z][a-z0-9]*?)(?:_(?P<suffix>[a-z]+)|\s*\((?P<unit>[^)]*)\))?$")


def header_cells(line: str) -> list[str]:
    """The stripped cells of a header row: split at commas, semicolons or tabs if it has any, else at spaces."""
    text = line.strip()
    return [c.strip() for c in (re.split(r"[,;\t]", text) if re.search(r"[,;\t]", text) else text.split())]


def header_columns(line: str) -> dict[str, tuple[int, str | None]] | None:
    """``{name: (index, unit or None)}`` of a header row that names a magnetometer (:data:`MAG_COLUMNS`), else None;
    a name is lower case without its unit, given as ``_<suffix>`` (``mx_ut``, ``gx_dps``) or ``(<unit>)``.
    """
    columns = {}
    for j, cell in enumerate(header_cells(line)):
        m = _COLUMN.match(cell.lower())
        if m is None:
            columns[cell.lower()] = (j, None)
            continue
        suffix = m["suffix"]
        known = suffix in UNIT_SUFFIX or suffix in RATE_SUFFIX or suffix == "s"
        base = m["base"] if suffix is None or known else f"{m['base']}_{suffix}"
        columns[base] = (j, m["unit"] if m["unit"] is not None else suffix if known else None)
    return columns if any(all(c in columns for c in names) for names in MAG_COLUMNS) else None


def sniff(head: list[str]) -> bool:
    """The first line names the magnetometer's columns (``bx,by,bz``, ``mx,my,mz`` or ``x,y,z``)."""
    return header_columns(head[0].strip()) is not None


def read(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """The readings, their times and the gyroscope stream when the file has them, and its other columns."""
    lines = read_lines(path)
    header = header_cells(lines[0]) if lines else []
    check_unique([h.lower() for h in header], path.name)
    columns = header_columns(lines[0]) if lines else None
    if columns is None:
        raise MagexpError(f"{path.name}: header {excerpt(','.join(header))} is not allowed: it must name the "
                          f"magnetometer's columns, one of {'; '.join(', '.join(n) for n in MAG_COLUMNS)}")
    rows = lines[1:] if "," in lines[0] else [",".join(header_cells(ln)) for ln in lines[1:]]
    table = numeric_table(rows, path.name, 2, len(header))
    mag = next(names for names in MAG_COLUMNS if all(c in columns for c in names))
    times = _header_times(columns, table, path.name)
    rec = Recording(readings=table[:, [columns[c][0] for c in mag]] @ axis_map(mag_axes, "data.mag_axes").T,
                    angles=None, field=None, unit=_header_unit(columns, mag, unit, path.name),
                    meta={"format": "header-row"}, times=times, path=path,
                    columns={name: table[:, j] for name, (j, _) in columns.items()})
    if all(c in columns for c in GYRO):
        rates = _header_rates(columns, table, times, path.name)
        rec.gyro_stream = (times, rates @ axis_map(gyro_axes, "data.gyro_axes").T)
    return rec


def _one_unit(columns: dict, names, what: str, name: str) -> str | None:
    """The one unit the header gives the columns ``names`` (None: none), else one line."""
    units = {columns[c][1] for c in names}
    if len(units) != 1:
        raise MagexpError(f"{name}: {what} units {sorted(map(str, units))} are not allowed: give the three columns "
                          "one unit")
    return units.pop()


def _header_unit(columns: dict, mag, unit, name: str) -> str:
    """The magnetometer's unit: its columns' suffix (which ``data.unit`` must agree with), else ``data.unit``."""
    suffix = _one_unit(columns, mag, "magnetometer", name)
    if suffix is None:
        if unit is None:
            raise MagexpError(f"data.unit=None is not allowed for {name}: its header does not name the unit "
                              f"of {', '.join(mag)}, give data.unit=<{'|'.join((*UNITS, *RAW_UNITS))}>")
        return check_unit(unit, "data.unit")
    file_unit = check_unit(UNIT_SUFFIX.get(suffix.lower(), suffix), f"{name}: magnetometer unit")
    same_unit(unit, file_unit, name)
    return file_unit


def _header_times(columns: dict, table: np.ndarray, name: str) -> np.ndarray | None:
    """The time column (:data:`TIME_COLUMNS`, seconds, increasing), or None."""
    time = next((c for c in TIME_COLUMNS if c in columns), None)
    if time is None:
        return None
    times = table[:, columns[time][0]]
    if np.any(np.diff(times) <= 0):
        k = int(np.argmax(np.diff(times) <= 0)) + 3
        raise MagexpError(f"{name} line {k}: {time}={times[k - 2]:g} is not allowed: times must increase")
    return times


def _header_rates(columns: dict, table: np.ndarray, times, name: str) -> np.ndarray:
    """The gyroscope's ``gx, gy, gz`` in rad/s (their suffix: ``dps``, ``rps``, ``(deg/s)``; none: rad/s)."""
    if times is None:
        raise MagexpError(f"{name}: gyro columns gx, gy, gz need a time column (one of {', '.join(TIME_COLUMNS)}, "
                          "seconds) to be integrated")
    rate = _one_unit(columns, GYRO, "gyroscope", name)
    rate_unit = "rad/s" if rate is None else RATE_SUFFIX.get(rate, rate)
    if rate_unit not in GYRO_UNITS:
        raise MagexpError(f"{name}: gyroscope unit {rate!r} is not allowed: choose one of {', '.join(GYRO_UNITS)} "
                          "(suffix _dps or _rps)")
    return to_rad_s(table[:, [columns[c][0] for c in GYRO]], rate_unit)
