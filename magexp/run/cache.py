"""Run results stored under their keys (:mod:`magexp.run.runkeys`), in entries that are data, never code.

An entry (:mod:`magexp.run.entries`) holds a run's fields; reading one (:func:`load`) checks that it is
stored under the key asked for, of the kind asked for, with the digest it carries, and that it holds a
run's fields of their types. Anything else (truncated, corrupt, swapped with another key's entry, forged,
of another type, unreadable) is a miss: the run is computed again and the problem said once, in one line
per kind, at the end of the command (:func:`say_notes`).

An entry is written atomically (temporary file + ``os.replace``), readable by whom the cache folder
is readable (a folder shared by a group shares its entries: :func:`_modes`). A cache that cannot be
written keeps nothing and says so once; the computed runs are returned all the same. Processes
sharing a cache compute each run once: a worker claims a run (:func:`claim`: a ``flock`` on a lock file
beside its entry) before computing it, and a run another process is computing is waited for and read.
"""

from __future__ import annotations

import dataclasses
import fcntl
import os
import stat
import sys
import types
import typing
from collections import Counter
from functools import lru_cache
from pathlib import Path

from magexp.core.atomic import write_bytes
from magexp.paths import CACHE
from magexp.run.entries import MAGIC, InvalidEntry, pack, read
from magexp.run.folders import check_cache_folder

#: file name suffix of a stored run (``<root>/<key[:2]>/<key><SUFFIX>``)
SUFFIX = ".run"


def _modes(root: Path) -> tuple[int, int]:
    """``(file mode, folder mode)`` of what is written in the cache folder ``root``: readable by whom
    the folder is readable (a folder shared by a group, e.g. mode 2775, shares its entries with the
    group), folders with the root's permissions (never writable by others) and its setgid bit (so they
    keep its group)."""
    try:
        mode = root.stat().st_mode
    except OSError:
        return 0o600, 0o700
    return 0o600 | (mode & 0o044), 0o700 | (mode & 0o075) | (mode & stat.S_ISGID)


def _folder(path: Path, root: Path) -> None:
    """Create the folder ``path`` (``root`` or inside it) and the folders on the way, with the root's
    permissions (:func:`_modes`; the umask may have taken the group's bits)."""
    if path.is_dir():
        return
    if not root.is_dir():  # a new cache folder takes the permissions of the folder it is in
        root.parent.mkdir(parents=True, exist_ok=True)
        try:
            root.mkdir()
            os.chmod(root, _modes(root.parent)[1])
        except FileExistsError:
            pass
    mode, todo = _modes(root)[1], []
    while path != root and path != path.parent and not path.is_dir():
        todo.append(path)
        path = path.parent
    for folder in reversed(todo):
        try:
            folder.mkdir()
        except FileExistsError:
            continue
        os.chmod(folder, mode)


def write(path: Path, data: bytes, root: Path) -> None:
    """Write ``data`` to ``path`` (inside the cache folder ``root``) atomically
    (:func:`magexp.core.atomic.write_bytes`), with the permissions of :func:`_modes`. Raises ``OSError``,
    or MagexpError for a cache folder inside ``results/`` (:func:`magexp.run.folders.check_cache_folder`)."""
    check_cache_folder(str(root))
    _folder(path.parent, root)
    write_bytes(path, data, mode=_modes(root)[0])


# ---------------------------------------------------------------------------------------------
# what went wrong with the cache, said once per command

_NOTES: dict = {}  # (cache folder, key, kind) -> detail


def note(root: Path, key: str, kind: str, detail: str = "") -> None:
    """Remember a problem with ``key``'s entry: ``invalid`` (detail: why), ``unreadable``
    (permissions) or ``unwritable`` (detail: the error); :func:`say_notes` tells them."""
    _NOTES.setdefault((str(root), key, kind), detail)


def take_notes() -> list:
    """The problems noted in this process (for a worker to send to its parent), forgotten here."""
    notes = [(root, key, kind, detail) for (root, key, kind), detail in _NOTES.items()]
    _NOTES.clear()
    return notes


def add_notes(notes) -> None:
    """Notes of another process (:func:`take_notes`), merged with this one's (each entry once)."""
    for root, key, kind, detail in notes:
        note(root, key, kind, detail)


