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

from functools import cached_property

import numpy as np

from magexp.core.metrics import rms, total_field_rms, truth_cost
from magexp.problems import kernels
from magexp.problems.base import VECTOR, CalibrationProblem, inverse, reference_vectors


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

    ``cost`` forms each ``e_i = v_i - W (B_i - o)`` as the direct formula does and sums ``|e_i|`` per
    particle in one pass (:func:`magexp.problems.kernels.vector_cost`, memory ``O(P + N)``): a squared-norm
    expansion would cancel terms of hundreds of mG² and keep a swarm from the noise-free optimum.
    """

    objective = "vector"
    #: the columns :meth:`metrics` writes: the calibration's, ``field_rms`` and (with a truth) ``noise_floor``
    METRICS = (*CalibrationProblem.METRICS, "field_rms", "noise_floor")
    objective_is_rms = False  # F is a sum of norms: the RMS floor is not drawn against it

    def __init__(self, dataset, search, *, parameterisation: str = "forward"):
        super().__init__(dataset, search, parameterisation=parameterisation)
        self.reference = reference_vectors(dataset)
        self._readings = np.ascontiguousarray(dataset.readings, float)

    @cached_property
    def _swarm_kernel(self) -> tuple | None:
        """The compiled swarm cost's arguments, built once (:meth:`swarm_kernel` returns them)."""
        if self.parameterisation != "inverse" or kernels.compiled() is None:
            return None  # W = S^-1 is inverted by numpy in unpack
        return VECTOR, self._readings, np.ascontiguousarray(self.reference, float), np.zeros(4)

    @classmethod
    def cost_floats(cls, n_readings: int, n_particles: int) -> int:
        """The fused cost's working memory (:func:`magexp.problems.kernels.working_floats`, three
        components a particle-reading): ``O(P)`` compiled, one chunk in numpy; never ``N × P``.
        """
        return kernels.working_floats(n_particles, rows=3)

    def swarm_kernel(self) -> tuple | None:
        """``(VECTOR, readings, v_i (N, 3), ·)`` in the inverse parameterisation with numba, else None."""
        return self._swarm_kernel

    def cost(self, thetas: np.ndarray) -> np.ndarray:
        """``F`` of every particle, ``(n, 12) -> (n,)``; non-finite values become ``inf``."""
        if self._swarm_kernel is not None:
            return kernels.swarm_cost(self._swarm_kernel, thetas)
        w, o = self.unpack(thetas)
        return kernels.vector_cost(w, o, self._readings, self.reference)

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        """The stacked ``3N`` components of ``C_i H_i - W (r_i - o)`` (for least squares)."""
        return (self.reference - self.calibrate(theta)).ravel()

    def _dr_db(self, b: np.ndarray) -> np.ndarray:
        """``∂e_i/∂b_i = -I`` (``e_i = v_i - b_i``), ``(N, 3, 3)``."""
        return np.broadcast_to(-np.eye(3), (len(b), 3, 3))

    def cost_direct(self, theta: np.ndarray) -> float:
        """``F`` of one parameter vector, reading by reading (eq 8 as printed)."""
        s, b = np.reshape(theta[:9], (3, 3)), theta[9:]
        w = np.linalg.inv(s) if self.parameterisation == "forward" else s
        ds = self.dataset
        return float(sum(np.linalg.norm(c @ h - w @ (r - b)) for c, h, r in zip(ds.attitude, ds.field_nav, ds.readings)))

    def initial_estimate(self) -> np.ndarray:
        """Closed-form first estimate: the linear least squares of the forward model
        (:meth:`LinearVectorModel.least_squares`; the start of ``lm`` with ``start: problem``).
        """
        return self.least_squares()

    def metrics(self, theta: np.ndarray) -> dict:
        """:meth:`CalibrationProblem.metrics`, ``noise_floor`` (``F`` of the true calibration on these readings:
        what a perfect fit reaches) and ``field_rms`` (the total-field RMS, which a vector fit does not minimise)."""
        out = super().metrics(theta)
        out["field_rms"] = total_field_rms(self.calibrate(theta), self.dataset.reference_norm)
        floor = truth_cost(self)  # F at the truth, once per problem
        if floor is not None:
            out["noise_floor"] = floor
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

    @classmethod
    def cost_floats(cls, n_readings: int, n_particles: int) -> int:
        """One chunk of :func:`magexp.problems.kernels.vector_cost_numpy` (always numpy)."""
        return kernels.working_floats(n_particles, rows=3, fused=False)

    def cost(self, thetas: np.ndarray) -> np.ndarray:
        """RMS of every particle's residual components, ``(n, 12) -> (n,)``; non-finite -> ``inf``."""
        w, o = self.unpack(thetas)
        with np.errstate(invalid="ignore", over="ignore"):
            f = np.sqrt(kernels.vector_cost_numpy(w, o, self._readings, self.reference, squared=True)
                        / (3 * len(self._readings)))
        return np.where(np.isfinite(f), f, np.inf)

    def cost_direct(self, theta: np.ndarray) -> float:
        """RMS of the residual components of one parameter vector."""
        return rms(self.residuals(theta))
