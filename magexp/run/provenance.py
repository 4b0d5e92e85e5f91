"""Provenance of an output: which magexp, commit, Python, libraries and settings produced it.

:func:`provenance` is the one source of these fields for every writer (a run's ``metrics.csv``
and ``config.yaml``, a sweep's table, ``calibration.json``, ``summary.csv``)::

    magexp_version, magexp_commit, python, numpy, scipy, hydra, omegaconf, config_hash

``config_hash`` is the SHA-256 (first 16 hex digits) of the resolved config as canonical JSON
(sorted keys), so two outputs with the same hash were made with the same settings; the full
config is written beside the output (``config.yaml``).
"""

from __future__ import annotations

import functools
import importlib.util
import hashlib
import json
import platform
import subprocess
import sys
from pathlib import Path

from magexp._version import __version__
from magexp.paths import PACKAGE, ROOT, SOURCE_CHECKOUT

LIBRARIES = ("numpy", "scipy", "hydra", "omegaconf")
COMMIT_FILE = PACKAGE / "_resources" / "commit.txt"  # written into a wheel at build time


def version() -> str:
    """magexp's version (:data:`magexp._version.__version__`, its one home; ``pyproject.toml`` reads it)."""
    return __version__


def _git_dir(root) -> "Path | None":
    """The git folder of the checkout at ``root`` (a worktree's ``gitdir:``), or None."""
    git = root / ".git"
    if git.is_file():  # a worktree: "gitdir: <path>"
        text = git.read_text().strip()
        return Path(text.partition("gitdir:")[2].strip()) if text.startswith("gitdir:") else None
    return git if git.is_dir() else None


def _read_head(git_dir) -> str | None:
    """The commit HEAD points at, read from the repository's files (no git process)."""
    head = (git_dir / "HEAD").read_text().strip()
    if not head.startswith("ref:"):
        return head or None
    ref = head.partition("ref:")[2].strip()
    common = git_dir
    if (git_dir / "commondir").exists():
        common = (git_dir / (git_dir / "commondir").read_text().strip()).resolve()
    for folder in (git_dir, common):
        if (folder / ref).exists():
            return (folder / ref).read_text().strip()
    packed = common / "packed-refs"
    if packed.exists():
        for line in packed.read_text().splitlines():
            sha, _, name = line.partition(" ")
            if name == ref:
                return sha
    return None


@functools.cache
def commit() -> str:
    """The git commit of the code (12 hex digits), or ``unknown``.

    A source checkout reads it from ``.git`` (no git process: this runs on every run); an
    installed wheel reads the commit recorded when it was built (``_resources/commit.txt``)."""
    if SOURCE_CHECKOUT:
        try:
            git_dir = _git_dir(ROOT)
            sha = _read_head(git_dir) if git_dir else None
            if sha:
                return sha[:12]
        except OSError:
            pass
    try:
        return COMMIT_FILE.read_text().strip() or "unknown"
    except OSError:
        return "unknown"


def working_tree_state() -> str:
    """``clean`` or ``modified`` (uncommitted changes in the checkout), ``n/a`` for an installed wheel."""
    if not SOURCE_CHECKOUT:
        return "n/a"
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
                             capture_output=True, text=True, timeout=20)
    except (OSError, subprocess.SubprocessError):
        return "n/a"
    return "n/a" if out.returncode else ("modified" if out.stdout.strip() else "clean")


def config_hash(config: dict | None) -> str:
    """SHA-256 (16 hex digits) of a resolved config as canonical JSON; empty for no config."""
    if config is None:
        return ""
    text = json.dumps(config, sort_keys=True, default=str, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _library_version(name: str) -> str:
    """``name``'s version without importing it if it is not loaded yet: its ``__version__``, else the
    ``<name>-<version>.dist-info`` folder beside it (``importlib.metadata`` costs 0.1 s to import)."""
    if name in sys.modules:
        return str(getattr(sys.modules[name], "__version__", ""))
    spec = importlib.util.find_spec(name)
    if spec is None or not spec.origin:
        return ""
    site = Path(spec.origin).parent.parent
    dist = "hydra_core" if name == "hydra" else name
    found = sorted(site.glob(f"{dist}-*.dist-info"))
    return found[-1].name[len(dist) + 1:-len(".dist-info")] if found else ""


@functools.cache
def _libraries() -> dict:
    """Versions of the libraries a run's numbers depend on."""
    return {name: _library_version(name) for name in LIBRARIES}


def provenance(config: dict | None = None) -> dict:
    """The provenance fields of an output made with the resolved ``config`` (flat, str values)."""
    return {"magexp_version": version(), "magexp_commit": commit(), "python": platform.python_version(),
            **_libraries(), "config_hash": config_hash(config)}


def version_line() -> str:
    """``magexp <version> (commit <sha>[, with uncommitted changes])`` for ``magexp --version``."""
    state = working_tree_state()
    return f"magexp {version()} (commit {commit()}{', with uncommitted changes' if state == 'modified' else ''})"
