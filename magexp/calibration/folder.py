"""One calibration per output folder: which of its files a calibration wrote, and what replacing it touches.

An output folder of ``magexp calibrate`` holds the files of one calibration. ``calibration.json`` records
them: its ``files`` key (:data:`MANIFEST`) maps the name of every other file the calibration wrote
(``calibrated.csv``, the figure, the export) to the SHA-256 of its content. A file is **a calibration's**
(:func:`is_calibrations`) when

* the manifest lists it and its content is unchanged (the digest matches); a listed file changed since
  is the user's;
* else (a folder written before the manifest, or a file written by ``Calibration.save`` or
  ``Calibration.export``) its first bytes carry magexp's mark (:data:`MARKS`: the exports' opening
  comment, the calibrated readings' source line, ``calibration.json``'s format line);

never a symbolic link (magexp writes none). ``overwrite=true`` replaces the earlier calibration's whole
set (:func:`plan`): an output of the new one that is in the way is replaced only if it is the earlier
calibration's, and every file of the earlier set the new one does not write is removed and named.
A file no calibration wrote is never touched: in the way, it is refused in one line. A folder that holds
the recording being read is refused (:func:`check_recording`), whatever ``overwrite`` says.
"""

from __future__ import annotations

import hashlib
import json
import os
import stat
from dataclasses import dataclass
from pathlib import Path

from magexp.core.datafiles import TWO_STREAM
from magexp.errors import MagexpError

#: the key of ``calibration.json`` that lists the other files its calibration wrote (``{name: sha256}``)
MANIFEST = "files"
#: the calibration's parameters file, which holds the manifest
PARAMETERS = "calibration.json"
#: what the opening bytes of a file magexp's calibration wrote carry (exports, calibrated.csv, calibration.json)
MARKS = (b"magexp magnetometer calibration", b"calibrated by magexp", b'"format": "magexp-calibration')
#: how many opening bytes :func:`is_calibrations` reads for a mark
HEAD = 512


