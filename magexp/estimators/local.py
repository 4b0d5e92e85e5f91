"""The problem's own objective minimised by a local quasi-Newton method (``local``): :class:`LocalMinimiser`.

Where the closed-form start lies in the basin of the global minimum (every simulated scenario of
magexp with full rotations), this is the objective minimised *exactly*, whatever it is: eq 8's sum
of norms, its least-squares twin, the scalar RMS. It separates the effect of an objective from that
of the optimiser that minimises it (``experiments/benchmark/benchmark_objective.yaml``).

**Where it stops.** With finite-difference gradients on these scaled variables the gradient test
(``gtol``) is not reached (on eq 8 the minimum is a kink of the sum of norms): BFGS ends when its line
search can no longer decrease the cost at double precision ("precision loss"), after a number of
evaluations that depends on the round-off (``nit``/``nfev``: path diagnostics of ``magexp verify``), at
a point whose cost and parameters agree between processors far below the error metrics' resolution.
"""

from __future__ import annotations

import numpy as np

from magexp.errors import check_nonnegative, check_positive_int
from magexp.estimators.base import Stop, stopper
from magexp.estimators.lm import LevenbergMarquardt
from magexp.estimators.result import FitResult


class LocalMinimiser:
    """BFGS on ``problem.cost`` from the closed-form start (``scipy.optimize.minimize(method="BFGS")``).

    Minimises the problem's own objective (Ding 2024 eq 17, Yuan 2018 eq 8 or its least-squares twin)
    with finite-difference gradients, from the start of :class:`~magexp.estimators.lm.LevenbergMarquardt`
    (the vector problem's linear least squares, else the ellipsoid fit).

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator`.
    start : str
        As :class:`~magexp.estimators.lm.LevenbergMarquardt` (``problem``, ``ellipsoid``, ``centre``).
    max_iter : int
        BFGS iterations at most.
    gtol : float
        Gradient tolerance of BFGS, relative to the cost at the start.

    References
    ----------
    Nocedal & Wright (2006), Numerical Optimization, ch. 6 (BFGS).
    """

    references = "Nocedal & Wright 2006, Numerical Optimization, ch. 6 (BFGS)"
    label = ""
    smoke = {"max_iter": 12}
    needs = ("cost",)
    iterative = True

    def __init__(self, *, name: str = "local", start: str = "problem", max_iter: int = 500, gtol: float = 1e-10):
        self.name = name
        self.starter = LevenbergMarquardt(start=start)
        self.max_iter = check_positive_int(max_iter, "estimator.max_iter")
        self.gtol = check_nonnegative(gtol, "estimator.gtol")

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        """Minimise ``problem.cost`` from the closed-form start.

        Parameters
        ----------
        problem, rng, callback
            As in :meth:`magexp.estimators.base.Estimator.fit`. ``problem``: its ``cost`` and box. ``rng``:
            unused (the fit draws nothing). ``callback``: ``callback(k, best x, best cost)`` after every
            cost evaluation ``k``.

        Returns
        -------
        FitResult
            ``history`` the best cost after every evaluation.
        """
        # lazy: scipy.optimize, measured 0.40 s CPU to import (min of 5, after numpy); every command imports this module
        # to register its typed schema (magexp.run.compose.register_schemas), and only a local run needs it
        from scipy.optimize import minimize

        x0 = np.asarray(self.starter.initial(problem), float)
        best: dict = {}
        record = stopper(callback, best)
        scale = np.maximum(np.abs(x0), 1e-3 * (problem.upper - problem.lower))  # well-scaled variables
        f0 = float(problem.cost(x0[None])[0]) or 1.0

        def fun(z):
            x = x0 + z * scale
            f = float(problem.cost(x[None])[0])
            record(x, f)
            return f / f0

        try:
            sol = minimize(fun, np.zeros_like(x0), method="BFGS",
                           options={"maxiter": self.max_iter, "gtol": self.gtol})
            message, ok = str(sol.message), bool(sol.success)
        except Stop:
            message, ok = "stopped by the callback", False
        x = best["x"]
        history = np.asarray(best["history"])
        return FitResult(x=x, fun=problem.cost_direct(x), nit=len(history), nfev=len(history), history=history,
                         history_nfev=np.arange(1, len(history) + 1), success=ok, message=message)
