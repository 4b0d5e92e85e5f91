"""Extended Kalman filter over the 12 calibration parameters with the vector measurement.

The state is ``θ = [vec(S), b]`` (row-major), constant up to a random walk ``Q``.
Reading ``i`` with the gyro reference ``u_i = C_i^b H_i`` gives a 3-vector measurement
``z_i = h_i(θ) + ν_i``, ``ν_i ~ N(0, R)``, in one of two forms:

* ``form: forward`` (default; Yuan 2018 eq 1): ``z_i = B_{b,i}``, ``h_i = S u_i + b``, Jacobian
  ``∂h/∂S_kl = e_k u_l``, ``∂h/∂b = I`` (linear in θ, so the filter is exact);
* ``form: inverse`` (eq 3): ``z_i = u_i``, ``h_i = S^{-1}(B_{b,i} - b)``, Jacobian
  ``∂h/∂S_kl = -W_{:,k} h_l``, ``∂h/∂b = -W`` with ``W = S^{-1}``. From ``S = I`` it diverges
  whenever the true errors are large (measured: Table 3's truth, even without noise).

One filter step (readings taken in order, cycling when ``n_steps > N``):

.. math::

    P &\\leftarrow P + Q,\\quad K = P J^T (J P J^T + R)^{-1} \\\\
    \\theta &\\leftarrow \\theta + K (z_i - h_i(\\theta)),\\quad P \\leftarrow (I - K J) P

Yuan 2018 (Table 7) compares RDPSO with an EKF without giving its settings;
these defaults are magexp's.
"""

from __future__ import annotations

import numpy as np

from magexp.errors import check, check_nonnegative, check_positive_int
from magexp.estimators.kalman import kalman_update
from magexp.estimators.result import FitResult
from magexp.problems.vector import theta_to_state


def forward_measurement(theta: np.ndarray, reference: np.ndarray, reading: np.ndarray):
    """``(z, h, ∂h/∂θ)`` of the forward form: ``z = B``, ``h = S u + b`` (Yuan 2018 eq 1)."""
    h = theta[:9].reshape(3, 3) @ reference + theta[9:]
    return reading, h, np.hstack([np.kron(np.eye(3), reference[None, :]), np.eye(3)])


def inverse_measurement(theta: np.ndarray, reference: np.ndarray, reading: np.ndarray):
    """``(z, h, ∂h/∂θ)`` of the inverse form: ``z = u``, ``h = S^{-1}(B - b)`` (Yuan 2018 eq 3)."""
    w = np.linalg.inv(theta[:9].reshape(3, 3))
    h = w @ (reading - theta[9:])
    return reference, h, np.hstack([-np.kron(w, h[None, :]), -w])


FORMS = {"forward": forward_measurement, "inverse": inverse_measurement}


def ekf_step(theta, p, reference, reading, *, q, r, form=forward_measurement):
    """One predict + update of the filter.

    The linear Kalman update of :func:`magexp.estimators.kalman.kalman_update` applied to the
    measurement linearised at ``θ``: with ``y' = z - h(θ) + J θ`` it gives

    .. math:: \\theta + M (z - h(\\theta)),\\quad M = R J^T (J R J^T + r^2)^{-1},\\quad R = P + Q,
              \\quad P \\leftarrow (E - M J) R
    """
    z, h, jac = form(theta, reference, reading)
    y = (z - h + jac @ theta)[:, None]
    theta, p = kalman_update(theta[:, None], p, jac, y, q, r)
    return theta[:, 0], 0.5 * (p + p.T)


