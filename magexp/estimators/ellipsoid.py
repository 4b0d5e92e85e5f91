"""Closed-form algebraic ellipsoid fits as estimators (the classical baseline Ding 2024 did not run).

The fits themselves live in :mod:`magexp.core.ellipsoid` (:func:`~magexp.core.ellipsoid.fit_ellipsoid`,
Gander, Golub & Strebel 1994; :func:`~magexp.core.ellipsoid.fit_ellipsoid_specific`, Li & Griffiths
2004); :class:`EllipsoidFit` and :class:`EllipsoidSpecificFit` return their calibration in a problem's
parameters.
"""

from __future__ import annotations

import numpy as np

from magexp.core.ellipsoid import fit_ellipsoid, fit_ellipsoid_specific
from magexp.errors import check, check_nonnegative
from magexp.estimators.result import FitResult


class EllipsoidFit:
    """Algebraic ellipsoid fit (``ellipsoid``); returns the calibration in the problem's parameters.

    The readings lie on ``(r - o)^T W^T W (r - o) = B_a^2``: the quadric ``u^T A u + 2 b^T u + d = 0``
    of the centred readings is fitted in algebraic least squares and ``W`` is its symmetric root
    (:mod:`magexp.core.ellipsoid`), ``B_a`` the dataset's mean reference total field. If the fit is not
    an ellipsoid (too few or degenerate readings) the result has ``success=False`` and ``x`` at the
    centre of the search box.

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator` (``ellipsoid``).

    References
    ----------
    Gander, Golub & Strebel (1994), Least-squares fitting of circles and ellipses, BIT 34:558-578.
    """

    references = "Gander, Golub & Strebel 1994"
    label = "ellipsoid fit"
    smoke: dict = {}
    needs = ("total_field",)  # a scalar reference cannot fix the rotation of W
    iterative = False

    def __init__(self, *, name: str = "ellipsoid"):
        self.name = name

    def quadric(self, readings: np.ndarray, radius: float):
        """The calibration of the quadric fitted to ``readings`` (:func:`~magexp.core.ellipsoid.fit_ellipsoid`).

        Parameters
        ----------
        readings : numpy.ndarray, shape (N, 3)
            The raw readings.
        radius : float
            The field magnitude the calibrated readings should have.

        Returns
        -------
        tuple of numpy.ndarray or None
            ``(W, o)``, or None when the quadric is not an ellipsoid.
        """
        return fit_ellipsoid(readings, radius)

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        """Fit the quadric to the readings and return its calibration in the problem's parameters.

        Parameters
        ----------
        problem, rng, callback
            As :meth:`magexp.estimators.base.Estimator.fit`: its readings and reference field
            (``total_field``); a closed form draws nothing and does not iterate.

        Returns
        -------
        FitResult
            ``success=False`` and the box centre when the fit is not an ellipsoid.
        """
        ds = problem.dataset
        fitted = self.quadric(ds.readings, float(np.mean(ds.reference_norm)))
        if fitted is None:
            x, ok, msg = (problem.lower + problem.upper) / 2, False, "the algebraic fit is not an ellipsoid"
        else:
            x, ok, msg = problem.pack(*fitted), True, "closed form"
        fun = problem.cost_direct(x)
        return FitResult(x=x, fun=fun, nit=1, nfev=1, history=np.array([fun]), history_nfev=np.array([1]),
                         success=ok, message=msg)


class EllipsoidSpecificFit(EllipsoidFit):
    """Ellipsoid-specific least squares (``ellipsoid_specific``; Li & Griffiths 2004, as in Magneto):
    :func:`fit_ellipsoid_specific`, then the calibration of :class:`EllipsoidFit`.

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator`.
    k : float
        The constraint's ``k`` (4: Li & Griffiths' choice), > 0.

    References
    ----------
    Li & Griffiths (2004), Least squares ellipsoid specific fitting, GMP 2004, 335-340.
    """

    references = "Li & Griffiths 2004, Least squares ellipsoid specific fitting, GMP 2004, 335-340"
    label = ""

    def __init__(self, *, name: str = "ellipsoid_specific", k: float = 4.0):
        super().__init__(name=name)
        self.k = check_nonnegative(k, "estimator.k")
        check(self.k > 0, f"estimator.k={k!r} is not allowed: it must be a number > 0 (J > 0 for every ellipsoid, "
                          "so k J - I^2 = 1 has no solution with k <= 0)")

    def quadric(self, readings: np.ndarray, radius: float):
        """The calibration of the ellipsoid fitted to ``readings`` (:func:`~magexp.core.ellipsoid.fit_ellipsoid_specific`).

        Parameters
        ----------
        readings, radius
            As :meth:`EllipsoidFit.quadric`.

        Returns
        -------
        tuple of numpy.ndarray or None
            ``(W, o)``, or None when no ellipsoid fits.
        """
        return fit_ellipsoid_specific(readings, radius, self.k)
