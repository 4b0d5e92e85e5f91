"""Recorded magnetometer data: the ``magexp-recording v1`` CSV format, and plain 3-column files.

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
* Metadata lines ``# key: value`` (all optional):

  - ``unit``: unit of ``bx, by, bz``, ``total``, ``reference_total`` and ``field``, one of
    ``nT, uT, mG, G, T`` (default ``nT``; ``µT`` is read as ``uT``). Values are kept in this
    unit and the unit is carried along (:attr:`Recording.unit`; :data:`UNITS` gives the
    factor to nT); a calibration reports its numbers in the same unit.
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

A plain numeric file without header or metadata, exactly three columns ``x y z``
separated by tabs, commas or spaces, is read as readings only; its unit is not in the file,
so it must be given by the caller (``unit=``; on the command line ``data.unit=uT``).

:func:`load_recording` refuses a malformed file with one :class:`~magexp.errors.MagexpError`
line naming the file, the line and the fault.
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from magexp.errors import LARGEST, MagexpError
from magexp.paths import DATA

VERSION_LINE = "# magexp-recording v1"
FIELDS = ("bx", "by", "bz")
ANGLES = ("heading", "roll", "trim")
GYRO = ("gx", "gy", "gz")
ANGLE_UNITS = ("rad", "deg")
GYRO_UNITS = ("rad/s", "deg/s")
#: Allowed units of the readings and their factor to nT.
UNITS = {"nT": 1.0, "uT": 1e3, "mG": 100.0, "G": 1e5, "T": 1e9}
_ALIASES = {"µt": "uT", "μt": "uT"}


@dataclass
class Recording:
    """A loaded recording.

    Attributes
    ----------
    readings : (N, 3) sensor readings ``[bx, by, bz]`` in ``unit``.
    angles : (N, 3) ``[heading, roll, trim]`` in radians (converted if the file says ``deg``),
        or None if the file has no attitude columns.
    field : (3,) ambient field in the navigation frame, or None if the file gives none.
    unit : unit of ``readings``, ``field`` and the reference totals (a key of :data:`UNITS`).
    meta : every metadata line as ``{key: text}``.
    columns : every column as ``{name: (N,) array}``.
    total : (N,) reference total field per reading (``total`` column), or None.
    reference_total : the ``# reference_total:`` value, or None.
    gyro : (N, 3) gyro rates in rad/s, or None.
    sample_time : seconds between readings (with ``gyro``), or None.
    """

    readings: np.ndarray
    angles: np.ndarray | None
    field: np.ndarray | None
    unit: str
    meta: dict = field(default_factory=dict)
    columns: dict = field(default_factory=dict)
    total: np.ndarray | None = None
    reference_total: float | None = None
    gyro: np.ndarray | None = None
    sample_time: float | None = None
    path: Path | None = None

    @property
    def n(self) -> int:
        return int(self.readings.shape[0])


def resolve(path: str | Path) -> Path:
    """``path`` as given, or relative to the project's ``data/`` folder."""
    path = Path(path)
    return path if path.is_absolute() or path.exists() else DATA / path


def check_unit(unit: str, what: str) -> str:
    """``unit`` spelled as in :data:`UNITS`, or a one-line error naming ``what``."""
    text = str(unit).strip()
    text = _ALIASES.get(text.lower(), text)
    if text not in UNITS:
        raise MagexpError(f"{what}={unit!r} is not allowed: choose one of {', '.join(UNITS)}")
    return text


