"""Estimators: hyper-parameters only, built from ``conf/estimator/*.yaml`` by ``_target_``.

Every estimator follows :class:`magexp.estimators.base.Estimator`: ``name``, ``needs`` (the problem
capabilities it needs), ``iterative`` and ``fit(problem, *, rng, callback=None) -> FitResult``;
:func:`magexp.estimators.base.applies_to` says whether it applies to a problem.
"""

from magexp.estimators.result import FitResult

__all__ = ["FitResult"]
