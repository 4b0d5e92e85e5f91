"""magexp's own versioned CSV, ``# magexp-recording v1`` (any text file no other format claims is read as one).

A recording is a text file: comment lines with metadata, then a CSV header and one row per reading::

    # magexp-recording v1
    # source: Yan & Zhou 2022, Table 1
    # unit: nT
    # angles: rad
    # field: 34425, 1961, 35898
    bx,by,bz,heading,roll,trim
    4206,25290,36913,4.71239,0.02522,-0.00426
    ...

* The first line must be ``# magexp-recording v1`` (the format version).
* Metadata lines ``# key: value`` (all optional):

  - ``unit``: unit of ``bx, by, bz``, ``total``, ``reference_total`` and ``field``, one of
    ``nT, uT, mG, G, T`` (default ``nT``; ``µT`` is read as ``uT``). Values are kept in this
    unit and the unit is carried along (:attr:`Recording.unit`; :data:`magexp.core.recording.UNITS`
    gives the factor to nT); a calibration reports its numbers in the same unit.
  - ``reference_total``: the local total field, one number (for a scalar calibration).
  - ``field``: the ambient field vector in the navigation frame, three numbers separated by
    commas (needed by vector models: Yan & Zhou's ``B = K A Be + Bp``, the ``vector``
    objective). Its norm also serves as the reference total field when neither
    ``reference_total`` nor a ``total`` column is given.
  - ``angles``: ``rad`` (default) or ``deg``, unit of ``heading, roll, trim``.
  - ``gyro``: ``rad/s`` (default) or ``deg/s``, unit of ``gx, gy, gz``; ``sample_time``: the
    time between readings in seconds (required with gyro columns).
  - any other key (``source``, ...) is kept as free text in :attr:`Recording.meta`.

* Columns, in any order (header names are case-insensitive):

  - required: ``bx, by, bz`` (sensor axes x, y, z);
  - optional ``total``: reference total field per reading;
  - optional attitude angles ``heading`` (psi), ``roll`` (theta), ``trim`` (phi), all three
    or none: the attitude ``A = Ry(trim) Rx(roll) Rz(heading)`` of Yan & Zhou's eq 2,
    navigation -> sensor frame. The ship scenario requires them;
  - optional gyro rates ``gx, gy, gz`` (sensor frame), all three or none: the attitude of
    reading ``k`` is the rates integrated over the ``k`` preceding sample intervals, the
    sensor frame at the first reading being the navigation frame (``field`` is then given
    in that frame);
  - extra columns are kept in :attr:`Recording.columns`.

* Every value must be a finite number; every row must have as many fields as the header.
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np

from magexp.core.textfiles import GYRO, GYRO_UNITS, check_unique, number, read_lines
from magexp.core.recording import Recording, check_unit
from magexp.errors import MagexpError, excerpt

NAME = "magexp-v1"
PRIORITY = 50
SUFFIXES = ()
UNIT = "its `# unit:` line (default nT)"
EXTRA = None
BINARY = False
READ_MEMORY = 80
#: a text file no other format claims is read as this format (its reader then names what is wrong)
FALLBACK = True
#: the first line of every file of this format
VERSION_LINE = "# magexp-recording v1"
#: the readings' columns, the attitude's, and the units the angles may be given in
FIELDS = ("bx", "by", "bz")
ANGLES = ("heading", "roll", "trim")
ANGLE_UNITS = ("rad", "deg")


def sniff(head: list[str]) -> bool:
    """The first line is ``# magexp-recording v1``."""
    return head[0].strip() == VERSION_LINE


