"""Closed-form algebraic ellipsoid fit (the classical baseline Ding 2024 did not run).

The readings ``r`` of a sensor with a linear error lie on the ellipsoid
``(r - o)^T W^T W (r - o) = B_a^2``. With the readings centred and scaled
(``u = (r - c)/s``), the quadric ``u^T A u + 2 b^T u + d = 0`` is the
null vector of the design matrix ``[u², v², w², 2uv, 2uw, 2vw, 2u, 2v, 2w, 1]``
(smallest right singular vector). Then the centre is ``u_0 = -A^{-1} b``,
``Q = A / (u_0^T A u_0 - d)`` and the calibration is the symmetric square root
``W = B_a Q^{1/2} / s``, ``o = c + s u_0``. A scalar reference cannot fix the
rotation of ``W``; the symmetric root is the conventional choice.

References: Gander, Golub & Strebel (1994), *Least-squares fitting of circles and ellipses*;
Vasconcelos et al. (2011), *Geometric approach to strapdown magnetometer calibration*.
"""

from __future__ import annotations

import numpy as np

from magexp.estimators.result import FitResult
from magexp.problems.scalar import normalise, quadratic_features

LINEAR_TWICE = np.array([1, 1, 1, 1, 1, 1, 2, 2, 2, 1.0])  # the quadric u^T A u + 2 b^T u + d


def fit_ellipsoid(readings: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray] | None:
    """``(W, o)`` mapping ``readings`` onto the sphere of ``radius``; None if not an ellipsoid."""
    c, s, u = normalise(readings)
    design = quadratic_features(u) * LINEAR_TWICE  # [u², v², w², 2uv, 2uw, 2vw, 2u, 2v, 2w, 1]
    p = np.linalg.svd(design, full_matrices=False)[2][-1]
    a = np.array([[p[0], p[3], p[4]], [p[3], p[1], p[5]], [p[4], p[5], p[2]]])
    try:
        u0 = -np.linalg.solve(a, p[6:9])
    except np.linalg.LinAlgError:
        return None
    q = a / (u0 @ a @ u0 - p[9])
    eigval, eigvec = np.linalg.eigh(q)
    if not np.all(eigval > 0):
        return None
    w = radius * (eigvec * np.sqrt(eigval)) @ eigvec.T / s
    return w, c + s * u0


class EllipsoidFit:
    """Algebraic ellipsoid fit; returns the calibration in the problem's parameters.

    The radius is the mean reference total field of the dataset. If the fit is
    not an ellipsoid (too few or degenerate readings) the result has
    ``success=False`` and ``x`` at the centre of the search box.
    """

    references = "Gander, Golub & Strebel 1994"
    needs = ("total_field",)  # a scalar reference cannot fix the rotation of W
    iterative = False

    def __init__(self, *, name: str = "ellipsoid"):
        self.name = name

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        ds = problem.dataset
        fitted = fit_ellipsoid(ds.readings, float(np.mean(ds.reference_norm)))
        if fitted is None:
            x, ok, msg = (problem.lower + problem.upper) / 2, False, "the algebraic fit is not an ellipsoid"
        else:
            x, ok, msg = problem.pack(*fitted), True, "closed form"
        fun = problem.cost_direct(x)
        return FitResult(x=x, fun=fun, nit=1, nfev=1, history=np.array([fun]), history_nfev=np.array([1]),
                         success=ok, message=msg)
