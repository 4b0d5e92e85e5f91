"""Levenberg-Marquardt in numpy: the solver of ``estimator.solver=numpy`` (:class:`magexp.estimators.lm.LevenbergMarquardt`).

It minimises ``F(θ) = ½ ‖r(θ)‖²`` from a start ``θ_0`` with a Jacobian ``J`` the caller supplies (e.g.
:func:`magexp.estimators.lm.stacked_jacobian`). Each step solves the damped normal equations with
Marquardt's scaling (Moré 1978: ``D`` the largest diagonal of ``JᵀJ`` met so far)

.. math:: (J^\\top J + \\mu D)\\,\\boldsymbol\\delta = -J^\\top \\mathbf r,

and is taken when the gain ratio ``ρ = (F(θ) - F(θ + δ)) / (½ δᵀ(μ D δ - Jᵀ r))`` is positive; ``μ`` follows
Nielsen's rule (Madsen, Nielsen & Tingleff 2004, *Methods for non-linear least squares problems*, eq 3.16):
``μ ← μ max(1/3, 1 - (2ρ - 1)³)`` after a taken step, ``μ ← μ ν, ν ← 2 ν`` after a refused one. It stops,
successfully, when a taken step lowers ``F`` by less than ``tol`` of it, when the step is shorter than ``tol``
of ``‖θ‖``, or when the largest gradient entry is below ``tol`` (MINPACK's ``ftol``, ``xtol`` and ``gtol``,
all ``tol``); it fails after ``max_nfev`` residual evaluations (Jacobians not counted, as MINPACK's ``lmder``).

Why beside MINPACK (``scipy.optimize.least_squares``): importing ``scipy.optimize`` costs 0.45-0.5 CPU-s,
more than ``magexp calibrate``'s whole default fit of a few thousand readings; a 17-parameter problem
needs only ``numpy.linalg.solve``. The optima are the same (the problem's, not the solver's).
"""

from __future__ import annotations

import numpy as np


def minimise_numpy(residuals, x0, *, jac, tol: float = 1e-12, max_nfev: int = 2000):
    """Levenberg-Marquardt on ``residuals`` with the Jacobian ``jac`` (module docstring): ``(x, status, message,
    history)`` as :func:`magexp.estimators.lm.minimise_residuals`."""
    x = np.asarray(x0, float).copy()
    r = residuals(x)
    value = 0.5 * float(r @ r) if np.all(np.isfinite(r)) else np.inf
    history = [np.sqrt(2 * value / len(r))]
    jm = jac(x)
    a, g = jm.T @ jm, jm.T @ r
    scale = np.maximum(np.diag(a), np.finfo(float).tiny)
    mu, nu = 1e-3, 2.0
    while len(history) < max_nfev:
        if np.max(np.abs(g)) <= tol * max(value, np.finfo(float).tiny) ** 0.5 * np.sqrt(np.max(scale)):
            return x, 1, "the gradient is below tol", np.asarray(history)
        step = _step(a, g, mu * scale)
        if step is None or np.linalg.norm(step) <= tol * (np.linalg.norm(x) + tol):
            return x, 2, "the step is below tol", np.asarray(history)
        trial = x + step
        with np.errstate(over="ignore", invalid="ignore"):
            rt = residuals(trial)
            new = 0.5 * float(rt @ rt) if np.all(np.isfinite(rt)) else np.inf
        predicted = 0.5 * float(step @ (mu * scale * step - g))
        gain = (value - new) / predicted if predicted > 0 else -1.0
        if gain > 0:
            done = value - new <= tol * value
            x, r, value = trial, rt, new
            jm = jac(x)
            a, g = jm.T @ jm, jm.T @ r
            scale = np.maximum(scale, np.diag(a))
            mu, nu = mu * max(1 / 3, 1 - (2 * gain - 1) ** 3), 2.0
            if done:
                history.append(np.sqrt(2 * value / len(r)))
                return x, 2, "the reduction of the cost is below tol", np.asarray(history)
        else:
            mu, nu = mu * nu, nu * 2
        history.append(np.sqrt(2 * value / len(r)))
    return x, 0, f"the maximum number of residual evaluations ({max_nfev}) is exceeded", np.asarray(history)


def _step(a: np.ndarray, g: np.ndarray, damping: np.ndarray) -> np.ndarray | None:
    """The damped Gauss-Newton step ``-(A + diag(damping))⁻¹ g``, or None where it is singular."""
    try:
        step = np.linalg.solve(a + np.diag(damping), -g)
    except np.linalg.LinAlgError:
        return None
    return step if np.all(np.isfinite(step)) else None


def stacked_jacobian(problem):
    """``theta -> J`` (``(m, p)``) by forward differences, ``J[:, i] = (r(theta + h_i e_i) - r(theta)) / h_i`` with
    ``h_i = sqrt(eps) max(1, |theta_i|)``, from one call of the problem's ``residual_swarm`` on ``theta`` and its
    ``p`` steps stacked (:meth:`magexp.problems.gyro.GyroAidedCalibration.residual_swarm`).
    """

    def jac(theta):
        theta = np.asarray(theta, float)
        h = np.sqrt(np.finfo(float).eps) * np.maximum(1.0, np.abs(theta))
        points = np.vstack([theta, theta + np.diag(h)])
        r = problem.residual_swarm(points).reshape(len(points), -1)
        return ((r[1:] - r[0]) / h[:, None]).T

    return jac
