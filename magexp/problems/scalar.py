"""The scalar (total-field) calibration problem.

Objective (Ding 2024, eq 17; also its metric, eq 18)

.. math:: \\mathrm{RMS}(\\theta) = \\sqrt{\\frac1N\\sum_i \\big(\\lVert W(\\mathbf r_i - \\mathbf o)\\rVert - B_{a,i}\\big)^2}

A scalar objective cannot see a rotation of ``W``: ``Q W`` gives the same cost for
every orthogonal ``Q``. Only ``W^T W`` and ``o`` (9 numbers) are identifiable.
"""

from __future__ import annotations

import numpy as np

from magexp.problems.base import CalibrationProblem


def normalise(readings: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """``(c, s, u)``: the readings' mean ``c``, RMS distance ``s`` from it, and ``u = (r - c)/s``
    (well-conditioned quadratic features, whatever the reading units)."""
    c = readings.mean(axis=0)
    s = float(np.sqrt(((readings - c) ** 2).sum(axis=1).mean())) or 1.0
    return c, s, (readings - c) / s


def quadratic_features(u: np.ndarray) -> np.ndarray:
    """Features ``[x², y², z², 2xy, 2xz, 2yz, x, y, z, 1]`` of readings ``u`` (N, 3)."""
    x, y, z = u.T
    return np.column_stack([x * x, y * y, z * z, 2 * x * y, 2 * x * z, 2 * y * z, x, y, z, np.ones_like(x)])


class ScalarCalibration(CalibrationProblem):
    """Total-field RMS of the calibrated readings against the reference field.

    ``cost`` evaluates a whole swarm with one matrix product: with the readings
    centred and scaled, ``u = (r - c)/s``, the squared calibrated magnitude
    ``|W (r - o)|² = u^T A u - 2 o'^T A u + o'^T A o'`` (``A = s² W^T W``,
    ``o' = (o - c)/s``) is linear in the ten quadratic features of ``u``, so
    ``(N × 10) @ (10 × n)`` gives every particle's magnitudes at once.
    ``cost_direct`` evaluates the textbook formula and is used for reported numbers.
    """

    objective = "scalar"
    capabilities = CalibrationProblem.capabilities | {"total_field"}

    def __init__(self, dataset, search, *, parameterisation: str = "inverse"):
        super().__init__(dataset, search, parameterisation=parameterisation)
        self._centre, self._scale, u = normalise(dataset.readings)
        self._features = quadratic_features(u)
        self._reference = np.asarray(dataset.reference_norm, float)[:, None]

    def _coefficients(self, thetas: np.ndarray) -> np.ndarray:
        w, o = self.unpack(thetas)
        a = self._scale**2 * np.einsum("nki,nkj->nij", w, w)
        op = (o - self._centre) / self._scale
        ao = np.einsum("nij,nj->ni", a, op)
        return np.column_stack(
            [a[:, 0, 0], a[:, 1, 1], a[:, 2, 2], a[:, 0, 1], a[:, 0, 2], a[:, 1, 2],
             -2 * ao, np.einsum("ni,ni->n", ao, op)]
        )

    def magnitudes(self, thetas: np.ndarray) -> np.ndarray:
        """Calibrated total field of every reading for every particle, shape ``(N, n)``."""
        q = self._features @ self._coefficients(thetas).T
        return np.sqrt(np.maximum(q, 0.0))

    def cost(self, thetas: np.ndarray) -> np.ndarray:
        """Total-field RMS of every particle, ``(n, 12) -> (n,)``."""
        err = self.magnitudes(thetas) - self._reference
        return np.sqrt(np.mean(err * err, axis=0))

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        """``|W (r_i - o)| - B_a,i`` for one parameter vector (direct formula)."""
        return np.linalg.norm(self.calibrate(theta), axis=1) - self.dataset.reference_norm

    def cost_direct(self, theta: np.ndarray) -> float:
        """Total-field RMS of one parameter vector by the direct formula."""
        return float(np.sqrt(np.mean(self.residuals(theta) ** 2)))

    def invariants(self, theta: np.ndarray) -> np.ndarray:
        """What a scalar fit identifies: the 6 entries of ``W^T W`` (upper triangle) and ``o``."""
        w, o = self.unpack(theta)
        g = w[0].T @ w[0]
        return np.concatenate([g[np.triu_indices(3)], o[0]])

    def invariant_bounds(self, theta: np.ndarray, cov: np.ndarray) -> dict:
        w, _ = self.unpack(theta)
        g = w[0].T @ w[0]
        return {"offset_bound": float(np.sqrt(np.trace(cov[-3:, -3:]))),
                # Frobenius norm counts off-diagonal entries twice
                "gram_bound": float(np.sqrt(np.trace(cov[:6, :6]) + cov[[1, 2, 4], [1, 2, 4]].sum())
                                    / np.linalg.norm(g))}
