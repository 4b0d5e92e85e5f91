"""Levenberg-Marquardt refinement of the problem's residuals (``scipy.optimize.least_squares``).

Minimises ``sum(problem.residuals(theta)**2)`` with MINPACK's LM, started from
the ellipsoid fit (or the centre of the search box). For the scalar problem the
residuals are ``|W(r_i - o)| - B_a``: the maximum-likelihood fit under Gaussian noise.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from magexp.errors import check, check_positive_int
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

    def __init__(self, *, name: str = "lm", start: str = "problem", max_nfev: int = 2000, tol: float = 1e-15):
        check(start in STARTS, f"estimator.start={start!r} is not allowed: choose one of {', '.join(STARTS)}")
        self.name = name
        self.start = start
        self.max_nfev = check_positive_int(max_nfev, "estimator.max_nfev")
        self.tol = float(tol)

    def initial(self, problem) -> np.ndarray:
        if self.start == "problem" and hasattr(problem, "initial_estimate"):
            return problem.initial_estimate()
        if self.start in ("ellipsoid", "problem") and getattr(problem, "objective", None) in EllipsoidFit.objectives:
            first = EllipsoidFit().fit(problem)
            if first.success:
                return first.x
        return (problem.lower + problem.upper) / 2

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        x0 = self.initial(problem)
        costs: list[float] = []

        def residuals(theta):
            r = problem.residuals(theta)
            costs.append(float(np.sqrt(np.mean(r * r))))
            return r

        sol = least_squares(residuals, x0, method="lm", x_scale="jac",
                            xtol=self.tol, ftol=self.tol, gtol=self.tol, max_nfev=self.max_nfev)
        history = np.minimum.accumulate(np.asarray(costs))
        check(np.all(np.isfinite(sol.x)), "lm diverged: the residuals became non-finite")
        return FitResult(x=sol.x, fun=problem.cost_direct(sol.x), nit=len(costs), nfev=len(costs),
                         history=history, history_nfev=np.arange(1, len(costs) + 1),
                         success=bool(sol.status > 0), message=str(sol.message))
