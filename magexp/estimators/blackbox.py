"""What the black-box estimators (:mod:`~magexp.estimators.cmaes`, :mod:`~magexp.estimators.de`)
share: a counted, recorded view of the problem's vectorised cost, and the seed they derive from
the run's generator."""

from __future__ import annotations

import numpy as np

from magexp.errors import check
from magexp.estimators.result import FitResult


def child_seed(rng: np.random.Generator) -> int:
    """A seed in ``[1, 2**31 - 1)`` for a library that takes an integer, drawn from the run's generator."""
    return int(rng.integers(1, 2**31 - 1))


class RecordedCost:
    """``problem.cost`` on whole populations (one call a generation), counting evaluations and recording the
    best so far as the swarms' ``history`` and ``history_nfev``; non-finite costs become ``inf``."""

    def __init__(self, problem):
        self.problem = problem
        check(bool(np.all(np.isfinite(problem.lower)) and np.all(np.isfinite(problem.upper))),
              "the black-box estimators need a finite search box: problem.lower/upper are not finite")
        self.nfev = 0
        self.best_x: np.ndarray | None = None
        self.best_f = np.inf
        self.history: list[float] = []
        self.history_nfev: list[int] = []

    def __call__(self, thetas: np.ndarray) -> np.ndarray:
        """Evaluate one population."""
        f = np.asarray(self.problem.cost(thetas), float)
        f = np.where(np.isfinite(f), f, np.inf)
        k = int(np.argmin(f))
        if f[k] < self.best_f or self.best_x is None:
            self.best_f, self.best_x = float(f[k]), np.array(thetas[k], float)
        self.nfev += len(f)
        self.history.append(self.best_f)
        self.history_nfev.append(self.nfev)
        return f

    def result(self, message: str) -> FitResult:
        """The best point seen."""
        return FitResult(x=self.best_x, fun=self.best_f, nit=len(self.history) - 1, nfev=self.nfev,
                         history=np.asarray(self.history), history_nfev=np.asarray(self.history_nfev),
                         message=message)
