"""The algebraic ellipsoid fit: the readings of a sensor with a linear error lie on an ellipsoid.

The readings ``r`` of a sensor with a linear error lie on the ellipsoid
``(r - o)^T W^T W (r - o) = B_a^2``. With the readings centred and scaled
(``u = (r - c)/s``, :func:`normalise`), the quadric ``u^T A u + 2 b^T u + d = 0`` is the
null vector of the design matrix ``[u², v², w², 2uv, 2uw, 2vw, 2u, 2v, 2w, 1]``
(:func:`quadratic_features`; smallest right singular vector). Then the centre is ``u_0 = -A^{-1} b``,
``Q = A / (u_0^T A u_0 - d)`` and the calibration is the symmetric square root
``W = B_a Q^{1/2} / s``, ``o = c + s u_0`` (:func:`quadric_calibration`). A scalar reference cannot
fix the rotation of ``W``; the symmetric root is the conventional choice. Its simplest case, a sphere
(:func:`fit_sphere`: a centre and a radius, Pratt 1987), is linear least squares.

Its home is the core: the estimators (:mod:`magexp.estimators.ellipsoid`, ``triangular``) fit with it,
and so do problems (the start of :class:`magexp.problems.gyro.GyroAidedCalibration`), which must not
import estimators. The scalar problem's fast cost uses the same features (:mod:`magexp.problems.kernels`).

References: Gander, Golub & Strebel (1994), *Least-squares fitting of circles and ellipses*;
Vasconcelos et al. (2011), *Geometric approach to strapdown magnetometer calibration*;
Li & Griffiths (2004), *Least squares ellipsoid specific fitting*.
"""

from __future__ import annotations

import numpy as np


def normalise(readings: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """``(c, s, u)``: the readings' mean ``c``, RMS distance ``s`` from it, and ``u = (r - c)/s``
    (well-conditioned quadratic features, whatever the reading units).
    """
    c = readings.mean(axis=0)
    s = float(np.sqrt(((readings - c) ** 2).sum(axis=1).mean())) or 1.0
    return c, s, (readings - c) / s


def quadratic_features(u: np.ndarray) -> np.ndarray:
    """Features ``[x², y², z², 2xy, 2xz, 2yz, x, y, z, 1]`` of readings ``u`` (N, 3)."""
    x, y, z = u.T
    return np.column_stack([x * x, y * y, z * z, 2 * x * y, 2 * x * z, 2 * y * z, x, y, z, np.ones_like(x)])


LINEAR_TWICE = np.array([1, 1, 1, 1, 1, 1, 2, 2, 2, 1.0])  # the quadric u^T A u + 2 b^T u + d


def fit_sphere(readings: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre and radius of the sphere that best fits ``readings``: linear least squares of
    ``|r|² = 2 cᵀr + (R² - |c|²)`` (Pratt 1987), on readings centred on their mean. Not a sphere
    (readings on a line): the centroid and the mean distance from it.
    """
    r = np.asarray(readings, float)
    shift = r.mean(axis=0)
    u = r - shift
    design = np.column_stack([2 * u, np.ones(len(u))])
    sol = np.linalg.lstsq(design, (u * u).sum(axis=1), rcond=None)[0]
    radius2 = sol[3] + sol[:3] @ sol[:3]
    if np.isfinite(radius2) and radius2 > 0:
        return shift + sol[:3], float(np.sqrt(radius2))
    return shift, float(np.linalg.norm(u, axis=1).mean())


def fit_ellipsoid(readings: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray] | None:
    """``(W, o)`` mapping ``readings`` onto the sphere of ``radius``; None if not an ellipsoid."""
    c, s, u = normalise(readings)
    design = quadratic_features(u) * LINEAR_TWICE  # [u², v², w², 2uv, 2uw, 2vw, 2u, 2v, 2w, 1]
    p = np.linalg.svd(design, full_matrices=False)[2][-1]
    return quadric_calibration(p, c, s, radius)


#: Li & Griffiths' constraint ``k J - I² = v1^T C1 v1`` on ``v1 = [A11, A22, A33, A12, A13, A23]`` (k = 4).
def constraint_matrix(k: float = 4.0) -> np.ndarray:
    """``C1`` with ``v1^T C1 v1 = k J - I²``, ``I = a + b + c``, ``J = ab + bc + ca - f² - g² - h²``."""
    c1 = np.full((3, 3), k / 2 - 1) - (k / 2) * np.eye(3)
    return np.block([[c1, np.zeros((3, 3))], [np.zeros((3, 3)), -k * np.eye(3)]])


def fit_ellipsoid_specific(readings: np.ndarray, radius: float, k: float = 4.0) -> tuple[np.ndarray, np.ndarray] | None:
    """Li & Griffiths' ellipsoid-specific least squares (the fit of Magneto), then as :func:`fit_ellipsoid`.

    Minimise ``||D v||²`` subject to ``k J - I² = 1``: with the scatter ``D^T D`` split into the
    quadratic (6) and linear (4) blocks ``S11, S12, S22``, ``v1`` is the eigenvector of
    ``C1^{-1}(S11 - S12 S22^{-1} S12^T)`` of the one positive eigenvalue (the one with ``v1^T C1 v1 > 0``) and
    ``v2 = -S22^{-1} S12^T v1`` (Li & Griffiths 2004, eqs 13-17). With ``k = 4`` the solution
    is an ellipsoid whenever its short radius is at least half its long one, whatever the data.
    """
    c, s, u = normalise(readings)
    design = quadratic_features(u) * LINEAR_TWICE
    scatter = design.T @ design
    s11, s12, s22 = scatter[:6, :6], scatter[:6, 6:], scatter[6:, 6:]
    try:
        reduced = s11 - s12 @ np.linalg.solve(s22, s12.T)
        val, vec = np.linalg.eig(np.linalg.solve(constraint_matrix(k), reduced))
    except np.linalg.LinAlgError:
        return None
    vec = vec.real
    # C1 has one positive and five negative eigenvalues: one eigenvector has k J - I² > 0 (the
    # ellipsoid, eigenvalue v1^T M v1 / v1^T C1 v1 >= 0; exactly 0 for noise-free data)
    cv = np.einsum("ij,ik,kj->j", vec, constraint_matrix(k), vec)
    if not np.any(cv > 0):
        return None
    mv = np.einsum("ij,ik,kj->j", vec, reduced, vec)
    ratio = np.where(cv > 0, mv / np.where(cv > 0, cv, 1.0), np.inf)
    v1 = vec[:, int(np.argmin(ratio))]
    v2 = -np.linalg.solve(s22, s12.T @ v1)
    return quadric_calibration(np.concatenate([v1, v2]), c, s, radius)


def quadric_calibration(p: np.ndarray, c: np.ndarray, s: float, radius: float):
    """``(W, o)`` from the quadric ``u^T A u + 2 b^T u + d = 0``, ``p = [A11, A22, A33, A12, A13, A23,
    b, d]`` in the normalised readings ``u = (r - c)/s``; None if it is not an ellipsoid.
    """
    a = np.array([[p[0], p[3], p[4]], [p[3], p[1], p[5]], [p[4], p[5], p[2]]])
    try:
        u0 = -np.linalg.solve(a, p[6:9])
    except np.linalg.LinAlgError:
        return None
    q = a / (u0 @ a @ u0 - p[9])
    eigval, eigvec = np.linalg.eigh(q)
    if not np.all(eigval > 0):
        return None
    w = radius * (eigvec * np.sqrt(eigval)) @ eigvec.T / s
    return w, c + s * u0
