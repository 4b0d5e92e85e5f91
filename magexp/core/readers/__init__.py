"""Recording formats: one module per format in this package, found by listing it (as the artifact kinds
are, :mod:`magexp.artifacts.kinds`): every module here whose name does not start with ``_`` is a format
(``__main__`` writes the docs' table). What formats share lives beside the package, not in it:
:mod:`magexp.core.textfiles` (the parsing the text formats share) and :mod:`magexp.core.logfiles` (what
the flight and robot logs' readers share).

A format module holds all of its format:

* its docstring's first paragraph: what it reads (``magexp calibrate --help`` and the table of formats in
  ``docs/calibrate.md`` are generated from it, :func:`summary`, :func:`docs_section`), the rest the details;
* ``NAME``: its ``data.format`` value;
* ``PRIORITY``: where ``data.format=auto`` tries it (lower first; the formats are listed in this order);
* ``SUFFIXES``: the file name endings that make a file this format (lower case, ``()`` for none);
* ``claims(path)``, optional: a test of the path alone (a folder, a file name), before any file is read;
* ``sniff(head)``, optional: a test of the file's first three lines (``head``, a list of str);
* ``FALLBACK = True``, on one format only: a text file nothing claims is read as that format;
* ``UNIT``: where its readings' unit comes from (one line); ``EXTRA``: the ``pip install 'magexp[<extra>]'``
  its reader needs, or None;
* ``BINARY``: its files are bytes, not lines (the file gate, :mod:`magexp.run.files`, checks no line length);
  ``READ_MEMORY``: the most memory its reader holds, in bytes a byte of the file (the gate refuses a file
  whose reading would pass the memory limit; ``tests/test_file_gate.py`` measures the readers);
* ``read(path, *, unit=None, mag_axes=None, gyro_axes=None)``: the :class:`~magexp.core.recording.Recording`
  of the file (a format may take more keyword options: ``instance`` of ``dataflash``).

:func:`detect` tells a file's format: the suffixes of every format first, then each ``claims``, then each
``sniff`` of the first three lines, in ``PRIORITY`` order, else the fallback. Adding a format is adding one
module here. A reader imports :mod:`magexp.core.recording` (the type), never :mod:`magexp.core.recordings`
(the loader), and this package imports no format statically: the run cache keys a run on the module of the
reader its data's format names (:func:`reader_of`), found from the sources
(:mod:`magexp.run.codekey`), so an edit of one format reruns only the runs reading it.

``read``, ``claims`` and ``sniff`` are documented here, once; a format's own say in a line what they do
(``tests/test_docstrings.py`` checks these sections).

Parameters of ``read``
----------------------
path : Path
    The file (or, for a format whose ``claims`` says so, a folder or a stem), resolved by
    :func:`magexp.core.recordings.resolve`.
unit : str, optional
    ``data.unit``: the unit of a file that does not name it (:data:`magexp.core.recording.UNITS`, or
    ``counts``); for a file that names its unit it may be left None and must otherwise agree with it.
mag_axes, gyro_axes : str, optional
    Signed axis maps of the magnetometer and the gyroscope onto the common body axes (``"-x,y,z"``,
    :func:`magexp.core.geometry.axis_map`); None keeps the format's default.

Returns of ``read``
-------------------
Recording
    The readings in the common body axes, their unit, and what the format holds beside them (attitude
    angles, a gyroscope, times, a reference field, a log's GPS place and date).

Raises of ``read``
------------------
MagexpError
    One line naming the file, the line and the fault for a malformed file.

Parameters of ``claims``
------------------------
path : Path
    The recording as given (a file, a folder, or a stem that is neither).

Returns of ``claims``
---------------------
bool
    Whether the path alone makes it this format.

Parameters of ``sniff``
-----------------------
head : list of str
    The file's first :data:`HEAD_LINES` lines as read (``""`` past its end; decoded as UTF-8, a bad byte
    replaced).

Returns of ``sniff``
--------------------
bool
    Whether these lines make it this format.
"""

from __future__ import annotations

import functools
import importlib
import pkgutil
from pathlib import Path

from magexp.errors import MagexpError

#: the lines of a file :func:`detect` reads for the formats' ``sniff``
HEAD_LINES = 3


