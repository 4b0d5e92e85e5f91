"""The run cache's entry format: data that executes nothing when read, each entry proving what it holds.

An entry (:func:`pack`) is a line with a SHA-256 digest, a JSON header (its key, its kind, the tree of its
values) and the raw bytes of its numpy arrays. Reading one (:func:`read`, :func:`unpack`) parses JSON and
views bytes as numbers of a plain dtype, and checks that it is stored under the key asked for, of the kind
asked for, with the digest it carries; anything else raises :class:`InvalidEntry` naming what does not
hold. The digest proves integrity, not authorship: a cache folder is trusted as far as who may write into
it. Where entries live and how runs are kept in them: :mod:`magexp.run.cache`.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import stat
from pathlib import Path


#: first bytes of every entry (the format's version is part of it)
MAGIC = b"magexp-entry/1"
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
    (:func:`unpack`). Nothing in it is code: reading it parses JSON and views bytes as numbers."""
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


def unpack(buf: bytearray, key: str, kind: str, fields: tuple[str, ...] | None = None):
    """The value of an entry read into ``buf`` (writable: its arrays are views of it), after checking
    that it is an entry of ``kind`` under ``key`` whose content has the digest it carries.
    Raises :class:`InvalidEntry` naming what does not hold. With ``fields`` (of a value that is a dict),
    only those fields' arrays are made (:func:`_selected`): the rest is left as parsed."""
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
    if fields is not None:
        return _selected(buf, meta, bytes(view[_FIRST + m:start]), start, fields)
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


def _selected(buf: bytearray, meta: dict, doc: bytes, start: int, fields: tuple[str, ...]) -> dict:
    """The value (a dict) of an entry whose JSON ``doc`` is parsed, with the arrays of ``fields`` made and
    checked as :func:`unpack` makes them all: reading a run's row skips the arrays it does not show."""
    try:
        value, table = json.loads(doc), meta["arrays"]
    except (ValueError, KeyError):
        raise InvalidEntry("value is not JSON") from None
    if type(value) is not dict or not all(name in value for name in fields) or not isinstance(table, list):
        raise InvalidEntry("does not hold the fields asked for")
    made: dict[int, object] = {}

    def resolve(node):  # JSON gives lists, dicts and scalars: only a list or dict holds an array
        if type(node) is list:
            return [resolve(item) if type(item) in (list, dict) else item for item in node]
        if type(node) is not dict:
            return node
        if _ARRAY not in node:
            return {name: resolve(item) if type(item) in (list, dict) else item for name, item in node.items()}
        index = node[_ARRAY]
        if len(node) != 1 or type(index) is not int or not 0 <= index < len(table):
            raise InvalidEntry("an array reference is malformed")
        if index not in made:
            try:
                made[index] = _arrays(buf, table[index:index + 1], start)[0]
            except (TypeError, ValueError):
                raise InvalidEntry("its array table is malformed") from None
        return made[index]

    return {**value, **{name: resolve(value[name]) for name in fields}}


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


def read(path: Path, key: str, kind: str, fields: tuple[str, ...] | None = None):
    """The value of the entry at ``path`` (:func:`unpack`, of ``fields`` only where given). Raises ``FileNotFoundError`` if there
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
    return unpack(buf, key, kind, fields)
