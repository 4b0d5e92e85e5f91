"""``Fs,<Hz>`` and ``Initialization time,<s>`` lines, then ``mx,my,mz`` and raw counts (the QMC5883L file).

The metadata lines are kept in ``meta`` (every reading is kept); the readings' times are their index over ``Fs``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from magexp.core.geometry import axis_map
from magexp.core.textfiles import check_unique, number, numeric_table, read_lines
from magexp.core.recording import Recording, check_unit
from magexp.errors import MagexpError

NAME = "header-counts"
PRIORITY = 60
SUFFIXES = ()
UNIT = "`counts`, or `data.unit`"
EXTRA = None
BINARY = False
READ_MEMORY = 80


def sniff(head: list[str]) -> bool:
    """The first line starts with ``Fs,``."""
    return head[0].strip().lower().startswith("fs,")


def read(path: Path, *, unit=None, mag_axes=None, gyro_axes=None) -> Recording:
    """The counts (or readings in ``unit``), with ``Fs`` and the initialisation time in ``meta``."""
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
