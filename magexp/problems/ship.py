"""Yan & Zhou 2022: a ship's magnetization parameters ``K`` and ``Bp`` from known ``Be`` and attitudes.

Model (eq 1): :math:`\\mathbf B_i = \\mathbf K\\mathbf A_i\\mathbf B_e + \\mathbf B_p`, the forward form of
the vector problem (Yuan 2018 eq 1 with ``S = K``, ``b = Bp``, ``u_i = A_i Be``): every reading is one row
of ``Y = C x`` with ``C_i = [Be^T A_i^T, 1]`` (eq 6), and the design, least squares and the state <->
parameter maps come from :class:`~magexp.problems.vector.LinearVectorModel`; only the objective differs
(here the RMS of the forward residuals, there Yuan's eq 8). In the ``forward`` parameterisation of
:class:`~magexp.problems.base.CalibrationProblem`, :meth:`~magexp.problems.base.CalibrationProblem.calibrate` returns
``K^-1 (B - Bp) = A Be``, the ambient field in the ship frame.
"""

from __future__ import annotations

import numpy as np

from magexp.core.metrics import rms
from magexp.problems.base import CalibrationProblem
from magexp.problems.vector import LinearVectorModel, theta_to_state


class ShipMagnetization(LinearVectorModel, CalibrationProblem):
    """Fit residual of ``B = K A Be + Bp`` (Yan 2022 eqs 1-2): ``cost`` the RMS of the ``3N`` components of ``C x - Y``.

    The swarm cost does not depend on ``N``: with ``C = Q R`` (thin QR) and ``Z = Q^T Y``, Pythagoras
    splits off the least-squares residual ``rho`` no particle can change,

    .. math:: \\mathrm{cost}(x) = \\sqrt{\\tfrac{1}{3N}\\big(\\lVert R x - Z\\rVert_F^2 + \\rho\\big)},\\qquad
              \\rho = \\lVert (I - Q Q^T) Y\\rVert_F^2

    and ``vec(R x)`` is linear in ``theta`` (one ``(n × 12) @ (12 × 12)`` product for the swarm). Both
    terms are sums of squares, so nothing cancels (the Gram expansion ``tr(x^T C^T C x) - 2 tr(x^T C^T Y)
    + ||Y||^2`` would subtract numbers of ``||Y||^2`` and lose the noise-free optimum to rounding).
    """

    objective = "ship"
    #: its 12 parameters (``theta``'s order): ``K11``...``K33``, ``Bp1``...``Bp3``
    PARAMETERS = {"forward": (*(f"K{i + 1}{j + 1}" for i in range(3) for j in range(3)),
                              *(f"Bp{i + 1}" for i in range(3)))}
    #: the columns :meth:`metrics` writes (the errors with a known truth); each parameter's estimate, and its
    #: ``truth_<parameter>`` with a known truth
    METRICS = ("fit_rms", "ls_fit_rms", "k_vs_ls", "bp_vs_ls", "k_error", "bp_error", "offset_error")
    PARAMETER_METRICS = ("truth_",)

    def __init__(self, dataset, search):
        super().__init__(dataset, search, parameterisation="forward")
        self.options = {}  # constructor options (none: the parameterisation is fixed)
        self._c, self._y = self.design()  # rows [Be^T A_i^T, 1] (measured attitude), readings
        q, r = np.linalg.qr(self._c)
        z = q.T @ self._y
        self._floor = float(np.sum((self._y - q @ z) ** 2))  # rho: the least-squares residual
        self._map = (r @ theta_to_state(np.eye(self.n_params))).reshape(self.n_params, -1)  # theta -> vec(R x)
        self._target = z.ravel()  # vec(Z)

    def predict(self, thetas: np.ndarray) -> np.ndarray:
        """Modelled readings ``C x`` for every particle, shape ``(n, N, 3)``."""
        return np.einsum("ij,njk->nik", self._c, theta_to_state(thetas))

    @classmethod
    def cost_floats(cls, n_readings: int, n_particles: int) -> int:
        """48 float64 numbers per particle, whatever the readings (``R x - Z`` and its squares;
        tracemalloc's peak of one call: 37 to 39 a particle, 50 and 200 particles).
        """
        return 48 * n_particles

    def cost(self, thetas: np.ndarray) -> np.ndarray:
        """Fit residual RMS of every particle, ``(n, 12) -> (n,)`` (class docstring: QR form)."""
        d = np.atleast_2d(thetas) @ self._map - self._target
        return np.sqrt((np.einsum("nk,nk->n", d, d) + self._floor) / self._y.size)

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        """``K A_i Be + Bp - B_i`` for every reading, stacked (3N,), by eq 1 directly."""
        k, bp = np.asarray(theta[:9], float).reshape(3, 3), np.asarray(theta[9:], float)
        body = np.einsum("nij,nj->ni", self.dataset.attitude, self.dataset.field_nav)
        return (body @ k.T + bp - self._y).ravel()

    def jacobians(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(J, G)`` of :meth:`residuals` (linear: independent of ``theta``): ``J`` ``(3N, 12)``
        with ``∂r_i/∂K_jk = e_j (A_i Be)_k`` and ``∂r_i/∂Bp = I``; ``G_i = ∂r_i/∂B_i = -I``.
        """
        body = self._c[:, :3]  # (A_i Be)^T, the regressors of eq 6
        n = len(body)
        jac = np.zeros((n, 3, 12))
        jac[:, :, :9].reshape(n, 3, 3, 3)[:, [0, 1, 2], [0, 1, 2], :] = body[:, None, :]
        jac[:, :, 9:] = np.eye(3)
        return jac.reshape(3 * n, 12), np.broadcast_to(-np.eye(3), (n, 3, 3))

    def cost_direct(self, theta: np.ndarray) -> float:
        """Fit residual RMS (nT) of one parameter vector."""
        return rms(self.residuals(theta))

    def metrics(self, theta: np.ndarray) -> dict:
        """``fit_rms`` (nT); the estimate per parameter (``K11``...``Bp3``); its distance to the
        least-squares solution (``k_vs_ls`` max abs, ``bp_vs_ls`` max abs nT) and ``ls_fit_rms``;
        with a known truth ``k_error`` (max abs), ``bp_error`` (max abs, nT) and ``truth_<name>``.
        """
        theta = np.asarray(theta, float)
        ls = self.least_squares()
        names = self.parameter_names()
        out = {"fit_rms": self.cost_direct(theta), "ls_fit_rms": self.cost_direct(ls),
               "k_vs_ls": float(np.max(np.abs(theta[:9] - ls[:9]))),
               "bp_vs_ls": float(np.max(np.abs(theta[9:] - ls[9:]))), **dict(zip(names, map(float, theta)))}
        truth = self.truth_theta()
        if truth is not None:
            out.update({"k_error": float(np.max(np.abs(theta[:9] - truth[:9]))),
                        "bp_error": float(np.max(np.abs(theta[9:] - truth[9:]))),
                        "offset_error": float(np.linalg.norm(theta[9:] - truth[9:])),  # as every problem
                        **{f"truth_{n}": float(v) for n, v in zip(names, truth)}})
        return out
