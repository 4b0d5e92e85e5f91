"""Closed-form and fixed solutions of linear problems.

:class:`LeastSquares` (``ls``) is the ordinary least-squares solution of the problem's
linear model (for Yan & Zhou 2022: ``min ||C x - Y||``, the solution the Kalman filter
converges to when the readings are reused). :class:`FixedParameters` returns a published
parameter vector unchanged, so that a paper's own solution is evaluated on the same data
by the same metrics as every estimator.
"""

from __future__ import annotations

import numpy as np

from magexp.errors import MagexpError
from magexp.estimators.result import FitResult


def _result(problem, x: np.ndarray, message: str) -> FitResult:
    """The :class:`FitResult` of a closed-form solution ``x``: one evaluation, one iteration."""
    fun = problem.cost_direct(x)
    return FitResult(x=x, fun=fun, nit=1, nfev=1, history=np.array([fun]), history_nfev=np.array([1]), message=message)


class LeastSquares:
    """Ordinary linear least squares through ``problem.least_squares()``: ``x̂ = argmin_x ||C x - Y||_F`` over
    the rows ``C_i = [u_i^T, 1]``, ``Y_i = B_i^T`` of the forward model ``B_i = S u_i + b`` (Yuan 2018 eq 1;
    Yan & Zhou 2022 eqs 1 and 6, the solution their filter converges to when the readings are reused).

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator` (``ls``).

    References
    ----------
    Gauss (1809), Theoria motus corporum coelestium; Golub & Van Loan, Matrix Computations, ch. 5 (the
    QR and SVD solutions).
    """

    references = "Gauss 1809; Golub & Van Loan, Matrix Computations"
    label = "least squares"
    smoke: dict = {}
    needs = ("linear_design",)
    iterative = False

    def __init__(self, *, name: str = "ls"):
        self.name = name

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        """The least-squares solution of the problem's linear model.

        Parameters
        ----------
        problem, rng, callback
            As :meth:`magexp.estimators.base.Estimator.fit`: its ``least_squares()`` (``linear_design``).

        Returns
        -------
        FitResult
            One evaluation, the solution.
        """
        return _result(problem, problem.least_squares(), "closed form")


class FixedParameters:
    """A given parameter vector (e.g. a paper's reported solution), evaluated as is.

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator`.
    x : list of float
        The parameter vector, in the problem's order (``problem.parameter_names()``).
    source : str
        Where the numbers come from (shown in the result message).

    Raises
    ------
    MagexpError
        When ``x`` is not a list of finite numbers.
    """

    references = ""  # an instance's: its source
    label = ""
    smoke: dict = {}
    needs = ("cost",)
    iterative = False
    only_objective = "ship"  # the printed solutions are of Yan & Zhou's model

    def __init__(self, *, name: str, x: list[float], source: str = ""):
        self.name = name
        self.x = np.asarray(x, dtype=float)
        self.source = self.references = source
        if self.x.ndim != 1 or not np.all(np.isfinite(self.x)):
            raise MagexpError(f"estimator.x={x!r} is not allowed: it must be a list of finite numbers")

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        """``x`` as it is, evaluated on the problem.

        Parameters
        ----------
        problem, rng, callback
            As :meth:`magexp.estimators.base.Estimator.fit` (one evaluation, nothing drawn, no iteration).

        Returns
        -------
        FitResult
            One evaluation, ``x``.

        Raises
        ------
        MagexpError
            When the problem's ``n_params`` is not the length of ``x``.
        """
        if self.x.size != problem.n_params:
            raise MagexpError(f"estimator.x has {self.x.size} values: the problem needs {problem.n_params}")
        return _result(problem, self.x.copy(), self.source or "fixed")
