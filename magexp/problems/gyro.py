"""Gyro-aided vector calibration with an unknown field and an unknown gyroscope bias (Yuan 2018, sec 4, on
a real IMU whose field direction and gyro bias are not known).

Yuan 2018's eq 8 with the attitude integrated from a biased gyroscope and the field direction
in the starting frame unknown:

.. math:: F_g(S, \\mathbf b, \\mathbf h, \\mathbf b_g) = \\sum_{j=1}^M
          \\big\\lVert R_j(\\mathbf b_g)^\\top \\mathbf h - S^{-1}(\\mathbf B_j - \\mathbf b)\\big\\rVert

* ``R_j(b_g)`` (body -> start frame at reading ``j``) is the gyro stream, less the bias ``b_g``,
  integrated at the magnetometer's times (:func:`magexp.core.geometry.preintegrate`: with a first-order
  bias Jacobian per pair of readings, a new bias costs a prefix scan, not a re-integration);
* ``h = F [cos e cos a, cos e sin a, sin e]`` is the field in the starting frame (the body frame at the
  first reading); ``F`` cannot be told from the scale of ``S`` (``S -> k S``, ``h -> h / k`` fit equally),
  so it is fixed to the dataset's reference total and only the direction ``(a, e)`` is estimated;
* ``S`` absorbs every linear map between the magnetometer's and the gyroscope's axes (their
  misalignment, and a reflection if the axis conventions differ).

Parameters (17): ``θ = [vec(S) (9, row-major), b (3), a, e (rad), b_g (3, deg/s)]``.

Closed-form start (:meth:`GyroAidedCalibration.projected_start`, ``magexp calibrate``'s): the ellipsoid
fit gives ``W = Q P`` up to the rotation ``Q`` and ``u_j = P (B_j - b)``; with the attitude ``R_j`` at zero
bias every reading says ``R_j Q u_j = h``, linear in ``vec(Q)``. Eliminating ``h`` (the mean of ``R_j Q u_j``),

.. math:: \\min_{\\lVert \\operatorname{vec} Q \\rVert = 1} \\sum_j \\big\\lVert (A_j - \\bar A) \\operatorname{vec} Q \\big\\rVert^2,
          \\qquad A_j \\operatorname{vec} Q = R_j Q \\mathbf u_j,

is the smallest eigenvector of ``Σ (A_j - Ā)ᵀ (A_j - Ā)``, projected onto the nearest proper rotation
(SVD; Wahba's problem with the field unknown, Markley 1988). No iteration, so no local minimum of a
rotation search (an iterative start from ``Q = I`` stalled on a recording with most readings held out).

Rotation modes: turns about one body axis only leave the component of ``h`` along that axis
constant in the body frame, so as in Yuan's mode 4 the column of ``S`` along it cannot be told
from ``b``, and the bias about the other axes trades against the field direction.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from magexp.core.ellipsoid import fit_ellipsoid
from magexp.core.geometry import attitude_with_bias, exp_so3
from magexp.core.identifiability import canonical, identifiability, spread
from magexp.core.metrics import total_field_rms
from magexp.errors import check
from magexp.core.marquardt import minimise_numpy, stacked_jacobian
from magexp.problems.base import CalibrationProblem

#: the starts of :meth:`GyroAidedCalibration.initial_estimate`
STARTS = ("two-stage", "projected")
#: the projected problem's Levenberg-Marquardt (:meth:`GyroAidedCalibration.initial_estimate`): tolerance and evaluations
PROJECTED_TOL, PROJECTED_NFEV = 1e-10, 100
EXTRA = ("field_azimuth", "field_elevation", "gyro_bias_x", "gyro_bias_y", "gyro_bias_z")


class GyroAidedCalibration(CalibrationProblem):
    """Yuan 2018 eq 8 over ``[vec(S), b, field direction, gyro bias]`` (module docstring), on the
    ``dataset.extra["preintegration"]`` of :func:`magexp.core.geometry.preintegrate`; ``search`` bounds
    ``S`` and ``b``, the gyro bias ``±bias_bound_deg_s`` (deg/s); ``start`` is :meth:`initial_estimate`'s.
    """

    objective = "gyro"
    objective_is_rms = False
    #: its 17 parameters (:meth:`pack_all`'s order): the 12 of the calibration, then :data:`EXTRA`
    PARAMETERS = {p: names + EXTRA for p, names in CalibrationProblem.PARAMETERS.items()}
    #: the columns :meth:`metrics` writes (``gyro_bias_rest_*`` and ``gyro_bias_difference`` with a rest recording)
    METRICS = ("fg", "field_rms", "vector_residual_fraction", "spread_after", *EXTRA,
               *(f"gyro_bias_rest_{a}" for a in "xyz"), "gyro_bias_difference", "field_azimuth_deg",
               "field_elevation_deg", "condition_number", "weakest_relative_sv", "weakest_combination")
    PARAMETER_METRICS = ("se_",)
    n_params = 17

    def __init__(self, dataset, search, *, parameterisation: str = "forward", bias_bound_deg_s: float = 10.0,
                 start: str = "two-stage"):
        super().__init__(dataset, search, parameterisation=parameterisation)
        check(start in STARTS, f"start={start!r} is not allowed for the gyro-aided problem: choose one of {', '.join(STARTS)}")
        self.start = start
        self.options = {"parameterisation": parameterisation, "bias_bound_deg_s": bias_bound_deg_s,
                        **({"start": start} if start != "two-stage" else {})}
        self.delta, self.jac = dataset.extra["preintegration"]
        self.total = float(np.mean(dataset.reference_norm))
        b = float(bias_bound_deg_s)
        self.lower = np.concatenate([self.lower, [-np.pi, -np.pi / 2, -b, -b, -b]])
        self.upper = np.concatenate([self.upper, [np.pi, np.pi / 2, b, b, b]])

    def unpack(self, thetas):
        """``(W, o)`` of the first 12 parameters (the field direction and gyro bias left out)."""
        w, o = super().unpack(thetas)
        return w, o[:, :3]

    def pack_all(self, w, o, field_dir, bias_deg_s) -> np.ndarray:
        """The 17 parameters from ``W``, ``o``, a field direction vector and a bias (deg/s)."""
        d = np.asarray(field_dir, float) / np.linalg.norm(field_dir)
        return np.concatenate([self.pack(w, o), [np.arctan2(d[1], d[0]), np.arcsin(np.clip(d[2], -1, 1))],
                               bias_deg_s])

    def field(self, thetas) -> np.ndarray:
        """The field ``h`` in the starting frame, ``(n, 3)``."""
        thetas = np.atleast_2d(thetas)
        a, e = thetas[:, 12], thetas[:, 13]
        return self.total * np.column_stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])

    def reference_swarm(self, thetas) -> np.ndarray:
        """``R_j(b_g)ᵀ h`` of every particle and reading, ``(n, M, 3)``."""
        thetas = np.atleast_2d(thetas)
        # the attitudes once per distinct bias: a stacked Jacobian's 18 points share 15 (magexp.estimators.lm)
        biases, which = np.unique(thetas[:, 14:17], axis=0, return_inverse=True)
        rot = attitude_with_bias(self.delta, self.jac, np.deg2rad(biases))[which.ravel()]
        return np.einsum("nmji,nj->nmi", rot, self.field(thetas))

    def residual_swarm(self, thetas) -> np.ndarray:
        """``R_jᵀ h - W (B_j - b)`` of every particle and reading, ``(n, M, 3)``."""
        w, o = self.unpack(thetas)
        with np.errstate(invalid="ignore", over="ignore"):
            cal = np.einsum("nij,nkj->nki", w, self.dataset.readings[None] - o[:, None, :])
            return self.reference_swarm(thetas) - cal

    @classmethod
    def cost_floats(cls, n_readings: int, n_particles: int) -> int:
        """48 float64 numbers per particle-reading: the ``(n, M, 3, 3)`` rotations of
        :func:`~magexp.core.geometry.attitude_with_bias`, their intermediates, the references and residuals."""
        # tracemalloc's peak of one call: 46.2 to 46.6 a particle-reading (300 readings, 50 and 200 particles)
        return 48 * n_readings * n_particles

    def cost(self, thetas) -> np.ndarray:
        """``F_g`` of every particle, ``(n, 17) -> (n,)``; non-finite values become ``inf``."""
        err = self.residual_swarm(thetas)
        f = np.sqrt(np.einsum("nmk,nmk->nm", err, err)).sum(axis=1)
        return np.where(np.isfinite(f), f, np.inf)

    def cost_direct(self, theta) -> float:
        """``F_g`` of one parameter vector (:meth:`cost` of a swarm of one)."""
        return float(self.cost(np.asarray(theta)[None])[0])

    def residuals(self, theta) -> np.ndarray:
        """The ``3M`` residual components (for least squares)."""
        return self.residual_swarm(np.asarray(theta)[None])[0].ravel()

    def fg(self, theta) -> float:
        """Yuan 2018's ``F_g`` (eq 8) with the estimated field direction and gyro bias: :meth:`cost_direct`."""
        return self.cost_direct(theta)

    def initial_estimate(self) -> np.ndarray:
        """The start of the fit: ``start="projected"`` :meth:`projected_start`, ``"two-stage"`` (the default, the
        papers' runs) :meth:`two_stage_start`.
        """
        return self.projected_start() if self.start == "projected" else self.two_stage_start()

    def two_stage_start(self) -> np.ndarray:
        """The ellipsoid fit's ``W = Q P`` and offset, then least squares over ``Q``, the field direction and the
        bias from ``Q = I`` (it can stall where few directions are left: ``magexp calibrate`` uses
        :meth:`projected_start`).
        """
        # lazy: scipy.optimize costs 0.45-0.5 CPU-s to import, which magexp calibrate's gyro fits do not need
        from scipy.optimize import least_squares

        base = self._ellipsoid_start()
        w0, o0 = (a[0] for a in self.unpack(base))

        def full(z):
            return np.concatenate([self.pack(exp_so3(z[:3]) @ w0, o0), z[3:]])

        z0 = np.concatenate([np.zeros(3), base[12:]])
        sol = least_squares(lambda z: self.residuals(full(z)), z0, method="lm", max_nfev=400)
        return full(sol.x)

    def projected_start(self) -> np.ndarray:
        """The module docstring's closed-form start (:func:`rotation_start`), then Levenberg-Marquardt over the
        field direction and gyro bias with ``W`` and the offset solved linearly at each (:meth:`projected`)."""
        base = self._ellipsoid_start()
        w0, o0 = (a[0] for a in self.unpack(base))
        u = (self.dataset.readings - o0) @ w0.T
        q, h = rotation_start(attitude_with_bias(self.delta, self.jac, np.zeros(3))[0], u)
        start = self.pack_all(q @ w0, o0, h, np.zeros(3))
        swarm = SimpleNamespace(residual_swarm=self.projected_residuals)
        z, *_ = minimise_numpy(lambda v: swarm.residual_swarm(v[None])[0], start[12:], jac=stacked_jacobian(swarm),
                               tol=PROJECTED_TOL, max_nfev=PROJECTED_NFEV)
        w, o = self.projected(z)
        return start if w is None else np.concatenate([self.pack(w, o), z])

    def projected_residuals(self, z) -> np.ndarray:
        """The residuals of the projected problem at the field directions and biases ``z`` ``(n, 5)``: the part of
        ``R_j(b_g)ᵀ h`` no affine map ``W B_j + c`` of the readings reaches, ``(n, 3M)`` (module docstring).
        """
        z = np.atleast_2d(z)
        y = self.reference_swarm(np.concatenate([np.zeros((len(z), 12)), z], axis=1))
        basis = self._affine_basis()
        return (y - np.einsum("mk,nkc->nmc", basis, np.einsum("mk,nmc->nkc", basis, y))).reshape(len(z), -1)

    def projected(self, z) -> tuple:
        """``(W, o)`` solved linearly at the field direction and bias ``z`` ``(5,)``: the least-squares
        ``R_jᵀ h = W B_j + c``, ``o = -W⁻¹ c``; ``(None, None)`` where ``W`` is singular.
        """
        y = self.reference_swarm(np.concatenate([np.zeros(12), z])[None])[0]
        design = np.column_stack([self.dataset.readings, np.ones(len(y))])
        coef = np.linalg.lstsq(design, y, rcond=None)[0]
        w = coef[:3].T
        try:
            return w, -np.linalg.solve(w, coef[3])
        except np.linalg.LinAlgError:
            return None, None

    def _affine_basis(self) -> np.ndarray:
        """An orthonormal basis ``(M, 4)`` of the columns ``[B_j, 1]`` (cached)."""
        if getattr(self, "_basis", None) is None:
            self._basis = np.linalg.qr(np.column_stack([self.dataset.readings, np.ones(len(self.dataset.readings))]))[0]
        return self._basis

    def _ellipsoid_start(self) -> np.ndarray:
        """A 17-parameter start from an ellipsoid fit of the readings (a sphere about their mean if it fails)."""
        r = self.dataset.readings
        fitted = fit_ellipsoid(r, self.total)
        w, o = fitted if fitted is not None else (np.eye(3) * self.total / np.linalg.norm(r - r.mean(0), axis=1).mean(),
                                                  r.mean(axis=0))
        w = canonical(w)
        return self.pack_all(w, o, w @ (self.dataset.readings[0] - o), np.zeros(3))

    def metrics(self, theta) -> dict:
        """``fg``; ``vector_residual_fraction``: RMS of ``|R_jᵀh - W(B_j - b)|`` over ``F``;
        ``field_rms`` and the spread of the calibrated magnitudes; with a rest recording, its mean rate
        and ``gyro_bias_difference`` (deg/s, norm) from the estimate; the field direction (also as
        ``field_azimuth_deg``/``field_elevation_deg`` on their principal branches); the gyro bias;
        ``condition_number``, ``weakest_relative_sv`` and ``weakest_combination`` of the column-scaled
        Jacobian, and ``se_<parameter>``, each parameter's standard error from it (``inf`` where the data
        leave it undetermined; :func:`magexp.core.identifiability.identifiability`).
        """
        theta = np.asarray(theta, float)
        err = self.residual_swarm(theta[None])[0]
        calibrated = self.calibrate(theta)
        mags = np.linalg.norm(calibrated, axis=1)
        out = {"fg": self.fg(theta), "field_rms": total_field_rms(calibrated, self.total),
               "vector_residual_fraction": float(np.sqrt(np.mean(np.sum(err**2, axis=1))) / self.total),
               "spread_after": spread(mags)}
        out.update(dict(zip(EXTRA, theta[12:].tolist())))
        rest = self.dataset.extra.get("rest_gyro_bias_deg_s")
        if rest is not None:  # the same gyroscope at rest: its mean rate
            out.update({f"gyro_bias_rest_{a}": float(v) for a, v in zip("xyz", rest)})
            out["gyro_bias_difference"] = float(np.linalg.norm(theta[14:17] - rest))
        h = self.field(theta)[0] / self.total  # the direction, whatever the angles' branch
        out.update({"field_azimuth_deg": float(np.rad2deg(np.arctan2(h[1], h[0]))),
                    "field_elevation_deg": float(np.rad2deg(np.arcsin(np.clip(h[2], -1, 1))))})
        ident = identifiability(lambda t: self.residual_swarm(t).reshape(len(np.atleast_2d(t)), -1), theta,
                                self.parameter_names())
        weakest = ident["weakest_combinations"][0]
        out.update({f"se_{name}": v for name, v in ident["standard_errors"].items()})
        out.update({"condition_number": ident["condition_number"],
                    "weakest_relative_sv": weakest["relative_singular_value"],
                    "weakest_combination": weakest["combination"]})
        return out

    def invariants(self, theta):
        """What the data identify: here every parameter (the weak combinations are reported by :meth:`metrics`)."""
        return np.asarray(theta, float)


def rotation_start(rot: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(Q, h)``: the rotation ``Q`` and field ``h`` of the closed-form start (module docstring) from the
    attitudes ``rot`` ``(M, 3, 3)`` (body -> start) and the ellipsoid-calibrated readings ``u`` ``(M, 3)``.
    """
    rows = np.einsum("mia,mb->miab", rot, u).reshape(len(u), 3, 9)  # R_j Q u_j = rows_j vec(Q)
    rows = rows - rows.mean(axis=0)
    q = np.linalg.eigh(np.einsum("mik,mil->kl", rows, rows))[1][:, 0].reshape(3, 3)
    left, _, right = np.linalg.svd(q)
    q = left @ right
    q = -q if np.linalg.det(q) < 0 else q  # -Q with -h fits as well: the proper one
    return q, np.einsum("mia,ab,mb->i", rot, q, u) / len(u)
