"""The one gate of every file magexp reads: :func:`check_file`, called wherever a path enters (``data.path``, a
recording scenario's ``file``/``rest_file``/``path``, ``magexp.calibrate(path)``, ``Calibration.load(path)``, the
files of ``magexp verify``'s folders), before any reader opens the file.

A path passes when it is

* a regular file (following links), or a folder where one is expected (a ROS 2 bag, a results folder); a device
  (``/dev/zero``), a FIFO or a socket is refused without being opened (reading it may never end, opening it may
  never return), and so is a file whose size its folder does not know (``/proc/self/status``: size 0, yet it
  reads);
* at most the file-size limit (``MAGEXP_MAX_FILE``) and, read by a reader that holds about
  :data:`READ_MEMORY` times the bytes it reads, within the memory limit (``MAGEXP_MAX_RUN_MEMORY``);
* for a text format, no line longer than the line limit (``MAGEXP_MAX_LINE``): checked by a scan of the file in
  blocks of :data:`CHUNK` bytes, so the scan holds one block whatever the file (a 10 MB file of one line is
  refused after reading it once, holding 1 MiB). A binary log (ULog, DataFlash, a bag) has no lines: only its
  size is checked.

The same numbers hold everywhere (:data:`magexp.core.limits.LIMITS`); a path that does not exist passes (the
reader names it).

Memory of a reader (:data:`READ_MEMORY`): the peak of a process's resident memory (``ru_maxrss``) while it reads
a file of known size, above the same process after a small file of that format, divided by the file's bytes,
on the worst file measured (the shortest lines, ``1,2,3``; ``tests/test_file_gate.py`` measures each again and
holds it under the stated multiple): the plain reader (blocks parsed by pandas) at most 16 bytes a byte read, the
other text readers (``magexp-v1``, header-row, two-stream, named-columns, header-counts: the file's lines held as
strings) at most 80, ``json.loads`` of a calibration at most 32 (a list of empty objects), the ULog reader at most
8 and the DataFlash reader at most 32 (the logs of ``../shared/data``); the ROS bag reader, with no bag to measure,
is held to 32 as DataFlash's.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import numpy as np

from magexp.core.datafiles import BAG_MARKER, TWO_STREAM
from magexp.core.readers import by_suffix, detect, formats
from magexp.core.limits import LIMITS, limit, refuse_over, show
from magexp.errors import MagexpError
from magexp.run.budget import CALIBRATION_FLOATS_PER_READING, estimate_file_readings

#: bytes the line scan reads at a time (and so holds)
CHUNK = 1 << 20
#: the most entries of a folder read as one recording (a ROS 2 bag) the gate looks at
MAX_ENTRIES = 1000
#: the formats read as bytes, not lines: no line limit (a ``figure``: a file ``magexp verify`` counts, never reads)
BINARY_FORMATS = frozenset({*(m.NAME for m in formats() if m.BINARY), "figure"})
#: the most memory a reader holds above the interpreter, in bytes a byte of the file it reads (measured: module
#: docstring): the plain reader (blocks parsed by pandas), the other text readers (the file's lines as strings),
#: the logs' readers, ``json.loads`` of a calibration
READ_MEMORY = {"text": 80, "json": 32, "figure": 0, **{m.NAME: m.READ_MEMORY for m in formats()}}

#: the kinds of file that are not a recording: reading one never ends (``/dev/zero``) or blocks (a FIFO)
SPECIAL_FILES = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO"),
                 (stat.S_ISSOCK, "a socket"))


def _stat(path) -> os.stat_result | None:
    """``os.stat(path)``, None for a path that does not exist or cannot be named."""
    try:
        return os.stat(path)
    except (OSError, ValueError):
        return None


def check_regular(path, what: str) -> None:
    """Refuse, in one line and without opening it, a ``path`` that is a device, a FIFO or a socket (following
    links): its size says nothing of what reading it costs, and reading it may never end or never start.

    Raises
    ------
    MagexpError
        A special file."""
    st = _stat(path)
    if st is None:
        return
    for test, kind in SPECIAL_FILES:
        if test(st.st_mode):
            stream = " (a live stream: data.serial=PORT, or data.path=- for standard input)" if what == "data.path" else ""
            raise MagexpError(f"{what}={str(path)!r} is not allowed: it is {kind}, not a file; give a file{stream}")


def check_file(path, what: str, *, kind: str = "text", folder: bool = False) -> int:
    """The gate of a file about to be read (module docstring): refuse, in one line naming ``what`` and the limit,
    a device, FIFO or socket, a folder where a file is expected, a file of unknown size, one over the file-size
    limit or whose reading would exceed the memory limit (:data:`READ_MEMORY` bytes a byte for its reader), and,
    of a text file, a line over the line limit (scanned in blocks of :data:`CHUNK` bytes: memory O(CHUNK)
    whatever the file). ``kind`` is its reader: a key of :data:`READ_MEMORY` (``plain``, ``text`` and ``json``
    are line-checked, the logs only sized), or ``recording`` (a text recording whose reader
    :func:`magexp.core.readers.detect` tells once its lines are checked); ``folder``: a folder is expected
    (it passes). Returns the file's size in bytes (0 for a folder or a path that does not exist).

    Raises
    ------
    MagexpError
        Any of the above."""
    check_regular(path, what)
    st = _stat(path)
    if st is None:
        return 0
    subject = f"{what}={str(path)!r}"
    if stat.S_ISDIR(st.st_mode):
        if folder:
            return 0
        raise MagexpError(f"{subject} is not allowed: it is a folder; give a file")
    size = st.st_size
    refuse_over(size, "file_size", subject, "the file has")
    _check_memory(size, min(READ_MEMORY[k] for k in READERS_OF.get(kind, (kind,))), subject)
    if kind in BINARY_FORMATS:
        _check_known_size(path, subject, size)
        return size
    scan_lines(path, subject, size)
    if kind == "recording":
        _check_memory(size, READ_MEMORY[detect(Path(path))], subject)
    return size


#: the readers a kind of :func:`check_file` may be read by
READERS_OF = {"recording": tuple(m.NAME for m in formats() if not m.BINARY)}


def _check_memory(size: int, multiple: int, subject: str) -> None:
    """Refuse a file whose reader would hold ``multiple`` times its ``size`` beyond the memory limit."""
    refuse_over(size * multiple, "run_memory", subject, f"reading its {show(size, 'bytes')} needs")


def _check_known_size(path, subject: str, size: int) -> None:
    """Refuse a file of size 0 that reads (``/proc``, ``/sys``: its size is not what reading it costs)."""
    if size:
        return
    with open(path, "rb") as fh:
        more = fh.read(1)
    if more:
        raise MagexpError(f"{subject} is not allowed: its size is unknown (its folder says 0 bytes, yet it reads: a "
                          "file of /proc or /sys); copy what you need into a file")


def scan_lines(path, subject: str, size: int) -> int:
    """Refuse a text file with a line longer than the line limit, or that reads more than its ``size`` (a file
    of ``/proc``, or one growing while read), scanning it in blocks of :data:`CHUNK` bytes (each block's line ends
    found by numpy: a byte a byte and 16 bytes a line end of it held beside it, under 6 blocks in all); returns its longest line's length.

    Raises
    ------
    MagexpError
        A line over the limit, or more bytes than ``size``."""
    longest, current, total, bound = 0, 0, 0, limit("line")
    with open(path, "rb") as fh:
        while block := fh.read(CHUNK):
            total += len(block)
            if total > size:
                _check_known_size(path, subject, 0)  # says it is a /proc-like file when size is 0
                raise MagexpError(f"{subject} is not allowed: it grows while it is read (more than its "
                                  f"{show(size, 'bytes')}); give a file that is complete")
            ends = np.flatnonzero(np.frombuffer(block, np.uint8) == ord("\n"))
            if ends.size:
                inner = int(np.diff(ends).max()) - 1 if ends.size > 1 else 0
                longest = max(longest, current + int(ends[0]), inner)
                current = len(block) - int(ends[-1]) - 1
            else:
                current += len(block)
            if max(longest, current) > bound:
                raise MagexpError(f"{subject} is not allowed: it has a line longer than {show(bound, 'bytes')}, the "
                                  f"line limit ({LIMITS['line'].env}=... raises it); a recording has a reading a line")
    return max(longest, current)


def recording_files(path) -> list[Path]:
    """The files the recording ``path`` names: itself; with its partner for a two-stream file or stem
    (``<stem>_mag.csv`` and ``<stem>_imu.csv``); the entries of a ROS 2 bag folder (at most :data:`MAX_ENTRIES`)."""
    path = Path(path)
    text = str(path)
    stem = next((text[: -len(tail)] for tail in TWO_STREAM if text.endswith(tail)), None)
    if stem is None and _stat(path) is None and _stat(text + TWO_STREAM[0]) is not None:
        stem = text
    if stem is not None:
        return [Path(stem + tail) for tail in TWO_STREAM]
    if path.is_dir() and (path / BAG_MARKER).is_file():
        with os.scandir(path) as entries:
            return [path, *(Path(e.path) for _, e in zip(range(MAX_ENTRIES), entries))]
    return [path]


def check_recording(path, what: str, format: str | None = "auto") -> int:
    """:func:`check_file` of every file the recording ``path`` names (:func:`recording_files`), each as its reader
    reads it (``format``, else its name; a ROS 2 bag's files as a bag); returns the bytes of the largest."""
    path = Path(path)
    bag = path.is_dir()
    sizes = [0]
    for file in recording_files(path):
        key = "rosbag" if bag else format if format not in (None, "", "auto") else by_suffix(file)
        kind = key if key in READ_MEMORY else "text" if key else "recording"
        sizes.append(check_file(file, what, kind=kind, folder=file == path))
    return max(sizes)


def check_recording_file(path, what: str = "data.path", format: str | None = "auto") -> int:
    """Refuse what the file gate refuses (:func:`magexp.run.files.check_recording`: a device, FIFO or socket, a
    file over the size, line or reading-memory limits, of each file the recording names), a recording file whose
    estimated readings exceed the readings limit, or whose calibration would exceed the memory limit
    (:data:`CALIBRATION_FLOATS_PER_READING` a reading), before it is read; returns the estimated readings."""
    path = Path(path)
    check_recording(path, what, format)
    if not path.is_file():
        return 0
    n = estimate_file_readings(path)
    subject, size = f"{what}={str(path)!r}", show(path.stat().st_size, "bytes")
    refuse_over(n, "readings", subject, f"its {size} hold")
    refuse_over(8 * n * CALIBRATION_FLOATS_PER_READING, "run_memory", subject,
                f"its {size} (about {n} readings) need to calibrate")
    return n