def read(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """The readings, angles or gyro rates, the file's field and reference total, and its other columns."""
    return _versioned(read_lines(path), path.name, unit)


def _header(lines: list[str], name: str) -> tuple[dict, int]:
    """The ``# key: value`` metadata and the index of the first line after it; one line if line 1 is not the version line."""
    if not lines or lines[0].strip() != VERSION_LINE:
        first = lines[0].rstrip("\r\n") if lines else ""
        col = len(os.path.commonprefix([first, VERSION_LINE])) + 1  # where it departs from the version line
        found = f"found {excerpt(first[col - 1:col])}" if col <= len(first) else "the line ends"
        raise MagexpError(f"{name} line 1, column {col}: {found}, expected {VERSION_LINE!r} as the first line "
                          "(or plain numbers in three columns)")
    meta, i = {}, 1
    while i < len(lines) and lines[i].lstrip().startswith("#"):
        key, sep, value = lines[i].lstrip()[1:].partition(":")
        if sep:
            meta[key.strip().lower()] = value.strip()
        i += 1
    return meta, i


def _field(meta: dict, name: str) -> np.ndarray | None:
    """The ``# field:`` vector (three numbers), or None without the line."""
    if "field" not in meta:
        return None
    parts = meta["field"].split(",")
    if len(parts) != 3:
        raise MagexpError(f"{name}: field={meta['field']!r} is not allowed: it must be three numbers separated by commas")
    return np.array([number(p, name, "field") for p in parts])


def _choice(meta: dict, key: str, allowed: tuple[str, ...], name: str) -> str:
    """The ``# <key>:`` value (default: the first of ``allowed``), one of ``allowed``, else one line."""
    value = meta.get(key, allowed[0])
    if value not in allowed:
        raise MagexpError(f"{name}: {key}={value!r} is not allowed: choose one of {', '.join(allowed)}")
    return value


def _group(columns: dict, names: tuple[str, ...], what: str, name: str) -> np.ndarray | None:
    """The columns ``names`` stacked (N, len(names)), None if none is present; all or none."""
    present = [c for c in names if c in columns]
    if not present:
        return None
    missing = [c for c in names if c not in columns]
    if missing:
        raise MagexpError(f"{name}: missing column {', '.join(missing)}: {what} needs all of {', '.join(names)}")
    return np.column_stack([columns[c] for c in names])


def _csv_table(lines: list[str], name: str, first_line: int) -> tuple[list[str], np.ndarray]:
    """Header and values of CSV ``lines``; ``first_line`` is the file line number of the header."""
    rows = list(csv.reader(lines))
    if not rows:
        raise MagexpError(f"{name}: no header line: it must name the columns {', '.join(FIELDS)}")
    header = [h.strip().lower() for h in rows[0]]
    check_unique(header, name)
    missing = [c for c in FIELDS if c not in header]
    if missing:
        raise MagexpError(f"{name}: missing column {', '.join(missing)}: the header must name "
                          f"{', '.join(FIELDS)} (has {excerpt(', '.join(header))})")
    values = []
    for k, row in enumerate(rows[1:], start=first_line + 1):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise MagexpError(f"{name} line {k}: {len(row)} values, but the header has {len(header)} columns")
        values.append([number(cell, f"{name} line {k}", col) for cell, col in zip(row, header)])
    if not values:
        raise MagexpError(f"{name}: no data rows after the header")
    return header, np.array(values)


def _versioned(lines: list[str], name: str, unit: str | None) -> Recording:
    """The Recording of a ``magexp-recording v1`` file's ``lines`` (module docstring)."""
    meta, start = _header(lines, name)
    file_unit = _file_unit(meta, name, unit)
    angle_unit = _choice(meta, "angles", ANGLE_UNITS, name)
    gyro_unit = _choice(meta, "gyro", GYRO_UNITS, name)
    header, table = _csv_table(lines[start:], name, start + 1)
    columns = {col: table[:, j] for j, col in enumerate(header)}
    angles = _group(columns, ANGLES, "an attitude", name)
    gyro = _group(columns, GYRO, "a gyro", name)
    sample_time = None if gyro is None else _sample_time(meta, name)
    reference = _positive_meta(meta, "reference_total", name)
    if "total" in columns and np.any(columns["total"] <= 0):
        k = int(np.argmax(columns["total"] <= 0))
        raise MagexpError(f"{name} line {start + 2 + k}: total={columns['total'][k]:g} is not allowed: it must be > 0")
    return Recording(
        readings=np.column_stack([columns[c] for c in FIELDS]),
        angles=None if angles is None else (np.deg2rad(angles) if angle_unit == "deg" else angles),
        field=_field(meta, name),
        unit=file_unit,
        meta=meta,
        columns=columns,
        total=columns.get("total"),
        reference_total=reference,
        gyro=None if gyro is None else (np.deg2rad(gyro) if gyro_unit == "deg/s" else gyro),
        sample_time=sample_time,
    )


def _file_unit(meta: dict, name: str, unit: str | None) -> str:
    """The unit the file's ``# unit:`` line gives (nT without one); a ``data.unit`` given as well must agree."""
    file_unit = check_unit(meta.get("unit", "nT"), f"{name}: unit")
    if unit is not None and check_unit(unit, "data.unit") != file_unit:
        raise MagexpError(f"data.unit={unit!r} is not allowed for {name}: the file says '# unit: {file_unit}' "
                          "(leave data.unit unset)")
    return file_unit


def _sample_time(meta: dict, name: str) -> float:
    """The ``# sample_time:`` (seconds, > 0) that gyro columns need."""
    if "sample_time" not in meta:
        raise MagexpError(f"{name}: gyro columns gx, gy, gz need a '# sample_time: <seconds>' line")
    return _positive_meta(meta, "sample_time", name)


def _positive_meta(meta: dict, key: str, name: str) -> float | None:
    """The number of the ``# <key>:`` line, which must be > 0 (None without the line)."""
    if key not in meta:
        return None
    value = number(meta[key], name, key)
    if value <= 0:
        raise MagexpError(f"{name}: {key}={meta[key]!r} is not allowed: it must be > 0")
    return value
