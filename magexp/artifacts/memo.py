"""Outputs memoised by their inputs: work that writes files is done again only when what it reads changed.

A reproduction whose runs are all cached still writes every artifact (its CSVs and figure), then builds
the report from them: deterministic work, the same inputs giving the same bytes. A :class:`Memo` keeps,
under the key of a piece of work's inputs (a digest its caller computes: the figure's in
:mod:`magexp.artifacts.plots.memo`, an artifact's in :mod:`magexp.artifacts.artifact_memo`, the report's in
:mod:`magexp.artifacts.report_memo`), the SHA-256 digest of each file the work wrote (named relative to the
folder it wrote into) and, optionally, a value it returned. The work is skipped when its key is known and
every one of those files is still in place with its digest; a changed input (another key), a file edited or
deleted by hand, or a damaged entry does the work again. ``--force`` does every piece of work and records it.

An entry is a run cache entry (:func:`magexp.run.entries.pack`: JSON and its digest, never code), written
atomically beside the run cache (``<run cache>-<name>``), never in ``results/``; where the cache cannot be
written, nothing is kept and the work is done each time. A memo is bounded: once per process, at its first
record, the least recently used entries (an entry read is touched) are removed beyond :data:`MAX_ENTRIES`
entries or :data:`MAX_BYTES` bytes.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path

from magexp import paths
from magexp.run.cache import write
from magexp.run.entries import InvalidEntry, pack, read
from magexp.run.runkeys import files_digest

#: the most entries, and bytes, one memo keeps (:meth:`Memo.prune`)
MAX_ENTRIES, MAX_BYTES = 20_000, 256 * 2**20
#: file name suffix of a memo's entry
SUFFIX = ".memo"


@lru_cache(maxsize=1)
def source_digest() -> str:
    """The SHA-256 of magexp's own source (each ``.py`` of the package, its path and content), once per process:
    what the plan cache (:func:`magexp.artifacts.plan_cache.inputs_digest`) and the figure memo
    (:func:`magexp.artifacts.plots.memo.figure_code_version`) key on beside their own inputs."""
    return files_digest(sorted(paths.PACKAGE.rglob("*.py")), paths.PACKAGE).hexdigest()


def digests(files: list[Path]) -> list[str] | None:
    """SHA-256 of each file (None if one is missing)."""
    try:
        return [hashlib.sha256(Path(f).read_bytes()).hexdigest() for f in files]
    except (FileNotFoundError, IsADirectoryError, NotADirectoryError):
        return None


def beside_cache(name: str) -> Path:
    """The folder ``<run cache>-<name>``: beside the run cache (:data:`magexp.paths.CACHE`), never inside it."""
    return paths.CACHE.parent / f"{paths.CACHE.name}-{name}"


class Memo:
    """The files a piece of work wrote, and the value it returned, kept under the key of its inputs.

    Parameters
    ----------
    kind : str
        The kind of its entries (:func:`magexp.run.entries.pack`): an entry of another kind is a miss.
    root : callable
        Returns the folder of its entries (called on each use, so that a test may move it).
    """

    _pruned: set = set()  # the folders pruned by this process

    def __init__(self, kind: str, root: Callable[[], Path]):
        self.kind, self.root = kind, root

    def entry(self, key: str) -> Path:
        """Where the entry of ``key`` is kept."""
        return self.root() / key[:2] / f"{key}{SUFFIX}"

    def recall(self, key: str, base: Path):
        """The entry of ``key`` (``{"files": {name: digest}, "value": ...}``) if every file it names, under the
        folder ``base``, still has its digest; else None."""
        path = self.entry(key)
        try:
            kept = read(path, key, self.kind)
        except (OSError, InvalidEntry):
            return None
        if not isinstance(kept, dict) or not isinstance(kept.get("files"), dict) or not kept["files"]:
            return None
        names = sorted(kept["files"])
        if digests([Path(base) / name for name in names]) != [kept["files"][name] for name in names]:
            return None
        try:
            os.utime(path)  # used: the last to be pruned
        except OSError:
            pass
        return kept

    def record(self, key: str, base: Path, files: list[Path], value=None) -> bool:
        """Keep the digests of ``files`` (just written, under the folder ``base``) and ``value`` (numbers,
        strings, lists, dicts) under ``key``; whether it was kept (not where a file is missing or the cache
        cannot be written)."""
        found = digests(files)
        if not files or found is None:
            return False
        names = [os.path.relpath(f, base) for f in files]
        try:
            entry = pack(key, self.kind, {"files": dict(zip(names, found)), "value": value})
            write(self.entry(key), entry, self.root())
        except (OSError, TypeError):  # a read-only cache, or a value JSON cannot hold
            return False
        self.prune()
        return True

    def prune(self) -> None:
        """Remove the least recently used entries beyond :data:`MAX_ENTRIES` or :data:`MAX_BYTES` (once per
        process and folder)."""
        root = self.root()
        if root in Memo._pruned:
            return
        Memo._pruned.add(root)
        entries = []
        for path in root.glob(f"*/*{SUFFIX}"):
            try:
                st = path.stat()
            except OSError:
                continue
            entries.append((st.st_mtime_ns, st.st_size, path))
        entries.sort(reverse=True)
        count = total = 0
        for _, size, path in entries:
            count, total = count + 1, total + size
            if count > MAX_ENTRIES or total > MAX_BYTES:
                path.unlink(missing_ok=True)

