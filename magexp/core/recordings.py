"""The loader of recorded magnetometer data (:func:`load_recording`): it finds the file
(:func:`resolve`), tells its format (:func:`magexp.core.readers.detect`, or ``data.format``) and reads it
with that format's module of :mod:`magexp.core.readers` (one module per format, found by listing the
package; ``magexp calibrate --help`` and ``docs/calibrate.md`` list them). What a reader returns,
:class:`~magexp.core.recording.Recording`, lives in :mod:`magexp.core.recording`, which this module
re-exports. Imports go one way: this module -> readers -> recording.

:func:`load_recording` refuses a malformed file with one :class:`~magexp.errors.MagexpError`
line naming the file, the line and the fault.
"""

from __future__ import annotations

import inspect
from pathlib import Path

from magexp.core.datafiles import BAG_MARKER, TWO_STREAM
from magexp.core.readers import detect, format_of, reader_of
from magexp.core.recording import RAW_UNITS, UNITS, Recording, check_unit
from magexp.errors import MagexpError
from magexp.paths import DATA

#: what other modules take from here: the loader, and the recording's type and units re-exported beside it
__all__ = ["detect", "exists", "load_recording", "reader_of", "resolve", "Recording", "UNITS", "RAW_UNITS",
           "check_unit"]


def exists(path: Path) -> bool:
    """Whether ``path`` names a recording: a file, a folder (a ROS 2 bag), or a two-stream stem
    (``<path>_mag.csv`` exists; its ``_imu.csv`` is checked by the reader).
    """
    return path.exists() or Path(f"{path}{TWO_STREAM[0]}").is_file()


def resolve(path: str | Path) -> Path:
    """Where the recording ``path`` is (not checked to exist): an absolute path as given; a relative one from the
    working folder if it :func:`exists` there, else from the project's ``data/`` (the recordings shipped with magexp).
    """
    path = Path(path)
    return path if path.is_absolute() or exists(path) else DATA / path


def load_recording(path: str | Path, *, unit: str | None = None, format: str = "auto",
                   mag_axes: str | None = None, gyro_axes: str | None = None, instance: int | None = None) -> Recording:
    """The :class:`~magexp.core.recording.Recording` of ``path`` read by the module of ``format`` (a name of
    :func:`magexp.core.readers.names`, or ``auto``: :func:`detect`); ``path``, ``unit``, ``mag_axes``, ``gyro_axes``
    as in the ``read`` protocol of :mod:`magexp.core.readers`; ``instance`` goes to a reader that takes it (DataFlash).
    One :class:`~magexp.errors.MagexpError` line for a missing file, an unknown format or a malformed file.
    """
    file = resolve(path)
    if file.is_dir() and not (file / BAG_MARKER).is_file():  # a ROS 2 bag is a folder with metadata.yaml
        raise MagexpError(f"recording {str(path)!r} is a directory: give a file")
    if not exists(file):
        raise MagexpError(f"recording {str(path)!r} does not exist (looked in the working folder and {DATA})")
    key = detect(file) if format in (None, "auto") else format
    read = format_of(key).read
    options = {"unit": unit}
    if mag_axes is not None:
        options["mag_axes"] = mag_axes
    if gyro_axes is not None:
        options["gyro_axes"] = gyro_axes
    if instance is not None and "instance" in inspect.signature(read).parameters:
        options["instance"] = instance
    rec = read(file, **options)
    rec.meta.setdefault("format", key)
    rec.path = rec.path or file
    return rec
