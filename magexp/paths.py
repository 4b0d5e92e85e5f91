"""The one place that knows where things live."""

from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CONF = ROOT / "conf"
EXPERIMENTS = ROOT / "experiments"
RESULTS = ROOT / "results"
CACHE = Path(os.environ.get("MAGEXP_CACHE", ROOT / ".cache" / "runs"))  # finished runs, keyed by config
DATA = ROOT / "data"
# recorded data of others (never copied into the project): $MAGEXP_DATA, else ../shared/data beside
# the checkout (or beside its parent folder, for a git worktree)
SHARED_DATA = Path(os.environ["MAGEXP_DATA"]) if os.environ.get("MAGEXP_DATA") else next(
    (p for p in (ROOT.parent / "shared" / "data", ROOT.parent.parent / "shared" / "data") if p.is_dir()),
    ROOT.parent / "shared" / "data")


def paper_results(paper: str) -> Path:
    """``results/<paper>/``, created on demand."""
    path = RESULTS / paper
    path.mkdir(parents=True, exist_ok=True)
    return path
