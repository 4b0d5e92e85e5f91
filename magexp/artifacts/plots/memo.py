"""Figures drawn once per content: a figure is drawn again only when what it is drawn from changes.

Drawing a figure (:func:`magexp.artifacts.plots.style.save`: a PNG and its PDF twin, each laid out and drawn
twice by matplotlib) is most of the CPU a reproduction spends outside its fits once the runs are
cached. The drawing is deterministic: the same CSV, artifact spec, code and libraries give the same
bytes. So a figure is keyed by

* the bytes of the CSV it is drawn from,
* its artifact spec (``repr`` of the validated :class:`magexp.artifacts.spec.Artifact`),
* magexp's source (every ``magexp/**/*.py``: a plot, style or spec edit redraws every figure),
* the versions of matplotlib, numpy and pandas, and matplotlib's settings (``rcParams``),

(:func:`figure_code_version` is not the run cache's :func:`magexp.run.cache.code_version`: a run is
keyed by the code it executes only, so that a plot edit keeps every run; a figure by all of magexp's
source (:func:`magexp.artifacts.memo.source_digest`) and the drawing libraries, since the artifact,
summary, style and plot code all shape it)

and the cache (a :class:`magexp.artifacts.memo.Memo`) keeps, under that key, the SHA-256 digests of the
PNG and PDF the draw wrote. A figure whose two files are still in place with those digests is not drawn
again; otherwise it is drawn and its digests recorded. Any change (a new CSV, a deleted or edited figure,
a code edit) draws it. ``--force`` draws every figure. The cache lives beside the run cache
(``<run cache>-figures``), never in ``results/``.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

import matplotlib
import numpy
import pandas

from magexp.artifacts.memo import Memo, beside_cache, source_digest
from magexp.artifacts.plots.style import plt


def root() -> Path:
    """The figure cache: beside the run cache (:data:`magexp.paths.CACHE`), never inside it."""
    return beside_cache("figures")


#: the drawn figures' digests (its folder is :func:`root`, looked up on each use)
FIGURES = Memo("Figure", lambda: root())


@lru_cache(maxsize=1)
def figure_code_version() -> str:
    """Hash of all of magexp's source and of the drawing libraries' versions (module docstring)."""
    h = hashlib.sha256(source_digest().encode())
    h.update(f"{matplotlib.__version__} {numpy.__version__} {pandas.__version__}".encode())
    return h.hexdigest()


def drawing_version() -> str:
    """:func:`figure_code_version` with matplotlib's settings as they are now: all a drawing depends on but
    its CSV and spec."""
    h = hashlib.sha256(figure_code_version().encode())
    h.update(repr(sorted(plt.rcParams.items())).encode())  # the settings the draw uses: magexp's style on the user's
    return h.hexdigest()


def key(spec, csv_bytes: bytes) -> str:
    """The key of the figure of ``spec`` drawn from a CSV holding ``csv_bytes`` (module docstring),
    with matplotlib's settings as they are now (a user's ``matplotlibrc`` draws otherwise).
    """
    h = hashlib.sha256(drawing_version().encode())
    h.update(repr(spec).encode())
    h.update(hashlib.sha256(csv_bytes).digest())
    return h.hexdigest()[:32]


def current(k: str, files: list[Path]) -> bool:
    """Whether ``files`` (a figure's PNG and PDF, in one folder) are what the draw of key ``k`` wrote."""
    kept = FIGURES.recall(k, Path(files[0]).parent)
    return kept is not None and sorted(kept["files"]) == sorted(Path(f).name for f in files)


def record(k: str, files: list[Path]) -> None:
    """Keep the digests of the ``files`` just drawn under key ``k`` (where the cache cannot be written, nothing
    is kept and the figure is drawn again next time)."""
    FIGURES.record(k, Path(files[0]).parent, list(files))
