"""Nine-parameter scalar calibrations: triangular least squares (Merayo et al. 2000) and the
noise-weighted maximum-likelihood calibration (Vasconcelos et al. 2011).

A scalar reference identifies only ``W^T W`` and ``o`` (9 numbers): ``Q W`` fits as well as ``W``
for every rotation ``Q``. A 12-parameter search wanders along that valley; a triangular ``W`` with
a positive diagonal is a unique factor of ``W^T W`` (Cholesky), so the valley is gone.

**Merayo's model** (the Ørsted magnetometer): the sensor axes are unit vectors ``e_1 = (1, 0, 0)``,
``e_2 = (\\sin u_1, \\cos u_1, 0)``, ``e_3 = (\\sin u_2, \\sin u_3\\cos u_2, \\cos u_3\\cos u_2)`` of an
orthogonal frame (rows of ``T``), with gains ``S = diag(s_i)`` and offsets ``O``:

.. math:: \\mathbf E = S\\,T\\,\\mathbf B + \\mathbf O,\\qquad
          \\mathbf B = W(\\mathbf E - \\mathbf O),\\quad W = T^{-1}S^{-1}

``T`` is lower triangular, so ``W`` is: 6 entries plus 3 offsets, the 9 parameters (3 gains,
3 angles, 3 offsets) of Merayo's calibration.
"""

from __future__ import annotations

import numpy as np

from magexp.core.ellipsoid import fit_ellipsoid
from magexp.errors import check
from magexp.estimators.lm import LevenbergMarquardt, minimise_residuals
from magexp.estimators.result import FitResult

FORMS = {"lower": np.tril_indices(3), "upper": np.triu_indices(3)}


def triangular_factor(gram: np.ndarray, form: str = "lower") -> np.ndarray:
    """The triangular ``W`` with a positive diagonal and ``W^T W = gram``.

    ``upper``: ``W = L^T`` of the Cholesky factor ``gram = L L^T``; ``lower``: the same on the
    axes in reverse order (``P`` the reversal), ``W = P (chol(P gram P))^T P``.
    """
    if form == "upper":
        return np.linalg.cholesky(gram).T
    p = np.eye(3)[::-1]
    return p @ np.linalg.cholesky(p @ gram @ p).T @ p


def merayo_matrix(gains, angles) -> np.ndarray:
    """``S T`` of Merayo's model: rows ``s_i e_i`` (module docstring)."""
    u1, u2, u3 = angles
    t = np.array([[1.0, 0.0, 0.0], [np.sin(u1), np.cos(u1), 0.0],
                  [np.sin(u2), np.sin(u3) * np.cos(u2), np.cos(u3) * np.cos(u2)]])
    return np.diag(gains) @ t


