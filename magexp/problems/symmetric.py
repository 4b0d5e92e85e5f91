"""The symmetric 9-parameter form of a 12-parameter calibration: ``q = [M11, M12, M13, M22, M23, M33, o]``.

A matrix part ``M`` that is symmetric (``M = M^T``) has 6 unique entries; with the offset ``o`` the
calibration is 9 numbers. :func:`expand` maps them back to the problems' 12-vector ``[vec(M), o]``
(row-major). A scalar (total-field) fit identifies ``W^T W`` only, whose unique symmetric root is
such an ``M``: the gauge of Yuan 2018's traditional PSO (:mod:`magexp.estimators.reduced`), of
Levenberg-Marquardt's default (:mod:`magexp.estimators.lm`) and of ``magexp calibrate``.
"""

from __future__ import annotations

import numpy as np

UPPER = np.array([0, 1, 2, 4, 5, 8])  # row-major positions of M11 M12 M13 M22 M23 M33
MIRROR = np.array([0, 1, 2, 1, 3, 4, 2, 4, 5])  # the 9 row-major entries from the 6 unique ones


def expand(q: np.ndarray) -> np.ndarray:
    """12-vectors ``[vec(M), o]`` with ``M`` symmetric from 9-vectors ``q``."""
    q = np.atleast_2d(q)
    return np.concatenate([q[:, MIRROR], q[:, 6:]], axis=1)
