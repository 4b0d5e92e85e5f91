"""Initial swarm positions in the box ``[lower, upper]``.

An initialiser is called as ``init(n, lower, upper, rng=rng) -> (n, d)``.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from magexp.errors import MagexpError


class Uniform:
    """Independent uniform positions (traditional PSO)."""

    def __call__(self, n: int, lower: np.ndarray, upper: np.ndarray, *, rng: np.random.Generator) -> np.ndarray:
        return lower + rng.random((n, lower.size)) * (upper - lower)


def printed_step(z):
    """Ding 2024 eq 15 as printed, on a float or an array (see :func:`circle_map`)."""
    return np.mod(2.0 * z + 0.2 - 0.7 / (2 * np.pi) * np.cos(2 * np.pi * z + 0.5 * np.pi), 1.0)


def usual_step(z):
    """The standard Circle map, on a float or an array (see :func:`circle_map`)."""
    return np.mod(z + 0.2 - 0.5 / (2 * np.pi) * np.sin(2 * np.pi * z), 1.0)


FORMS = {"printed": printed_step, "usual": usual_step}


def circle_map(z: np.ndarray, form: str = "printed") -> np.ndarray:
    """One step of the Circle chaotic map, element-wise on ``z`` in [0, 1).

    ``printed`` (Ding 2024, eq 15, as printed):

    .. math:: z_{k+1} = \\mathrm{mod}\\big(2 z_k + 0.2 - \\tfrac{0.7}{2\\pi}\\cos(2\\pi z_k + 0.5\\pi),\\ 1\\big)

    ``usual`` (the standard Circle map):

    .. math:: z_{k+1} = \\mathrm{mod}\\big(z_k + 0.2 - \\tfrac{0.5}{2\\pi}\\sin(2\\pi z_k),\\ 1\\big)
    """
    if form not in FORMS:
        raise MagexpError(f"circle map form={form!r} is not allowed: choose printed or usual")
    return FORMS[form](z)


def _numpy_sequence(z0: np.ndarray, n: int, burn_in: int, form: str) -> np.ndarray:
    """:meth:`CircleMap.sequence` in numpy: one vectorised map step per iterate."""
    z = np.asarray(z0, float)
    for _ in range(burn_in):
        z = circle_map(z, form)
    out = np.empty((n, z.size))
    for k in range(n):
        z = circle_map(z, form)
        out[k] = z
    return out


@cache
def _compiled_sequence():
    """The compiled sequence (:func:`magexp.estimators._compiled.circle_sequence`) if numba is on
    and it gives numpy's bits on a probe of both forms (``cos``, ``sin`` and ``mod`` come from
    libraries that could differ between numba and numpy on some machine), else None."""
    from magexp.estimators.swarm import compiled

    nb = compiled()
    if nb is None:
        return None
    z0 = (np.arange(64) + 0.5) / 64
    same = all(np.array_equal(nb.circle_sequence(z0, 40, 3, form == "printed"), _numpy_sequence(z0, 40, 3, form))
               for form in FORMS)
    return nb.circle_sequence if same else None


class CircleMap:
    """Circle-map chaotic initialisation (Ding 2024, sec 2.2.3).

    A random seed ``z_0 ~ U(0, 1)^d`` is iterated ``burn_in`` times, then particle
    ``k`` (k = 1..n) takes the ``k``-th further iterate: ``x_k = lower + z_k (upper - lower)``.
    The map runs along the particles, vectorised over the dimensions (compiled with numba: the
    same numbers, :func:`_compiled_sequence`).
    """

    def __init__(self, form: str = "printed", burn_in: int = 0):
        circle_map(np.zeros(1), form)  # validates the form
        self.form = form
        self.burn_in = int(burn_in)

    def sequence(self, z0: np.ndarray, n: int) -> np.ndarray:
        """The ``n`` iterates after ``burn_in`` steps from ``z0``, shape ``(n, d)``."""
        run = _compiled_sequence()
        if run is None:
            return _numpy_sequence(z0, n, self.burn_in, self.form)
        return run(np.asarray(z0, float), n, self.burn_in, self.form == "printed")

    def __call__(self, n: int, lower: np.ndarray, upper: np.ndarray, *, rng: np.random.Generator) -> np.ndarray:
        return lower + self.sequence(rng.random(lower.size), n) * (upper - lower)
