"""How the bench times (:mod:`magexp.perf.bench`): variants side by side, reported as median and IQR rows."""

from __future__ import annotations

import time

import numpy as np

def row(measure: str, estimator: str, values, unit: str) -> dict:
    """One long-format row: the median of ``values`` and their interquartile range."""
    values = np.asarray(values, float)
    if values.size == 0 or not np.any(np.isfinite(values)):
        return {"measure": measure, "estimator": estimator, "value": np.nan, "unit": unit, "lo": np.nan, "hi": np.nan}
    lo, med, hi = np.nanpercentile(values, [25, 50, 75])
    return {"measure": measure, "estimator": estimator, "value": med, "unit": unit, "lo": lo, "hi": hi}


def side_by_side(variants: dict, rounds: int, target: float = 0.05, clock=time.perf_counter) -> dict:
    """Seconds per call of every variant, alternating variants within each round.

    Each variant is called in batches of about ``target`` seconds (sized by a first call); the
    result maps each name to its ``rounds`` batch means, by ``clock`` (wall clock by default;
    ``time.process_time``: this process's CPU time, which leaves out waiting for a core on a
    shared machine).
    """
    number = {}
    for name, fn in variants.items():
        fn()
        start = time.perf_counter()
        fn()
        number[name] = max(1, int(target / max(time.perf_counter() - start, 1e-7)))
    times = {name: [] for name in variants}
    for _ in range(rounds):
        for name, fn in variants.items():
            start = clock()
            for _ in range(number[name]):
                fn()
            times[name].append((clock() - start) / number[name])
    return {name: np.asarray(t) for name, t in times.items()}

