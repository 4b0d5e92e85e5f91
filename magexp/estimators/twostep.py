"""TWOSTEP (Alonso & Shuster 2002): a centred linear estimate, then Gauss-Newton.

Model (Alonso & Shuster 2002 and its complete-calibration extension, :class:`TwoStep`'s
References; Ding 2024's ref. [17])

.. math:: \\mathbf B_k = (I + D)^{-1}(O^T A_k \\mathbf H_k + \\mathbf b + \\boldsymbol\\varepsilon_k),
          \\qquad D = D^T

The attitude drops out of the scalar measurement

.. math:: z_k = |\\mathbf B_k|^2 - |\\mathbf H_k|^2
              = L_k \\theta - \\mathbf c^T (I + E)^{-1} \\mathbf c + v_k,\\qquad
          L_k = [\\,2\\mathbf B_k^T,\\ -S_k\\,],\\quad
          S_k = [B_1^2, B_2^2, B_3^2, 2B_1B_2, 2B_1B_3, 2B_2B_3]

with :math:`E = 2D + D^2`, :math:`\\mathbf c = (I + D)\\mathbf b`, :math:`\\theta = [\\mathbf c;
E_{11}, E_{22}, E_{33}, E_{12}, E_{13}, E_{23}]`. With isotropic reading noise :math:`\\sigma`
the effective noise :math:`v_k` has mean :math:`\\mu_k = -3\\sigma^2` and variance
:math:`\\sigma_k^2 = 4\\sigma^2|\\mathbf H_k|^2 + 6\\sigma^4`.

**Step 1 (centred estimate).** (With a constant reference magnitude it is resolved as in
:func:`centred_estimate`.) With weights :math:`w_k = 1/\\sigma_k^2`, centring
:math:`\\tilde z_k = z_k - \\bar z`, :math:`\\tilde L_k = L_k - \\bar L` (weighted means)
removes the nonlinear constant :math:`\\mathbf c^T(I+E)^{-1}\\mathbf c`:

.. math:: \\tilde\\theta = \\Big(\\sum_k w_k\\tilde L_k^T\\tilde L_k\\Big)^{-1}
                         \\sum_k w_k \\tilde L_k^T (\\tilde z_k - \\tilde\\mu_k)

(exact for noise-free data). **Step 2.** Gauss-Newton on the full weighted least squares
:math:`J(\\theta) = \\tfrac12\\sum_k w_k\\,(z_k - \\mu_k - L_k\\theta + \\mathbf c^T(I+E)^{-1}\\mathbf c)^2`
from :math:`\\tilde\\theta`, with the Jacobian of the residual
:math:`r_k = z_k - \\mu_k - L_k\\theta + \\mathbf c^T(I+E)^{-1}\\mathbf c`:
:math:`\\partial r_k/\\partial\\mathbf c = -2\\mathbf B_k + 2(I+E)^{-1}\\mathbf c`,
:math:`\\partial r_k/\\partial E = S_k - [(I+E)^{-1}\\mathbf c\\mathbf c^T(I+E)^{-1}]` (off-diagonal
entries counted twice).

**Calibration.** :math:`I + D = (I + E)^{1/2}` (symmetric root), :math:`\\mathbf b = (I+D)^{-1}\\mathbf c`,
so :math:`O^T A_k \\mathbf H_k = (I + D)\\mathbf B_k - \\mathbf b`: in magexp's form
:math:`W = I + D`, :math:`\\mathbf o = (I+E)^{-1}\\mathbf c`. Readings are scaled by the mean
reference field for conditioning.
"""

from __future__ import annotations

import numpy as np

from magexp.core.ellipsoid import quadratic_features
from magexp.errors import check_nonnegative, check_positive_int
from magexp.estimators.result import FitResult

UPPER = (np.array([0, 1, 2, 0, 0, 1]), np.array([0, 1, 2, 1, 2, 2]))  # E11 E22 E33 E12 E13 E23


def sym(e6: np.ndarray) -> np.ndarray:
    """The symmetric matrix of six entries."""
    e = np.zeros((3, 3))
    e[UPPER] = e6
    return e + np.triu(e, 1).T


