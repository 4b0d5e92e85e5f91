"""Calibration problems: a parameter vector <-> a calibration, and a vectorised cost (the protocol:
:class:`magexp.problems.base.Problem`). Problems are made with :func:`make_problem` from a dataset and
an objective name (:data:`OBJECTIVES`).
"""

from __future__ import annotations

import importlib

from magexp.errors import MagexpError

OBJECTIVES: dict[str, str] = {
    "scalar": "magexp.problems.scalar:ScalarCalibration",
    "vector": "magexp.problems.vector:VectorCalibration",  # Yuan 2018 eq 8
    "vector_ls": "magexp.problems.vector:VectorLeastSquares",  # eq 8's residuals in least squares
    "ship": "magexp.problems.ship:ShipMagnetization",  # Yan & Zhou 2022 B = K A Be + Bp
    "gyro": "magexp.problems.gyro:GyroAidedCalibration",  # eq 8 with unknown field direction and gyro bias
}


def register(name: str, target: str) -> None:
    """Register an objective ``name`` implemented by ``"module:Class"``."""
    OBJECTIVES[name] = target


def problem_class(objective: str):
    """The class implementing ``objective`` (imported, not built): its ``capabilities`` say which
    estimators apply before any data is simulated.
    """
    if objective not in OBJECTIVES:
        raise MagexpError(f"objective={objective!r} is not allowed: choose one of {', '.join(sorted(OBJECTIVES))}")
    module, cls = OBJECTIVES[objective].split(":")
    return getattr(importlib.import_module(module), cls)


def make_problem(objective: str, dataset, search, **options):
    """Build the problem ``objective`` on ``dataset`` within ``search`` (a SearchBox)."""
    return problem_class(objective)(dataset, search, **options)
