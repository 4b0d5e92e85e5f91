"""Recorded magnetometer data with attitudes: the ``magexp-recording v1`` CSV format.

A recording is a text file: comment lines with metadata, then a CSV header and one
row per reading::

    # magexp-recording v1
    # source: Yan & Zhou 2022, Table 1
    # unit: nT
    # angles: rad
    # field: 34425, 1961, 35898
    bx,by,bz,heading,roll,trim
    4206,25290,36913,4.71239,0.02522,-0.00426
    ...

* The first line must be ``# magexp-recording v1`` (the format version).
* Metadata lines ``# key: value`` (optional): ``unit`` of ``bx, by, bz`` and ``field``
  (default ``nT``); ``angles`` ``rad`` (default) or ``deg``; ``field``: the ambient field
  vector in the geographic frame, three numbers (needed by models such as Yan & Zhou's
  ``B = K A Be + Bp`` unless the scenario config gives it); any other key (``source``...)
  is kept as free text.
* Required columns, in any order: ``bx, by, bz`` (sensor axes x, y, z) and the ship
  attitude ``heading`` (psi), ``roll`` (theta), ``trim`` (phi). Extra columns are kept
  in :attr:`Recording.columns`.
* Every value must be a finite number; every row must have as many fields as the header.

:func:`load_recording` refuses a malformed file with one :class:`~magexp.errors.MagexpError`
line naming the file, the line and the fault.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from magexp.errors import MagexpError
from magexp.paths import DATA

VERSION_LINE = "# magexp-recording v1"
FIELDS = ("bx", "by", "bz")
ANGLES = ("heading", "roll", "trim")
ANGLE_UNITS = ("rad", "deg")


@dataclass
class Recording:
    """A loaded recording.

    Attributes
    ----------
    readings : (N, 3) sensor readings ``[bx, by, bz]`` in ``unit``.
    angles : (N, 3) ``[heading, roll, trim]`` in radians (converted if the file says ``deg``).
    field : (3,) ambient field in the geographic frame, or None if the file gives none.
    unit : unit of ``readings`` and ``field``.
    meta : every metadata line as ``{key: text}``.
    columns : every column as ``{name: (N,) array}``.
    """

    readings: np.ndarray
    angles: np.ndarray
    field: np.ndarray | None
    unit: str
    meta: dict = field(default_factory=dict)
    columns: dict = field(default_factory=dict)


def resolve(path: str | Path) -> Path:
    """``path`` as given, or relative to the project's ``data/`` folder."""
    path = Path(path)
    return path if path.is_absolute() or path.exists() else DATA / path


def _number(text: str, where: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise MagexpError(f"{where}: {what}={text.strip()!r} is not a number") from None
    if not np.isfinite(value):
        raise MagexpError(f"{where}: {what}={text.strip()!r} is not allowed: it must be a finite number")
    return value


def _header(lines: list[str], name: str) -> tuple[dict, int]:
    if not lines or lines[0].strip() != VERSION_LINE:
        first = lines[0].strip() if lines else ""
        raise MagexpError(f"{name}: first line {first!r} is not allowed: it must be {VERSION_LINE!r}")
    meta, i = {}, 1
    while i < len(lines) and lines[i].lstrip().startswith("#"):
        key, sep, value = lines[i].lstrip()[1:].partition(":")
        if sep:
            meta[key.strip().lower()] = value.strip()
        i += 1
    return meta, i


def _field(meta: dict, name: str) -> np.ndarray | None:
    if "field" not in meta:
        return None
    parts = meta["field"].split(",")
    if len(parts) != 3:
        raise MagexpError(f"{name}: field={meta['field']!r} is not allowed: it must be three numbers separated by commas")
    return np.array([_number(p, name, "field") for p in parts])


def load_recording(path: str | Path) -> Recording:
    """Read a ``magexp-recording v1`` CSV (see the module docstring).

    Parameters
    ----------
    path : the file; a relative path not found from the working folder is looked up in ``data/``.

    Raises
    ------
    MagexpError
        One line for a missing file, a wrong version line, a missing column, a row of the
        wrong length, a value that is not a number, NaN or infinite, or a bad metadata value.
    """
    file = resolve(path)
    if not file.is_file():
        raise MagexpError(f"recording {str(path)!r} does not exist (looked in the working folder and {DATA})")
    name = file.name
    lines = file.read_text().splitlines()
    meta, start = _header(lines, name)
    unit = meta.get("unit", "nT")
    angle_unit = meta.get("angles", "rad")
    if angle_unit not in ANGLE_UNITS:
        raise MagexpError(f"{name}: angles={angle_unit!r} is not allowed: choose one of {', '.join(ANGLE_UNITS)}")
    rows = list(csv.reader(lines[start:]))
    if not rows:
        raise MagexpError(f"{name}: no header line: it must name the columns {', '.join(FIELDS + ANGLES)}")
    header = [h.strip().lower() for h in rows[0]]
    missing = [c for c in FIELDS + ANGLES if c not in header]
    if missing:
        raise MagexpError(f"{name}: missing column {', '.join(missing)}: the header must name "
                          f"{', '.join(FIELDS + ANGLES)} (has {', '.join(header)})")
    values = []
    for k, row in enumerate(rows[1:], start=start + 2):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise MagexpError(f"{name} line {k}: {len(row)} values, but the header has {len(header)} columns")
        values.append([_number(cell, f"{name} line {k}", col) for cell, col in zip(row, header)])
    if not values:
        raise MagexpError(f"{name}: no data rows after the header")
    table = np.array(values)
    columns = {col: table[:, j] for j, col in enumerate(header)}
    angles = np.column_stack([columns[c] for c in ANGLES])
    return Recording(
        readings=np.column_stack([columns[c] for c in FIELDS]),
        angles=np.deg2rad(angles) if angle_unit == "deg" else angles,
        field=_field(meta, name),
        unit=unit,
        meta=meta,
        columns=columns,
    )
