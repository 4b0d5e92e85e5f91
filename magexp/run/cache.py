"""Run results stored under a key derived from everything a run reads.

The key of a run (:func:`run_key`) hashes

* its fully resolved config (every setting, the seed included),
* the content of every data file the config names (:func:`magexp.core.datafiles.data_files`), so that editing a
  recording such as ``data/yan2022_mockup.csv`` reruns exactly the runs that read it,
* the source of the code the run executes (:func:`code_version`): the modules of what it names
  (:func:`run_targets`: every ``_target_`` of its config, the reader of each data file it reads, its
  objective's problem class) with their import closure and the core every run executes, found and hashed by
  :mod:`magexp.run.codekey` and kept under the sources' stamp. So an estimator edit reruns the runs of that
  estimator and of the estimators importing its module, a reader edit the runs reading a file of its format,
  and code downstream of a run (``plots/``, ``summary``, ``report``, ``reproduce``, the executor, this module)
  is not part of any key: a figure or report edit costs no run.

An entry (:func:`pack`) is data, never code: a line with a SHA-256 digest, a JSON header (its key, its
kind, the tree of its values) and the raw bytes of its numpy arrays. Reading one (:func:`load`)
parses JSON and views bytes as numbers of a plain dtype, and checks that it is stored under the key
asked for, of the kind asked for, with the digest it carries, and that it holds a run's fields of
their types. Anything else (truncated, corrupt, swapped with another key's entry, forged, of another
type, unreadable) is a miss: the run is computed again and the problem said once, in one line per
kind, at the end of the command (:func:`say_notes`). The digest proves integrity, not authorship: a
cache folder is trusted as far as who may write into it.

An entry is written atomically (temporary file + ``os.replace``), readable by whom the cache folder
is readable (a folder shared by a group shares its entries: :func:`_modes`). A cache that cannot be
written keeps nothing and says so once; the computed runs are returned all the same. Processes
sharing a cache compute each run once: a worker claims a run (:func:`claim`: a ``flock`` on a lock file
beside its entry) before computing it, and a run another process is computing is waited for and read.
"""

from __future__ import annotations

import dataclasses
import fcntl
import hashlib
import json
import math
import os
import re
import stat
import sys
import types
import typing
from collections import Counter
from functools import lru_cache
from pathlib import Path

from magexp.core.atomic import write_bytes
from magexp.core.datafiles import data_files, data_formats
from magexp.core.formats import reader_of
from magexp.paths import CACHE
from magexp.problems import OBJECTIVES
from magexp.run.codekey import code_hash, default_objective, source_stamp
from magexp.run.folders import check_cache_folder


# ---------------------------------------------------------------------------------------------
# keys

def files_digest(files, base: Path):
    """A SHA-256 object fed with the path (relative to ``base``) and content of each of ``files``."""
    h = hashlib.sha256()
    for path in files:
        h.update(path.relative_to(base).as_posix().encode())
        h.update(path.read_bytes())
    return h


def _targets_in(node, found: set) -> set:
    """Every ``_target_`` string in a config tree (nested strategy objects included), added to ``found``."""
    if isinstance(node, dict):
        for key, value in node.items():
            if key == "_target_" and isinstance(value, str):
                found.add(value)
            else:
                _targets_in(value, found)
    elif isinstance(node, (list, tuple)):
        for value in node:
            _targets_in(value, found)
    return found


def data_readers(formats: dict) -> set[str]:
    """The readers of a config's data files (``formats``: its :func:`magexp.core.datafiles.data_formats`):
    the dotted name of the function reading each (:func:`magexp.core.formats.reader_of`) in the
    format named beside it, else in the one detected from its name or first lines. None is imported: a
    log's reader module is imported by name when the log is read."""
    return {reader_of(path, format) for path, format in formats.items()}


def run_targets(resolved: dict, formats: dict | None = None) -> tuple[str, ...]:
    """What a run instantiates or calls by name: every ``_target_`` of its resolved config, the reader of
    each data file it names (:func:`data_readers`; ``formats``: its data files' formats, found here if
    None), and the problem class of its objective (``objective``, else its scenario's: in its config,
    else fixed by its class, :func:`magexp.run.codekey.default_objective`; one not found so: every registered problem
    class)."""
    formats = data_formats(resolved) if formats is None else formats
    found = _targets_in(resolved, set()) | data_readers(formats)
    scenario = resolved.get("scenario") if isinstance(resolved.get("scenario"), dict) else {}
    objective = resolved.get("objective") or scenario.get("objective")
    if objective is None and isinstance(scenario.get("_target_"), str):
        objective = default_objective(scenario["_target_"])
    problems = [OBJECTIVES[objective]] if objective in OBJECTIVES else list(OBJECTIVES.values())
    found.update(p.replace(":", ".") for p in problems)
    return tuple(sorted(found))


