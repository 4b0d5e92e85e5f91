"""The report built once per content of the folder it is built from.

:func:`magexp.artifacts.report.build` reads an output folder (the papers' CSVs and summaries, which figures
exist, the peers' bench) and writes the report into it (``summary.csv``, ``claims.csv``, ``REPORT.md``,
``APPENDIX.md``, the readings figures, the LaTeX twins of its tables): deterministic work. Its outputs are
the files a build replaces (each is written atomically: a new file); its inputs every other file of the
folder, but :data:`OUTSIDE`. So the report's memo (:class:`magexp.artifacts.memo.Memo`,
``<run cache>-reports``) keeps, under the key of the folder and of what builds it
(:func:`magexp.artifacts.artifact_memo.code_version`: magexp's source, ``conf/``, ``experiments/``, the
drawing libraries and settings), the digests of its outputs and the digest of its inputs. A build is skipped
when both still hold; an edited, added or deleted file of the folder, or an output edited or deleted by hand,
builds it again. ``versions.csv`` records the commit and the libraries, not the folder: it is rewritten
whenever that record changes.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import pandas as pd

from magexp.artifacts.artifact_memo import code_version
from magexp.artifacts.memo import Memo, beside_cache
from magexp.artifacts.report import build, versions
from magexp.core.atomic import atomic_path

#: the files of an output folder that are neither read nor written by a build: the wall time of the last
#: reproduction, written after it, and the versions (:func:`write_versions`)
OUTSIDE = ("timing.csv", "versions.csv")

#: the reports' outputs and inputs, per output folder
REPORTS = Memo("BuiltReport", lambda: beside_cache("reports"))


def _files(root: Path) -> dict[str, os.stat_result]:
    """Every file under ``root`` (by name relative to it) with its status, but :data:`OUTSIDE` and the
    temporary files of an atomic write."""
    found = {}
    for folder, _, names in os.walk(root):
        for name in names:
            path = os.path.join(folder, name)
            rel = os.path.relpath(path, root)
            if rel not in OUTSIDE and not (name.startswith(".") and name.endswith(".tmp")):
                found[rel] = os.stat(path)
    return found


def inputs_digest(root: Path, outputs) -> str:
    """The digest of the names and contents of the files of ``root`` a build reads: all but ``outputs``
    and :data:`OUTSIDE`."""
    h = hashlib.sha256()
    for rel in sorted(set(_files(root)) - set(outputs)):
        h.update(rel.encode() + b"\0")
        h.update(hashlib.sha256((root / rel).read_bytes()).digest())
    return h.hexdigest()


def key(root: Path) -> str:
    """The key of the report of the folder ``root`` built by this code."""
    return hashlib.sha256(f"{code_version()} {Path(root).resolve()}".encode()).hexdigest()[:32]


def write_versions(root: Path) -> None:
    """``root/versions.csv`` as :func:`magexp.artifacts.report.build` writes it, where its content changed."""
    text = pd.DataFrame([{"package": k, "version": v} for k, v in versions().items()]).to_csv(index=False)
    path = root / "versions.csv"
    if not path.is_file() or path.read_text() != text:
        with atomic_path(path) as tmp:
            tmp.write_text(text)


def built(root: Path, *, force: bool = False) -> bool:
    """Build the report of ``root`` (:func:`magexp.artifacts.report.build`) unless its inputs and outputs are
    those of the last build (``force``: build it all the same); whether it built."""
    root = Path(root)
    k = key(root)
    kept = None if force else REPORTS.recall(k, root)
    if kept is not None and kept.get("value") == inputs_digest(root, kept["files"]):
        write_versions(root)
        return False
    before = {rel: (st.st_ino, st.st_mtime_ns, st.st_size) for rel, st in _files(root).items()}
    build(root)
    after = {rel: (st.st_ino, st.st_mtime_ns, st.st_size) for rel, st in _files(root).items()}
    outputs = sorted(rel for rel, stamp in after.items() if before.get(rel) != stamp)  # each written anew
    REPORTS.record(k, root, [root / rel for rel in outputs], inputs_digest(root, outputs))
    return True
