"""Velocity rules of the swarm engine: pure, vectorised kernels over ``(n, d)`` arrays.

A rule is called as ``rule(x, v, pbest, gbest, t, t_max, rng=rng) -> v_new``.
"""

from __future__ import annotations

import numpy as np

from magexp.estimators.schedules import Constant


def inertia_velocity(v, x, pbest, gbest, *, w, c1, c2, r1, r2):
    """Global-best PSO velocity (Kennedy & Eberhart 1995; Ding 2024 eq 10).

    .. math:: v \\leftarrow w v + c_1 r_1 (p - x) + c_2 r_2 (g - x)
    """
    return w * v + c1 * r1 * (pbest - x) + c2 * r2 * (gbest - x)


class InertiaVelocity:
    """Inertia-weight velocity with scheduled ``w``, ``c1``, ``c2``.

    Traditional PSO uses :class:`~magexp.estimators.schedules.Constant` schedules;
    Ding's IPSO uses :class:`~magexp.estimators.schedules.Linear` ones (eqs 12-14).
    ``r1, r2 ~ U(0, 1)`` independently per particle and dimension.
    """

    def __init__(self, inertia=None, c1=None, c2=None):
        self.inertia = inertia if inertia is not None else Constant(0.7298)
        self.c1 = c1 if c1 is not None else Constant(1.49618)
        self.c2 = c2 if c2 is not None else Constant(1.49618)

    def __call__(self, x, v, pbest, gbest, t, t_max, *, rng):
        r1 = rng.random(x.shape)
        r2 = rng.random(x.shape)
        return inertia_velocity(
            v, x, pbest, gbest,
            w=self.inertia(t, t_max), c1=self.c1(t, t_max), c2=self.c2(t, t_max), r1=r1, r2=r2,
        )

    def move(self, kernels, x, v, pbest, g, t, t_max, vmax, lower, upper, clip_box, *, rng):
        """The compiled step (:func:`magexp.estimators._compiled.inertia_move`): this rule, the
        clamp to ``vmax``, ``x += v`` and, if ``clip_box``, the clip to the box, in place; the
        same draws (``r1`` then ``r2``, one call) and the same numbers as :meth:`__call__`."""
        kernels.inertia_move(x, v, pbest, g, rng.random((2, *x.shape)), self.inertia(t, t_max),
                             self.c1(t, t_max), self.c2(t, t_max), vmax, lower, upper, clip_box)
