"""Velocity rules of the swarm engine: each rule is one kernel.

A rule's kernel gives the new velocity of particle ``i`` in dimension ``j``, before the clamp::

    kernel(i, j, x, v, pbest, g, mean, r, c) -> v_ij

with ``x``, ``v``, ``pbest`` the positions, velocities and personal bests ``(n, d)``, ``g`` the
global best's index (its position is ``pbest[g]``), ``mean`` the mean personal best ``(d,)``
(``M`` of Yuan 2018 eq 13; given only to a rule that ``needs_mean``), ``r`` the rule's random
factors ``(k, n, d)`` and ``c`` its three coefficients at this iteration. It is written once,
with arithmetic and ``[i, j]`` indexing only, and runs two ways, as pyswarms'
``compute_velocity`` is one function per rule:

* compiled (numba), called with integer ``i, j`` for every element inside the engine's loop
  (:func:`magexp.estimators._compiled.engine`);
* in numpy, called once with ``i = j =`` :data:`ALL` (``slice(None)``): ``x[i, j]`` is then the
  whole array and ``pbest[g, j]`` the global best's row, so the same expression computes every
  element at once, with the same IEEE operations in the same order.

A rule is a :class:`VelocityRule` (its attributes: what else the engine needs);
:meth:`VelocityRule.factors` turns the draws into the kernel's random factors in numpy, on whole
blocks of draws, so that both paths use the same ``log``.
"""

from __future__ import annotations

import numpy as np

from magexp.errors import MagexpError
from magexp.estimators.schedules import Constant, values

ALL = slice(None)  #: ``i = j = ALL``: a kernel computes the whole swarm in numpy


def inertia(i, j, x, v, pbest, g, mean, r, c):
    """Global-best PSO velocity with inertia weight (Kennedy & Eberhart 1995; Ding 2024 eq 10).

    .. math:: v_{ij} \\leftarrow w\\,v_{ij} + c_1 r_{1,ij} (p_{ij} - x_{ij}) + c_2 r_{2,ij} (p_{gj} - x_{ij})
    """
    return c[0] * v[i, j] + c[1] * r[0, i, j] * (pbest[i, j] - x[i, j]) + c[2] * r[1, i, j] * (pbest[g, j] - x[i, j])


def check_schedule(schedule, role: str):
    """``schedule`` of the coefficient ``role``, refused if negative."""
    for part in ("value", "start", "end"):
        v = getattr(schedule, part, None)
        if isinstance(v, float) and v < 0:
            raise MagexpError(f"estimator.velocity.{role}.{part}={v:g} is not allowed: it must be a number >= 0 "
                              f"(a negative {role} reverses its term of the velocity update)")
    return schedule


class VelocityRule:
    """What the swarm engine needs of a velocity rule; a new rule subclasses it and sets ``kernel``.

    Attributes
    ----------
    kernel : function
        ``kernel(i, j, x, v, pbest, g, mean, r, c)`` (the module docstring), a ``staticmethod``.
    n_draws : int
        Uniform numbers ``U(0, 1)`` drawn per particle and dimension in one iteration.
    coefficients : tuple of 3 str
        The attributes holding the three coefficients ``c`` (each a schedule ``s(t, t_max)`` or a number).
    needs_mean : bool
        Whether the kernel reads ``mean`` (computed only then: it costs 3 % of a numpy iteration).
    """

    n_draws = 2
    coefficients = ("inertia", "c1", "c2")
    needs_mean = False

    def schedule(self, t: np.ndarray, t_max: int) -> np.ndarray:
        """The coefficients at every time of ``t``."""
        return np.stack([values(getattr(self, name), t, t_max) for name in self.coefficients], axis=1)

    @staticmethod
    def factors(r: np.ndarray) -> np.ndarray:
        """The kernel's random factors from the uniform draws (here: the draws themselves)."""
        return r


class InertiaVelocity(VelocityRule):
    """Inertia-weight velocity (:func:`inertia`) with scheduled ``w``, ``c1``, ``c2``.

    Traditional PSO uses :class:`~magexp.estimators.schedules.Constant` schedules; Ding's IPSO
    uses :class:`~magexp.estimators.schedules.Linear` ones (Ding 2024 eqs 12-14). ``r1, r2 ~
    U(0, 1)`` independently per particle and dimension.

    Parameters
    ----------
    inertia : schedule, optional
        ``w(t, t_max)`` (default: constant 0.7298, Eberhart & Shi 2000).
    c1, c2 : schedule, optional
        Cognitive and social learning factors (default: constant 1.49618 each).
    """

    kernel = staticmethod(inertia)

    def __init__(self, inertia=None, c1=None, c2=None):
        self.inertia = check_schedule(inertia if inertia is not None else Constant(0.7298), "inertia")
        self.c1 = check_schedule(c1 if c1 is not None else Constant(1.49618), "c1")
        self.c2 = check_schedule(c2 if c2 is not None else Constant(1.49618), "c2")
