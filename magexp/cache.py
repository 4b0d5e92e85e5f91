"""Run results stored under a key derived from everything a run reads.

The key of a run (:func:`run_key`) hashes

* its fully resolved config (every setting, the seed included),
* the content of every data file the config names (:func:`magexp.datafiles.data_files`), so that editing a
  recording such as ``data/yan2022_mockup.csv`` reruns exactly the runs that read it,
* the source of the code *upstream* of a run (:func:`code_version`): the static import closure of
  :mod:`magexp.runner` and of the packages a config instantiates (scenarios, problems, estimators).
  Code downstream of a run (``plots/``, ``summary``, ``report``, ``reproduce``, the executor) is
  not part of it, so a figure or report edit costs no run.

A result is written atomically (temporary file + ``os.replace``), so an interrupted sweep never
leaves a half-written result; an unreadable file is treated as missing and the run is done again.
"""

from __future__ import annotations

import ast
import hashlib
import json
import os
import pickle
import tempfile
from functools import lru_cache
from pathlib import Path

from magexp.datafiles import data_files
from magexp.paths import CACHE, ROOT

#: where the import closure starts: the run itself and the packages its configs instantiate by name
UPSTREAM_ROOTS = ("magexp/runner.py", "magexp/scenarios", "magexp/problems", "magexp/estimators")


def _module_file(name: str) -> Path | None:
    """The source file of module ``magexp.a.b`` (a module or a package), or None."""
    parts = name.split(".")
    if parts[0] != "magexp":
        return None
    base = ROOT.joinpath(*parts)
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


def _package_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path: Path) -> set[str]:
    """Every ``magexp`` module that ``path`` imports anywhere (function bodies included)."""
    own = _package_name(path)
    package = own if path.name == "__init__.py" else own.rpartition(".")[0]
    names = set()
    for node in ast.walk(ast.parse(path.read_bytes(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            names.add(module)
            names.update(f"{module}.{a.name}" for a in node.names)  # `from pkg import submodule`
    return {n for n in names if n == "magexp" or n.startswith("magexp.")}


def upstream_files() -> list[Path]:
    """The source files a run executes: the import closure of :data:`UPSTREAM_ROOTS`, with the
    ``__init__.py`` of every package on the way. The top-level ``magexp/__init__.py`` is included
    but its own imports are not followed (they serve the API, not a run)."""
    todo = []
    for root in UPSTREAM_ROOTS:
        path = ROOT / root
        todo.extend(sorted(path.rglob("*.py")) if path.is_dir() else [path])
    seen: set[Path] = set()
    top = ROOT / "magexp" / "__init__.py"
    while todo:
        path = todo.pop()
        if path in seen:
            continue
        seen.add(path)
        for parent in path.relative_to(ROOT).parents:  # packages on the way are executed too
            init = ROOT / parent / "__init__.py"
            if parent.parts and init.is_file() and init not in seen:
                todo.append(init)
        if path == top:
            continue
        for name in _imports(path):
            found = _module_file(name)
            if found is not None and found not in seen:
                todo.append(found)
    return sorted(seen)


def files_digest(files, base: Path):
    """A SHA-256 object fed with the path (relative to ``base``) and content of each of ``files``."""
    h = hashlib.sha256()
    for path in files:
        h.update(path.relative_to(base).as_posix().encode())
        h.update(path.read_bytes())
    return h


def _closure_hash() -> str:
    """Hash of the path and content of every file of :func:`upstream_files`."""
    return files_digest(upstream_files(), ROOT).hexdigest()[:16]


def _source_stamp() -> str:
    """A digest of where the package's sources are and of every ``.py`` file's path, size,
    modification time and inode: any edit, checkout or copy changes it (cheap: stats, no reads)."""
    h = hashlib.sha256(str(ROOT).encode())
    for path in sorted((ROOT / "magexp").rglob("*.py")):
        st = path.stat()
        h.update(f"{path.relative_to(ROOT).as_posix()}\0{st.st_size}\0{st.st_mtime_ns}\0{st.st_ino}\n".encode())
    return h.hexdigest()[:32]


@lru_cache(maxsize=1)
def code_version() -> str:
    """Hash of the code upstream of a run (:func:`upstream_files`): only such a change invalidates runs.

    Finding the import closure parses every module (about 0.1 s); the result is kept in the run
    cache folder (``code-version.json``, beside the results' two-letter folders) under the sources'
    :func:`_source_stamp`, so a later command with unchanged sources reads it instead (a changed
    stamp only recomputes it: never a stale version)."""
    memo = CACHE / "code-version.json"
    stamp = _source_stamp()
    try:
        known = json.loads(memo.read_text())
        if not isinstance(known, dict):
            known = {}
    except (OSError, ValueError):
        known = {}
    if isinstance(known.get(stamp), str):
        return known[stamp]
    version = _closure_hash()
    known = {**dict(list(known.items())[-7:]), stamp: version}  # the last few source trees
    try:
        memo.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=memo.parent, suffix=".tmp")
        with os.fdopen(fd, "w") as fh:
            json.dump(known, fh)
        os.replace(tmp, memo)
    except OSError:  # a read-only cache folder: compute it each time
        pass
    return version


def run_key(resolved: dict, files: dict[str, str] | None = None) -> str:
    """Key of a run: its resolved config, the content of the data files it names (``files``:
    its :func:`data_files`, found here if None), the upstream code."""
    text = json.dumps(resolved, sort_keys=True, default=str)
    files = data_files(resolved) if files is None else files
    if files:
        text += json.dumps(sorted(files.values()))
    text += code_version()
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def run_keys(configs) -> list[str]:
    """:func:`run_key` of each config; the data files are looked up once per config that differs
    in more than its seed."""
    files: dict[str, dict] = {}
    keys = []
    for cfg in configs:
        rest = json.dumps({k: v for k, v in cfg.items() if k != "seed"}, sort_keys=True, default=str)
        if rest not in files:
            files[rest] = data_files(cfg)
        keys.append(run_key(cfg, files[rest]))
    return keys


def _path(key: str, root: Path) -> Path:
    return root / key[:2] / f"{key}.pkl"


def load(key: str, root: Path | None = None):
    """The stored result of ``key``, or None if absent or unreadable."""
    path = _path(key, CACHE if root is None else root)
    try:
        with path.open("rb") as fh:
            return pickle.load(fh)
    except FileNotFoundError:
        return None
    except Exception:  # a partial or corrupt file: drop it and run again
        path.unlink(missing_ok=True)
        return None


def exists(key: str, root: Path | None = None) -> bool:
    """Whether a result of ``key`` is stored (without reading it)."""
    return _path(key, CACHE if root is None else root).is_file()


def store(key: str, value, root: Path | None = None) -> None:
    """Write ``value`` under ``key`` atomically."""
    path = _path(key, CACHE if root is None else root)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            pickle.dump(value, fh, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
