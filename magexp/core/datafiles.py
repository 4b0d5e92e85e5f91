"""The data files a run reads: every existing file that a string value of its config names.

A file is looked up as recordings are (:func:`magexp.core.recordings.resolve`): as given, else relative to
``data/``. Its content, not its name, enters the run's cache key and the reuse of built scenarios,
so an edited recording reruns exactly the runs that read it.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

from magexp.paths import DATA


def _strings(node):
    if isinstance(node, dict):
        for value in node.values():
            yield from _strings(value)
    elif isinstance(node, (list, tuple)):
        for value in node:
            yield from _strings(value)
    elif isinstance(node, str):
        yield node


def _as_file(text: str) -> Path | None:
    """``text`` as an existing file (as given, or relative to ``data/``, as recordings are found)."""
    if not text or len(text) > 4096 or "\n" in text:
        return None
    for path in (Path(text), DATA / text):
        try:
            if path.is_file():
                return path.resolve()
        except OSError:
            pass
    return None


@lru_cache(maxsize=4096)
def _file_digest(path: Path, mtime_ns: int, size: int) -> str:
    h = hashlib.sha256()
    with path.open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def data_files(resolved: dict) -> dict[str, str]:
    """``{path: sha256}`` of every existing file that a string value of the config names."""
    out = {}
    for text in _strings(resolved):
        path = _as_file(text)
        if path is not None:
            stat = path.stat()
            out[str(path)] = _file_digest(path, stat.st_mtime_ns, stat.st_size)
    return out

