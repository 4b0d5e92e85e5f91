"""Recorded magnetometer data: one reader per file format, in one registry (:data:`READERS`).

Formats (``data.format=<key>``; ``auto``, the default, detects the format from the file):

================== ========================================================================
key                file
================== ========================================================================
``magexp-v1``      the ``magexp-recording v1`` CSV below (the project's own format)
``plain``          headerless ``x y z`` numbers (tabs, commas or spaces), unit given by the
                   caller (e.g. the FXOS8700 file, µT)
``two-stream``     a magnetometer file ``<stem>_mag.csv`` (``t_s, mx_<unit>, ...``) and an IMU
                   file ``<stem>_imu.csv`` (``t_s, gx_dps, ...``) with their own timestamps
                   and rates (the HMC5883L + MPU6050 recordings); name either file or the stem
``named-columns``  one CSV with named, unit-bearing columns ``Time (s)``,
                   ``Gyroscope X (deg/s)``, ``Magnetometer X (uT)``, ... (the x-io Fusion file);
                   a magnetometer slower than the row rate repeats its value: only the rows
                   where it changes are readings, the gyroscope keeps every row
``header-counts``  ``Fs,<Hz>`` and ``Initialization time,<s>`` lines, then ``mx,my,mz`` and raw
                   counts (the QMC5883L file); unit ``counts``
``header-row``     a CSV whose first row names its columns: ``x,y,z``, ``mx,my,mz`` or ``bx,by,bz``,
                   optionally ``t`` (s), ``gx,gy,gz`` (rad/s; ``gx_dps``: deg/s), ``ax,ay,az`` (kept)
                   (:func:`read_header_row`); unit from a suffix (``mx_uT``) or ``data.unit``
``ulog``           a PX4 ULog ``*.ulg`` (:mod:`magexp.core.readers.ulog`; ``pip install 'magexp[ulog]'``)
``dataflash``      an ArduPilot DataFlash ``*.bin`` (:mod:`magexp.core.readers.dataflash`;
                   ``magexp[dataflash]``)
``rosbag``         a ROS 1 ``*.bag``, a ROS 2 bag folder or its ``*.db3``/``*.mcap``, an MCAP file
                   (:mod:`magexp.core.readers.rosbag`; ``magexp[ros]``)
================== ========================================================================

The logs' readers give the magnetometer before the onboard calibration, the attitude, the
gyroscope, the GPS position and date, on the log's clock (:mod:`magexp.core.readers`).

Streams with their own times: the gyroscope is *integrated* at the magnetometer's times, not
resampled (:func:`magexp.core.geometry.attitude_at`: each gyro sample held until the next one and
propagated exactly over the merged time grid). Axes: ``mag_axes`` / ``gyro_axes`` (e.g.
``"-x,y,z"``, :func:`magexp.core.geometry.axis_map`) map each sensor onto the common body axes
(default: as recorded). For the HMC5883L + MPU6050 files the data decide: a gyro-aided fit
(:mod:`magexp.problems.gyro`) with the gyroscope as recorded leaves about 2 % of the field as
vector residual, with its x axis flipped (``-x,y,z``, the authors' note on the gyroscope alone)
over 50 %: the magnetometer's unstated x convention evidently matches the gyroscope's.

The ``magexp-recording v1`` format:

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
import io
import os
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from magexp.core.datafiles import BAG_MARKER, TWO_STREAM
from magexp.core.geometry import attitude_at, axis_map, ship_attitude
from magexp.errors import LARGEST, MagexpError, excerpt
from magexp.paths import DATA

VERSION_LINE = "# magexp-recording v1"
FIELDS = ("bx", "by", "bz")
ANGLES = ("heading", "roll", "trim")
GYRO = ("gx", "gy", "gz")
ANGLE_UNITS = ("rad", "deg")
GYRO_UNITS = ("rad/s", "deg/s")
#: Allowed units of the readings and their factor to nT.
UNITS = {"nT": 1.0, "uT": 1e3, "mG": 100.0, "G": 1e5, "T": 1e9}
#: Raw sensor units without a known factor to nT (a calibration then reports in them).
RAW_UNITS = ("counts",)
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
    gyro : (N, 3) gyro rates in rad/s per reading (``gx, gy, gz`` columns), or None.
    sample_time : seconds between readings (with ``gyro``), or None.
    times : (N,) time of every reading in seconds, or None.
    gyro_stream : ``(times (K,), rates (K, 3) rad/s in the common axes)`` of a gyroscope with
        its own timestamps, or None.
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
    times: np.ndarray | None = None
    gyro_stream: tuple | None = None

    @property
    def n(self) -> int:
        return int(self.readings.shape[0])

    @property
    def name(self) -> str:
        return self.path.name if self.path is not None else self.meta.get("name", "readings")

    def gyro_rates(self) -> tuple[np.ndarray, np.ndarray] | None:
        """``(times, rates)`` of the gyroscope and the reading times, or None without one."""
        if self.gyro_stream is not None:
            return self.gyro_stream
        if self.gyro is not None:
            return np.arange(self.n) * self.sample_time, self.gyro
        return None

    def reading_times(self) -> np.ndarray | None:
        if self.times is not None:
            return self.times
        return None if self.sample_time is None else np.arange(self.n) * self.sample_time

    def attitude(self, *, bias=None) -> np.ndarray | None:
        """Navigation -> sensor rotations ``(N, 3, 3)`` from the angles, else from the gyroscope
        integrated at the reading times (the sensor frame at the first reading is the navigation
        frame; ``bias`` rad/s subtracted), else None."""
        if self.angles is not None:
            return ship_attitude(*self.angles.T)
        stream = self.gyro_rates()
        if stream is None:
            return None
        return np.transpose(attitude_at(*stream, self.reading_times(), bias=bias), (0, 2, 1))

    def subset(self, index) -> "Recording":
        """The readings ``index`` (a slice or index array), with their attitudes' sources."""
        pick = lambda a: None if a is None else np.asarray(a)[index]  # noqa: E731
        times = self.reading_times()
        return replace(self, readings=self.readings[index], angles=pick(self.angles), total=pick(self.total),
                       columns={k: v[index] for k, v in self.columns.items()}, gyro=None, sample_time=None,
                       times=pick(times), gyro_stream=self.gyro_rates())


