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

from magexp.problems.base import CalibrationProblem, inverse, reference_vectors


def state_to_theta(x: np.ndarray) -> np.ndarray:
    """Forward ``theta = [vec(S) (row-major), b]`` (..., 12) from linear states ``x = [S b]^T`` (..., 4, 3)."""
    x = np.asarray(x, float)
    k = np.swapaxes(x[..., :3, :], -1, -2)
    return np.concatenate([k.reshape(*x.shape[:-2], 9), x[..., 3, :]], axis=-1)


def theta_to_state(thetas: np.ndarray) -> np.ndarray:
    """Linear states (n, 4, 3) from forward ``thetas`` (n, 12): the inverse of :func:`state_to_theta`."""
    thetas = np.atleast_2d(np.asarray(thetas, float))
    k = thetas[:, :9].reshape(-1, 3, 3)
    return np.concatenate([np.swapaxes(k, 1, 2), thetas[:, None, 9:]], axis=1)


class LinearVectorModel:
    """The forward vector model, linear in its parameters (capability ``linear_design``).

    Yuan 2018 eq 1 and Yan & Zhou 2022 eq 1 are one model: with the reference vector
    ``u_i = C_i H_i`` (Yuan: gyro attitude times the nav field; Yan: ``A_i Be``),

    .. math:: \\mathbf B_i = S\\,\\mathbf u_i + \\mathbf b,\\qquad
              \\mathbf y_i = \\mathbf B_i^T = [\\mathbf u_i^T,\\ 1]\\,\\mathbf x,\\qquad
              \\mathbf x = [S\\ \\mathbf b]^T\\ (4\\times3)

    (Yan's ``K``, ``Bp`` are ``S``, ``b``). Every reading is one row of ``Y = C x``: the Kalman
    filters, the EKF and least squares use :meth:`design`, and :meth:`from_linear` turns a state
    ``x`` into the problem's own parameter vector (``forward``: ``[vec(S), b]``; ``inverse``:
    ``[vec(S^-1), b]``). Mixed into a :class:`~magexp.problems.base.CalibrationProblem`.
    """

    capabilities = CalibrationProblem.capabilities | {"linear_design"}

    def design(self) -> tuple[np.ndarray, np.ndarray]:
        """Regressors ``C`` (N, 4) with rows ``[u_i^T, 1]`` and observations ``Y`` (N, 3), the readings."""
        if getattr(self, "_design", None) is None:
            u = reference_vectors(self.dataset)
            self._design = (np.column_stack([u, np.ones(len(u))]), np.asarray(self.dataset.readings, float))
        return self._design

    def from_linear(self, states: np.ndarray) -> np.ndarray:
        """The problem's parameter vectors (..., 12) from linear states ``x`` (..., 4, 3)."""
        theta = state_to_theta(states)
        if self.parameterisation == "forward":
            return theta
        lead = theta.shape[:-1]
        w = inverse(theta[..., :9].reshape(-1, 3, 3)).reshape(*lead, 9)
        return np.concatenate([w, theta[..., 9:]], axis=-1)

    def least_squares(self) -> np.ndarray:
        """``theta`` minimising ``||C x - Y||_F`` (``numpy.linalg.lstsq``, columns scaled to unit norm)."""
        c, y = self.design()
        scale = np.linalg.norm(c, axis=0)
        scale[scale == 0] = 1.0
        return self.from_linear(np.linalg.lstsq(c / scale, y, rcond=None)[0] / scale[:, None])


class VectorCalibration(LinearVectorModel, CalibrationProblem):
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
        """Closed-form first estimate: the linear least squares of the forward model
        (:meth:`LinearVectorModel.least_squares`; the start of ``lm`` with ``start: problem``)."""
        return self.least_squares()

    def metrics(self, theta: np.ndarray) -> dict:
        out = super().metrics(theta)
        truth = self.truth_theta()
        if truth is not None:
            out["noise_floor"] = self.cost_direct(truth)
        return out



class VectorLeastSquares(VectorCalibration):
    """The residuals of eq 8 in least squares (objective ``vector_ls``): the same model and data as
    :class:`VectorCalibration`, with the RMS of the ``3N`` residual components as the cost

    .. math:: \\mathrm{RMS}(S, \\mathbf b) = \\sqrt{\\frac{1}{3N}\\sum_{i=1}^N
              \\big\\lVert C_i^b \\mathbf H_i - S^{-1}(\\mathbf B_{b,i} - \\mathbf b)\\big\\rVert^2}

    instead of their sum of norms, so an optimiser can be compared on both objectives
    (``experiments/benchmark/benchmark_objective.yaml``): under Gaussian noise this is the
    maximum-likelihood criterion that ``lm`` minimises, eq 8 is not.
    """

    objective = "vector_ls"
    objective_is_rms = True

    def cost(self, thetas: np.ndarray) -> np.ndarray:
        """RMS of every particle's residual components, ``(n, 12) -> (n,)``; non-finite -> ``inf``."""
        with np.errstate(invalid="ignore", over="ignore"):
            err = self.residual_swarm(thetas)
            f = np.sqrt(np.einsum("nkj,nkj->n", err, err) / err[0].size)
        return np.where(np.isfinite(f), f, np.inf)

    def cost_direct(self, theta: np.ndarray) -> float:
        """RMS of the residual components of one parameter vector."""
        return float(np.sqrt(np.mean(self.residuals(theta) ** 2)))
