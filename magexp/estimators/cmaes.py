"""CMA-ES (the ``cma`` package) on the problem's vectorised cost, within the search box: :class:`CMAES`.

The search runs in box-normalised coordinates ``z ∈ [0, 1]^p``, ``θ = l + z (u - l)``, because the
parameters differ in scale by orders of magnitude (gains ~1, offsets ~10³ nT); the box is enforced by
cma's ``BoundTransform`` (every evaluated candidate is feasible). The normal draws come from a
generator seeded from the run's ``rng`` (cma's ``randn`` option), so a seed gives the same run bit for bit.
"""

from __future__ import annotations

import numpy as np

from magexp.errors import check, check_nonnegative, check_positive_int
from magexp.estimators.blackbox import RecordedCost, child_seed
from magexp.estimators.result import FitResult

STARTS = ("uniform", "centre")


class CMAES:
    """CMA-ES with a budget of cost evaluations (Hansen & Ostermeier 2001; Hansen 2016).

    Each generation samples ``λ`` candidates

    .. math:: \\mathbf z_k = \\mathbf m + \\sigma\\,\\mathbf B\\mathbf D\\,\\mathbf n_k,\\qquad
              \\mathbf n_k \\sim \\mathcal N(0, I),\\quad k = 1..λ,

    evaluates them with one call of ``problem.cost``, and moves the mean ``m`` to the weighted mean of
    the best ``μ``, adapting the covariance ``C = B D² Bᵀ`` (rank-one and rank-μ updates) and the step
    size ``σ`` (cumulative step-size adaptation). The budget counts cost evaluations, as for the swarms:
    the start ``m_0`` costs one, each generation ``λ``; the run stops when the next generation would
    exceed it, at cma's own termination criteria, or when ``callback`` returns true.

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator`.
    max_evaluations : int
        Budget of cost evaluations (default: the swarms' 50 × 801), at least 2.
    popsize : int
        ``λ``; 0 keeps cma's default ``4 + ⌊3 ln p⌋``.
    sigma0 : float
        Initial step size in box-normalised coordinates (fraction of the box width), > 0.
    start : str
        ``uniform`` (``m_0`` uniform in the box, from ``rng``) or ``centre``.

    References
    ----------
    Hansen & Ostermeier (2001), Evolutionary Computation 9(2):159-195; Hansen (2016), The CMA Evolution
    Strategy: A Tutorial, arXiv:1604.00772; the ``cma`` package (pycma).
    """

    references = "Hansen & Ostermeier 2001; Hansen 2016 (arXiv:1604.00772); pycma"
    label = ""
    smoke = {"max_evaluations": 240}
    needs = ("cost",)
    iterative = True

    def __init__(self, *, name: str = "cmaes", max_evaluations: int = 40050, popsize: int = 0,
                 sigma0: float = 0.3, start: str = "uniform"):
        self.name = name
        self.max_evaluations = check_positive_int(max_evaluations, "estimator.max_evaluations", minimum=2)
        self.popsize = check_positive_int(popsize, "estimator.popsize", minimum=0)
        self.sigma0 = check_nonnegative(sigma0, "estimator.sigma0")
        check(self.sigma0 > 0, f"estimator.sigma0={sigma0!r} is not allowed: it must be > 0")
        check(start in STARTS, f"estimator.start={start!r} is not allowed: choose one of {', '.join(STARTS)}")
        self.start = start

    def fit(self, problem, *, rng: np.random.Generator, callback=None) -> FitResult:
        """CMA-ES within the budget (the class docstring), from ``m_0`` by ``start``.

        Parameters
        ----------
        problem, rng, callback
            As :meth:`magexp.estimators.base.Estimator.fit`. ``problem``: a cost with a finite box; ``rng``
            seeds cma's ``randn`` (:func:`~magexp.estimators.blackbox.child_seed`); ``callback`` after every
            generation of ``popsize`` candidates.

        Returns
        -------
        FitResult
            The best point evaluated; ``history[k]`` the best cost after generation ``k``.
        """
        import cma  # lazy: 1.3 s CPU to import (min of 5, after numpy), paid only by a cmaes run

        cost = RecordedCost(problem)
        lo, width = problem.lower, problem.upper - problem.lower
        normal = np.random.default_rng(child_seed(rng))
        p = len(lo)
        m0 = normal.random(p) if self.start == "uniform" else np.full(p, 0.5)
        cost(lo + m0[None] * width)
        opts = {"bounds": [0.0, 1.0], "randn": lambda *shape: normal.standard_normal(shape),
                "maxfevals": self.max_evaluations - 1, "verbose": -9, "verb_disp": 0, "verb_log": 0,
                "verb_time": False}
        if self.popsize:
            opts["popsize"] = self.popsize
        es = cma.CMAEvolutionStrategy(m0, self.sigma0, opts)
        message = f"budget of {self.max_evaluations} evaluations"
        while cost.nfev + es.popsize <= self.max_evaluations:
            stop = es.stop()
            if stop:
                message = "cma: " + ", ".join(sorted(stop))
                break
            z = np.asarray(es.ask())
            es.tell(list(z), cost(lo + z * width))
            if callback is not None and callback(len(cost.history) - 1, cost.best_x, cost.best_f):
                message = "stopped by callback"
                break
        return cost.result(message)