def exists(path: Path) -> bool:
    """Whether ``path`` names a recording: a file, a folder (a ROS 2 bag), or a two-stream stem
    (``<path>_mag.csv`` exists; its ``_imu.csv`` is checked by the reader)."""
    return path.exists() or Path(f"{path}{TWO_STREAM[0]}").is_file()


def resolve(path: str | Path) -> Path:
    """Where the recording ``path`` is: an absolute path as given; a relative one against the
    working folder first (a file, a folder or a two-stream stem found there, :func:`exists`), else
    relative to the project's ``data/`` folder (the recordings shipped with magexp)."""
    path = Path(path)
    return path if path.is_absolute() or exists(path) else DATA / path


def check_unit(unit: str, what: str) -> str:
    """``unit`` spelled as in :data:`UNITS`, or a one-line error naming ``what``."""
    text = str(unit).strip()
    text = _ALIASES.get(text.lower(), text)
    if text not in UNITS and text not in RAW_UNITS:
        raise MagexpError(f"{what}={unit!r} is not allowed: choose one of {', '.join((*UNITS, *RAW_UNITS))}")
    return text


def _number(text: str, where: str, what: str) -> float:
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
        values.append([_number(cell, f"{name} line {k}", col) for cell, col in zip(row, header)])
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
    value = _number(meta[key], name, key)
    if value <= 0:
        raise MagexpError(f"{name}: {key}={meta[key]!r} is not allowed: it must be > 0")
    return value


def check_unique(header: list[str], name: str) -> None:
    """Fail in one line if a column name appears twice."""
    seen = set()
    for col in header:
        if col in seen:
            raise MagexpError(f"{name}: column {col!r} is duplicated: each column must appear once")
        seen.add(col)


