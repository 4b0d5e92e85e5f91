"""Velocity rules of the swarm engine: pure, vectorised kernels over ``(n, d)`` arrays.

A rule is called as ``rule(x, v, pbest, gbest, t, t_max, rng=rng) -> v_new``.
"""

from __future__ import annotations

import numpy as np

from magexp.errors import MagexpError
from magexp.estimators.schedules import Constant, values

_NO_DRAWS = np.empty((2, 0, 0))  # the random numbers of a step that does not move
_NO_LOG = np.empty((0, 0, 0))  # ln(1/u) of a rule that draws no u


def inertia_velocity(v, x, pbest, gbest, *, w, c1, c2, r1, r2):
    """Global-best PSO velocity (Kennedy & Eberhart 1995; Ding 2024 eq 10).

    .. math:: v \\leftarrow w v + c_1 r_1 (p - x) + c_2 r_2 (g - x)
    """
    return w * v + c1 * r1 * (pbest - x) + c2 * r2 * (gbest - x)


def check_schedule(schedule, role: str):
    """``schedule`` of the coefficient ``role`` (``inertia``, ``c1``, ``c2``), refused if a value it
    is given (``value``, ``start``, ``end``: a linear schedule's extremes) is negative: a negative
    inertia reverses the velocity every step, a negative learning factor drives a particle away from
    the best position found."""
    for part in ("value", "start", "end"):
        v = getattr(schedule, part, None)
        if isinstance(v, float) and v < 0:
            raise MagexpError(f"estimator.velocity.{role}.{part}={v:g} is not allowed: it must be a number >= 0 "
                              f"(a negative {role} reverses its term of the velocity update)")
    return schedule


class InertiaVelocity:
    """Inertia-weight velocity with scheduled ``w``, ``c1``, ``c2``.

    Traditional PSO uses :class:`~magexp.estimators.schedules.Constant` schedules;
    Ding's IPSO uses :class:`~magexp.estimators.schedules.Linear` ones (eqs 12-14).
    ``r1, r2 ~ U(0, 1)`` independently per particle and dimension.
    """

    def __init__(self, inertia=None, c1=None, c2=None):
        self.inertia = check_schedule(inertia if inertia is not None else Constant(0.7298), "inertia")
        self.c1 = check_schedule(c1 if c1 is not None else Constant(1.49618), "c1")
        self.c2 = check_schedule(c2 if c2 is not None else Constant(1.49618), "c2")

    def __call__(self, x, v, pbest, gbest, t, t_max, *, rng):
        r1 = rng.random(x.shape)
        r2 = rng.random(x.shape)
        return inertia_velocity(
            v, x, pbest, gbest,
            w=self.inertia(t, t_max), c1=self.c1(t, t_max), c2=self.c2(t, t_max), r1=r1, r2=r2,
        )

    n_draws = 2  # random numbers per particle and dimension in one iteration (r1, r2)

    drift = False  # the rule of :func:`magexp.estimators._compiled.inertia_move` in a compiled run

    def coefficients(self, t: np.ndarray, t_max: int) -> np.ndarray:
        """``[w, c1, c2]`` at every time of the integer array ``t``, ``(len(t), 3)``: the
        coefficients of :func:`magexp.estimators._compiled.run` (the same floats as :meth:`step`)."""
        coef = np.empty((len(t), 3))
        for k, schedule in enumerate((self.inertia, self.c1, self.c2)):
            coef[:, k] = values(schedule, t, t_max)
        return coef

    def log_u(self, r: np.ndarray) -> np.ndarray:
        """``ln(1/u)`` of the draws ``r`` (k, 2, n, d) in a compiled run: none (this rule draws no ``u``)."""
        return _NO_LOG

    def step(self, kernels, x, v, pbest, pcost, cost, r, t, t_max, limits, clip_box):
        """One compiled call (:func:`magexp.estimators._compiled.inertia_step`): the best updates
        with ``cost``, then, unless ``r`` is None (after the last iteration), iteration ``t``'s move
        in place (this rule with ``r1, r2 = r``, the clamp to ``limits[0]``, ``x += v`` and, if
        ``clip_box``, the clip to ``limits[1:]``): the same numbers as :meth:`__call__` on the
        same draws. Returns the global best's index."""
        if r is None:
            return kernels.inertia_step(x, v, pbest, pcost, cost, False, _NO_DRAWS, 0.0, 0.0, 0.0, limits, clip_box)
        return kernels.inertia_step(x, v, pbest, pcost, cost, True, r, self.inertia(t, t_max), self.c1(t, t_max),
                                    self.c2(t, t_max), limits, clip_box)
