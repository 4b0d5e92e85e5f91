"""A headerless ``x y z`` table: three numbers a line, separated by tabs, commas or spaces (e.g. the FXOS8700 file).

Its unit is not in the file, so it must be given (``unit=``; on the command line ``data.unit=uT``).
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np

from magexp.core.geometry import axis_map
from magexp.core.textfiles import number, read_lines
from magexp.core.recording import UNITS, Recording, check_unit
from magexp.errors import LARGEST, MagexpError

NAME = "plain"
PRIORITY = 90
SUFFIXES = ()
UNIT = "`data.unit` (required)"
EXTRA = None
BINARY = False
READ_MEMORY = 16


def split(line: str) -> list[str]:
    """The cells of a plain ``line``, separated by commas or white space."""
    return [cell for cell in re.split(r"[,\s]+", line.strip()) if cell]


def sniff(head: list[str]) -> bool:
    """The first non-blank line is numbers only."""
    first = next((ln for ln in head if ln.strip()), "")
    try:
        [float(cell) for cell in split(first)]
    except ValueError:
        return False
    return bool(split(first))


def read(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """The readings alone, in ``unit`` (required: a file without header does not name its unit)."""
    if unit is None:
        raise MagexpError(f"data.unit=None is not allowed for {path.name}: a file without header does not name "
                          f"its unit, give data.unit=<{'|'.join(UNITS)}>")
    table = _plain_values(path)
    if table is None:  # the slow reader, line by line: it names the first bad line
        table = _plain_table(read_lines(path), path.name)
    return Recording(readings=table @ axis_map(mag_axes).T,
                     angles=None, field=None, unit=check_unit(unit, "data.unit"), meta={"format": "plain 3 columns"})


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
    """The ``(N, 3)`` values read line by line: the slow path, which names the first bad line."""
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