def merayo_parameters(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merayo's parameters of a calibration."""
    m = np.linalg.inv(w)
    gains = np.linalg.norm(m, axis=1)  # every row of T is a unit vector
    t = m / gains[:, None]
    u1 = np.arcsin(t[1, 0])
    u2 = np.arcsin(t[2, 0])
    u3 = np.arctan2(t[2, 1], t[2, 2])
    return gains, np.array([u1, u2, u3])


class TriangularCalibration:
    """Scalar calibration with a triangular ``W`` (``triangular``; Merayo et al. 2000, module docstring).

    Levenberg-Marquardt from the ellipsoid fit (whose ``W^T W`` gives the start by Cholesky) on

    .. math:: \\sum_k \\big(\\lVert W(\\mathbf r_k - \\mathbf o)\\rVert - B_{a,k}\\big)^2

    over the 6 entries of the triangle of ``W`` and ``o``.

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator`.
    form : str
        ``lower`` (Merayo's: the first sensor axis is the reference, the second in the plane of
        the first two) or ``upper`` (the same with the axes in reverse order).
    max_nfev, tol
        As in :class:`~magexp.estimators.lm.LevenbergMarquardt` (the refinement's).

    References
    ----------
    Merayo, Brauer, Primdahl et al. (2000), Scalar calibration of vector magnetometers, Meas. Sci.
    Technol. 11:120-132.
    """

    references = "Merayo et al. 2000, Meas. Sci. Technol. 11:120-132"
    label = ""
    smoke = {"max_nfev": 50}
    needs = ("total_field",)
    iterative = True
    weighted = False

    def __init__(self, *, name: str = "triangular", form: str = "lower", max_nfev: int = 2000, tol: float = 1e-15):
        check(form in FORMS, f"estimator.form={form!r} is not allowed: choose one of {', '.join(FORMS)}")
        self.name, self.form = name, form
        self.refine = LevenbergMarquardt(max_nfev=max_nfev, tol=tol)  # its settings (checked there)

    def unpack(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The calibration of 9 parameters.

        Parameters
        ----------
        q : numpy.ndarray, shape (9,)
            ``[triangle of W (row-major), o]``.

        Returns
        -------
        tuple of numpy.ndarray
            ``(W, o)``.
        """
        w = np.zeros((3, 3))
        w[FORMS[self.form]] = q[:6]
        return w, q[6:]

    def start(self, problem) -> np.ndarray:
        """The start: the ellipsoid fit's ``W^T W`` and ``o`` as 9 parameters (else the box centre's).

        Parameters
        ----------
        problem : magexp.problems.base.Problem
            Its readings and reference magnitudes, else its box.

        Returns
        -------
        numpy.ndarray, shape (9,)
            ``[triangle of W, o]`` (:meth:`unpack`).
        """
        ds = problem.dataset
        fitted = fit_ellipsoid(ds.readings, float(np.mean(ds.reference_norm)))
        w, o = fitted if fitted is not None else (a[0] for a in problem.unpack((problem.lower + problem.upper) / 2))
        return np.concatenate([triangular_factor(w.T @ w, self.form)[FORMS[self.form]], o])

    def residuals_of(self, problem):
        """The residual function of the 9 parameters (the class docstring's; weighted for the ML variant).

        Parameters
        ----------
        problem : magexp.problems.base.Problem
            Its readings and reference magnitudes.

        Returns
        -------
        callable
            ``residuals(q) -> (N,)``.
        """
        readings, reference = problem.dataset.readings, np.asarray(problem.dataset.reference_norm)

        def residuals(q):
            w, o = self.unpack(q)
            u = (readings - o) @ w.T
            norm = np.linalg.norm(u, axis=1)
            e = norm - reference
            if not self.weighted:
                return e
            spread = np.linalg.norm(u @ w, axis=1) / np.maximum(norm, 1e-300)  # ||W^T u|| / ||u|| = sigma_k / sigma
            return e / np.maximum(spread, 1e-300)

        return residuals

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        """Levenberg-Marquardt on the 9 parameters from :meth:`start`.

        Parameters
        ----------
        problem, rng, callback
            As in :meth:`magexp.estimators.base.Estimator.fit`. ``problem``: a total-field problem. ``rng``:
            unused (the fit draws nothing). ``callback``: ``callback(k, x, fun)`` after each residual
            evaluation.

        Returns
        -------
        FitResult
            ``history`` the best value of the problem's objective after each evaluation.
        """
        def to_x(q):
            return problem.pack(*self.unpack(q))

        relay = None if callback is None else (lambda k, q, fun: callback(k, to_x(q), fun))
        measure = (lambda q: problem.cost_direct(to_x(q))) if self.weighted else None
        q, status, message, history = minimise_residuals(self.residuals_of(problem), self.start(problem),
                                                         tol=self.refine.tol, max_nfev=self.refine.max_nfev,
                                                         callback=relay,
                                                         measure=measure)
        x = to_x(q)
        # history: the best value of the problem's objective after each evaluation (for ``ml_scalar``
        # not what it minimises, so its final x need not be the history's best)
        return FitResult(x=x, fun=problem.cost_direct(x), nit=len(history), nfev=len(history), history=history,
                         history_nfev=np.arange(1, len(history) + 1), success=status > 0, message=message)


class MaximumLikelihoodScalar(TriangularCalibration):
    """Noise-weighted maximum-likelihood scalar calibration (``ml_scalar``; Vasconcelos et al. 2011).

    With isotropic reading noise ``σ``, to first order the residual ``e_k = ||u_k|| - B_{a,k}``,
    ``u_k = W(r_k - o)``, has the variance (the gradient of ``||W(r - o)||`` in ``r`` is ``W^T u_k / ||u_k||``)

    .. math:: \\sigma_k^2 = \\sigma^2\\,\\frac{\\lVert W^T\\mathbf u_k\\rVert^2}{\\lVert\\mathbf u_k\\rVert^2}

    and the estimate minimises :math:`\\sum_k e_k^2/\\sigma_k^2` (``σ`` a common factor) with the
    parameters and start of :class:`TriangularCalibration`. With ``W`` a multiple of a rotation all
    weights are equal and it is the triangular least squares.

    Parameters
    ----------
    name, form, max_nfev, tol
        As :class:`TriangularCalibration`.

    References
    ----------
    Vasconcelos, Elkaim, Silvestre, Oliveira & Cardeira (2011), Geometric approach to strapdown
    magnetometer calibration in sensor frame, IEEE TAES 47(2):1293-1306.
    """

    references = "Vasconcelos et al. 2011, IEEE TAES 47(2):1293-1306"
    weighted = True
    monotone_history = False  # it minimises the weighted criterion: its x is not the best of the problem's objective

    def __init__(self, *, name: str = "ml_scalar", form: str = "lower", max_nfev: int = 2000, tol: float = 1e-15):
        super().__init__(name=name, form=form, max_nfev=max_nfev, tol=tol)
