"""Random drift PSO (RDPSO) velocity rule, Yuan 2018 eqs 10-16 (after Sun et al.'s RDPSO).

A particle's velocity is a random thermal motion plus a directed drift:

.. math::

    v_{ij} &= \\alpha\\,\\lvert M_j - x_{ij}\\rvert\\,\\varphi_{ij}
             + r_1 c_1 (p_{ij} - x_{ij}) + r_2 c_2 (g_j - x_{ij}) \\\\
    \\alpha &= 0.3 + 0.6 / (1 + 4 k / k_{max}) \\quad\\text{(eq 12, as printed)} \\\\
    M_j &= \\frac1m \\sum_i p_{ij} \\quad\\text{(mean personal best, eq 13)} \\\\
    \\varphi_{ij} &= \\pm \\ln(1/u_{ij}),\\ u \\sim U(0, 1],\\ + \\text{ if } s_{ij} > 0.5 \\quad\\text{(eq 14)}

with ``r_1, r_2, s ~ U(0, 1)`` per particle and dimension; the position moves by
the new velocity (eq 17). The swarm engine clamps velocity and position.

References: Yuan, Wang & Chen (2018), Navigation Positioning & Timing 5(6):92-98;
Sun, Wu, Palade et al. (2015), *Random drift particle swarm optimization algorithm*.
"""

from __future__ import annotations

import numpy as np

from magexp.errors import check_nonnegative
from magexp.estimators.schedules import values
from magexp.estimators.velocity import _NO_DRAWS


