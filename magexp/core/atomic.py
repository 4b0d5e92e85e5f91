"""Every output file written atomically: a temporary file in the same folder, then ``os.replace``.

A command killed (or failing) midway leaves each output either as it was before or complete,
never truncated: the new content is written to a hidden temporary file beside the target
(``.<name>.<random>.tmp``, the same file system, so the rename is atomic) and renamed onto
the target only once it is complete; an error removes the temporary file. The file gets the
permissions an ordinary ``open(path, "w")`` would give (``0666`` less the umask), not the
``0600`` of :func:`tempfile.mkstemp`.

    from magexp.core.atomic import atomic_path, write_text

    write_text(folder / "config.yaml", text)
    with atomic_path(folder / "figure.png") as tmp:   # for writers that take a path
        fig.savefig(tmp, format="png")
    with atomic_open(folder / "table.csv", newline="") as fh:
        csv.writer(fh).writerows(rows)
"""

from __future__ import annotations

import os
import signal
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache
from pathlib import Path


@cache
def _mode() -> int:
    """``0666`` less the process's umask (read once: setting it is the only way to read it)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


#: the signals that stop a command (Ctrl-C, ``kill``): held back while a temporary file is made or removed
_STOPS = {signal.SIGINT, signal.SIGTERM}


@contextmanager
def _stops_held() -> Iterator[None]:
    """:data:`_STOPS` held back in this thread, delivered when the block ends: a temporary file is
    created and named, or removed, whole (a stop between ``mkstemp`` and the ``try`` that removes it,
    or inside that removal, left a ``.tmp`` file behind; seen once in ``make test``)."""
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _STOPS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


@contextmanager
def atomic_path(path: Path | str, *, mode: int | None = None) -> Iterator[Path]:
    """A temporary path beside ``path``: renamed onto ``path`` when the block ends, removed if it raises
    (a stop signal included: :func:`_stops_held`). ``mode``: the file's permissions (default: ``0666``
    less the umask).
    """
    path = Path(path)
    tmp = None
    try:
        with _stops_held():  # a stop delivered as it ends finds ``tmp`` named, inside the ``try``
            fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
            os.close(fd)
        yield Path(tmp)
        os.chmod(tmp, _mode() if mode is None else mode)
        os.replace(tmp, path)
    finally:
        with _stops_held():
            if tmp is not None and os.path.exists(tmp):
                os.unlink(tmp)


@contextmanager
def atomic_open(path: Path | str, mode: str = "w", **kwargs) -> Iterator:
    """``open(path, mode)`` onto a temporary file that replaces ``path`` once closed without error."""
    with atomic_path(path) as tmp, open(tmp, mode, **kwargs) as fh:
        yield fh


def write_text(path: Path | str, text: str, encoding: str = "utf-8") -> Path:
    """``Path.write_text``, atomically; returns ``path``."""
    with atomic_open(path, "w", encoding=encoding) as fh:
        fh.write(text)
    return Path(path)


def write_bytes(path: Path | str, data: bytes, *, mode: int | None = None) -> Path:
    """``Path.write_bytes``, atomically (``mode``: as :func:`atomic_path`); returns ``path``."""
    with atomic_path(path, mode=mode) as tmp:
        Path(tmp).write_bytes(data)
    return Path(path)
