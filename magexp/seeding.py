"""Every random draw of a run derives from its seed."""

from __future__ import annotations

import numpy as np

from magexp.errors import MagexpError


def run_generators(seed) -> tuple[np.random.Generator, np.random.Generator]:
    """Independent generators for the data and for the estimator of run ``seed``.

    The data stream depends on the seed only, so every estimator of a seed sees
    the same readings (common random numbers: paired comparisons).
    """
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise MagexpError(f"seed={seed!r} is not allowed: it must be an integer >= 0")
    data, est = np.random.SeedSequence(seed).spawn(2)
    return np.random.default_rng(data), np.random.default_rng(est)
