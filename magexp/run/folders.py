"""Where a command may write: its output folder, the run cache, each sweep job's folder, and what a
failed command leaves behind.

* :func:`check_destination`: an output folder a command may write into. Never an empty path
  (it would mean the working folder), never a filesystem root, and never inside ``results/``
  (:data:`magexp.paths.RESULTS`, compared as resolved paths, so ``results/x``, ``./results``
  and a symbolic link into it are all inside) unless the command is a canonical reproduction
  writing ``results/`` itself; :func:`check_output_folder` adds that it is (or can be made) a
  writable folder, :func:`check_cache_folder` applies it to the run cache;
* :func:`check_subdir`, :func:`check_job_folders`: each sweep job's folder is its own, inside the sweep's folder;
* :func:`create_unique`: a new folder of its own, never one that exists;
* :func:`removed_on_failure`: what a command created is removed again when it fails
  (a refused or interrupted command leaves nothing behind; :func:`first_missing` names what it made).

Every refusal is a :class:`~magexp.errors.MagexpError` of one line that names the folder and what
is allowed.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import os
import shutil
import tempfile
from pathlib import Path, PurePosixPath

from magexp import paths
from magexp.errors import MagexpError


def _results() -> Path:
    """The canonical ``results/`` folder, resolved (what no other folder may lie inside)."""
    return paths.RESULTS.resolve()


def check_destination(folder, what: str, *, canonical: bool = False) -> Path:
    """The resolved output folder ``folder``, or one line (naming it by ``what``: ``--out``, ``hydra.run.dir``...)
    saying why a command may not write there; ``canonical``: a canonical reproduction, which may write
    ``results/`` itself (but no folder inside it: the canonical layout is ``results/<paper>/``)."""
    text = "" if folder is None else str(folder)
    if not text.strip():
        raise MagexpError(f"{what}={text!r} is not allowed: name a folder (an empty path would write into the "
                          "working folder)")
    path = Path(text).expanduser().resolve()
    if path == Path(path.anchor):
        raise MagexpError(f"{what}={text!r} is not allowed: it is the root folder {path.anchor!r}; name a folder "
                          "of its own")
    results = _results()
    if path == results and canonical:
        return path
    if path == results or results in path.parents:
        raise MagexpError(f"{what}={text!r} is not allowed: it is inside results/ ({results}), which only a "
                          "canonical reproduction writes; name a folder outside it")
    return path


@functools.lru_cache(maxsize=16)
def check_cache_folder(root: str) -> None:
    """A run cache (``$MAGEXP_CACHE``) or a cache beside it (the figures'), never inside ``results/``
    (:func:`check_destination`), checked before any command starts and before every cache write."""
    check_destination(root, "MAGEXP_CACHE (the run cache folder)")


def check_subdir(subdir: str, what: str = "hydra.sweep.subdir") -> None:
    """A sweep job's folder name: relative, not empty, and with no ``..``, so that every job's
    folder is a folder of its own inside the sweep's folder."""
    text = str(subdir)
    parts = PurePosixPath(text.replace("\\", "/")).parts
    if not text.strip() or text.startswith(("/", "~")) or ".." in parts or all(p == "." for p in parts):
        raise MagexpError(f"{what}={text!r} is not allowed: it must be a relative folder name without '..' "
                          "(each job's folder inside the sweep's folder), e.g. ${{hydra.job.num}}")


def check_job_folders(folders: list[Path], sweep_dir: Path) -> None:
    """Each job's folder (``hydra.sweep.subdir`` resolved for it, whose overrides may hold a ``/``)
    strictly inside the sweep's folder, and no two jobs sharing one (the second would overwrite
    the first's files)."""
    outer = Path(sweep_dir).resolve()
    seen: dict = {}
    for n, folder in enumerate(folders):
        inner = Path(folder).resolve()
        if outer not in inner.parents:
            raise MagexpError(f"hydra.sweep.subdir={str(folder.relative_to(sweep_dir))!r} is not allowed: job {n}'s "
                              f"folder must be inside the sweep's folder {str(outer)!r}")
        if inner in seen:
            raise MagexpError(f"hydra.sweep.subdir={str(folder.relative_to(sweep_dir))!r} is not allowed: jobs "
                              f"{seen[inner]} and {n} would share a folder; include ${{hydra.job.num}}")
        seen[inner] = n


@contextlib.contextmanager
def removed_on_failure(folder: Path, created: Path | None = None):
    """Undo what the block creates in ``folder`` if it fails (an exception, a non-zero exit, Ctrl-C).

    A folder that did not exist (or ``created``, the highest folder the caller made for it) is
    removed with every parent made for it; in a folder that existed, only the entries the block
    added are removed (what the user had is kept)."""
    folder = Path(folder).absolute()
    top = created if created is not None else first_missing(folder)
    before = set() if top is not None or not folder.is_dir() else {p.name for p in folder.iterdir()}
    try:
        yield
    except SystemExit as exc:
        if exc.code not in (0, None):
            _undo(folder, top, before)
        raise
    except BaseException:
        _undo(folder, top, before)
        raise


def _undo(folder: Path, top: Path | None, before: set) -> None:
    """Remove ``top`` (a folder made for the failed command), else the entries of ``folder`` not in ``before``."""
    if top is not None:
        shutil.rmtree(top, ignore_errors=True)
    elif folder.is_dir():
        for entry in folder.iterdir():
            if entry.name not in before:
                if entry.is_dir() and not entry.is_symlink():
                    shutil.rmtree(entry, ignore_errors=True)
                else:
                    entry.unlink(missing_ok=True)


def check_output_folder(folder: Path | str, what: str = "output folder", *, canonical: bool = False) -> Path:
    """Fail unless ``folder`` is (or can be created as) a writable directory a command may write
    (:func:`magexp.run.folders.check_destination`: not empty, not a root, not inside ``results/`` unless
    ``canonical``); create nothing."""
    check_destination(folder, what, canonical=canonical)
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise MagexpError(f"{what} {str(folder)!r} is a file, not a folder: name a folder")
    probe = folder
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise MagexpError(f"{what} {str(folder)!r} cannot be created: {str(probe)!r} is a file")
    try:  # a real probe (permissions alone say nothing for root or a read-only mount)
        fd, tmp = tempfile.mkstemp(dir=probe, prefix=".magexp-probe-")
        os.close(fd)
        os.unlink(tmp)
    except OSError as exc:
        raise MagexpError(f"{what} {str(folder)!r} is not writable: {str(probe)!r}: {exc.strerror}") from None
    return folder


def first_missing(folder: Path) -> Path | None:
    """The highest of ``folder`` and its parents that does not exist yet (None if ``folder`` exists):
    removing it after a failure leaves no trace of the folders made for it."""
    if folder.exists():
        return None
    top = folder
    while not top.parent.exists():
        top = top.parent
    return top


def create_unique(folder: Path | str) -> tuple[Path, Path]:
    """Create ``folder`` exclusively; if it exists, ``folder-2``, ``folder-3``...: two runs started
    in the same second never share a folder. Returns ``(folder, top)``, ``top`` the highest
    folder this call created (remove it to leave no trace)."""
    folder = Path(folder)
    top = first_missing(folder)
    folder.parent.mkdir(parents=True, exist_ok=True)
    for k in itertools.count(1):
        candidate = folder if k == 1 else folder.with_name(f"{folder.name}-{k}")
        try:
            candidate.mkdir()
            return candidate, (top if top != folder else candidate)
        except FileExistsError:
            continue
