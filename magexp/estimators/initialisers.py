"""Initial swarm positions in the box ``[lower, upper]``.

An initialiser is called as ``init(n, lower, upper, rng=rng) -> (n, d)``.
"""

from __future__ import annotations

import numpy as np

from magexp.errors import MagexpError


class Uniform:
    """Independent uniform positions (traditional PSO)."""

    def __call__(self, n: int, lower: np.ndarray, upper: np.ndarray, *, rng: np.random.Generator) -> np.ndarray:
        return lower + rng.random((n, lower.size)) * (upper - lower)


def circle_map(z: np.ndarray, form: str = "printed") -> np.ndarray:
    """One step of the Circle chaotic map, element-wise on ``z`` in [0, 1).

    ``printed`` (Ding 2024, eq 15, as printed):

    .. math:: z_{k+1} = \\mathrm{mod}\\big(2 z_k + 0.2 - \\tfrac{0.7}{2\\pi}\\cos(2\\pi z_k + 0.5\\pi),\\ 1\\big)

    ``usual`` (the standard Circle map):

    .. math:: z_{k+1} = \\mathrm{mod}\\big(z_k + 0.2 - \\tfrac{0.5}{2\\pi}\\sin(2\\pi z_k),\\ 1\\big)
    """
    if form == "printed":
        return np.mod(2.0 * z + 0.2 - 0.7 / (2 * np.pi) * np.cos(2 * np.pi * z + 0.5 * np.pi), 1.0)
    if form == "usual":
        return np.mod(z + 0.2 - 0.5 / (2 * np.pi) * np.sin(2 * np.pi * z), 1.0)
    raise MagexpError(f"circle map form={form!r} is not allowed: choose printed or usual")


class CircleMap:
    """Circle-map chaotic initialisation (Ding 2024, sec 2.2.3).

    A random seed ``z_0 ~ U(0, 1)^d`` is iterated ``burn_in`` times, then particle
    ``k`` (k = 1..n) takes the ``k``-th further iterate: ``x_k = lower + z_k (upper - lower)``.
    The map runs along the particles, vectorised over the dimensions.
    """

    def __init__(self, form: str = "printed", burn_in: int = 0):
        circle_map(np.zeros(1), form)  # validates the form
        self.form = form
        self.burn_in = int(burn_in)

    def sequence(self, z0: np.ndarray, n: int) -> np.ndarray:
        """The ``n`` iterates after ``burn_in`` steps from ``z0``, shape ``(n, d)``."""
        z = np.asarray(z0, float)
        for _ in range(self.burn_in):
            z = circle_map(z, self.form)
        out = np.empty((n, z.size))
        for k in range(n):
            z = circle_map(z, self.form)
            out[k] = z
        return out

    def __call__(self, n: int, lower: np.ndarray, upper: np.ndarray, *, rng: np.random.Generator) -> np.ndarray:
        return lower + self.sequence(rng.random(lower.size), n) * (upper - lower)