def _numeric_table(lines: list[str], name: str, first_line: int, ncols: int) -> np.ndarray:
    """Comma-separated numbers, ``ncols`` per row, every value finite (one-line errors)."""
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
                _number(cell, f"{name} line {k}", f"column {j + 1}")
        raise MagexpError(f"{name}: no data rows")
    return table


_UNIT_SUFFIX = {"g": "G", "ut": "uT", "nt": "nT", "mg": "mG", "t": "T"}
_RATE_SUFFIX = {"dps": "deg/s", "rps": "rad/s"}


def _read_lines(path: Path) -> list[str]:
    """The file's lines; a UTF-8 byte-order mark is accepted, a binary file refused in one line."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise MagexpError(f"{path.name}: byte {exc.start} is not UTF-8 text: a recording must be a text file "
                          "(CSV or 3 numeric columns)") from None
    if "\x00" in text:
        raise MagexpError(f"{path.name}: character {text.index(chr(0))} is a NUL byte, so this is not a text file: a "
                          "recording must be a text file (CSV or 3 numeric columns)")
    return text.splitlines()


def _stream(path: Path, prefix: str, suffixes: dict) -> tuple[np.ndarray, np.ndarray, str]:
    """``(times, xyz, unit)`` of a ``t_s, <p>x_<u>, <p>y_<u>, <p>z_<u>[, ...]`` CSV."""
    lines = _read_lines(path)
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
    table = _numeric_table(lines[1:], path.name, 2, len(header))
    t = table[:, 0]
    if np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0)) + 3
        raise MagexpError(f"{path.name} line {k}: t_s={t[k - 2]:g} is not allowed: times must increase")
    return t, table[:, [header.index(c) for c in cols]], suffixes[next(iter(units))]


def _rates(values: np.ndarray, unit: str) -> np.ndarray:
    return np.deg2rad(values) if unit == "deg/s" else values


def read_two_stream(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """``<stem>_mag.csv`` + ``<stem>_imu.csv``: readings at the magnetometer's times, the gyroscope
    stream at its own (integrated at the readings' times by :meth:`Recording.attitude`)."""
    stem = str(path)
    for tail in TWO_STREAM:
        stem = stem[: -len(tail)] if stem.endswith(tail) else stem
    mag_path, imu_path = (Path(stem + tail) for tail in TWO_STREAM)
    for p in (mag_path, imu_path):
        if not p.is_file():
            raise MagexpError(f"recording {str(p)!r} does not exist: a two-stream recording needs both "
                              f"{mag_path.name} and {imu_path.name}")
    t_mag, mag, mag_unit = _stream(mag_path, "m", _UNIT_SUFFIX)
    t_imu, gyro, rate_unit = _stream(imu_path, "g", _RATE_SUFFIX)
    _same_unit(unit, mag_unit, mag_path.name)
    rates = _rates(gyro, rate_unit) @ axis_map(gyro_axes, "data.gyro_axes").T
    return Recording(readings=mag @ axis_map(mag_axes, "data.mag_axes").T, angles=None, field=None,
                     unit=mag_unit, meta={"format": "two-stream", "gyro_axes": str(gyro_axes)},
                     times=t_mag, gyro_stream=(t_imu, rates), path=mag_path)


_NAMED = re.compile(r"^\s*(\w+)\s+([xyz])\s*\((.+)\)\s*$", re.IGNORECASE)


def read_named_columns(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """One CSV with ``Time (s)``, ``Gyroscope X (deg/s)``, ``Magnetometer X (uT)``, ... columns.

    The magnetometer's value repeats while it has not updated: only the rows where any axis
    changes are readings (at their row times); the gyroscope stream keeps every row.
    """
    from magexp.core.geometry import axis_map

    lines = _read_lines(path)
    header = [h.strip() for h in lines[0].split(",")]
    check_unique([h.lower() for h in header], path.name)
    groups = _named_groups(header)
    time_col = next((j for j, h in enumerate(header) if h.lower().startswith("time")), None)
    mag = groups.get("magnetometer", {})
    if time_col is None or sorted(mag) != ["x", "y", "z"]:
        raise MagexpError(f"{path.name}: columns must include 'Time (s)' and 'Magnetometer X/Y/Z (<unit>)'")
    table = _numeric_table(lines[1:], path.name, 2, len(header))
    mag_unit = check_unit({mag[a][1] for a in "xyz"}.pop(), f"{path.name}: magnetometer unit")
    _same_unit(unit, mag_unit, path.name)
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
        m = _NAMED.match(h)
        if m:
            groups.setdefault(m.group(1).lower(), {})[m.group(2).lower()] = (j, m.group(3).strip())
    return groups


def _named_rates(table: np.ndarray, gyro: dict[str, tuple[int, str]], name: str) -> np.ndarray:
    """The gyroscope columns ``gyro`` (:func:`_named_groups`) of ``table`` in rad/s."""
    rate_unit = {gyro[a][1] for a in "xyz"}.pop()
    if rate_unit not in GYRO_UNITS:
        raise MagexpError(f"{name}: gyroscope unit {rate_unit!r} is not allowed: choose one of "
                          f"{', '.join(GYRO_UNITS)}")
    return _rates(table[:, [gyro[a][0] for a in "xyz"]], rate_unit)


def read_header_counts(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """``Fs,<Hz>``, ``Initialization time,<s>`` (kept as metadata; every reading is kept),
    ``mx,my,mz``, then raw counts."""
    lines = _read_lines(path)
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
    rate = _number(meta.get("fs", "nan"), path.name, "Fs")
    if rate <= 0:
        raise MagexpError(f"{path.name}: Fs={meta['fs']!r} is not allowed: it must be > 0")
    table = _numeric_table(lines[k + 1:], path.name, k + 2, len(header))
    file_unit = check_unit(unit, "data.unit") if unit is not None else "counts"
    return Recording(readings=table[:, [header.index(c) for c in ("mx", "my", "mz")]] @ axis_map(mag_axes).T,
                     angles=None, field=None, unit=file_unit, meta=meta, sample_time=None,
                     times=np.arange(len(table)) / rate, path=path)


#: the magnetometer columns a header row may name, first found used (:func:`read_header_row`; a DataFrame's too)
MAG_COLUMNS = (("bx", "by", "bz"), ("mx", "my", "mz"), ("x", "y", "z"))
#: the names of a header row's time column (seconds)
TIME_COLUMNS = ("t", "t_s", "time", "time_s", "timestamp")
#: a header row's column: a name, then optionally its unit as ``_<suffix>`` or `` (<unit>)``
_COLUMN = re.compile(r"^(?P<base>[a-z][a-z0-9]*?)(?:_(?P<suffix>[a-z]+)|\s*\((?P<unit>[^)]*)\))?$")


def _header_cells(line: str) -> list[str]:
    """The cells of a header row: separated by commas, semicolons or tabs if it has any, else by spaces."""
    text = line.strip()
    return [c.strip() for c in (re.split(r"[,;\t]", text) if re.search(r"[,;\t]", text) else text.split())]


def header_columns(line: str) -> dict[str, tuple[int, str | None]] | None:
    """``{name: (column, unit or None)}`` of a header row that names a magnetometer (:data:`MAG_COLUMNS`),
    else None. A column's unit comes from its ``_<suffix>`` (``mx_ut``, ``gx_dps``) or ``(<unit>)``."""
    columns = {}
    for j, cell in enumerate(_header_cells(line)):
        m = _COLUMN.match(cell.lower())
        if m is None:
            columns[cell.lower()] = (j, None)
            continue
        suffix = m["suffix"]
        known = suffix in _UNIT_SUFFIX or suffix in _RATE_SUFFIX or suffix == "s"
        base = m["base"] if suffix is None or known else f"{m['base']}_{suffix}"
        columns[base] = (j, m["unit"] if m["unit"] is not None else suffix if known else None)
    return columns if any(all(c in columns for c in names) for names in MAG_COLUMNS) else None


def read_header_row(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """A CSV whose first row names its columns: the magnetometer ``x, y, z``, ``mx, my, mz`` or ``bx, by, bz``
    (first found of :data:`MAG_COLUMNS`; unit from a suffix, ``mx_uT`` or ``mx (uT)``, else ``data.unit``),
    optionally a time ``t`` (seconds; :data:`TIME_COLUMNS`) and a gyroscope ``gx, gy, gz`` (rad/s, or
    ``gx_dps`` / ``gx (deg/s)``; it needs the time column); other columns (``ax, ay, az``, ...) are kept.
    Separated by commas, semicolons, tabs or spaces."""
    lines = _read_lines(path)
    header = _header_cells(lines[0]) if lines else []
    check_unique([h.lower() for h in header], path.name)
    columns = header_columns(lines[0]) if lines else None
    if columns is None:
        raise MagexpError(f"{path.name}: header {excerpt(','.join(header))} is not allowed: it must name the "
                          f"magnetometer's columns, one of {'; '.join(', '.join(n) for n in MAG_COLUMNS)}")
    rows = lines[1:] if "," in lines[0] else [",".join(_header_cells(ln)) for ln in lines[1:]]
    table = _numeric_table(rows, path.name, 2, len(header))
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
    file_unit = check_unit(_UNIT_SUFFIX.get(suffix.lower(), suffix), f"{name}: magnetometer unit")
    _same_unit(unit, file_unit, name)
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
    rate_unit = "rad/s" if rate is None else _RATE_SUFFIX.get(rate, rate)
    if rate_unit not in GYRO_UNITS:
        raise MagexpError(f"{name}: gyroscope unit {rate!r} is not allowed: choose one of {', '.join(GYRO_UNITS)} "
                          "(suffix _dps or _rps)")
    return _rates(table[:, [columns[c][0] for c in GYRO]], rate_unit)


def read_versioned(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """The ``magexp-recording v1`` CSV (module docstring)."""
    return _versioned(_read_lines(path), path.name, unit)


def read_plain(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """Headerless ``x y z`` numbers; the unit must be given."""
    if unit is None:
        raise MagexpError(f"data.unit=None is not allowed for {path.name}: a file without header does not name "
                          f"its unit, give data.unit=<{'|'.join(UNITS)}>")
    table = _plain_values(path)
    if table is None:  # the slow reader, line by line: it names the first bad line
        table = _plain_table(_read_lines(path), path.name)
    return Recording(readings=table @ axis_map(mag_axes).T,
                     angles=None, field=None, unit=check_unit(unit, "data.unit"), meta={"format": "plain 3 columns"})


def _same_unit(unit, file_unit: str, name: str) -> None:
    if unit is not None and check_unit(unit, "data.unit") != file_unit:
        raise MagexpError(f"data.unit={unit!r} is not allowed for {name}: the file's columns say {file_unit} "
                          "(leave data.unit unset)")


def _log_reader(module: str, function: str):
    """The reader ``magexp.core.readers.<module>.<function>``, imported when a log is read: those
    modules import this one (its :class:`Recording`), so importing them here at the top would be a cycle."""
    def read(path: Path, **options) -> Recording:
        from importlib import import_module

        return getattr(import_module(f"magexp.core.readers.{module}"), function)(path, **options)

    # it stands for that function (:func:`reader_of` names it): the run cache keys a run on that module
    read.__module__, read.__name__, read.__qualname__ = f"magexp.core.readers.{module}", function, function
    read.__doc__ = f"See :func:`magexp.core.readers.{module}.{function}`."
    return read


#: The readers, keyed by format (``data.format``); the logs' readers need their optional extras.
READERS = {
    "magexp-v1": read_versioned,
    "plain": read_plain,
    "two-stream": read_two_stream,
    "named-columns": read_named_columns,
    "header-counts": read_header_counts,
    "header-row": read_header_row,
    "ulog": _log_reader("ulog", "read_ulog"),
    "dataflash": _log_reader("dataflash", "read_dataflash"),
    "rosbag": _log_reader("rosbag", "read_rosbag"),
}
#: file name endings of the binary logs (:func:`detect`); a ROS 2 bag folder (``metadata.yaml``) is ``rosbag`` too
LOG_SUFFIXES = {".ulg": "ulog", ".bin": "dataflash", ".bag": "rosbag", ".mcap": "rosbag", ".db3": "rosbag"}


def detect(path: Path) -> str:
    """The format key of ``path`` (see the module docstring)."""
    if path.suffix.lower() in LOG_SUFFIXES:
        return LOG_SUFFIXES[path.suffix.lower()]
    if path.is_dir() and (path / BAG_MARKER).is_file():
        return "rosbag"
    if str(path).endswith(TWO_STREAM) or (not path.is_file() and Path(f"{path}{TWO_STREAM[0]}").is_file()):
        return "two-stream"
    with open(path, encoding="utf-8-sig", errors="replace") as fh:
        head = [fh.readline() for _ in range(3)]
    first = head[0].strip()
    if first == VERSION_LINE:
        return "magexp-v1"
    if first.lower().startswith("fs,"):
        return "header-counts"
    if _NAMED.match(first.split(",")[-1] if "," in first else ""):
        return "named-columns"
    if header_columns(first) is not None:
        return "header-row"
    return "plain" if _is_plain(head) else "magexp-v1"


def reader_of(path: Path, format: str | None = "auto") -> str:
    """The dotted name of the function of :data:`READERS` that reads the recording ``path`` in ``format``
    (``auto``, None or a name not of :data:`READERS`: :func:`detect`'s, from its name or its first
    three lines). A log's reader module is named, not imported: the run cache keys a run
    that reads ``path`` on that module's source (:func:`magexp.run.cache.data_readers`)."""
    read = READERS[format if format in READERS else detect(path)]
    return f"{read.__module__}.{read.__qualname__}"


def load_recording(path: str | Path, *, unit: str | None = None, format: str = "auto",
                   mag_axes: str | None = None, gyro_axes: str | None = None, instance: int | None = None) -> Recording:
    """Read a recording in any format of :data:`READERS` (see the module docstring).

    Parameters
    ----------
    path : the file (for ``two-stream``, either file or their common stem); a relative path is
        looked up from the working folder first, then in ``data/`` (:func:`resolve`).
    unit : unit of a plain file's readings (required for one); for a file that names its unit it
        may be left None and must otherwise agree with it.
    format : a key of :data:`READERS`, or ``auto`` (:func:`detect`).
    mag_axes, gyro_axes : signed axis maps onto the common body axes (:func:`magexp.core.geometry.axis_map`);
        None keeps the format's default.
    instance : the compass (and IMU) instance of a DataFlash log (0: the first; None: 0); the other
        formats hold one magnetometer and ignore it.

    Raises
    ------
    MagexpError
        One line for a missing file, an unknown format, a wrong version line, a missing or
        duplicated column, a row of the wrong length, a value that is not a number, NaN or
        infinite, an unknown unit, or a bad metadata value (e.g. ``reference_total <= 0``).
    """
    file = resolve(path)
    if file.is_dir() and not (file / BAG_MARKER).is_file():  # a ROS 2 bag is a folder with metadata.yaml
        raise MagexpError(f"recording {str(path)!r} is a directory: give a file")
    if not exists(file):
        raise MagexpError(f"recording {str(path)!r} does not exist (looked in the working folder and {DATA})")
    key = detect(file) if format in (None, "auto") else format
    if key not in READERS:
        raise MagexpError(f"data.format={format!r} is not allowed: choose one of auto, {', '.join(READERS)}")
    options = {"unit": unit}
    if mag_axes is not None:
        options["mag_axes"] = mag_axes
    if gyro_axes is not None:
        options["gyro_axes"] = gyro_axes
    if instance is not None and key == "dataflash":
        options["instance"] = instance
    rec = READERS[key](file, **options)
    rec.meta.setdefault("format", key)
    rec.path = rec.path or file
    return rec
