"""The parsing the text formats of :mod:`magexp.core.readers` share (a helper, not a format): their
lines read (:func:`read_lines`), numbers checked (:func:`number`, :func:`numeric_table`), column names and
units checked, with one-line errors naming the file, the line and the fault.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from magexp.core.recording import check_unit
from magexp.errors import LARGEST, MagexpError, excerpt

#: a column's unit suffix (``mx_ut``) and the unit it names; a gyroscope's rate suffix (``gx_dps``) and its unit
UNIT_SUFFIX = {"g": "G", "ut": "uT", "nt": "nT", "mg": "mG", "t": "T"}
RATE_SUFFIX = {"dps": "deg/s", "rps": "rad/s"}
#: the gyroscope's columns, and the units its rates may be given in
GYRO = ("gx", "gy", "gz")
GYRO_UNITS = ("rad/s", "deg/s")


def number(text: str, where: str, what: str) -> float:
    """``text`` as a finite number of magnitude at most :data:`LARGEST`, else one line naming ``where`` (file and line) and ``what`` (the column)."""
    try:
        value = float(text)
    except ValueError:
        raise MagexpError(f"{where}: {what}={excerpt(text)} is not a number") from None
    if not abs(value) <= LARGEST:
        raise MagexpError(f"{where}: {what}={excerpt(text)} is not allowed: it must be a finite number "
                          f"of magnitude <= {LARGEST:g}")
    return value


def check_unique(header: list[str], name: str) -> None:
    """Refuse in one line, naming the file ``name``, a column that appears twice in ``header``."""
    seen = set()
    for col in header:
        if col in seen:
            raise MagexpError(f"{name}: column {col!r} is duplicated: each column must appear once")
        seen.add(col)


def numeric_table(lines: list[str], name: str, first_line: int, ncols: int) -> np.ndarray:
    """The ``(N, ncols)`` comma-separated numbers of the data rows ``lines`` (the first on file line ``first_line``);
    if any is malformed, one line naming the first bad line of the file ``name``.
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
    """The lines of the text file ``path`` (a UTF-8 byte-order mark accepted); a binary file refused in one line."""
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
    """The rates ``values`` in rad/s, from ``unit`` ``deg/s`` or ``rad/s``."""
    return np.deg2rad(values) if unit == "deg/s" else values


def same_unit(unit, file_unit: str, name: str) -> None:
    """Refuse in one line a ``data.unit`` (``unit``; None: nothing checked) that disagrees with the unit ``file_unit`` the columns of ``name`` name."""
    if unit is not None and check_unit(unit, "data.unit") != file_unit:
        raise MagexpError(f"data.unit={unit!r} is not allowed for {name}: the file's columns say {file_unit} "
                          "(leave data.unit unset)")
