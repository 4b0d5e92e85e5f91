"""Differential evolution (``scipy.optimize.differential_evolution``) on the problem's vectorised cost,
within the search box: :class:`DifferentialEvolution`.

With ``updating="deferred"`` and ``vectorized=True`` a generation is one call of ``problem.cost`` on all
``S`` trials; SciPy's generator is seeded from the run's ``rng``. The budget counts cost evaluations, as
for the swarms: the initial population costs ``S``, each generation ``S``, so
``maxiter = ⌊budget / S⌋ - 1``. No polishing step (it would spend evaluations outside the budget).
"""

from __future__ import annotations

import numpy as np

from magexp.errors import check, check_nonnegative, check_positive_int
from magexp.estimators.blackbox import RecordedCost, child_seed
from magexp.estimators.result import FitResult


class DifferentialEvolution:
    """SciPy's differential evolution with a budget of cost evaluations (Storn & Price 1997).

    Strategy ``best1bin`` by default: for each member ``x_k`` of a population of ``S = popsize · p``, a
    mutant and a binomial crossover

    .. math:: \\mathbf y = \\mathbf x_{best} + F\\,(\\mathbf x_{r_1} - \\mathbf x_{r_2}),\\qquad
              t_j = \\begin{cases} y_j & U_j < CR \\text{ or } j = j_{rand} \\\\ x_{k,j} & \\text{else}\\end{cases}

    (``F`` dithered uniformly in ``mutation`` every generation) replaces ``x_k`` if it is no worse.

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator`.
    max_evaluations : int
        Budget of cost evaluations (default: the swarms' 50 × 801): at least two populations.
    popsize : int
        Population size multiplier (population ``S = popsize · p``; 10: Storn & Price's ``NP = 10 D``).
    strategy : str
        SciPy's mutation strategy.
    mutation : float or [float, float]
        ``F``, a number or a ``[low, high]`` dithering range.
    recombination : float
        ``CR`` in [0, 1] (0.9: Storn & Price's first choice for non-separable costs; SciPy: 0.7).
    tol : float
        SciPy's relative convergence tolerance (0, the default: run the whole budget unless ``callback``
        returns true).
    init : str
        SciPy's initialisation (``latinhypercube``, ``sobol``, ``halton``, ``random``).

    References
    ----------
    Storn & Price (1997), J. Global Optimization 11:341-359; SciPy's ``differential_evolution``.
    """

    references = "Storn & Price 1997; SciPy differential_evolution"
    label = ""
    smoke = {"max_evaluations": 240}  # two generations of 10 x 12
    needs = ("cost",)
    iterative = True

    def __init__(self, *, name: str = "de", max_evaluations: int = 40050, popsize: int = 10,
                 strategy: str = "best1bin", mutation: float | list[float] = (0.5, 1.0), recombination: float = 0.9,
                 tol: float = 0.0, init: str = "latinhypercube"):
        self.name = name
        self.max_evaluations = check_positive_int(max_evaluations, "estimator.max_evaluations")
        self.popsize = check_positive_int(popsize, "estimator.popsize")
        self.strategy = strategy
        self.mutation = tuple(mutation) if isinstance(mutation, (list, tuple)) else float(mutation)
        self.recombination = check_nonnegative(recombination, "estimator.recombination")
        check(self.recombination <= 1, f"estimator.recombination={recombination!r} is not allowed: it must be in [0, 1]")
        self.tol = check_nonnegative(tol, "estimator.tol")
        self.init = init

    def fit(self, problem, *, rng: np.random.Generator, callback=None) -> FitResult:
        """SciPy's ``differential_evolution`` within the budget, one vectorised cost call a generation.

        Parameters
        ----------
        problem, rng, callback
            As :meth:`magexp.estimators.base.Estimator.fit`. SciPy's generator is seeded from ``rng``
            (:func:`~magexp.estimators.blackbox.child_seed`); ``problem`` needs a finite box; ``callback``
            runs after each generation of ``popsize · p`` trials.

        Returns
        -------
        FitResult
            The best trial; ``history[k]`` the best cost after generation ``k``.
        """
        # lazy: scipy.optimize, measured 0.40 s CPU to import (min of 5, after numpy); every command imports this module
        # to register its typed schema (magexp.run.compose.register_schemas), and only a de run needs it
        from scipy.optimize import Bounds, differential_evolution

        cost = RecordedCost(problem)
        size = self.popsize * len(problem.lower)
        maxiter = self.max_evaluations // size - 1
        check(maxiter >= 1, f"estimator.max_evaluations={self.max_evaluations} is not allowed: it must be at "
                            f"least two populations ({2 * size} evaluations with popsize={self.popsize})")
        stopped = []

        def generation(intermediate_result):
            stopped.append(callback is not None and bool(callback(len(cost.history) - 1, cost.best_x, cost.best_f)))
            return stopped[-1]

        try:
            differential_evolution(lambda x: cost(x.T), Bounds(problem.lower, problem.upper), strategy=self.strategy,
                                   maxiter=maxiter, popsize=self.popsize, tol=self.tol, mutation=self.mutation,
                                   recombination=self.recombination, rng=np.random.default_rng(child_seed(rng)),
                                   callback=generation, polish=False, init=self.init, updating="deferred",
                                   vectorized=True)
        except ValueError as exc:  # SciPy's own check of a bad strategy / init / mutation
            check(False, f"estimator de could not run: {str(exc).splitlines()[0]}")
        message = "stopped by callback" if stopped and stopped[-1] else f"{len(cost.history) - 1} generations"
        return cost.result(message)
