"""The one place that knows where things live."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CONF = ROOT / "conf"
EXPERIMENTS = ROOT / "experiments"
RESULTS = ROOT / "results"
CACHE = ROOT / ".cache" / "runs"
DATA = ROOT / "data"
SHARED_DATA = ROOT.parent / "shared" / "data"


def paper_results(paper: str) -> Path:
    """``results/<paper>/``, created on demand."""
    path = RESULTS / paper
    path.mkdir(parents=True, exist_ok=True)
    return path
