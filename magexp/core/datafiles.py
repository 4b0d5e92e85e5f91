"""The data files a run reads: every existing file that a string value of its config names.

A file is looked up where recordings are: as given, relative to ``data/``
(:func:`magexp.core.recordings.resolve`) and to the shared data folder
(:class:`magexp.scenarios.recording.RecordingScenario`); each of these that exists counts, and a
two-stream recording or a ROS 2 bag folder, named by its stem, its folder or one of its files, is all
its files. Its content,
not its name, enters the run's cache key and the reuse of built scenarios, so an edited recording
reruns exactly the runs that read it. The format named beside it (:func:`data_formats`) tells the
run cache which reader's code the run executes.
"""

from __future__ import annotations

import hashlib
import os
import stat
from functools import lru_cache
from pathlib import Path

from magexp.paths import DATA, SHARED_DATA

#: the endings of the two files of a two-stream recording, which is named by their common stem or by
#: either file (:mod:`magexp.core.readers.two_stream`)
TWO_STREAM = ("_mag.csv", "_imu.csv")
#: the file that makes a folder a ROS 2 bag (:mod:`magexp.core.readers.rosbag`)
BAG_MARKER = "metadata.yaml"


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


def _names(path: str) -> list[str]:
    """The files that ``path`` names: itself if a file; both files of a two-stream recording
    (:data:`TWO_STREAM`) if it is its stem or one of them; every file of a ROS 2 bag (:data:`BAG_MARKER`)
    if it is its folder or one of its files (the bag is read whole); none if nothing of these exists."""
    stem = next((path[: -len(tail)] for tail in TWO_STREAM if path.endswith(tail)), None)
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        mode = 0
    folder = path if stat.S_ISDIR(mode) else os.path.dirname(path) if stat.S_ISREG(mode) else None
    if folder is not None and os.path.isfile(os.path.join(folder, BAG_MARKER)):
        return sorted(os.path.join(folder, name) for name in os.listdir(folder))
    if stem is None and (stat.S_ISREG(mode) or not os.path.isfile(path + TWO_STREAM[0])):
        return [path] if stat.S_ISREG(mode) else []
    return [(path if stem is None else stem) + tail for tail in TWO_STREAM]


def _as_files(text: str) -> list[Path]:
    """``text`` as existing files (:func:`_names`): as given, relative to ``data/`` and to the shared
    data folder."""
    if not text or len(text) > 4096 or "\n" in text:
        return []
    found = []
    for path in dict.fromkeys((text, os.path.join(DATA, text), os.path.join(SHARED_DATA, text))):  # absolute: one
        for name in _names(path):
            if os.path.isfile(name) and (file := Path(name).resolve()) not in found:
                found.append(file)
    return found


@lru_cache(maxsize=4096)
def _file_digest(path: Path, mtime_ns: int, size: int) -> str:
    """The sha256 of ``path``, cached on its ``mtime_ns`` and ``size`` so an unchanged file is read once per process."""
    h = hashlib.sha256()
    with path.open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def data_formats(resolved: dict) -> dict[Path, str | None]:
    """``{path: format}`` of every existing file a string of the ``resolved`` config names, with the ``format``
    value beside that string (``scenario.format``, ``data.format``; None if none): which reader the run executes.
    """
    found = {}
    for text, format in dict.fromkeys(_strings(resolved)):
        for path in _as_files(text):
            found.setdefault(path, format)
    return found


def data_files(resolved: dict, formats: dict | None = None) -> dict[str, str]:
    """``{path: sha256}`` of those files (``formats``: their :func:`data_formats`, found here if None): the
    content part of a run's cache key.
    """
    out = {}
    for path in data_formats(resolved) if formats is None else formats:
        st = path.stat()
        out[str(path)] = _file_digest(path, st.st_mtime_ns, st.st_size)
    return out