def _number(text: str, where: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise MagexpError(f"{where}: {what}={text.strip()!r} is not a number") from None
    if not abs(value) <= LARGEST:
        raise MagexpError(f"{where}: {what}={text.strip()!r} is not allowed: it must be a finite number "
                          f"of magnitude <= {LARGEST:g}")
    return value


def _header(lines: list[str], name: str) -> tuple[dict, int]:
    if not lines or lines[0].strip() != VERSION_LINE:
        first = lines[0].strip() if lines else ""
        raise MagexpError(f"{name}: first line {first!r} is not allowed: it must be {VERSION_LINE!r} "
                          "(or the file must be plain numbers in three columns)")
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


def _choice(meta: dict, key: str, allowed: tuple[str, ...], name: str) -> str:
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


def _split(line: str) -> list[str]:
    return [cell for cell in re.split(r"[,\s]+", line.strip()) if cell]


def _is_plain(lines: list[str]) -> bool:
    """A headerless numeric file: the first non-blank line is numbers only."""
    first = next((ln for ln in lines if ln.strip()), "")
    try:
        [float(cell) for cell in _split(first)]
    except ValueError:
        return False
    return bool(_split(first))


def _plain_table(lines: list[str], name: str) -> np.ndarray:
    values = []
    for k, line in enumerate(lines, start=1):
        cells = _split(line)
        if not cells:
            continue
        if len(cells) != 3:
            raise MagexpError(f"{name} line {k}: {len(cells)} values, but a file without header must have "
                              "exactly 3 columns x y z")
        values.append([_number(cell, f"{name} line {k}", axis) for cell, axis in zip(cells, "xyz")])
    return np.array(values)


def _csv_table(lines: list[str], name: str, first_line: int) -> tuple[list[str], np.ndarray]:
    """Header and values of CSV ``lines``; ``first_line`` is the file line number of the header."""
    rows = list(csv.reader(lines))
    if not rows:
        raise MagexpError(f"{name}: no header line: it must name the columns {', '.join(FIELDS)}")
    header = [h.strip().lower() for h in rows[0]]
    missing = [c for c in FIELDS if c not in header]
    if missing:
        raise MagexpError(f"{name}: missing column {', '.join(missing)}: the header must name "
                          f"{', '.join(FIELDS)} (has {', '.join(header)})")
    values = []
    for k, row in enumerate(rows[1:], start=first_line + 1):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise MagexpError(f"{name} line {k}: {len(row)} values, but the header has {len(header)} columns")
        values.append([_number(cell, f"{name} line {k}", col) for cell, col in zip(row, header)])
    if not values:
        raise MagexpError(f"{name}: no data rows after the header")
    return header, np.array(values)


def _versioned(lines: list[str], name: str, unit: str | None) -> Recording:
    meta, start = _header(lines, name)
    file_unit = check_unit(meta.get("unit", "nT"), f"{name}: unit")
    if unit is not None and check_unit(unit, "data.unit") != file_unit:
        raise MagexpError(f"data.unit={unit!r} is not allowed for {name}: the file says '# unit: {file_unit}' "
                          "(leave data.unit unset)")
    angle_unit = _choice(meta, "angles", ANGLE_UNITS, name)
    gyro_unit = _choice(meta, "gyro", GYRO_UNITS, name)
    header, table = _csv_table(lines[start:], name, start + 1)
    columns = {col: table[:, j] for j, col in enumerate(header)}
    angles = _group(columns, ANGLES, "an attitude", name)
    gyro = _group(columns, GYRO, "a gyro", name)
    sample_time = None
    if gyro is not None:
        if "sample_time" not in meta:
            raise MagexpError(f"{name}: gyro columns gx, gy, gz need a '# sample_time: <seconds>' line")
        sample_time = _number(meta["sample_time"], name, "sample_time")
        if sample_time <= 0:
            raise MagexpError(f"{name}: sample_time={meta['sample_time']!r} is not allowed: it must be > 0")
    reference = _number(meta["reference_total"], name, "reference_total") if "reference_total" in meta else None
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


def load_recording(path: str | Path, *, unit: str | None = None) -> Recording:
    """Read a ``magexp-recording v1`` CSV or a plain 3-column numeric file (see the module docstring).

    Parameters
    ----------
    path : the file; a relative path not found from the working folder is looked up in ``data/``.
    unit : unit of a plain file's readings (required for one); for a ``magexp-recording v1``
        file it may be left None, and must otherwise agree with the file's ``# unit:``.

    Raises
    ------
    MagexpError
        One line for a missing file, a wrong version line, a missing column, a row of the
        wrong length, a value that is not a number, NaN or infinite, an unknown unit, or a
        bad metadata value.
    """
    file = resolve(path)
    if file.is_dir():
        raise MagexpError(f"recording {str(path)!r} is a directory: give a file")
    if not file.is_file():
        raise MagexpError(f"recording {str(path)!r} does not exist (looked in the working folder and {DATA})")
    name = file.name
    try:  # a UTF-8 byte-order mark is accepted
        lines = file.read_text(encoding="utf-8-sig").splitlines()
    except UnicodeDecodeError as exc:
        raise MagexpError(f"{name}: byte {exc.start} is not UTF-8 text: a recording must be a text file "
                          "(CSV or 3 numeric columns)") from None
    if _is_plain(lines):
        if unit is None:
            raise MagexpError(f"data.unit=None is not allowed for {name}: a file without header does not name "
                              f"its unit, give data.unit=<{'|'.join(UNITS)}>")
        rec = Recording(readings=_plain_table(lines, name), angles=None, field=None,
                        unit=check_unit(unit, "data.unit"), meta={"format": "plain 3 columns"})
    else:
        rec = _versioned(lines, name, unit)
    rec.path = file
    return rec
