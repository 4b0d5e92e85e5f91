"""The one result type every estimator returns."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class FitResult:
    """Outcome of ``estimator.fit`` (after ``scipy.optimize.OptimizeResult``).

    Attributes
    ----------
    x : best parameter vector.
    fun : objective at ``x``.
    nit : iterations (swarm iterations, filter steps, or least-squares evaluations).
    nfev : objective evaluations (one particle = one evaluation).
    history : best objective after each iteration, ``history[0]`` before the first.
    history_nfev : evaluations spent when each ``history`` entry was recorded.
    trace : optional per-iteration arrays (e.g. a filter's state at every step).
    metrics : optional estimator-specific scalar outcomes, added to the run's metrics.
    success, message : as in scipy.
    """

    x: np.ndarray
    fun: float
    nit: int
    nfev: int
    history: np.ndarray
    history_nfev: np.ndarray
    success: bool = True
    message: str = ""
    trace: dict = field(default_factory=dict)
    metrics: dict = field(default_factory=dict)