def digest(path: Path) -> str:
    """The SHA-256 of the file ``path``, read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def manifest(folder: Path) -> dict | None:
    """The manifest of the calibration in ``folder`` (its ``calibration.json``'s :data:`MANIFEST`)."""
    path = Path(folder) / PARAMETERS
    if path.is_symlink() or not path.is_file():
        return None
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None
    if not isinstance(data, dict) or not str(data.get("format", "")).startswith("magexp-calibration"):
        return None
    listed = data.get(MANIFEST)
    return {str(k): str(v) for k, v in listed.items()} if isinstance(listed, dict) else {}


def is_calibrations(path: Path, listed: dict | None = None) -> bool:
    """Whether the file ``path`` was written by a calibration and is unchanged since (module docstring)."""
    path = Path(path)
    if path.is_symlink() or not path.is_file():
        return False
    if listed and path.name in listed:
        return digest(path) == listed[path.name]
    with open(path, "rb") as fh:
        head = fh.read(HEAD)
    return any(mark in head for mark in MARKS)


@dataclass(frozen=True)
class Plan:
    """What writing a calibration into a folder does to what is there: the names it ``replaces`` (an
    earlier calibration's files in the way) and the earlier calibration's files it ``removes``."""

    replaces: tuple = ()
    removes: tuple = ()


def plan(folder: Path, names, *, overwrite: bool, known=(), option: str = "out") -> Plan:
    """The :class:`Plan` of writing the files ``names`` into ``folder``, or one line refusing it."""
    folder, names = Path(folder), list(names)
    if not folder.is_dir():
        return Plan()
    where = f"{option}={str(folder)!r} is not allowed"
    taken = [n for n in names if _present(folder / n)]
    if taken and not overwrite:
        raise MagexpError(f"{where}: it already holds {', '.join(taken)} (never overwritten unless overwrite=true), "
                          "choose another folder")
    listed = manifest(folder)
    foreign = [n for n in taken if not is_calibrations(folder / n, listed)]
    if foreign:
        raise MagexpError(f"{where}: {foreign[0]} is in the way and no calibration wrote it (or it changed since), "
                          "so overwrite=true does not replace it: move it away or choose another folder")
    return Plan(tuple(taken), _leftovers(folder, names, listed, known, where))


def _leftovers(folder: Path, names: list, listed: dict | None, known, where: str) -> tuple:
    """The earlier calibration's files in ``folder`` that ``names`` does not write again: those its manifest
    lists (one changed since: one line refusing it) and the ``known`` names carrying a mark (an export
    written beside it by ``Calibration.export``, a folder written before the manifest); nothing else."""
    if listed is None:
        return ()
    left = sorted(n for n in (set(listed) | set(known)) - set(names) if _present(folder / n))
    changed = [n for n in left if n in listed and not is_calibrations(folder / n, listed)]
    if changed:
        raise MagexpError(f"{where}: {changed[0]} was written by the calibration in it and changed since, so "
                          "overwrite=true does not remove it: move it away or choose another folder")
    return tuple(n for n in left if is_calibrations(folder / n, listed))


def _present(path: Path) -> bool:
    """Whether there is an entry at ``path`` (a dangling symbolic link included)."""
    return path.exists() or path.is_symlink()


def recording_files(rec) -> list[Path]:
    """The files a recording was read from (both of a two-stream recording)."""
    if rec is None or rec.path is None:
        return []
    path = Path(rec.path)
    if rec.meta.get("format") != "two-stream":
        return [path]
    stem = str(path)
    for tail in TWO_STREAM:
        stem = stem[: -len(tail)] if stem.endswith(tail) else stem
    return [Path(stem + tail) for tail in TWO_STREAM]


def check_recording(folder: Path, files, *, option: str = "out") -> None:
    """Refuse, in one line, an output ``folder`` that holds one of the recording's ``files``: the file itself
    (as given or resolved through symbolic links) or, among the folder's entries, a link to it (hard or
    symbolic)."""
    folder = Path(folder)
    files = [Path(f) for f in files if Path(f).exists()]
    if not files:
        return
    inside = {folder.absolute(), folder.resolve()}
    ids = {(st.st_dev, st.st_ino): f for f in files for st in [f.stat()]}
    held = [f for f in files if inside & ({*f.absolute().parents, *f.resolve().parents})]
    if not held and folder.is_dir():
        with os.scandir(folder) as entries:
            held = [ids[key] for e in entries if e.is_file() and (key := (e.stat().st_dev, e.stat().st_ino)) in ids]
    if held:
        raise MagexpError(f"{option}={str(folder)!r} is not allowed: it holds the recording being read "
                          f"({held[0].name}), which a calibration never writes over: choose another folder")


def file_path(path, option: str = "path") -> Path:
    """``path``, a file a calibration is about to write, as a :class:`~pathlib.Path`; one line refusing anything
    else (a number, None, an empty string)."""
    if not isinstance(path, (str, os.PathLike)) or not str(os.fspath(path)).strip() or "\0" in str(os.fspath(path)):
        raise MagexpError(f"{option}={path!r} is not allowed: give a file's path (a str or a Path)")
    return Path(path)


def _kind(path: Path) -> str | None:
    """What the entry ``path`` is when it is not a regular file a calibration may replace (None: it is one, or absent)."""
    if path.is_symlink():
        return "a symbolic link (magexp writes none, and replaces none)"
    if not path.exists():
        return None
    mode = path.stat().st_mode
    kinds = ((stat.S_ISDIR, "a folder"), (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
             (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"))
    return next((kind for test, kind in kinds if test(mode)), None)


def check_file(path: Path, *, overwrite: bool, recording=(), option: str = "path") -> None:
    """Refuse, in one line, writing the single file ``path`` (``Calibration.save``, ``Calibration.export``) over
    an existing file without ``overwrite``, over one no calibration wrote (:func:`plan`), or over the recording."""
    path = Path(path)
    where = f"{option} {str(path)!r} is not allowed"
    if not isinstance(overwrite, bool):
        raise MagexpError(f"overwrite={overwrite!r} is not allowed: give True or False")
    if not path.parent.is_dir():
        raise MagexpError(f"{where}: its folder {str(path.parent)!r} does not exist or is not a folder (a calibration "
                          "creates none here): create it first or choose another")
    if not _present(path):
        return
    if (kind := _kind(path)) is not None:
        raise MagexpError(f"{where}: it is {kind}, not a file a calibration wrote; a calibration replaces only "
                          "its own regular files: choose another")
    if any(f.exists() and os.path.samefile(path, f) for f in map(Path, recording)):
        raise MagexpError(f"{where}: it is the recording being read, which a calibration never writes over: "
                          "choose another file")
    if not overwrite:
        raise MagexpError(f"{where}: it exists already (never overwritten unless overwrite=True), choose another")
    if not is_calibrations(path, manifest(path.parent)):
        raise MagexpError(f"{where}: no calibration wrote it (or it changed since), so overwrite=True does not "
                          "replace it: move it away or choose another")
