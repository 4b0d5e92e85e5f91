"""Run results stored under a key derived from the fully resolved config and the code.

A result is written atomically (temporary file + ``os.replace``), so an
interrupted sweep never leaves a half-written result; an unreadable file is
treated as missing and the run is done again.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import tempfile
from functools import lru_cache
from pathlib import Path

from magexp.paths import CACHE, ROOT


@lru_cache(maxsize=1)
def code_version() -> str:
    """Hash of every source file of the package: a code change invalidates the cache."""
    h = hashlib.sha256()
    for path in sorted((ROOT / "magexp").rglob("*.py")):
        h.update(path.relative_to(ROOT).as_posix().encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def run_key(resolved: dict) -> str:
    """Key of a run: its resolved config and the code version."""
    text = json.dumps(resolved, sort_keys=True, default=str) + code_version()
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _path(key: str, root: Path) -> Path:
    return root / key[:2] / f"{key}.pkl"


def load(key: str, root: Path = CACHE):
    """The stored result of ``key``, or None if absent or unreadable."""
    path = _path(key, root)
    try:
        with path.open("rb") as fh:
            return pickle.load(fh)
    except FileNotFoundError:
        return None
    except Exception:  # a partial or corrupt file: drop it and run again
        path.unlink(missing_ok=True)
        return None


def store(key: str, value, root: Path = CACHE) -> None:
    """Write ``value`` under ``key`` atomically."""
    path = _path(key, root)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            pickle.dump(value, fh, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
