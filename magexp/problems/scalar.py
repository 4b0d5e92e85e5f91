"""The scalar (total-field) calibration problem.

Objective (Ding 2024, eq 17; also its metric, eq 18)

.. math:: \\mathrm{RMS}(\\theta) = \\sqrt{\\frac1N\\sum_i \\big(\\lVert W(\\mathbf r_i - \\mathbf o)\\rVert - B_{a,i}\\big)^2}

A scalar objective cannot see a rotation of ``W``: ``Q W`` gives the same cost for
every orthogonal ``Q``. Only ``W^T W`` and ``o`` (9 numbers) are identifiable.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from magexp.core.ellipsoid import normalise
from magexp.core.metrics import rms
from magexp.problems import kernels
from magexp.problems.base import SCALAR, CalibrationProblem


class ScalarCalibration(CalibrationProblem):
    """Total-field RMS of the calibrated readings against the reference field (Ding 2024 eqs 17-18).

    ``cost`` is the fused swarm cost of :mod:`magexp.problems.kernels` (the ten quadratic features of the
    centred readings, memory ``O(P + N)``); ``cost_direct`` the textbook formula, used for reported numbers.
    """

    objective = "scalar"
    capabilities = CalibrationProblem.capabilities | {"total_field"}

    def __init__(self, dataset, search, *, parameterisation: str = "inverse"):
        super().__init__(dataset, search, parameterisation=parameterisation)
        self._reference = np.ascontiguousarray(dataset.reference_norm, float)

    @cached_property
    def _normalised(self) -> tuple[np.ndarray, float, np.ndarray]:
        """:func:`normalise` of the readings, on the first :meth:`cost` call (a problem built only
        for its residuals, e.g. by :mod:`magexp.core.bounds`, never pays for it)."""
        return normalise(self.dataset.readings)

    @cached_property
    def _swarm_kernel(self) -> tuple | None:
        """The compiled swarm cost's arguments, built once (:meth:`swarm_kernel` returns them)."""
        if self.parameterisation != "inverse" or kernels.compiled() is None:
            return None  # W = S^-1 is inverted by numpy in unpack
        c, s, u = self._normalised
        return SCALAR, u, self._reference.reshape(-1, 1), np.append(c, s)

    @classmethod
    def cost_floats(cls, n_readings: int, n_particles: int) -> int:
        """The fused cost's working memory (:func:`magexp.problems.kernels.working_floats`): ``O(P)``
        compiled, one chunk in numpy; never ``N × P``.
        """
        return kernels.working_floats(n_particles)

    def swarm_kernel(self) -> tuple | None:
        """``(SCALAR, u, B_a (N, 1), [c, s])`` in the inverse parameterisation with numba, else None."""
        return self._swarm_kernel

    def cost(self, thetas: np.ndarray) -> np.ndarray:
        """Total-field RMS of every particle, ``(n, 12) -> (n,)``."""
        if self._swarm_kernel is not None:
            return kernels.swarm_cost(self._swarm_kernel, thetas)
        w, o = self.unpack(thetas)
        return kernels.scalar_cost(w, o, *self._normalised, self._reference)

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        """``|W (r_i - o)| - B_a,i`` for one parameter vector (direct formula)."""
        w, o = self.unpack(theta)
        return kernels.scalar_residuals(w[0], o[0], self.dataset.readings, self._reference)

    def _dr_db(self, b: np.ndarray) -> np.ndarray:
        """``∂r_i/∂b_i = b_i^T / |b_i|`` (``r_i = |b_i| - B_a,i``), ``(N, 1, 3)``."""
        return (b / np.sqrt(np.einsum("ni,ni->n", b, b))[:, None])[:, None, :]

    def cost_direct(self, theta: np.ndarray) -> float:
        """Total-field RMS of one parameter vector by the direct formula: the RMS of :meth:`residuals`,
        :func:`magexp.core.metrics.total_field_rms` with compiled residuals for many readings (the
        ``field_rms`` metric the vector problem adds; here the runs carry it once, as ``fun``).
        """
        return rms(self.residuals(theta))

    def invariants(self, theta: np.ndarray) -> np.ndarray:
        """What a scalar fit identifies: the 6 entries of ``W^T W`` (upper triangle) and ``o``."""
        w, o = self.unpack(theta)
        g = w[0].T @ w[0]
        return np.concatenate([g[np.triu_indices(3)], o[0]])

    def invariant_bounds(self, theta: np.ndarray, cov: np.ndarray) -> dict:
        """Expected error sizes from the CRB covariance of :meth:`invariants`."""
        w, _ = self.unpack(theta)
        g = w[0].T @ w[0]
        return {"offset_bound": float(np.sqrt(np.trace(cov[-3:, -3:]))),
                # Frobenius norm counts off-diagonal entries twice
                "gram_bound": float(np.sqrt(np.trace(cov[:6, :6]) + cov[[1, 2, 4], [1, 2, 4]].sum())
                                    / np.linalg.norm(g))}