def say_notes(stream=None) -> list[str]:
    """Print one line per kind of problem noted (and forget them); returns the lines."""
    groups: dict = {}
    for (root, _, kind), detail in _NOTES.items():
        groups.setdefault((root, kind), []).append(detail)
    _NOTES.clear()
    lines = []
    for (root, kind), details in groups.items():
        n = len(details)
        entries = f"{n} entr{'y' if n == 1 else 'ies'}"
        if kind == "invalid":
            why = ", ".join(f"{d}: {c}" for d, c in sorted(Counter(details).items()))
            lines.append(f"note: run cache {root}: {entries} not valid ({why}); computed again")
        elif kind == "unreadable":
            lines.append(f"note: run cache {root}: {entries} not readable by this user (permissions); "
                         "computed again, left in place")
        else:
            lines.append(f"note: run cache {root} cannot be written ({details[0]}): {n} computed "
                         f"run{'s' if n != 1 else ''} not kept")
    for line in lines:
        print(line, file=stream or sys.stderr)
    return lines


# ---------------------------------------------------------------------------------------------
# runs

def entry_path(key: str, root: Path | None = None) -> Path:
    """Where the run of ``key`` is stored."""
    return (CACHE if root is None else Path(root)) / key[:2] / f"{key}{SUFFIX}"


def _checker(hint):
    """A function telling whether a value is of the annotated type ``hint`` (``X | None``, ``list[X]``,
    ``float``, a class)."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        checks = [_checker(a) for a in args]
        return lambda v: any(check(v) for check in checks)
    if hint is type(None):
        return lambda v: v is None
    if origin is list:
        item = _checker(args[0])
        return lambda v: type(v) is list and all(item(x) for x in v)
    kind = origin or hint
    return lambda v: isinstance(v, kind) and not (kind is int and type(v) is bool)


@lru_cache(maxsize=1)
def _run_checks() -> dict:
    """The fields of :class:`magexp.estimators.result.RunOutput`, each with the :func:`_checker` of its type."""
    from magexp.estimators.result import RunOutput  # numpy: as in _tree

    return {name: _checker(hint) for name, hint in typing.get_type_hints(RunOutput).items()}


def _run_output(value):
    """The :class:`magexp.estimators.result.RunOutput` of an entry's value, or :class:`InvalidEntry`."""
    from magexp.estimators.result import RunOutput  # as in _tree

    checks = _run_checks()
    if type(value) is not dict or value.keys() != checks.keys():
        raise InvalidEntry("does not hold a run's fields")
    for name, check in checks.items():
        if not check(value[name]):
            raise InvalidEntry(f"its field {name} is not of its type")
    return RunOutput(**value)


def _fields(value, fields: tuple[str, ...]) -> types.SimpleNamespace:
    """The ``fields`` of a run entry's value, each checked as :func:`_run_output` checks it, or :class:`InvalidEntry`."""
    checks = _run_checks()
    if type(value) is not dict or value.keys() != checks.keys():
        raise InvalidEntry("does not hold a run's fields")
    for name in fields:
        if not checks[name](value[name]):
            raise InvalidEntry(f"its field {name} is not of its type")
    return types.SimpleNamespace(**{name: value[name] for name in fields})


def load(key: str, root: Path | None = None, fields: tuple[str, ...] | None = None):
    """The stored run of ``key`` (a :class:`magexp.estimators.result.RunOutput`; with ``fields``, a namespace of
    those fields only, the other arrays never made: a run's row needs three), or None: absent, or not a
    valid entry of ``key`` (a miss noted for :func:`say_notes`; the entry is left in place, the
    recomputed run replaces it), or not readable by this user (noted, never replaced)."""
    root = CACHE if root is None else Path(root)
    try:
        if fields is not None:
            return _fields(read(entry_path(key, root), key, "RunOutput", fields), fields)
        return _run_output(read(entry_path(key, root), key, "RunOutput"))
    except (FileNotFoundError, NotADirectoryError):  # absent (or no cache folder at all)
        return None
    except PermissionError:
        note(root, key, "unreadable")
    except InvalidEntry as exc:
        note(root, key, "invalid", str(exc))
    except OSError as exc:
        note(root, key, "invalid", exc.strerror or type(exc).__name__)
    return None


#: the rows of the valid entries of a two-letter folder, kept in it (:func:`known_rows`)
ROWS = "rows.memo"


