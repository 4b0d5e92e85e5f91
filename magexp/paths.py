"""The one place that knows where things live.

In a source checkout (or an editable install) the configs, experiment specs and shipped data
are the repository's top-level ``conf/``, ``experiments/`` and ``data/``. A wheel carries the
same folders as package data under ``magexp/_resources/`` (see ``pyproject.toml``); a
non-editable install finds them there, and writes results and its run cache relative to the
working folder / the user's cache folder instead of into site-packages.
"""

from __future__ import annotations

import os
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
ROOT = PACKAGE.parent
SOURCE_CHECKOUT = (ROOT / "conf").is_dir() and (ROOT / "experiments").is_dir()
RESOURCES = ROOT if SOURCE_CHECKOUT else PACKAGE / "_resources"

CONF = RESOURCES / "conf"
EXPERIMENTS = RESOURCES / "experiments"
DATA = RESOURCES / "data"
RESULTS = ROOT / "results" if SOURCE_CHECKOUT else Path.cwd() / "results"
_default_cache = (ROOT / ".cache" / "runs" if SOURCE_CHECKOUT
                  else Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "magexp" / "runs")
CACHE = Path(os.environ.get("MAGEXP_CACHE") or _default_cache)  # finished runs, keyed by config (empty: unset)
# recorded data of others (never copied into the project): $MAGEXP_DATA, else ../shared/data beside
# the checkout (or beside its parent folder, for a git worktree)
SHARED_DATA = Path(os.environ["MAGEXP_DATA"]) if os.environ.get("MAGEXP_DATA") else next(
    (p for p in (ROOT.parent / "shared" / "data", ROOT.parent.parent / "shared" / "data") if p.is_dir()),
    ROOT.parent / "shared" / "data")
