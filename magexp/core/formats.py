"""The recording formats by name, and how a file's format is told (:func:`detect`) without reading it whole:
the one home of the format keys (``data.format``), of the reader that reads each (:data:`READER_NAMES`, by
name: the run cache keys a run on the reader of its data files' format, :func:`reader_of`, without importing
any reader) and of the column names and unit suffixes the text formats share.

This module imports no reader and nothing that imports one: :mod:`magexp.core.recordings` (the loader) and
:mod:`magexp.core.text_readers` import it.
"""

from __future__ import annotations

import re
from pathlib import Path

from magexp.core.datafiles import BAG_MARKER, TWO_STREAM

VERSION_LINE = "# magexp-recording v1"
#: The reader of each format (``data.format``), by its dotted name: :data:`magexp.core.recordings.READERS`
#: holds the functions (a test holds the two equal); the logs' readers need their optional extras.
READER_NAMES = {
    "magexp-v1": "magexp.core.text_readers.read_versioned",
    "plain": "magexp.core.text_readers.read_plain",
    "two-stream": "magexp.core.text_readers.read_two_stream",
    "named-columns": "magexp.core.text_readers.read_named_columns",
    "header-counts": "magexp.core.text_readers.read_header_counts",
    "header-row": "magexp.core.text_readers.read_header_row",
    "ulog": "magexp.core.readers.ulog.read_ulog",
    "dataflash": "magexp.core.readers.dataflash.read_dataflash",
    "rosbag": "magexp.core.readers.rosbag.read_rosbag",
}
#: a column's unit suffix (``mx_ut``) and the unit it names; a gyroscope's rate suffix (``gx_dps``) and its unit
UNIT_SUFFIX = {"g": "G", "ut": "uT", "nt": "nT", "mg": "mG", "t": "T"}
RATE_SUFFIX = {"dps": "deg/s", "rps": "rad/s"}
#: a ``named-columns`` column: ``<Sensor> <X|Y|Z> (<unit>)``
NAMED = re.compile(r"^\s*(\w+)\s+([xyz])\s*\((.+)\)\s*$", re.IGNORECASE)
#: the magnetometer columns a header row may name, first found used (:func:`read_header_row`; a DataFrame's too)
MAG_COLUMNS = (("bx", "by", "bz"), ("mx", "my", "mz"), ("x", "y", "z"))
#: the names of a header row's time column (seconds)
TIME_COLUMNS = ("t", "t_s", "time", "time_s", "timestamp")
#: a header row's column: a name, then optionally its unit as ``_<suffix>`` or `` (<unit>)``
_COLUMN = re.compile(r"^(?P<base>[a-z][a-z0-9]*?)(?:_(?P<suffix>[a-z]+)|\s*\((?P<unit>[^)]*)\))?$")


def header_cells(line: str) -> list[str]:
    """The cells of a header row: separated by commas, semicolons or tabs if it has any, else by spaces.

    Parameters
    ----------
    line : str
        A header row.

    Returns
    -------
    list of str
        Its cells, stripped.
    """
    text = line.strip()
    return [c.strip() for c in (re.split(r"[,;\t]", text) if re.search(r"[,;\t]", text) else text.split())]


def header_columns(line: str) -> dict[str, tuple[int, str | None]] | None:
    """``{name: (column, unit or None)}`` of a header row that names a magnetometer (:data:`MAG_COLUMNS`),
    else None. A column's unit comes from its ``_<suffix>`` (``mx_ut``, ``gx_dps``) or ``(<unit>)``.

    Parameters
    ----------
    line : str
        The first row of a CSV (:func:`header_cells`).

    Returns
    -------
    dict or None
        Column name (lower case, unit suffix removed) -> (its index, its unit or None).
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


def split(line: str) -> list[str]:
    """The cells of a plain line, separated by commas or white space.

    Parameters
    ----------
    line : str
        A line of numbers.

    Returns
    -------
    list of str
        Its cells.
    """
    return [cell for cell in re.split(r"[,\s]+", line.strip()) if cell]


def is_plain(lines: list[str]) -> bool:
    """A headerless numeric file: the first non-blank line is numbers only.

    Parameters
    ----------
    lines : list of str
        The file's first lines.

    Returns
    -------
    bool
        True when the first non-blank line is numbers only.
    """
    first = next((ln for ln in lines if ln.strip()), "")
    try:
        [float(cell) for cell in split(first)]
    except ValueError:
        return False
    return bool(split(first))


#: file name endings of the binary logs (:func:`detect`); a ROS 2 bag folder (``metadata.yaml``) is ``rosbag`` too
LOG_SUFFIXES = {".ulg": "ulog", ".bin": "dataflash", ".bag": "rosbag", ".mcap": "rosbag", ".db3": "rosbag"}


def detect(path: Path) -> str:
    """The format key of ``path``: by its name (:data:`LOG_SUFFIXES`, a bag folder, a two-stream stem), else by
    its first line (the version line, ``Fs,``, a ``<Sensor> X (<unit>)`` column, a row naming magnetometer
    columns, numbers; :mod:`magexp.core.recordings`).

    Parameters
    ----------
    path : Path
        A recording file or folder.

    Returns
    -------
    str
        A format key.
    """
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
    if NAMED.match(first.split(",")[-1] if "," in first else ""):
        return "named-columns"
    if header_columns(first) is not None:
        return "header-row"
    return "plain" if is_plain(head) else "magexp-v1"


def reader_of(path: Path, format: str | None = "auto") -> str:
    """The dotted name of the function (:data:`READER_NAMES`) that reads the recording ``path`` in ``format``
    (``auto``, None or a name not of :data:`READER_NAMES`: :func:`detect`'s, from its name or its first
    three lines): the run cache keys a run that reads ``path`` on that module's source
    (:func:`magexp.run.cache.data_readers`).

    Parameters
    ----------
    path : Path
        A recording.
    format : str, optional
        A format key, ``auto`` or None.

    Returns
    -------
    str
        ``module.function`` of the reader.
    """
    return READER_NAMES[format if format in READER_NAMES else detect(path)]