def _stamp(path: Path) -> list[int] | None:
    """Size, modification time and inode of an entry file (None: absent): an entry replaced changes it."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return [st.st_size, st.st_mtime_ns, st.st_ino]


def known_rows(keys, root: Path | None = None) -> dict[str, dict]:
    """``{key: row}`` of the ``keys`` whose row :func:`keep_rows` kept and whose entry is the file it was read
    from (same stamp): a warm command reads one small file per folder instead of every entry."""
    root = CACHE if root is None else Path(root)
    by_folder: dict[str, list[str]] = {}
    for key in keys:
        by_folder.setdefault(key[:2], []).append(key)
    rows = {}
    for folder, wanted in by_folder.items():
        try:
            kept = read(root / folder / ROWS, folder, "Rows")
        except (OSError, InvalidEntry):
            continue
        for key in wanted:
            item = kept.get(key) if isinstance(kept, dict) else None
            if isinstance(item, list) and len(item) == 2 and isinstance(item[1], dict) \
                    and item[0] == _stamp(entry_path(key, root)):
                rows[key] = item[1]
    return rows


def keep_rows(rows: dict[str, dict], root: Path | None = None) -> None:
    """Keep ``rows`` (``{key: row}`` just read from valid entries) beside their entries, each with its entry's
    stamp, merged with what each folder kept (atomically; nothing where the cache cannot be written)."""
    root = CACHE if root is None else Path(root)
    by_folder: dict[str, dict] = {}
    for key, row in rows.items():
        by_folder.setdefault(key[:2], {})[key] = row
    for folder, new in by_folder.items():
        try:
            kept = read(root / folder / ROWS, folder, "Rows")
        except (OSError, InvalidEntry):
            kept = {}
        kept = {k: v for k, v in (kept if isinstance(kept, dict) else {}).items()
                if isinstance(v, list) and v and v[0] == _stamp(entry_path(k, root))}
        kept.update({key: [_stamp(entry_path(key, root)), row] for key, row in new.items()})
        try:
            write(root / folder / ROWS, pack(folder, "Rows", kept), root)
        except (OSError, TypeError):  # a read-only cache; a row JSON cannot hold: read from its entry each time
            pass


def exists(key: str, root: Path | None = None) -> bool:
    """Whether a run of ``key`` is stored (its file's first bytes are those of an entry; the
    content is checked when it is read)."""
    try:  # not blocking: a FIFO planted in the cache would hold a plain open forever; only a regular file is an entry
        with os.fdopen(os.open(entry_path(key, root), os.O_RDONLY | os.O_NONBLOCK), "rb") as fh:
            return stat.S_ISREG(os.fstat(fh.fileno()).st_mode) and fh.read(len(MAGIC)) == MAGIC
    except OSError:
        return False


def store(key: str, value, root: Path | None = None) -> bool:
    """Store the run ``value`` under ``key`` atomically; whether it was kept. A cache that cannot be
    written, or an entry of another user this user cannot read (left in place), keeps nothing (noted)."""
    root = CACHE if root is None else Path(root)
    path = entry_path(key, root)
    try:  # an entry this user cannot read belongs to another user: never replaced (not blocking on a FIFO there)
        os.close(os.open(path, os.O_RDONLY | os.O_NONBLOCK))
    except PermissionError:
        note(root, key, "unreadable")
        return False
    except OSError:
        pass
    data = pack(key, "RunOutput", {f.name: getattr(value, f.name) for f in dataclasses.fields(value)})
    try:
        write(path, data, root)
    except OSError as exc:
        note(root, key, "unwritable", exc.strerror or type(exc).__name__)
        return False
    return True


# ---------------------------------------------------------------------------------------------
# one computation of a run at a time, across processes sharing the cache

class Claim:
    """The right to compute the run of a key: an exclusive ``flock`` on ``<key>.lock`` beside its
    entry, held until :meth:`release`. ``fd`` is None where the cache cannot be written (nothing is
    shared then). The lock is the kernel's: a process that dies releases it."""

    def __init__(self, fd: int | None, path: Path):
        self.fd, self.path = fd, path

    def release(self) -> None:
        """Give the claim up: its lock file removed while still locked, then closed."""
        if self.fd is not None:
            try:
                os.unlink(self.path)  # while locked: whoever opened it before sees its inode gone
            except OSError:
                pass
            os.close(self.fd)
            self.fd = None


def claim(key: str, root: Path | None = None, *, wait: bool = False) -> Claim | None:
    """A :class:`Claim` on computing ``key``'s run, or None if another process holds it (``wait``:
    wait until it is released instead). Processes that wait must claim their keys in sorted order
    while holding only claims of smaller keys (so no two wait for each other)."""
    root = CACHE if root is None else Path(root)
    path = entry_path(key, root).with_suffix(".lock")
    while True:
        try:
            _folder(path.parent, root)
            fd = os.open(path, os.O_RDONLY | os.O_CREAT, _modes(root)[0])
        except OSError:
            return Claim(None, path)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
        except BlockingIOError:
            os.close(fd)
            return None
        except OSError:  # a file system without locks
            os.close(fd)
            return Claim(None, path)
        try:
            same = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            return Claim(fd, path)
        os.close(fd)  # its holder removed it while this process waited: claim the new one
