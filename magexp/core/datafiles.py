"""The data files a run reads: every existing file that a string value of its config names.

A file is looked up where recordings are: as given, relative to ``data/``
(:func:`magexp.core.recordings.resolve`) and to the shared data folder
(:class:`magexp.scenarios.recording.RecordingScenario`); each of these that exists counts. Its content,
not its name, enters the run's cache key and the reuse of built scenarios, so an edited recording
reruns exactly the runs that read it. The format named beside it (:func:`data_formats`) tells the
run cache which reader's code the run executes.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

from magexp.paths import DATA, SHARED_DATA


def _strings(node, format=None):
    """``(text, format)`` of every string value of a config tree: ``format`` is the ``format`` value of
    the mapping holding it (through lists), None if it has none."""
    if isinstance(node, dict):
        format = node.get("format") if isinstance(node.get("format"), str) else None
        for value in node.values():
            yield from _strings(value, format)
    elif isinstance(node, (list, tuple)):
        for value in node:
            yield from _strings(value, format)
    elif isinstance(node, str):
        yield node, format


def _as_files(text: str) -> list[Path]:
    """``text`` as existing files: as given, relative to ``data/`` and to the shared data folder."""
    if not text or len(text) > 4096 or "\n" in text:
        return []
    found = []
    for path in (Path(text), DATA / text, SHARED_DATA / text):
        try:
            if path.is_file() and path.resolve() not in found:
                found.append(path.resolve())
        except OSError:
            pass
    return found


@lru_cache(maxsize=4096)
def _file_digest(path: Path, mtime_ns: int, size: int) -> str:
    h = hashlib.sha256()
    with path.open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def data_formats(resolved: dict) -> dict[Path, str | None]:
    """``{path: format}`` of every existing file that a string value of the config names: the
    ``format`` value beside that string (``scenario.format``, ``data.format``), None if there is none."""
    found = {}
    for text, format in _strings(resolved):
        for path in _as_files(text):
            found.setdefault(path, format)
    return found


def data_files(resolved: dict) -> dict[str, str]:
    """``{path: sha256}`` of every existing file that a string value of the config names."""
    out = {}
    for path in data_formats(resolved):
        stat = path.stat()
        out[str(path)] = _file_digest(path, stat.st_mtime_ns, stat.st_size)
    return out
