"""The readers of the text formats: magexp's own ``magexp-recording v1`` CSV (:func:`read_versioned`, the
format described in :mod:`magexp.core.recordings`), a headerless ``x y z`` table (:func:`read_plain`), a
magnetometer and an IMU file with their own clocks (:func:`read_two_stream`), unit-bearing named columns
(:func:`read_named_columns`), raw counts after ``Fs,``/``Initialization time,`` lines
(:func:`read_header_counts`) and a CSV whose first row names its columns (:func:`read_header_row`); and the
parsing they share, with one-line errors naming the file, the line and the fault. Their format names and
detection: :mod:`magexp.core.formats`; the logs' readers: :mod:`magexp.core.readers`.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path

import numpy as np

from magexp.core.datafiles import TWO_STREAM
from magexp.core.formats import (MAG_COLUMNS, NAMED, RATE_SUFFIX, TIME_COLUMNS, UNIT_SUFFIX, VERSION_LINE,
                                 header_cells, header_columns, split)
from magexp.core.geometry import axis_map
from magexp.core.recording import RAW_UNITS, UNITS, Recording, check_unit
from magexp.errors import LARGEST, MagexpError, excerpt

FIELDS = ("bx", "by", "bz")
ANGLES = ("heading", "roll", "trim")
GYRO = ("gx", "gy", "gz")
ANGLE_UNITS = ("rad", "deg")
GYRO_UNITS = ("rad/s", "deg/s")


def number(text: str, where: str, what: str) -> float:
    """``text`` as a finite number of magnitude at most :data:`LARGEST`, else one line.

    Parameters
    ----------
    text, where, what : str
        A cell, and the file and line and the column named in the refusal.

    Returns
    -------
    float
        The number.
    """
    try:
        value = float(text)
    except ValueError:
        raise MagexpError(f"{where}: {what}={excerpt(text)} is not a number") from None
    if not abs(value) <= LARGEST:
        raise MagexpError(f"{where}: {what}={excerpt(text)} is not allowed: it must be a finite number "
                          f"of magnitude <= {LARGEST:g}")
    return value


def _header(lines: list[str], name: str) -> tuple[dict, int]:
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
    if "field" not in meta:
        return None
    parts = meta["field"].split(",")
    if len(parts) != 3:
        raise MagexpError(f"{name}: field={meta['field']!r} is not allowed: it must be three numbers separated by commas")
    return np.array([number(p, name, "field") for p in parts])


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


#: bytes of a plain file parsed at a time (:func:`_plain_values` reads the file block by block)
PLAIN_BLOCK = 1 << 24
_SEPARATORS = bytes.maketrans(b",\t\r", b"   ")
_BOM = b"\xef\xbb\xbf"


def _plain_values(path: Path) -> np.ndarray | None:
    """The ``(N, 3)`` values of a plain file, read in blocks of :data:`PLAIN_BLOCK` bytes cut at line
    ends and parsed by pandas' C reader (commas and tabs read as spaces; its numbers are Python's
    ``float`` of each cell, to the bit); None as soon as a block is not three numbers of magnitude
    <= LARGEST a line (:func:`_plain_table` then names the bad line). Memory: the values and one
    block, never the whole text. Pandas is imported here, not at the top: a run that reads no plain
    file never pays its import (270 ms CPU, min of 5 after numpy)."""
    import pandas as pd

    blocks, tail = [], b""
    with open(path, "rb") as fh:
        start = fh.read(len(_BOM))
        tail = b"" if start == _BOM else start
        while True:
            chunk = fh.read(PLAIN_BLOCK)
            data = tail + chunk
            cut = len(data) if not chunk else data.rfind(b"\n") + 1
            block, tail = data[:cut], data[cut:]
            if block.strip():
                try:
                    values = pd.read_csv(io.BytesIO(block.translate(_SEPARATORS)), sep=r"\s+", header=None,
                                         dtype=float, engine="c").to_numpy()
                except (ValueError, pd.errors.ParserError):
                    return None
                if values.shape[1] != 3 or not np.all(np.abs(values) <= LARGEST):
                    return None
                blocks.append(values)
            if not chunk:
                return np.concatenate(blocks) if blocks else None


def _plain_table(lines: list[str], name: str) -> np.ndarray:
    values = []
    for k, line in enumerate(lines, start=1):
        cells = split(line)
        if not cells:
            continue
        if len(cells) != 3:
            raise MagexpError(f"{name} line {k}: {len(cells)} values, but a file without header must have "
                              "exactly 3 columns x y z")
        values.append([number(cell, f"{name} line {k}", axis) for cell, axis in zip(cells, "xyz")])
    return np.array(values)


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


def check_unique(header: list[str], name: str) -> None:
    """Fail in one line if a column name appears twice.

    Parameters
    ----------
    header, name : list of str, str
        The column names, and the file named in the refusal.
    """
    seen = set()
    for col in header:
        if col in seen:
            raise MagexpError(f"{name}: column {col!r} is duplicated: each column must appear once")
        seen.add(col)


def numeric_table(lines: list[str], name: str, first_line: int, ncols: int) -> np.ndarray:
    """Comma-separated numbers, ``ncols`` per row, every value finite (one-line errors).

    Parameters
    ----------
    lines, name : list of str, str
        The data rows, and the file named in a refusal.
    first_line, ncols : int
        The file line number of ``lines[0]``, and the columns of a row.

    Returns
    -------
    ndarray, shape (N, ncols)
        The numbers.
    """
    try:
        table = np.loadtxt(lines, delimiter=",", ndmin=2)
    except ValueError:
        table = None
    if table is None or table.shape[1] != ncols or not np.all(np.isfinite(table)):
        for k, line in enumerate(lines, start=first_line):  # find the bad line for the message
            cells = line.split(",")
            if not line.strip():
                continue
            if len(cells) != ncols:
                raise MagexpError(f"{name} line {k}: {len(cells)} values, but the header has {ncols} columns")
            for j, cell in enumerate(cells):
                number(cell, f"{name} line {k}", f"column {j + 1}")
        raise MagexpError(f"{name}: no data rows")
    return table


def read_lines(path: Path) -> list[str]:
    """The file's lines; a UTF-8 byte-order mark is accepted, a binary file refused in one line.

    Parameters
    ----------
    path : Path
        A text file.

    Returns
    -------
    list of str
        Its lines.
    """
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise MagexpError(f"{path.name}: byte {exc.start} is not UTF-8 text: a recording must be a text file "
                          "(CSV or 3 numeric columns)") from None
    if "\x00" in text:
        raise MagexpError(f"{path.name}: character {text.index(chr(0))} is a NUL byte, so this is not a text file: a "
                          "recording must be a text file (CSV or 3 numeric columns)")
    return text.splitlines()



def to_rad_s(values: np.ndarray, unit: str) -> np.ndarray:
    """Angular rates in rad/s.

    Parameters
    ----------
    values, unit : ndarray, str
        Rates and their unit, ``deg/s`` or ``rad/s``.

    Returns
    -------
    ndarray
        ``values`` in rad/s.
    """
    return np.deg2rad(values) if unit == "deg/s" else values



def read_versioned(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """The ``magexp-recording v1`` CSV (module docstring).

    Parameters
    ----------
    path, unit, mag_axes, gyro_axes
        As :func:`magexp.core.recordings.load_recording` (a malformed file refused in one line).

    Returns
    -------
    Recording
        The readings, angles or gyro rates, the file's field and reference total, its other columns.
    """
    return _versioned(read_lines(path), path.name, unit)


def read_plain(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """Headerless ``x y z`` numbers; the unit must be given.

    Parameters
    ----------
    path, unit, mag_axes, gyro_axes
        As :func:`magexp.core.recordings.load_recording`; ``unit`` is required here.

    Returns
    -------
    Recording
        The readings alone.
    """
    if unit is None:
        raise MagexpError(f"data.unit=None is not allowed for {path.name}: a file without header does not name "
                          f"its unit, give data.unit=<{'|'.join(UNITS)}>")
    table = _plain_values(path)
    if table is None:  # the slow reader, line by line: it names the first bad line
        table = _plain_table(read_lines(path), path.name)
    return Recording(readings=table @ axis_map(mag_axes).T,
                     angles=None, field=None, unit=check_unit(unit, "data.unit"), meta={"format": "plain 3 columns"})


def same_unit(unit, file_unit: str, name: str) -> None:
    """Refuse, in one line, a ``data.unit`` that disagrees with the unit the file's columns name.

    Parameters
    ----------
    unit, file_unit : str
        ``data.unit`` (None: not given, nothing checked) and the file's unit.
    name : str
        The file, named in the refusal.
    """
    if unit is not None and check_unit(unit, "data.unit") != file_unit:
        raise MagexpError(f"data.unit={unit!r} is not allowed for {name}: the file's columns say {file_unit} "
                          "(leave data.unit unset)")


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



def read_two_stream(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """``<stem>_mag.csv`` + ``<stem>_imu.csv``: readings at the magnetometer's times, the gyroscope
    stream at its own (integrated at the readings' times by :meth:`Recording.attitude`).

    Parameters
    ----------
    path, unit, mag_axes, gyro_axes
        As :func:`magexp.core.recordings.load_recording`; the unit comes from the columns' suffix.

    Returns
    -------
    Recording
        The readings at their times and the gyroscope stream.
    """
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


def read_named_columns(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """One CSV with ``Time (s)``, ``Gyroscope X (deg/s)``, ``Magnetometer X (uT)``, ... columns.

    The magnetometer's value repeats while it has not updated: only the rows where any axis
    changes are readings (at their row times); the gyroscope stream keeps every row.

    Parameters
    ----------
    path, unit, mag_axes, gyro_axes
        As :func:`magexp.core.recordings.load_recording`; the unit comes from the column names.

    Returns
    -------
    Recording
        The readings where the magnetometer updated, at their times, and the gyroscope stream.
    """
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


def read_header_counts(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """``Fs,<Hz>``, ``Initialization time,<s>`` (kept as metadata; every reading is kept),
    ``mx,my,mz``, then raw counts.

    Parameters
    ----------
    path, unit, mag_axes, gyro_axes
        As :func:`magexp.core.recordings.load_recording`; without ``unit``, raw ``counts``.

    Returns
    -------
    Recording
        The counts, ``Fs`` and the initialisation time in ``meta``.
    """
    lines = read_lines(path)
    meta = {"format": "header-counts"}
    k = 0
    while k < len(lines) and not lines[k].strip().lower().startswith("mx"):
        key, _, value = lines[k].partition(",")
        meta[key.strip().lower()] = value.strip()
        k += 1
    if k == len(lines):
        raise MagexpError(f"{path.name}: no 'mx,my,mz' header line after the metadata lines")
    header = [h.strip().lower() for h in lines[k].split(",")]
    check_unique(header, path.name)
    rate = number(meta.get("fs", "nan"), path.name, "Fs")
    if rate <= 0:
        raise MagexpError(f"{path.name}: Fs={meta['fs']!r} is not allowed: it must be > 0")
    table = numeric_table(lines[k + 1:], path.name, k + 2, len(header))
    file_unit = check_unit(unit, "data.unit") if unit is not None else "counts"
    return Recording(readings=table[:, [header.index(c) for c in ("mx", "my", "mz")]] @ axis_map(mag_axes).T,
                     angles=None, field=None, unit=file_unit, meta=meta, sample_time=None,
                     times=np.arange(len(table)) / rate, path=path)


def read_header_row(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """A CSV whose first row names its columns: the magnetometer ``x, y, z``, ``mx, my, mz`` or ``bx, by, bz``
    (first found of :data:`MAG_COLUMNS`; unit from a suffix, ``mx_uT`` or ``mx (uT)``, else ``data.unit``),
    optionally a time ``t`` (seconds; :data:`TIME_COLUMNS`) and a gyroscope ``gx, gy, gz`` (rad/s, or
    ``gx_dps`` / ``gx (deg/s)``; it needs the time column); other columns (``ax, ay, az``, ...) are kept.
    Separated by commas, semicolons, tabs or spaces.

    Parameters
    ----------
    path, unit, mag_axes, gyro_axes
        As :func:`magexp.core.recordings.load_recording`; a unit suffix must agree with ``unit``.

    Returns
    -------
    Recording
        The readings, their times and the gyroscope stream when the file has them, and its other columns.
    """
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


