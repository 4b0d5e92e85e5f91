"""Random drift PSO (RDPSO) velocity rule, Yuan 2018 eqs 10-17 (after Sun et al.'s RDPSO): a
particle's velocity is a random thermal motion plus a directed drift (:class:`RandomDriftVelocity`);
the swarm engine clamps velocity and position.
"""

from __future__ import annotations

import numpy as np

from magexp.errors import check_nonnegative
from magexp.estimators.velocity import VelocityRule


def random_drift(i, j, x, v, pbest, g, mean, r, c):
    """RDPSO velocity (Yuan 2018 eq 16): the kernel of :class:`RandomDriftVelocity`."""
    phi = (2.0 * (r[2, i, j] > 0.5) - 1.0) * r[3, i, j]  # ±1 times ln(1/u): exact, on a number or an array
    return c[0] * np.abs(mean[j] - x[i, j]) * phi + c[1] * r[0, i, j] * (pbest[i, j] - x[i, j]) \
        + c[2] * r[1, i, j] * (pbest[g, j] - x[i, j])


def drift_factors(r: np.ndarray) -> np.ndarray:
    """The random factors of :func:`random_drift` from its draws (eq 14)."""
    np.log(1.0 / (1.0 - r[:, 3]), out=r[:, 3])
    return r


class ThermalCoefficient:
    """``α(k) = base + span / (1 + rate k / k_max)`` (Yuan 2018 eq 12), from ``base + span`` at ``k = 0``
    down to ``base + span / (1 + rate)``.

    Parameters
    ----------
    base, span, rate : float
        The constants of eq 12, >= 0 (as printed: 0.3, 0.6, 4).
    """

    def __init__(self, base: float = 0.3, span: float = 0.6, rate: float = 4.0):
        self.base = check_nonnegative(base, "estimator.velocity.alpha.base")
        self.span = check_nonnegative(span, "estimator.velocity.alpha.span")
        self.rate = check_nonnegative(rate, "estimator.velocity.alpha.rate")

    def __call__(self, t, t_max: int):
        """``α`` at iteration ``t``.

        Parameters
        ----------
        t, t_max
            As :meth:`magexp.estimators.schedules.Linear.__call__`.

        Returns
        -------
        float or numpy.ndarray
            ``α(t)``, element-wise for an array ``t``.
        """
        return self.base + self.span / (1.0 + self.rate * t / t_max)


class RandomDriftVelocity(VelocityRule):
    """The RDPSO velocity rule: the kernel :func:`random_drift` on the draws ``r1, r2, s, u``.

    .. math::

        v_{ij} &= \\alpha\\,\\lvert M_j - x_{ij}\\rvert\\,\\varphi_{ij}
                 + r_1 c_1 (p_{ij} - x_{ij}) + r_2 c_2 (g_j - x_{ij}) \\quad\\text{(eq 16)} \\\\
        \\alpha &= 0.3 + 0.6 / (1 + 4 k / k_{max}) \\quad\\text{(eq 12, as printed)} \\\\
        M_j &= \\frac1m \\sum_i p_{ij} \\quad\\text{(mean personal best, eq 13)} \\\\
        \\varphi_{ij} &= \\pm \\ln(1/u_{ij}),\\ u \\sim U(0, 1],\\ + \\text{ if } s_{ij} > 0.5 \\quad\\text{(eq 14)}

    with ``r_1, r_2, s ~ U(0, 1)`` per particle and dimension; the position moves by the new velocity
    (eq 17).

    Parameters
    ----------
    c1, c2 : float
        Learning factors (Yuan 2018 Table 1: 1.45 each), >= 0.
    alpha : schedule, optional
        Thermal-coefficient schedule ``alpha(t, t_max)`` (default :class:`ThermalCoefficient`).

    References
    ----------
    Yuan, Wang & Chen (2018), Navigation Positioning & Timing 5(6):92-98, eqs 10-17; Sun, Wu, Palade
    et al. (2015), Random drift particle swarm optimization algorithm.
    """

    kernel = staticmethod(random_drift)
    n_draws = 4
    coefficients = ("alpha", "c1", "c2")
    factors = staticmethod(drift_factors)
    needs_mean = True

    def __init__(self, c1: float = 1.45, c2: float = 1.45, alpha=None):
        self.c1 = check_nonnegative(c1, "estimator.velocity.c1")
        self.c2 = check_nonnegative(c2, "estimator.velocity.c2")
        self.alpha = alpha if alpha is not None else ThermalCoefficient()