def code_versions(target_sets) -> dict[tuple, str]:
    """:func:`code_version` of each tuple of ``target_sets``, the memo read and written once.

    Finding the code of a run parses the modules of its closure (about 20 ms for one run's, 60 ms
    for every run of ``reproduce all``). The versions of targets that are all magexp's are kept in
    the run cache folder (``code-version.json``, beside the results' two-letter folders) under the
    sources' :func:`magexp.run.codekey.source_stamp`, so a later command with unchanged sources reads
    them instead (a changed stamp only recomputes them: never a stale version). A target of another package is
    worked out each time: the stamp does not cover its files."""
    memo, stamp = CACHE / "code-version.json", source_stamp()
    try:
        known = json.loads(memo.read_text())
        known = known if isinstance(known, dict) else {}
    except (OSError, ValueError):
        known = {}
    kept = known.get(stamp) if isinstance(known.get(stamp), dict) else {}
    versions, new = {}, {}
    for targets in dict.fromkeys(target_sets):
        name = "|".join(targets)
        if isinstance(kept.get(name), str):
            versions[targets] = kept[name]
            continue
        versions[targets] = code_hash(targets)
        if all(t.startswith("magexp.") for t in targets):
            new[name] = versions[targets]
    if new:
        known = {**{k: v for k, v in list(known.items())[-7:] if k != stamp}, stamp: {**kept, **new}}  # the last few trees
        try:
            write(memo, json.dumps(known).encode(), CACHE)
        except OSError:  # a read-only cache folder: worked out each time
            pass
    return versions


def code_version(targets: tuple[str, ...] = ()) -> str:
    """Hash of the code a run of ``targets`` (its :func:`run_targets`) executes: the name and content of
    each file of :func:`magexp.run.codekey.code_files`. Only an edit of such a file invalidates the run.

    Parameters
    ----------
    targets : tuple of str
    """
    return code_versions([tuple(targets)])[tuple(targets)]


def run_key(resolved: dict, files: dict[str, str] | None = None, code: str | None = None) -> str:
    """Key of a run: its resolved config, the content of the data files it names, the code it executes.

    Parameters
    ----------
    resolved, files, code : dict, dict or None, str or None
        The resolved config; its :func:`data_files` and :func:`code_version` (None: found here).
    """
    files = data_files(resolved) if files is None else files
    code = code_version(run_targets(resolved)) if code is None else code
    return _key_of(json.dumps(resolved, sort_keys=True, default=str), files, code)


def _key_of(text: str, files: dict[str, str], code: str) -> str:
    """:func:`run_key` from the config's sorted JSON ``text``: one place that hashes a key."""
    if files:
        text += json.dumps(sorted(files.values()))
    return hashlib.sha256((text + code).encode()).hexdigest()[:32]


def _sorted_json(cfg: dict, parts: dict) -> str:
    """``json.dumps(cfg, sort_keys=True, default=str)`` of a config with string keys, each top-level value's
    text taken from ``parts`` (by identity: the seeds of a cell share every value but their seed)."""
    texts = []
    for name in sorted(cfg):
        value = cfg[name]
        if id(value) not in parts:
            parts[id(value)] = (value, json.dumps(value, sort_keys=True, default=str))
        texts.append(f"{json.dumps(name)}: {parts[id(value)][1]}")
    return "{" + ", ".join(texts) + "}"


def run_keys(configs) -> list[str]:
    """:func:`run_key` of each config; its data files and code version are looked up once per config
    that differs in more than its seed, and each top-level value written as JSON once (:func:`_sorted_json`)."""
    known: dict[str, tuple] = {}
    texts, rests, parts = [], [], {}  # parts hold their values: an id is not reused meanwhile
    for cfg in configs:
        plain = all(isinstance(name, str) for name in cfg)
        text = _sorted_json(cfg, parts) if plain else json.dumps(cfg, sort_keys=True, default=str)
        rest = _sorted_json({k: v for k, v in cfg.items() if k != "seed"}, parts) if plain else \
            json.dumps({k: v for k, v in cfg.items() if k != "seed"}, sort_keys=True, default=str)
        if rest not in known:
            formats = data_formats(cfg)
            known[rest] = (data_files(cfg, formats), run_targets(cfg, formats))
        texts.append(text)
        rests.append(rest)
    versions = code_versions(targets for _, targets in known.values())
    return [_key_of(text, known[rest][0], versions[known[rest][1]]) for text, rest in zip(texts, rests)]


# ---------------------------------------------------------------------------------------------
# entries: a data format that executes nothing when read, each proving what it holds