class ExtendedKalmanFilter:
    """EKF calibration (``fit(problem, rng=...) -> FitResult``, history indexed by filter step).

    State ``θ = [vec(S), b]``, measurement ``B_{b,i} = S u_i + b`` (Yuan 2018 eq 1, ``form: forward``)
    or ``u_i = S^{-1}(B_{b,i} - b)`` (eq 3, ``form: inverse``), ``u_i = C_i^b H_i``; the step is the
    module docstring's.

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator`.
    form : str
        Measurement form, ``forward`` or ``inverse`` (see the module docstring).
    n_steps : int
        Filter steps; the readings are used in order, again from the first after the last.
    s0, b0 : list, optional
        Initial state ``S`` (3 x 3) and ``b`` (3); None: ``S = I``, ``b = 0`` (a sensor without errors).
    p0_s, p0_b : float
        Initial standard deviations of the ``S`` entries and of ``b`` (``P0`` diagonal).
    q_s, q_b : float
        Process-noise standard deviations per step (``Q`` diagonal; 0: constant parameters).
    r : float
        Measurement-noise standard deviation per axis (``R = r² I``, reading units), > 0.

    References
    ----------
    Yuan, Wang & Chen (2018), Navigation Positioning & Timing 5(6):92-98 (Table 7's EKF); Kalman (1960).
    """

    references = "Yuan, Wang & Chen 2018 (EKF baseline of Table 7); Kalman 1960"
    label = "EKF"
    smoke = {"n_steps": 12}
    needs = ("linear_design",)  # the reference vectors u_i = C_i H_i and the readings
    iterative = True
    monotone_history = False  # a filter's objective per step need not decrease

    def __init__(self, *, name: str = "ekf", form: str = "forward", n_steps: int = 300,
                 s0: list[list[float]] | None = None, b0: list[float] | None = None, p0_s: float = 1.0,
                 p0_b: float = 100.0, q_s: float = 0.0, q_b: float = 0.0, r: float = 1.0):
        check(form in FORMS, f"estimator.form={form!r} is not allowed: choose one of {', '.join(FORMS)}")
        self.name = name
        self.form = form
        self.n_steps = check_positive_int(n_steps, "estimator.n_steps")
        self.theta0 = np.concatenate([np.ravel(np.eye(3) if s0 is None else s0), np.zeros(3) if b0 is None else b0])
        sd = [check_nonnegative(v, f"estimator.{k}") for k, v in
              (("p0_s", p0_s), ("p0_b", p0_b), ("q_s", q_s), ("q_b", q_b), ("r", r))]
        self.p0 = np.diag(np.r_[np.full(9, sd[0]), np.full(3, sd[1])] ** 2)
        self.q = np.diag(np.r_[np.full(9, sd[2]), np.full(3, sd[3])] ** 2)
        check(sd[4] > 0, f"estimator.r={r!r} is not allowed: it must be a number > 0 (R = r^2 I, the measurement "
                         "noise, must be positive definite: the gain inverts it)")
        self.r = max(sd[4], 1e-12) ** 2  # measurement variance r² (R = r² I)

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        """Run the filter over the readings (rows of ``problem.design()``).

        Parameters
        ----------
        problem, rng, callback
            As in :meth:`magexp.estimators.base.Estimator.fit`. ``problem``: its linear design: the
            reference vectors and the readings. ``rng``: unused (the filter draws nothing). ``callback``:
            ``callback(step, x, None)`` after every step (``x`` in the problem's parameters).

        Returns
        -------
        FitResult
            ``history`` the problem's objective at every step; ``trace["state"]`` the state at every
            step, ``trace["P_diag"]`` the final variances. A diverged filter returns its best finite state.
        """
        c, readings = problem.design()
        z = c[:, :3]  # the reference vectors u_i = C_i H_i
        theta, p = self.theta0.astype(float), self.p0.copy()
        states = [theta]
        for step in range(self.n_steps):
            i = step % len(readings)
            theta, p = ekf_step(theta, p, z[i], readings[i], q=self.q, r=self.r, form=FORMS[self.form])
            states.append(theta)
            if not np.all(np.isfinite(theta)) or (
                    callback is not None and callback(step + 1, problem.from_linear(theta_to_state(theta))[0], None)):
                break
        states = problem.from_linear(theta_to_state(np.array(states)))  # forward state -> the problem's theta
        theta = states[-1]
        history = problem.cost(states)
        ok = bool(np.all(np.isfinite(theta)))
        x = theta if ok else states[np.nanargmin(np.where(np.isfinite(history), history, np.nan))]
        return FitResult(x=x, fun=problem.cost_direct(x), nit=len(states) - 1, nfev=len(states) - 1,
                         history=history, history_nfev=np.arange(len(states)), success=ok,
                         message=f"{len(states) - 1} filter steps" if ok else "the filter diverged",
                         trace={"state": states, "P_diag": np.diag(p).copy()})
