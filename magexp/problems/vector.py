"""The vector calibration problem of Yuan 2018 (eq 8), gyro-aided.

.. math:: F(S, \\mathbf b) = \\sum_{i=1}^N \\big\\lVert C_i^b \\mathbf H_i - S^{-1}(\\mathbf B_{b,i} - \\mathbf b)\\big\\rVert

``C_i^b`` is the attitude the estimator may use (``Dataset.attitude``, gyro-integrated)
and ``H_i`` the nav-frame field of each reading (``Dataset.field_nav``). Unlike the
scalar objective, ``F`` sees every component, so all 12 parameters are identifiable
when the reference vectors ``C_i^b H_i`` are not coplanar. If they lie in one plane
(one turn about one axis: ``(C_i^b H_i)_z`` constant), ``S`` times that constant
component and ``b`` enter only as their sum: one column of ``S`` and ``b`` cannot be
separated (Yuan's rotation mode 4).
"""

from __future__ import annotations

import numpy as np

from magexp.problems.base import CalibrationProblem, reference_vectors


class VectorCalibration(CalibrationProblem):
    """Sum of vector-residual norms against the gyro reference (Yuan 2018, eq 8).

    ``cost`` evaluates a whole swarm with one matrix product. Each component of a residual,

    .. math:: \\mathbf e_i = \\mathbf v_i - W\\mathbf B_i + W\\mathbf o,\\qquad
              e_{ij} = [\\mathbf B_i^T,\\ 1,\\ \\mathbf v_i^T]\\,
                       [-W_{j\\cdot},\\ (W\\mathbf o)_j,\\ \\mathbf u_j^T]^T

    (``v_i = C_i H_i``, ``u_j`` the j-th unit vector), is the inner product of the reading's
    seven features with seven coefficients of the particle, so ``(3n × 7) @ (7 × N)`` gives
    every residual component of every particle; ``F = sum_i sqrt(e_i . e_i)`` follows.
    Each component is formed as in the direct formula (no squared-norm expansion), so
    ``F`` is exact to rounding even at a noise-free optimum where it is ~1e-11 mG.

    Measured (``python -m magexp.bench``, population 50, 300 readings, one BLAS thread):
    1.5e8 to 1.9e8 particle-readings/s against 1.5e7 to 1.7e7 for the batched ``einsum`` of
    :meth:`calibrated_swarm` (about 10x); largest relative difference from :meth:`cost_direct`
    ~3e-15 on random particles, rounding (~1e-12 mG) at a noise-free truth. The expansion
    ``|v|² - 2 v^T W B + 2 v^T W o + |W(B - o)|²`` (features ``v ⊗ B``, ``v``, ``|v|²`` and the
    scalar quadratic features, one ``(N × 23) @ (23 × n)`` product) was slower (~1.6e8)
    and inexact: relative error ~1e-10 with 0.45 mG noise, and ``F`` at the noise-free
    truth ~1e-3 mG instead of ~3e-11 mG (the terms of hundreds of mG² cancel), so the
    swarm could not reach the noise-free optimum.

    ``cost_direct`` is the textbook loop over readings.
    ``metrics`` sets ``noise_floor`` to ``F`` of the true calibration on the same
    readings (what a perfect fit reaches), since the scalar floor does not apply.
    """

    objective = "vector"
    objective_is_rms = False  # F is a sum of norms: the RMS floor is not drawn against it

    def __init__(self, dataset, search, *, parameterisation: str = "forward"):
        super().__init__(dataset, search, parameterisation=parameterisation)
        self.reference = reference_vectors(dataset)
        # the features [B_i, 1, v_i] of every reading, one column per reading: (7, N)
        self._features = np.column_stack([dataset.readings, np.ones(len(self.reference)), self.reference]).T.copy()

    def calibrated_swarm(self, thetas: np.ndarray) -> np.ndarray:
        """``W (r_i - o)`` of every particle and reading, shape ``(n, N, 3)`` (batched ``einsum``)."""
        w, o = self.unpack(thetas)
        return np.einsum("nij,nkj->nki", w, self.dataset.readings[None, :, :] - o[:, None, :])

    def residual_swarm(self, thetas: np.ndarray) -> np.ndarray:
        """``C_i H_i - W (r_i - o)`` of every particle, component and reading, shape ``(n, 3, N)``.

        One matrix product of the particles' coefficients ``[-W, W o, I]`` (3n × 7) with the
        readings' features ``[B_i, 1, v_i]`` (7 × N).
        """
        w, o = self.unpack(thetas)
        n = len(w)
        coef = np.concatenate([-w, np.einsum("nij,nj->ni", w, o)[:, :, None],
                               np.broadcast_to(np.eye(3), (n, 3, 3))], axis=2)
        return (coef.reshape(3 * n, 7) @ self._features).reshape(n, 3, -1)

    def cost(self, thetas: np.ndarray) -> np.ndarray:
        """``F`` of every particle, ``(n, 12) -> (n,)``; non-finite values become ``inf``."""
        with np.errstate(invalid="ignore", over="ignore"):
            err = self.residual_swarm(thetas)
            f = np.sqrt(np.einsum("nkj,nkj->nj", err, err)).sum(axis=1)
        return np.where(np.isfinite(f), f, np.inf)

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        """The stacked ``3N`` components of ``C_i H_i - W (r_i - o)`` (for least squares)."""
        return (self.reference - self.calibrate(theta)).ravel()

    def cost_direct(self, theta: np.ndarray) -> float:
        """``F`` of one parameter vector, reading by reading (eq 8 as printed)."""
        s, b = np.reshape(theta[:9], (3, 3)), theta[9:]
        w = np.linalg.inv(s) if self.parameterisation == "forward" else s
        ds = self.dataset
        return float(sum(np.linalg.norm(c @ h - w @ (r - b)) for c, h, r in zip(ds.attitude, ds.field_nav, ds.readings)))

    def initial_estimate(self) -> np.ndarray:
        """Closed-form first estimate: ``B_i = S u_i + b`` (``u_i = C_i H_i``) is linear in
        ``(S, b)``, so ordinary least squares on ``[u_i, 1]`` gives ``S`` and ``b`` at once
        (the start of ``lm`` with ``start: problem``)."""
        design = np.column_stack([self.reference, np.ones(len(self.reference))])
        coef = np.linalg.lstsq(design, self.dataset.readings, rcond=None)[0]  # (4, 3)
        s, b = coef[:3].T, coef[3]
        return self.pack(np.linalg.pinv(s), b)

    def metrics(self, theta: np.ndarray) -> dict:
        out = super().metrics(theta)
        truth = self.truth_theta()
        if truth is not None:
            out["noise_floor"] = self.cost_direct(truth)
        return out

