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
SHARED_DATA = ROOT.parent / "shared" / "data"


def paper_results(paper: str) -> Path:
    """``results/<paper>/``, created on demand."""
    path = RESULTS / paper
    path.mkdir(parents=True, exist_ok=True)
    return path
