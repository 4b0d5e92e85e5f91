"""Boundary handling of the swarm engine: what happens to a particle that leaves the search box.

A strategy is called as ``handle(x, v, lower, upper, rng=rng) -> (x, v)`` with the unconstrained
new positions ``x = x_old + v`` (n, d) and returns positions inside ``[lower, upper]`` and the
velocities to carry on with. Element-wise, vectorised over the swarm. Names
(Helwig, Branke & Mostaghim 2013, *Experimental analysis of bound handling techniques in
particle swarm optimization*, IEEE TEVC 17(2)):

* ``clip`` (the textbook "nearest" rule; Ding 2024's "positions clipped to the bounds"):
  :math:`x \\leftarrow \\min(\\max(x, l), u)`, velocity unchanged. A particle pushed outward sits
  on the face, so a swarm attracted outward collapses onto the boundary.
* ``reflect``: the excess is mirrored back into the box (any number of widths ``w = u - l``),
  :math:`x \\leftarrow u - |\\,((x - l) \\bmod 2w) - w\\,|`, and the velocity component reversed
  (``v <- -v``) where it left.
* ``random``: a coordinate that left is redrawn uniformly in ``[l, u]`` and its velocity set to
  zero (random re-entry).
"""

from __future__ import annotations

import numpy as np

from magexp.errors import MagexpError


def clip(x, v, lower, upper, *, rng):
    """Clip to the box; velocity unchanged."""
    return np.clip(x, lower, upper), v


def reflect(x, v, lower, upper, *, rng):
    """Mirror the excess back into the box (any number of widths); reverse the velocity where it left."""
    width = upper - lower
    y = np.mod(x - lower, 2.0 * width)
    inside = lower + np.where(y <= width, y, 2.0 * width - y)
    left = (x < lower) | (x > upper)
    return inside, np.where(left, -v, v)


def random_reentry(x, v, lower, upper, *, rng):
    """Redraw a coordinate that left uniformly in its range, with zero velocity."""
    left = (x < lower) | (x > upper)
    fresh = lower + rng.random(x.shape) * (upper - lower)
    return np.where(left, fresh, x), np.where(left, 0.0, v)


BOUNDARIES = {"clip": clip, "reflect": reflect, "random": random_reentry}


def boundary(name: str):
    """The strategy called ``name``."""
    if name not in BOUNDARIES:
        raise MagexpError(f"estimator.boundary={name!r} is not allowed: choose one of {', '.join(BOUNDARIES)}")
    return BOUNDARIES[name]
