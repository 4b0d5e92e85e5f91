"""Gyro-aided vector calibration with an unknown field and an unknown gyroscope bias (Yuan 2018, sec 4, on
a real IMU whose field direction and gyro bias are not known).

Yuan 2018's eq 8 with the attitude integrated from a biased gyroscope and the field direction
in the starting frame unknown:

.. math:: F_g(S, \\mathbf b, \\mathbf h, \\mathbf b_g) = \\sum_{j=1}^M
          \\big\\lVert R_j(\\mathbf b_g)^\\top \\mathbf h - S^{-1}(\\mathbf B_j - \\mathbf b)\\big\\rVert

* ``R_j(b_g)`` (body -> start frame at reading ``j``) is the gyro stream, less the bias ``b_g``,
  integrated at the magnetometer's times (:func:`magexp.core.geometry.preintegrate`: one
  preintegrated increment and its first-order bias Jacobian per pair of readings, so a new
  bias costs a prefix scan over the ``M`` readings, not a re-integration of the gyro stream);
* ``h`` is the field in the starting frame (the body frame at the first reading),
  ``h = F [cos e cos a, cos e sin a, sin e]``. Its magnitude ``F`` cannot be separated from the
  scale of ``S`` (``S -> k S``, ``h -> h / k`` fit equally), so ``F`` is fixed to the dataset's
  reference total and only the direction ``(a, e)`` is estimated;
* ``S`` absorbs every linear map between the magnetometer's and the gyroscope's axes (their
  misalignment, and a reflection if the axis conventions differ).

Parameters (17): ``θ = [vec(S) (9, row-major), b (3), a, e (rad), b_g (3, deg/s)]``.
Rotation modes: turns about one body axis only leave the component of ``h`` along that axis
constant in the body frame, so as in Yuan's mode 4 the column of ``S`` along it cannot be told
from ``b`` (the data determine only their combination), and the bias about the other axes
trades against the field direction.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from magexp.core.ellipsoid import fit_ellipsoid
from magexp.core.geometry import attitude_with_bias, exp_so3
from magexp.core.identifiability import canonical, identifiability, spread
from magexp.core.metrics import total_field_rms
from magexp.problems.base import CalibrationProblem

EXTRA = ("field_azimuth", "field_elevation", "gyro_bias_x", "gyro_bias_y", "gyro_bias_z")


class GyroAidedCalibration(CalibrationProblem):
    """Yuan 2018 eq 8 over ``[vec(S), b, field direction, gyro bias]`` (module docstring).

    ``dataset.extra["preintegration"]`` holds ``(ΔR, J)`` of :func:`magexp.core.geometry.preintegrate` at
    the readings' times; ``dataset.reference_norm`` the field magnitude ``F`` (fixed).
    ``search`` bounds ``S`` and ``b``; the field direction spans the sphere and the gyro bias
    ``±bias_bound_deg_s``.

    Parameters
    ----------
    dataset, search, parameterisation
        As :class:`magexp.problems.base.CalibrationProblem` (``search`` bounds ``S`` and ``b``).
    bias_bound_deg_s : float
        The gyro-bias bound of the search, deg/s.
    """

    objective = "gyro"
    objective_is_rms = False
    n_params = 17

    def __init__(self, dataset, search, *, parameterisation: str = "forward", bias_bound_deg_s: float = 10.0):
        super().__init__(dataset, search, parameterisation=parameterisation)
        self.options = {"parameterisation": parameterisation, "bias_bound_deg_s": bias_bound_deg_s}
        self.delta, self.jac = dataset.extra["preintegration"]
        self.total = float(np.mean(dataset.reference_norm))
        b = float(bias_bound_deg_s)
        self.lower = np.concatenate([self.lower, [-np.pi, -np.pi / 2, -b, -b, -b]])
        self.upper = np.concatenate([self.upper, [np.pi, np.pi / 2, b, b, b]])

    def unpack(self, thetas):
        """``(W, o)`` of the first 12 parameters (the field direction and gyro bias left out).

        Parameters
        ----------
        thetas : ndarray, shape (n, 17) or (17,)
            Parameter vectors (module docstring).

        Returns
        -------
        W : ndarray, shape (n, 3, 3)
            The calibration matrices (``S^-1`` in the forward form).
        o : ndarray, shape (n, 3)
            The offsets ``b``.
        """
        w, o = super().unpack(thetas)
        return w, o[:, :3]

    def pack_all(self, w, o, field_dir, bias_deg_s) -> np.ndarray:
        """The 17 parameters from ``W``, ``o``, a field direction vector and a bias (deg/s).

        Parameters
        ----------
        w : ndarray, shape (3, 3)
            The calibration matrix ``W``.
        o : ndarray, shape (3,)
            The offset ``b``.
        field_dir : array_like, shape (3,)
            The field's direction in the starting frame (any length).
        bias_deg_s : array_like, shape (3,)
            The gyro bias ``b_g`` (deg/s).

        Returns
        -------
        ndarray, shape (17,)
            ``[vec(S), b, a, e, b_g]``.
        """
        d = np.asarray(field_dir, float) / np.linalg.norm(field_dir)
        return np.concatenate([self.pack(w, o), [np.arctan2(d[1], d[0]), np.arcsin(np.clip(d[2], -1, 1))],
                               bias_deg_s])

    def field(self, thetas) -> np.ndarray:
        """The field ``h`` in the starting frame, ``(n, 3)``.

        Parameters
        ----------
        thetas : ndarray, shape (n, 17) or (17,)
            Parameter vectors (their ``a``, ``e``: columns 12, 13).

        Returns
        -------
        ndarray, shape (n, 3)
            ``h = F [cos e cos a, cos e sin a, sin e]``, ``F`` the dataset's reference total.
        """
        thetas = np.atleast_2d(thetas)
        a, e = thetas[:, 12], thetas[:, 13]
        return self.total * np.column_stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])

    def reference_swarm(self, thetas) -> np.ndarray:
        """``R_j(b_g)ᵀ h`` of every particle and reading, ``(n, M, 3)``.

        Parameters
        ----------
        thetas : ndarray, shape (n, 17) or (17,)
            Parameter vectors (their ``h`` and ``b_g``).

        Returns
        -------
        ndarray, shape (n, M, 3)
            The reference vectors of Yuan 2018's eq 8 with the attitude from the bias-corrected gyro.
        """
        thetas = np.atleast_2d(thetas)
        rot = attitude_with_bias(self.delta, self.jac, np.deg2rad(thetas[:, 14:17]))
        return np.einsum("nmji,nj->nmi", rot, self.field(thetas))

    def residual_swarm(self, thetas) -> np.ndarray:
        """``R_jᵀ h - W (B_j - b)`` of every particle and reading, ``(n, M, 3)``.

        Parameters
        ----------
        thetas : ndarray, shape (n, 17) or (17,)
            Parameter vectors (all 17 used).

        Returns
        -------
        ndarray, shape (n, M, 3)
            The residual vectors of ``F_g`` (module docstring).
        """
        w, o = self.unpack(thetas)
        with np.errstate(invalid="ignore", over="ignore"):
            cal = np.einsum("nij,nkj->nki", w, self.dataset.readings[None] - o[:, None, :])
            return self.reference_swarm(thetas) - cal

    @classmethod
    def cost_floats(cls, n_readings: int, n_particles: int) -> int:
        """48 float64 numbers per particle-reading: the ``(n, M, 3, 3)`` rotations of
        :func:`~magexp.core.geometry.attitude_with_bias` and their intermediates, the references and
        residuals (tracemalloc's peak of one call: 46.2 to 46.6 a particle-reading, 300 readings, 50
        and 200 particles).

        Parameters
        ----------
        n_readings, n_particles : int
            As :meth:`CalibrationProblem.cost_floats` (``M`` and ``n`` here).

        Returns
        -------
        int
            ``48 M n``.
        """
        return 48 * n_readings * n_particles

    def cost(self, thetas) -> np.ndarray:
        """``F_g`` of every particle, ``(n, 17) -> (n,)``; non-finite values become ``inf``.

        Parameters
        ----------
        thetas : ndarray, shape (n, 17)
            The swarm.

        Returns
        -------
        ndarray, shape (n,)
            ``F_g = sum_j |R_j(b_g)^T h - S^-1 (B_j - b)|`` of each (Yuan 2018, eq 8, module docstring).
        """
        err = self.residual_swarm(thetas)
        f = np.sqrt(np.einsum("nmk,nmk->nm", err, err)).sum(axis=1)
        return np.where(np.isfinite(f), f, np.inf)

    def cost_direct(self, theta) -> float:
        """``F_g`` of one parameter vector (:meth:`cost` of a swarm of one).

        Parameters
        ----------
        theta : ndarray, shape (17,)
            One particle of :meth:`cost`'s swarm.

        Returns
        -------
        float
            Its cost.
        """
        return float(self.cost(np.asarray(theta)[None])[0])

    def residuals(self, theta) -> np.ndarray:
        """The ``3M`` residual components (for least squares).

        Parameters
        ----------
        theta : ndarray, shape (17,)
            ``[vec(S), b, a, e, b_g]``.

        Returns
        -------
        ndarray, shape (3M,)
            The components of ``R_j^T h - W (B_j - b)``, reading by reading.
        """
        return self.residual_swarm(np.asarray(theta)[None])[0].ravel()

    def fg(self, theta) -> float:
        """Yuan 2018's ``F_g`` (eq 8) with the estimated field direction and gyro bias: :meth:`cost_direct`.

        Parameters
        ----------
        theta : ndarray, shape (17,)
            The estimate (with its field direction and gyro bias).

        Returns
        -------
        float
            ``F_g``, module docstring.
        """
        return self.cost_direct(theta)

    def initial_estimate(self) -> np.ndarray:
        """Two-stage start. The ellipsoid fit gives ``W`` up to a rotation, ``W = Q P`` (``P``
        canonical) and the offset; with them fixed, least squares over the 8 numbers of ``Q``
        (rotation vector), the field direction and the gyro bias (from zero, and the field direction
        of the first calibrated reading, ``R_0 = I``) fits ``R_jᵀ h = Q P (B_j - b)``; the full
        problem starts from there.

        Returns
        -------
        ndarray, shape (17,)
            The starting parameter vector.
        """
        base = self._ellipsoid_start()
        w0, o0 = (a[0] for a in self.unpack(base))

        def full(z):
            return np.concatenate([self.pack(exp_so3(z[:3]) @ w0, o0), z[3:]])

        z0 = np.concatenate([np.zeros(3), base[12:]])
        sol = least_squares(lambda z: self.residuals(full(z)), z0, method="lm", max_nfev=400)
        return full(sol.x)

    def _ellipsoid_start(self) -> np.ndarray:
        r = self.dataset.readings
        fitted = fit_ellipsoid(r, self.total)
        w, o = fitted if fitted is not None else (np.eye(3) * self.total / np.linalg.norm(r - r.mean(0), axis=1).mean(),
                                                  r.mean(axis=0))
        w = canonical(w)
        return self.pack_all(w, o, w @ (self.dataset.readings[0] - o), np.zeros(3))

    def parameter_names(self) -> list[str]:
        """The names of the 17 parameters, in :meth:`pack_all`'s order.

        Returns
        -------
        list of str
            :meth:`CalibrationProblem.parameter_names` and :data:`EXTRA`.
        """
        return super().parameter_names() + list(EXTRA)

    def metrics(self, theta) -> dict:
        """``fg``; ``vector_residual_fraction``: RMS of ``|R_jᵀh - W(B_j - b)|`` over ``F``;
        ``field_rms`` and the spread of the calibrated magnitudes; with a rest recording, its mean rate
        and ``gyro_bias_difference`` (deg/s, norm) from the estimate; the field direction (also as
        ``field_azimuth_deg``/``field_elevation_deg`` on their principal branches); the gyro bias;
        ``condition_number``, ``weakest_relative_sv`` and ``weakest_combination`` of the column-scaled
        Jacobian, and ``se_<parameter>``, each parameter's standard error from it (``inf`` where the data
        leave it undetermined; :func:`magexp.core.identifiability.identifiability`).

        Parameters
        ----------
        theta : ndarray, shape (17,)
            The estimator's result ``x``.

        Returns
        -------
        dict
            The keys above (floats; ``weakest_combination`` a text).
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
        """What the data identify: here every parameter (the weak combinations are reported by :meth:`metrics`).

        Parameters
        ----------
        theta : ndarray, shape (17,)
            The estimate.

        Returns
        -------
        ndarray, shape (17,)
            ``theta`` as floats.
        """
        return np.asarray(theta, float)
