"""The search box of the 12-parameter calibration problems."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from magexp.errors import LARGEST, MagexpError


def _interval(value, name: str) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise MagexpError(f"search.{name}={value!r} is not allowed: it must be [low, high]") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise MagexpError(f"search.{name}={value!r} is not allowed: it must be finite with low < high")
    if max(abs(lo), abs(hi)) > LARGEST:
        raise MagexpError(f"search.{name}={value!r} is not allowed: bounds must be of magnitude <= {LARGEST:g}")
    return lo, hi


@dataclass(frozen=True)
class SearchBox:
    """Bounds for ``[vec(matrix) (row-major, 9), offset (3)]``.

    Parameters
    ----------
    diag, offdiag : [low, high] for the diagonal / off-diagonal matrix entries.
    offset : [low, high] for the three offset entries (reading units).
    """

    diag: tuple[float, float]
    offdiag: tuple[float, float]
    offset: tuple[float, float]

    @classmethod
    def from_config(cls, cfg) -> "SearchBox":
        if cfg is None:
            raise MagexpError("search=None is not allowed: the scenario must give search.diag, .offdiag, .offset")
        missing = [k for k in ("diag", "offdiag", "offset") if k not in cfg]
        if missing:
            raise MagexpError(f"search is missing {', '.join(missing)}: give [low, high] for diag, offdiag and offset")
        return cls(*(_interval(cfg[k], k) for k in ("diag", "offdiag", "offset")))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bound vectors of length 12."""
        eye = np.eye(3, dtype=bool).ravel()
        lo = np.where(eye, self.diag[0], self.offdiag[0])
        hi = np.where(eye, self.diag[1], self.offdiag[1])
        return (np.concatenate([lo, np.full(3, self.offset[0])]), np.concatenate([hi, np.full(3, self.offset[1])]))
