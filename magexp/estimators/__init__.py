"""Estimators: hyper-parameters only, built from ``conf/estimator/*.yaml`` by ``_target_``.

Every estimator has ``name`` and ``fit(problem, *, rng, callback=None) -> FitResult``.
"""

from magexp.estimators.result import FitResult

__all__ = ["FitResult"]
