"""Yuan 2018's traditional PSO: the swarm on the simplified 9-parameter (symmetric) model.

Yuan, Wang & Chen 2018 (sec 1 and Tables 2, 7) describe the traditional PSO calibration as using
the total-field objective on a simplified model "assuming at least one sensor axis coincides
with the body frame, reducing the 12 unknowns to 9" (their refs [12, 13]); its Table 7 solution
is exactly symmetric (``S12 = S21``, ``S13 = S31``, ``S23 = S32``). :class:`SymmetricSwarm` runs
the shared swarm engine over

.. math:: \\mathbf q = [M_{11}, M_{12}, M_{13}, M_{22}, M_{23}, M_{33}, \\mathbf o],\\qquad M = M^T

(:func:`magexp.problems.symmetric.expand`; ``M`` the matrix part of the problem's parameters, Yuan's
``S`` or ``W``; each ``q`` entry boxed as its entry of the 12-vector). A symmetric ``W`` is the unique
symmetric root of ``W^T W`` (what a scalar fit identifies), so the rotation valley is gone; a
non-symmetric truth (Yuan's ``S``) cannot be reached.
"""

from __future__ import annotations

import numpy as np

from magexp.estimators.swarm import SwarmOptimizer
from magexp.problems.symmetric import UPPER, expand


class SymmetricView:
    """The problem seen through the 9 parameters ``q`` (box and cost of the expanded vector)."""

    def __init__(self, problem):
        self.problem = problem
        keep = np.concatenate([UPPER, [9, 10, 11]])
        self.lower, self.upper = problem.lower[keep], problem.upper[keep]
        self.n_params = 9

    def cost(self, q: np.ndarray) -> np.ndarray:
        """The problem's cost of the expanded vectors."""
        return self.problem.cost(expand(q))


class SymmetricSwarm(SwarmOptimizer):
    """``pso9``: a :class:`~magexp.estimators.swarm.SwarmOptimizer` (same settings) on the
    symmetric 9-parameter model of a total-field problem (module docstring).

    Parameters
    ----------
    **settings
        Those of :class:`~magexp.estimators.swarm.SwarmOptimizer`.

    References
    ----------
    Yuan, Wang & Chen (2018), sec 1 and Table 7 (their refs [12, 13]); Kennedy & Eberhart (1995).
    """

    needs = ("total_field",)
    label = "PSO (9-parameter)"

    def fit(self, problem, *, rng: np.random.Generator, callback=None):
        """The swarm over ``q`` (:class:`SymmetricView`), its best returned as a 12-vector.

        Parameters
        ----------
        problem, rng, callback
            As in :meth:`magexp.estimators.base.Estimator.fit`. ``problem``: a total-field problem of 12
            parameters ``[vec(M), o]``. ``rng``: the run's estimator stream. ``callback``: ``callback(t, x,
            fun)`` after every iteration, ``x`` expanded to 12.

        Returns
        -------
        FitResult
            ``x`` the expanded best, ``fun`` the problem's objective at it.
        """
        relay = None if callback is None else (lambda t, q, fun: callback(t, expand(q)[0], fun))
        result = super().fit(SymmetricView(problem), rng=rng, callback=relay)
        result.x = expand(result.x)[0]
        result.fun = problem.cost_direct(result.x)
        return result
