"""Recorded magnetometer data: one reader per file format, in one registry (:data:`READERS`), and the loader
that picks one (:func:`load_recording`). The text formats' readers live in :mod:`magexp.core.text_readers`,
each log format's in its own module of :mod:`magexp.core.readers`;
what they return, :class:`~magexp.core.recording.Recording`, in :mod:`magexp.core.recording`, which they
import and this module re-exports. Imports go one way: this module -> readers -> recording.

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

from importlib import import_module
from pathlib import Path

from magexp.core.datafiles import BAG_MARKER, TWO_STREAM
from magexp.core.formats import LOG_SUFFIXES, MAG_COLUMNS, READER_NAMES, VERSION_LINE, detect, reader_of
from magexp.core.recording import RAW_UNITS, UNITS, Recording, check_unit
from magexp.core.text_readers import (check_unique, read_header_counts, read_header_row, read_named_columns,
                                      read_plain, read_two_stream, read_versioned)
from magexp.errors import MagexpError
from magexp.paths import DATA

#: what other modules take from here: the loader, and the recording's type and units re-exported beside it
__all__ = ["READERS", "LOG_SUFFIXES", "detect", "exists", "load_recording", "reader_of", "resolve", "Recording",
           "UNITS", "RAW_UNITS", "check_unit", "check_unique", "MAG_COLUMNS", "VERSION_LINE"]


def exists(path: Path) -> bool:
    """Whether ``path`` names a recording: a file, a folder (a ROS 2 bag), or a two-stream stem
    (``<path>_mag.csv`` exists; its ``_imu.csv`` is checked by the reader).

    Parameters
    ----------
    path : Path
        A path.

    Returns
    -------
    bool
        True when it names a recording.
    """
    return path.exists() or Path(f"{path}{TWO_STREAM[0]}").is_file()


def resolve(path: str | Path) -> Path:
    """Where the recording ``path`` is: an absolute path as given; a relative one against the
    working folder first (a file, a folder or a two-stream stem found there, :func:`exists`), else
    relative to the project's ``data/`` folder (the recordings shipped with magexp).

    Parameters
    ----------
    path : str or Path
        The recording as given.

    Returns
    -------
    Path
        The path to read (not checked to exist).
    """
    path = Path(path)
    return path if path.is_absolute() or exists(path) else DATA / path


def _log_reader(format: str):
    """The reader of the log ``format`` (:data:`magexp.core.formats.READER_NAMES`), imported when a log of it is
    read, by that name. Not at the top: the run cache keys a run on the reader of its data's format only
    (:func:`magexp.run.cache.data_readers`, docs/guide/caching.md): a log reader imported here would be in the
    key of every run reading a recording, and an edit of it would rerun them all. The readers do not import
    this module (:class:`~magexp.core.recording.Recording` is :mod:`magexp.core.recording`'s): no cycle."""
    module, _, function = READER_NAMES[format].rpartition(".")

    def read(path: Path, **options) -> Recording:
        return getattr(import_module(module), function)(path, **options)

    # it stands for that function (:func:`magexp.core.formats.reader_of` names it)
    read.__module__, read.__name__, read.__qualname__ = module, function, function
    read.__doc__ = f"See :func:`{READER_NAMES[format]}`."
    return read


#: The readers, keyed by format (``data.format``); the logs' readers need their optional extras.
READERS = {
    "magexp-v1": read_versioned,
    "plain": read_plain,
    "two-stream": read_two_stream,
    "named-columns": read_named_columns,
    "header-counts": read_header_counts,
    "header-row": read_header_row,
    "ulog": _log_reader("ulog"),
    "dataflash": _log_reader("dataflash"),
    "rosbag": _log_reader("rosbag"),
}
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

    Returns
    -------
    Recording
        The readings in the common body axes, their unit, and what the format holds beside them
        (attitude angles, a gyroscope, times, a reference field, the log's GPS place and date).

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