def drift_sign_log(u: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The drift term's random factor ``φ = ±ln(1/u)``, ``+`` where ``s > 0.5`` (Yuan 2018 eq 14).

    Parameters
    ----------
    u : numpy.ndarray
        Draws in (0, 1].
    s : numpy.ndarray
        Draws in [0, 1), the sign.

    Returns
    -------
    numpy.ndarray
        ``φ``.
    """
    return np.where(s > 0.5, 1.0, -1.0) * np.log(1.0 / u)


def random_drift_velocity(x, pbest, gbest, *, alpha, c1, c2, r1, r2, phi):
    """RDPSO velocity for given random draws (Yuan 2018 eq 16).

    .. math:: v = \\alpha \\lvert M - x\\rvert \\varphi + c_1 r_1 (p - x) + c_2 r_2 (g - x)

    Parameters
    ----------
    x : numpy.ndarray
        Positions (n, d).
    pbest : numpy.ndarray
        Personal bests (n, d); ``M`` is their mean over particles (eq 13).
    gbest : numpy.ndarray
        The global best (d,).
    alpha, c1, c2 : float
        The thermal coefficient and the learning factors.
    r1, r2 : numpy.ndarray
        Uniform draws (n, d).
    phi : numpy.ndarray
        :func:`drift_sign_log` of the draws (n, d).

    Returns
    -------
    numpy.ndarray
        The new velocities (n, d).
    """
    mean_best = pbest.mean(axis=0)
    return alpha * np.abs(mean_best - x) * phi + c1 * r1 * (pbest - x) + c2 * r2 * (gbest - x)


class ThermalCoefficient:
    """``α(k) = base + span / (1 + rate k / k_max)`` (eq 12 with base 0.3, span 0.6, rate 4).

    Decreases from ``base + span`` (0.9) at ``k = 0`` to ``base + span / (1 + rate)`` (0.42).

    Parameters
    ----------
    base, span, rate : float
        >= 0 (Yuan 2018 eq 12 as printed: 0.3, 0.6, 4).
    """

    def __init__(self, base: float = 0.3, span: float = 0.6, rate: float = 4.0):
        self.base = check_nonnegative(base, "estimator.velocity.alpha.base")
        self.span = check_nonnegative(span, "estimator.velocity.alpha.span")
        self.rate = check_nonnegative(rate, "estimator.velocity.alpha.rate")

    def __call__(self, t: int, t_max: int) -> float:
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


class RandomDriftVelocity:
    """The RDPSO velocity rule: draws ``r1, r2, u, s`` and calls :func:`random_drift_velocity`.

    Parameters
    ----------
    c1, c2 : float
        Learning factors (Yuan 2018 Table 1: 1.45 each), >= 0.
    alpha : callable, optional
        Thermal-coefficient schedule ``alpha(t, t_max)`` (default :class:`ThermalCoefficient`).

    References
    ----------
    Yuan, Wang & Chen (2018), eqs 10-17; Sun, Wu, Palade et al. (2015), Random drift particle swarm
    optimization algorithm.
    """

    def __init__(self, c1: float = 1.45, c2: float = 1.45, alpha=None):
        self.c1 = check_nonnegative(c1, "estimator.velocity.c1")
        self.c2 = check_nonnegative(c2, "estimator.velocity.c2")
        self.alpha = alpha if alpha is not None else ThermalCoefficient()

    def __call__(self, x, v, pbest, gbest, t, t_max, *, rng):
        """The new velocities (:func:`random_drift_velocity` on fresh draws).

        Parameters
        ----------
        x, v, pbest : numpy.ndarray
            Positions, velocities, personal bests (n, d).
        gbest : numpy.ndarray
            The global best (d,).
        t, t_max : int
            The iteration and the last one.
        rng : numpy.random.Generator
            The run's estimator stream: ``r1, r2, s, u`` are drawn from it in that order.

        Returns
        -------
        numpy.ndarray
            ``(n, d)``.
        """
        r1, r2, s = rng.random(x.shape), rng.random(x.shape), rng.random(x.shape)
        u = 1.0 - rng.random(x.shape)  # in (0, 1]: ln(1/u) stays finite
        return random_drift_velocity(x, pbest, gbest, alpha=self.alpha(t, t_max), c1=self.c1, c2=self.c2,
                                     r1=r1, r2=r2, phi=drift_sign_log(u, s))

    n_draws = 4  # random numbers per particle and dimension in one iteration (r1, r2, s, u)

    drift = True  # the rule of :func:`magexp.estimators._compiled.drift_move` in a compiled run

    def coefficients(self, t: np.ndarray, t_max: int) -> np.ndarray:
        """``[α, c1, c2]`` at every time of ``t``: the coefficients of
        :func:`magexp.estimators._compiled.run` (the same floats as :meth:`step`).

        Parameters
        ----------
        t : numpy.ndarray
            Integer times.
        t_max : int
            The last iteration.

        Returns
        -------
        numpy.ndarray
            ``(len(t), 3)``.
        """
        coef = np.empty((len(t), 3))
        coef[:, 0], coef[:, 1], coef[:, 2] = values(self.alpha, t, t_max), self.c1, self.c2
        return coef

    def log_u(self, r: np.ndarray) -> np.ndarray:
        """``ln(1/u)``, ``u = 1 - r[:, 3]``, of the draws of a compiled run, as :meth:`step` computes it
        (numpy's ``log``).

        Parameters
        ----------
        r : numpy.ndarray
            Draws (k, 4, n, d).

        Returns
        -------
        numpy.ndarray
            ``(k, n, d)``.
        """
        return np.log(1.0 / (1.0 - r[:, 3]))

    def step(self, kernels, x, v, pbest, pcost, cost, r, t, t_max, limits, clip_box):
        """One compiled call (:func:`magexp.estimators._compiled.drift_step`): the best updates
        with ``cost``, then, unless ``r`` is None, iteration ``t``'s move in place (as
        :meth:`magexp.estimators.velocity.InertiaVelocity.step`) with ``r1, r2, s = r[:3]`` and
        ``u = 1 - r[3]``: the same numbers as :meth:`__call__` on the same draws (``ln(1/u)`` by
        numpy, its sign ``s > 0.5`` in the kernel: :func:`drift_sign_log`).

        Parameters
        ----------
        kernels : module
            :mod:`magexp.estimators._compiled`.
        x, v, pbest : numpy.ndarray
            Positions, velocities, personal bests (n, d), updated in place.
        pcost, cost : numpy.ndarray
            Personal-best costs (updated in place) and the costs of ``x`` (n,).
        r : numpy.ndarray or None
            The draws ``(4, n, d)`` of the move, None for the best updates only.
        t, t_max : int
            The iteration and the last one.
        limits : numpy.ndarray
            ``[v_max, lower, upper]`` (3, d).
        clip_box : bool
            Whether the move clips to the box.

        Returns
        -------
        int
            The global best's index.
        """
        if r is None:
            return kernels.drift_step(x, v, pbest, pcost, cost, False, _NO_DRAWS, _NO_DRAWS[0], 0.0, 0.0, 0.0,
                                      limits, clip_box)
        return kernels.drift_step(x, v, pbest, pcost, cost, True, r, np.log(1.0 / (1.0 - r[3])), self.alpha(t, t_max),
                                  self.c1, self.c2, limits, clip_box)
