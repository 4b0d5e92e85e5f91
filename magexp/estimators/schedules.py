"""Time-varying coefficients of the swarm update (inertia and learning factors).

A schedule is called as ``schedule(t, t_max)`` with the iteration number
``t = 1..t_max`` and returns a float; called with an integer array ``t`` it returns the values
of every iteration at once (element-wise the same floats, :func:`values`).
"""

from __future__ import annotations

import numpy as np

from magexp.errors import MagexpError


def values(schedule, t: np.ndarray, t_max: int) -> np.ndarray:
    """``schedule`` at every iteration of ``t`` in one vectorised call: the same floats as one call per ``t_k``
    (the same IEEE operations, each exact ``int -> float`` conversion included)."""
    out = schedule(t, t_max) if callable(schedule) else schedule
    return out if isinstance(out, np.ndarray) else np.full(t.shape, out, float)  # a constant: one float


def _number(value, name: str) -> float:
    """``value`` as a finite float, else one line naming ``name``: a schedule refuses what is not a number."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise MagexpError(f"{name}={value!r} is not allowed: it must be a finite number") from None
    if v != v or abs(v) == float("inf"):
        raise MagexpError(f"{name}={value!r} is not allowed: it must be a finite number")
    return v


class Constant:
    """A fixed coefficient (traditional PSO)."""

    def __init__(self, value: float):
        self.value = _number(value, "schedule value")

    def __call__(self, t: int, t_max: int) -> float:
        """The coefficient, whatever the iteration."""
        return self.value


class Linear:
    """Linear change from ``start`` (t = 0) to ``end`` (t = t_max).

    .. math:: s(t) = s_{start} + (s_{end} - s_{start})\\,t / t_{max}

    With ``start = w_max, end = w_min`` this is Ding 2024 eq 12,
    ``w = w_min + (w_max - w_min)(iter_max - iter)/iter_max``; with
    ``c1: start = c1_max, end = c1_min`` and ``c2: start = c2_min, end = c2_max``
    it is eqs 13-14.

    Parameters
    ----------
    start, end : float
        The values at ``t = 0`` and ``t = t_max``, finite.
    """

    def __init__(self, start: float, end: float):
        self.start = _number(start, "schedule start")
        self.end = _number(end, "schedule end")

    def __call__(self, t: int, t_max: int) -> float:
        """``s(t)``.

        Parameters
        ----------
        t : int or numpy.ndarray
            Iteration(s).
        t_max : int
            The last iteration.

        Returns
        -------
        float or numpy.ndarray
        """
        return self.start + (self.end - self.start) * t / t_max
