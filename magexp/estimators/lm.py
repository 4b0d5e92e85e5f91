"""Levenberg-Marquardt refinement of the problem's residuals (``scipy.optimize.least_squares``).

Minimises ``sum(problem.residuals(theta)**2)`` with MINPACK's LM, started from
the ellipsoid fit (or the centre of the search box). For the scalar problem the
residuals are ``|W(r_i - o)| - B_a``: the maximum-likelihood fit under Gaussian noise.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from magexp.errors import check, check_positive_int
from magexp.estimators.base import Stop, applies_to, stopper
from magexp.estimators.ellipsoid import EllipsoidFit
from magexp.estimators.result import FitResult

STARTS = ("ellipsoid", "centre", "problem")


class LevenbergMarquardt:
    """Least-squares refinement.

    Parameters
    ----------
    name : config name.
    start : ``problem`` (default): the problem's own closed-form ``initial_estimate()`` (e.g. the
        linear least-squares fit of the vector problem), else the ellipsoid fit (scalar objective),
        else the centre of the search box; ``ellipsoid``: the ellipsoid fit, else the centre;
        ``centre``.
    max_nfev : cap on residual evaluations.
    tol : ``xtol = ftol = gtol`` of ``least_squares``.
    """

    references = "Levenberg 1944; Marquardt 1963; More 1978 (MINPACK)"
    needs = ("residuals",)
    iterative = True

    def __init__(self, *, name: str = "lm", start: str = "problem", max_nfev: int = 2000, tol: float = 1e-12):
        check(start in STARTS, f"estimator.start={start!r} is not allowed: choose one of {', '.join(STARTS)}")
        self.name = name
        self.start = start
        self.max_nfev = check_positive_int(max_nfev, "estimator.max_nfev")
        self.tol = float(tol)

    def initial(self, problem) -> np.ndarray:
        if self.start == "problem" and hasattr(problem, "initial_estimate"):
            return problem.initial_estimate()
        if self.start in ("ellipsoid", "problem") and applies_to(EllipsoidFit, problem)[0]:
            first = EllipsoidFit().fit(problem)
            if first.success:
                return first.x
        return (problem.lower + problem.upper) / 2

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        """Minimise ``sum(problem.residuals(x)^2)``; ``callback(k, best x, best RMS)`` after each
        residual evaluation ``k`` may stop it (the best point so far is returned)."""
        x, status, message, history = minimise_residuals(problem.residuals, self.initial(problem), tol=self.tol,
                                                         max_nfev=self.max_nfev, callback=callback)
        check(np.all(np.isfinite(x)), "lm diverged: the residuals became non-finite")
        return FitResult(x=x, fun=problem.cost_direct(x), nit=len(history), nfev=len(history),
                         history=history, history_nfev=np.arange(1, len(history) + 1),
                         success=status > 0, message=message)


def minimise_residuals(residuals, x0, *, tol: float = 1e-15, max_nfev: int = 2000, callback=None, measure=None):
    """Levenberg-Marquardt (MINPACK through ``scipy.optimize.least_squares``) on ``residuals``.

    Returns ``(x, status, message, history)``: scipy's solution (the best ``x`` evaluated when the
    callback stopped it: status ``-2``), its message, and the best value after every evaluation
    of ``measure(x)`` (default: the RMS of the residuals; an estimator minimising a weighted
    criterion reports its problem's objective). Shared by every least-squares refinement.
    """
    best: dict = {}
    record = stopper(callback, best)

    def fun(theta):
        r = residuals(theta)
        if not np.all(np.isfinite(r)):
            record(theta, np.inf)
        else:
            record(theta, float(np.sqrt(np.mean(r * r))) if measure is None else measure(theta))
        return r

    try:
        sol = least_squares(fun, np.asarray(x0, float), method="lm", x_scale="jac",
                            xtol=tol, ftol=tol, gtol=tol, max_nfev=max_nfev)
        x, status, message = sol.x, int(sol.status), str(sol.message)
    except Stop:
        x, status, message = best["x"], -2, "stopped by the callback"
    return x, status, message, np.asarray(best["history"])
