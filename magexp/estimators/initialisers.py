"""Initial swarm positions in the box ``[lower, upper]``.

An initialiser is called as ``init(n, lower, upper, rng=rng) -> (n, d)``.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from magexp.core.limits import refuse_over
from magexp.errors import check_positive_int
from magexp.estimators.circle import FORMS, circle_map
from magexp.problems import kernels


class Uniform:
    """Independent uniform positions (traditional PSO)."""

    def __call__(self, n: int, lower: np.ndarray, upper: np.ndarray, *, rng: np.random.Generator) -> np.ndarray:
        """Draw ``n`` positions ``lower + U(0, 1) (upper - lower)``.

        Parameters
        ----------
        n : int
            Particles.
        lower, upper : numpy.ndarray
            The box (d,).
        rng : numpy.random.Generator
            The run's estimator stream.

        Returns
        -------
        numpy.ndarray
            ``(n, d)`` positions in the box.
        """
        return lower + rng.random((n, lower.size)) * (upper - lower)


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
    if kernels.compiled() is None:  # numba off or absent
        return None
    # lazy: _compiled imports numba at its top (205 ms CPU to import, min of 5, after numpy), which a numpy-only run
    # must not pay for nor fail on; reached only once kernels.compiled() has loaded numba
    from magexp.estimators import _compiled as nb

    z0 = (np.arange(64) + 0.5) / 64
    same = all(np.array_equal(nb.circle_sequence(z0, 40, 3, form == "printed"), _numpy_sequence(z0, 40, 3, form))
               for form in FORMS)
    return nb.circle_sequence if same else None


class CircleMap:
    """Circle-map chaotic initialisation (Ding 2024, sec 2.2.3).

    .. math:: z_{n+1} = \\mathrm{mod}(2 z_n + 0.2 - \\tfrac{0.7}{2\\pi}\\cos(2\\pi z_n + 0.5\\pi), 1)

    (Ding 2024 eq 15 as printed; ``form: usual`` the usual circle map). A random seed
    ``z_0 ~ U(0, 1)^d`` is iterated ``burn_in`` times, then particle
    ``k`` (k = 1..n) takes the ``k``-th further iterate: ``x_k = lower + z_k (upper - lower)``.
    The map runs along the particles, vectorised over the dimensions (compiled with numba: the
    same numbers, :func:`_compiled_sequence`).

    Parameters
    ----------
    form : str
        ``printed`` (Ding 2024 eq 15 as printed) or ``usual`` (:func:`~magexp.estimators.circle.circle_map`).
    burn_in : int
        Map steps before the first particle's iterate, >= 0.

    References
    ----------
    Ding 2024, Digital Ocean & Underwater Warfare 7(3):285-292, sec 2.2.3, eq 15.
    """

    def __init__(self, form: str = "printed", burn_in: int = 0):
        circle_map(np.zeros(1), form)  # validates the form
        self.form = form
        self.burn_in = check_positive_int(burn_in, "estimator.init.burn_in", minimum=0)
        refuse_over(self.burn_in, "run_work", f"estimator.init.burn_in={burn_in!r}", "its steps of the map are")

    def sequence(self, z0: np.ndarray, n: int) -> np.ndarray:
        """The ``n`` iterates after ``burn_in`` steps.

        Parameters
        ----------
        z0 : numpy.ndarray
            The seed ``(d,)`` in [0, 1).
        n : int
            Iterates.

        Returns
        -------
        numpy.ndarray
            ``(n, d)``.
        """
        run = _compiled_sequence()
        if run is None:
            return _numpy_sequence(z0, n, self.burn_in, self.form)
        return run(np.asarray(z0, float), n, self.burn_in, self.form == "printed")

    def __call__(self, n: int, lower: np.ndarray, upper: np.ndarray, *, rng: np.random.Generator) -> np.ndarray:
        """Draw the seed ``z_0`` from ``rng`` and place particle ``k`` at the ``k``-th iterate.

        Parameters
        ----------
        n, lower, upper, rng
            As :meth:`Uniform.__call__` (``z_0`` drawn from ``rng``).

        Returns
        -------
        numpy.ndarray
            ``(n, d)`` positions in the box, on the map's orbit.
        """
        return lower + self.sequence(rng.random(lower.size), n) * (upper - lower)