def measurement(b: np.ndarray, h_norm: np.ndarray, sigma: float):
    """``(z - mu, L, w)`` of the module docstring: the scalar measurements, their regressors and weights ``1/σ_k²``.
    """
    z = (b * b).sum(axis=1) - h_norm**2
    mu = -3.0 * sigma**2
    var = 4.0 * sigma**2 * h_norm**2 + 6.0 * sigma**4
    w = 1.0 / np.where(var > 0, var, 1.0)
    quad = quadratic_features(b)[:, :6]  # S_k = [B1², B2², B3², 2B1B2, 2B1B3, 2B2B3]
    return z - mu, np.column_stack([2.0 * b, -quad]), w


def centred_estimate(z: np.ndarray, lmat: np.ndarray, w: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Step 1: the weighted least squares of the centred measurements.

    With a constant reference magnitude (a ground calibration) the centred equations only fix
    ``(I + E, c)`` up to a common factor ``λ``: writing ``F = I + E``,
    ``centred(B^T F B - 2 c^T B) = centred(|H|²) = 0``. Then ``(F_0, c_0)`` is the smallest right
    singular vector of the centred, weighted ``[S_k, -2 B_k]`` and ``λ`` comes from the mean equation
    the centring set aside, :math:`\\overline{z - \\mu} = \\overline{L}\\theta - c^T F^{-1} c`:

    .. math:: \\lambda = \\frac{\\overline{|\\mathbf H|^2 - 3\\sigma^2}}
              {\\overline{\\mathbf B^T F_0\\mathbf B} - 2\\mathbf c_0^T\\overline{\\mathbf B}
               + \\mathbf c_0^T F_0^{-1}\\mathbf c_0}
    """
    wn = w / w.sum()
    zt, lt = z - wn @ z, lmat - wn @ lmat
    sw = np.sqrt(w)[:, None]
    hh = (b * b).sum(axis=1) - z  # |H|² - 3σ² (z is already bias-corrected)
    if np.std(hh) > 1e-9 * abs(np.mean(hh)):  # the reference magnitude varies: TWOSTEP as printed
        return np.linalg.lstsq(lt * sw, zt * sw[:, 0], rcond=None)[0]
    quad = np.column_stack([-lt[:, 3:], -lt[:, :3]])  # centred [S_k, -2 B_k] (L = [2B, -S])
    v = np.linalg.svd(quad * sw, full_matrices=False)[2][-1]
    f0, c0 = sym(v[:6]), v[6:]
    try:
        denom = wn @ np.einsum("ni,ij,nj->n", b, f0, b) - 2 * c0 @ (wn @ b) + c0 @ np.linalg.solve(f0, c0)
    except np.linalg.LinAlgError:
        return np.concatenate([np.zeros(3), -np.ones(3), np.zeros(3)])  # I + E = 0: rejected by the caller
    lam = (wn @ hh) / denom
    return np.concatenate([lam * c0, (lam * f0 - np.eye(3))[UPPER]])


def residual_and_jacobian(theta: np.ndarray, z, lmat, w):
    """Step 2's weighted residuals ``sqrt(w) (z - L theta + c^T (I+E)^-1 c)`` and their Jacobian."""
    c, e = theta[:3], sym(theta[3:])
    g = np.linalg.solve(np.eye(3) + e, c)  # (I+E)^-1 c
    sw = np.sqrt(w)
    r = sw * (z - lmat @ theta + c @ g)
    outer = np.outer(g, g)
    d_const = np.concatenate([2.0 * g, -outer[UPPER] * np.array([1, 1, 1, 2, 2, 2])])
    jac = sw[:, None] * (-lmat + d_const)  # d r / d theta
    return r, jac


def calibration(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The calibration of ``θ``, ``(W, o) = ((I+E)^{1/2}, (I+E)^{-1} c)``; None if ``I + E`` is not positive definite.
    """
    f = np.eye(3) + sym(theta[3:])
    val, vec = np.linalg.eigh(f)
    if not np.all(val > 0):
        return None
    return (vec * np.sqrt(val)) @ vec.T, np.linalg.solve(f, theta[:3])


class TwoStep:
    """TWOSTEP complete scalar calibration (``twostep``): the module docstring's two steps.

    Both fit the attitude-free measurement ``z_k = |B_k|² - |H_k|² = L_k θ - c^T (I + E)^{-1} c + v_k``
    (Alonso & Shuster 2002): step 1 centred and linear, step 2 Gauss-Newton on its weighted squares.

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator`.
    max_iter : int
        Gauss-Newton iterations at most (step 2).
    tol : float
        Stop when the step is below ``tol`` (relative, in the scaled units).
    sigma : float, optional
        Reading-noise standard deviation per axis (reading units) for the weights and the bias
        ``mu``; None: the dataset's own (``noise_std``), else 0 (equal weights).

    References
    ----------
    Alonso & Shuster (2002), TWOSTEP, J. Astronaut. Sci. 50(4):433-451; Complete linear
    attitude-independent magnetometer calibration, 50(4):477-490.
    """

    references = "Alonso & Shuster 2002 (TWOSTEP), J. Astronaut. Sci. 50(4):433-451 and 477-490"
    label = ""
    smoke = {"max_iter": 12}
    METRICS = ("twostep_centred_fun",)  # the columns its fit writes (:meth:`fit`'s ``metrics``)
    needs = ("total_field",)
    iterative = True
    monotone_history = False  # it minimises J (squared magnitudes), not the problem's RMS of magnitudes

    def __init__(self, *, name: str = "twostep", max_iter: int = 50, tol: float = 1e-12, sigma: float | None = None):
        self.name = name
        self.max_iter = check_positive_int(max_iter, "estimator.max_iter")
        self.tol = check_nonnegative(tol, "estimator.tol")
        self.sigma = None if sigma is None else check_nonnegative(sigma, "estimator.sigma")

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        """Step 1, then Gauss-Newton (module docstring).

        Parameters
        ----------
        problem, rng, callback
            As in :meth:`magexp.estimators.base.Estimator.fit`. ``problem``: a total-field problem
            (readings, reference magnitudes, the dataset's noise). ``rng``: unused (the fit draws nothing).
            ``callback``: ``callback(k, x, fun)`` after every Gauss-Newton step.

        Returns
        -------
        FitResult
            ``metrics["twostep_centred_fun"]`` the objective at step 1's estimate.
        """
        ds = problem.dataset
        scale = float(np.mean(ds.reference_norm))
        sigma = self.sigma if self.sigma is not None else (ds.noise_std or 0.0)
        z, lmat, w = measurement(ds.readings / scale, np.asarray(ds.reference_norm) / scale, sigma / scale)
        theta = centred_estimate(z, lmat, w, ds.readings / scale)

        def x_of(th):
            cal = calibration(th)
            return None if cal is None else problem.pack(cal[0], cal[1] * scale)

        x = x_of(theta)
        if x is None:
            x = (problem.lower + problem.upper) / 2
            fun = problem.cost_direct(x)
            return FitResult(x=x, fun=fun, nit=0, nfev=1, history=np.array([fun]), history_nfev=np.array([1]),
                             success=False, message="the centred estimate has I + E not positive definite")
        history = [problem.cost_direct(x)]
        nit, message = 0, f"no convergence in {self.max_iter} Gauss-Newton steps"
        r, jac = residual_and_jacobian(theta, z, lmat, w)
        for nit in range(1, self.max_iter + 1):
            step = np.linalg.lstsq(jac, -r, rcond=None)[0]
            trial = x_of(theta + step)
            r_new, jac_new = residual_and_jacobian(theta + step, z, lmat, w)
            if trial is None or r_new @ r_new > r @ r:  # J(theta) of the module docstring
                message = "converged (a Gauss-Newton step no longer decreases J)"
                nit -= 1
                break
            theta, x, r, jac = theta + step, trial, r_new, jac_new
            history.append(problem.cost_direct(x))
            if callback is not None and callback(nit, x, history[-1]):
                message = "stopped by the callback"
                break
            if np.linalg.norm(step) <= self.tol * (1.0 + np.linalg.norm(theta)):
                message = "converged"
                break
        return FitResult(x=x, fun=problem.cost_direct(x), nit=nit, nfev=len(history), history=np.asarray(history),
                         history_nfev=np.arange(1, len(history) + 1), message=message,
                         metrics={"twostep_centred_fun": float(history[0])})