#: first bytes of every entry (the format's version is part of it)
MAGIC = b"magexp-entry/1"
#: file name suffix of a stored run (``<root>/<key[:2]>/<key><SUFFIX>``)
SUFFIX = ".run"
_ARRAY = "$array"  # marks an array in an entry's JSON tree: {"$array": index}
_DTYPE = re.compile(r"[<>|=]?[biufc][1-9][0-9]?")  # plain numbers only: no object, string or record arrays
_ALIGN = 16


class InvalidEntry(Exception):
    """An entry that does not prove it holds what its key names (the reason is the message)."""


def _tree(value, arrays: list, where: str):
    """``value`` as a JSON tree, each numpy array replaced by ``{"$array": i}`` and appended to ``arrays``."""
    import numpy as np  # lazy: a config entry has no array, and ``--cfg job`` no numpy (86 ms CPU, min of 5)

    if isinstance(value, np.ndarray):
        if not _DTYPE.fullmatch(value.dtype.str):
            raise TypeError(f"{where} is an array of {value.dtype}: an entry holds arrays of plain numbers only")
        arrays.append(value if value.flags.c_contiguous else value.copy(order="C"))
        return {_ARRAY: len(arrays) - 1}
    if isinstance(value, np.generic):  # a numpy scalar is kept as the Python number it equals
        return _tree(value.item(), arrays, where)
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, (list, tuple)):
        return [_tree(v, arrays, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, dict):
        if not all(isinstance(k, str) for k in value) or _ARRAY in value:
            raise TypeError(f"{where} has a key that is not a string (or is {_ARRAY!r})")
        return {k: _tree(v, arrays, f"{where}[{k!r}]") for k, v in value.items()}
    raise TypeError(f"{where} is a {type(value).__name__}: an entry holds numbers, strings, lists, dicts and arrays")


#: length of an entry's first line: ``MAGIC``, the digest, the lengths of its two JSON documents
_FIRST = len(MAGIC) + 1 + 64 + 2 * 13 + 1


def pack(key: str, kind: str, value) -> bytes:
    """The bytes of an entry holding ``value`` (numbers, strings, lists, dicts with string keys,
    numpy arrays of plain numbers) under ``key``.

    Layout: one line ``MAGIC <sha256> <m> <n>``; ``m`` bytes of JSON, ``{"key", "kind", "arrays"}``
    (each array's dtype, shape, offset and size); ``n`` bytes of JSON, the value, each array in it
    replaced by ``{"$array": i}``; spaces up to a multiple of 16 bytes; the arrays' raw bytes, each
    at a multiple of 16 bytes. The SHA-256 digest covers everything after the first line (the key
    and kind included), so a truncated, altered or swapped entry is detected when read
    (:func:`unpack`). Nothing in it is code: reading it parses JSON and views bytes as numbers.
    """
    arrays: list = []
    tree = _tree(value, arrays, kind)
    table, offset = [], 0
    for a in arrays:
        table.append([a.dtype.str, list(a.shape), offset, a.nbytes])
        offset += -(-a.nbytes // _ALIGN) * _ALIGN
    meta = json.dumps({"key": key, "kind": kind, "arrays": table}).encode()
    doc = json.dumps(tree, allow_nan=True).encode()
    doc += b" " * (-(_FIRST + len(meta) + len(doc)) % _ALIGN)
    payload = bytearray(offset)
    for a, (_, _, at, nbytes) in zip(arrays, table):
        payload[at:at + nbytes] = a.tobytes()
    body = meta + doc + bytes(payload)
    digest = hashlib.sha256(body).hexdigest()
    return MAGIC + f" {digest} {len(meta):12d} {len(doc):12d}\n".encode() + body


def unpack(buf: bytearray, key: str, kind: str):
    """The value of an entry read into ``buf`` (writable: its arrays are views of it), after checking
    that it is an entry of ``kind`` under ``key`` whose content has the digest it carries.
    Raises :class:`InvalidEntry` naming what does not hold."""
    view = memoryview(buf)
    if len(buf) < _FIRST or bytes(view[:len(MAGIC)]) != MAGIC or buf[_FIRST - 1] != 0x0A:
        raise InvalidEntry("not an entry of this format")
    try:
        digest = bytes(view[len(MAGIC) + 1:len(MAGIC) + 65]).decode("ascii")
        m, n = (int(part) for part in bytes(view[len(MAGIC) + 66:_FIRST - 1]).split())
    except ValueError:
        raise InvalidEntry("not an entry of this format") from None
    if hashlib.sha256(view[_FIRST:]).hexdigest() != digest:
        raise InvalidEntry("content does not match its digest")
    try:
        meta = json.loads(bytes(view[_FIRST:_FIRST + m]))
    except ValueError:
        raise InvalidEntry("header is not JSON") from None
    if not isinstance(meta, dict) or meta.get("key") != key:
        raise InvalidEntry("stored under another key")
    if meta.get("kind") != kind:
        raise InvalidEntry(f"holds a {str(meta.get('kind'))[:40]!r}, not a {kind!r}")
    start = _FIRST + m + n
    try:
        arrays = _arrays(buf, meta["arrays"], start) if meta["arrays"] else []
    except (TypeError, ValueError, KeyError):
        raise InvalidEntry("its array table is malformed") from None

    def array(node: dict):  # called by the JSON parser for each object, innermost first
        if _ARRAY not in node:
            return node
        index = node[_ARRAY]
        if len(node) != 1 or type(index) is not int or not 0 <= index < len(arrays):
            raise InvalidEntry("an array reference is malformed")
        return arrays[index]

    try:
        return json.loads(bytes(view[_FIRST + m:start]), object_hook=array)
    except ValueError:
        raise InvalidEntry("value is not JSON") from None


def _arrays(buf: bytearray, table: list, start: int) -> list:
    """The arrays of an entry's array table, views of ``buf`` from ``start`` on, each checked to be of a
    plain dtype and to lie inside the entry."""
    import numpy as np  # as in :func:`_tree`

    arrays = []
    for dtype, shape, at, nbytes in table:
        dtype = np.dtype(dtype) if isinstance(dtype, str) and _DTYPE.fullmatch(dtype) else None
        if dtype is None or not all(isinstance(d, int) and d >= 0 for d in shape):
            raise InvalidEntry("an array is not of plain numbers")
        count = math.prod(shape)
        if not (isinstance(at, int) and at >= 0 and nbytes == count * dtype.itemsize and start + at + nbytes <= len(buf)):
            raise InvalidEntry("an array lies outside the entry")
        arrays.append(np.frombuffer(buf, dtype, count, start + at).reshape(tuple(shape)))
    return arrays


#: the largest cache entry read (bytes): far above a run's output within the budget's limits
MAX_ENTRY = 2 ** 30


def read(path: Path, key: str, kind: str):
    """The value of the entry at ``path`` (:func:`unpack`). Raises ``FileNotFoundError`` if there
    is none, ``PermissionError`` if it cannot be read, :class:`InvalidEntry` if it is not valid.
    An entry is read only if it is a regular file (a FIFO or a device is never opened for a
    blocking read) of at most :data:`MAX_ENTRY` bytes (a huge file is refused by its size, unread)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except IsADirectoryError:
        raise InvalidEntry("a folder, not a file") from None
    with open(fd, "rb") as fh:
        st = os.fstat(fh.fileno())
        if not stat.S_ISREG(st.st_mode):
            raise InvalidEntry("not a regular file")
        if st.st_size > MAX_ENTRY:
            raise InvalidEntry(f"{st.st_size} bytes, more than an entry holds ({MAX_ENTRY})")
        buf = bytearray(st.st_size)
        if fh.readinto(buf) != len(buf):
            raise InvalidEntry("shorter than its size")
    return unpack(buf, key, kind)


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
    """Where the run of ``key`` is stored.

    Parameters
    ----------
    key, root : str, pathlib.Path or None
        The run's key; the cache folder (None: :data:`magexp.paths.CACHE`).
    """
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


def load(key: str, root: Path | None = None):
    """The stored run of ``key`` (a :class:`magexp.estimators.result.RunOutput`), or None: absent, or not a
    valid entry of ``key`` (a miss noted for :func:`say_notes`; the entry is left in place, the
    recomputed run replaces it), or not readable by this user (noted, never replaced).

    Parameters
    ----------
    key, root : str, pathlib.Path or None
    """
    root = CACHE if root is None else Path(root)
    try:
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


def exists(key: str, root: Path | None = None) -> bool:
    """Whether a run of ``key`` is stored (its file's first bytes are those of an entry; the
    content is checked when it is read).

    Parameters
    ----------
    key, root : str, pathlib.Path or None
    """
    try:  # not blocking: a FIFO planted in the cache would hold a plain open forever; only a regular file is an entry
        with os.fdopen(os.open(entry_path(key, root), os.O_RDONLY | os.O_NONBLOCK), "rb") as fh:
            return stat.S_ISREG(os.fstat(fh.fileno()).st_mode) and fh.read(len(MAGIC)) == MAGIC
    except OSError:
        return False


def store(key: str, value, root: Path | None = None) -> bool:
    """Store the run ``value`` under ``key`` atomically; whether it was kept. A cache that cannot be
    written, or an entry of another user this user cannot read (left in place), keeps nothing (noted).

    Parameters
    ----------
    key, value, root : str, RunOutput, pathlib.Path or None
    """
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
    while holding only claims of smaller keys (so no two wait for each other).

    Parameters
    ----------
    key, root, wait : str, pathlib.Path or None, bool
    """
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
