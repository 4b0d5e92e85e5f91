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

from magexp.problems import kernels
from magexp.problems.base import CalibrationProblem, reference_vectors


class VectorCalibration(CalibrationProblem):
    """Sum of vector-residual norms against the gyro reference (Yuan 2018, eq 8).

    ``cost`` evaluates a whole swarm in one pass over the readings
    (:func:`magexp.problems.kernels.vector_cost`): each particle-reading forms the three
    components of ``e_i = v_i - W (B_i - o)`` (``v_i = C_i H_i``) as in the direct formula and adds
    ``sqrt(e_i . e_i)`` to the particle's sum; memory is ``O(P + N)``. No squared-norm expansion:
    ``|v|² - 2 v^T W B + 2 v^T W o + |W(B - o)|²`` would cancel terms of hundreds of mG² and put
    ``F`` at the noise-free truth near 1e-3 mG instead of rounding, so a swarm could not reach the
    noise-free optimum.

    ``cost_direct`` is the textbook loop over readings.
    ``metrics`` sets ``noise_floor`` to ``F`` of the true calibration on the same
    readings (what a perfect fit reaches), since the scalar floor does not apply.
    """

    objective = "vector"
    objective_is_rms = False  # F is a sum of norms: the RMS floor is not drawn against it

    def __init__(self, dataset, search, *, parameterisation: str = "forward"):
        super().__init__(dataset, search, parameterisation=parameterisation)
        self.reference = reference_vectors(dataset)
        self._readings = np.ascontiguousarray(dataset.readings, float)

    def cost(self, thetas: np.ndarray) -> np.ndarray:
        """``F`` of every particle, ``(n, 12) -> (n,)``; non-finite values become ``inf``."""
        w, o = self.unpack(thetas)
        return kernels.vector_cost(w, o, self._readings, self.reference)

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