@functools.cache
def formats() -> tuple:
    """The format modules (this package's modules not starting with ``_``), imported, in ``PRIORITY`` order; a reader imports its optional package only when it reads."""
    found = [importlib.import_module(f"{__name__}.{m.name}") for m in pkgutil.iter_modules(__path__)
             if not m.name.startswith("_")]
    return tuple(sorted(found, key=lambda module: (module.PRIORITY, module.NAME)))


def names() -> tuple[str, ...]:
    """The formats' ``NAME`` (``data.format`` values), in ``PRIORITY`` order."""
    return tuple(module.NAME for module in formats())


def format_of(name: str):
    """The module of the format ``name``; one line naming the formats there are for any other name."""
    module = next((m for m in formats() if m.NAME == name), None)
    if module is None:
        raise MagexpError(f"data.format={name!r} is not allowed: choose one of auto, {', '.join(names())}")
    return module


def by_suffix(path: Path) -> str | None:
    """The format whose ``SUFFIXES`` hold ``path``'s suffix (``.ulg``, ...), else None."""
    suffix = path.suffix.lower()
    return next((m.NAME for m in formats() if suffix in m.SUFFIXES), None)


def detect(path: Path) -> str:
    """The format of the recording ``path``: by its suffix, then each format's ``claims``, then each ``sniff`` of its
    first lines, in ``PRIORITY`` order; a text file nothing claims is the ``FALLBACK`` format.
    """
    found = by_suffix(path) or next((m.NAME for m in formats() if hasattr(m, "claims") and m.claims(path)), None)
    if found is not None:
        return found
    with open(path, encoding="utf-8-sig", errors="replace") as fh:
        head = [fh.readline() for _ in range(HEAD_LINES)]
    return next((m.NAME for m in formats() if hasattr(m, "sniff") and m.sniff(head)),
                next(m.NAME for m in formats() if getattr(m, "FALLBACK", False)))


def reader_of(path: Path, format: str | None = "auto") -> str:
    """``module.function`` of the reader of ``path`` in ``format`` (``auto``, None or an unknown name: :func:`detect`'s):
    the run cache keys a run on that module's source (:func:`magexp.run.cache.data_readers`).
    """
    module = format_of(format if format in names() else detect(path))
    return f"{module.__name__}.{module.read.__name__}"


# -- the tables of formats in --help and docs/calibrate.md, written from the modules -------------------------

#: the lines around the generated table of formats in docs/calibrate.md
BEGIN, END = "<!-- formats: written by python -m magexp.core.readers; do not edit -->", "<!-- /formats -->"


def summary(module) -> str:
    """What the format ``module`` reads, for ``--help`` and the docs' table: its docstring's first paragraph on one line."""
    return " ".join(module.__doc__.split("\n\n")[0].split()).replace("``", "`")


def detection(module) -> str:
    """How ``data.format=auto`` tells the format ``module`` (its suffixes, ``claims``, ``sniff`` first lines, or fallback): one line for the docs' table."""
    ways = [", ".join(f"`{s}`" for s in module.SUFFIXES)] if module.SUFFIXES else []
    for test in ("claims", "sniff"):
        if hasattr(module, test):
            line = getattr(module, test).__doc__.splitlines()[0].rstrip(".")
            ways.append(line[0].lower() + line[1:])
    if getattr(module, "FALLBACK", False):
        ways.append("any other text file")
    return "; ".join(ways).replace("``", "`")


def docs_section() -> str:
    """The generated table of docs/calibrate.md, :data:`BEGIN` to :data:`END` (written by
    :func:`magexp.core.generated.with_section`): one row per format, in the order ``auto`` tries them.
    """
    lines = [BEGIN, "`auto` tries the formats in this order: a file's name first (every format's suffixes, "
             "then a folder or a file name), then its first lines.", "",
             "| format | what it reads | `auto` tells it by | unit | needs |", "|---|---|---|---|---|"]
    for m in formats():
        extra = f"`pip install 'magexp[{m.EXTRA}]'`" if m.EXTRA else ""
        lines.append(f"| `{m.NAME}` | {summary(m)} | {detection(m)} | {m.UNIT} | {extra} |")
    return "\n".join(lines + [END])
