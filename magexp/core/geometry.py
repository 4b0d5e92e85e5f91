"""Rotations, attitude from angles or gyro rates, axis conventions and the geomagnetic field.

All rotation matrices act on column vectors; stacks of them have shape ``(..., 3, 3)``.
Angles in configs are degrees unless a name says otherwise.

Attitude conventions used throughout magexp:

* ``R`` (body -> navigation) follows ``Ṙ = R [ω]×`` for body rates ``ω``; the attitude a
  magnetometer model uses is ``C = Rᵀ`` (navigation -> body), so ``B_body = C H_nav``;
* strapdown integration holds each gyro sample over the interval up to the next one (zero-order
  hold) and propagates with the exact exponential map of that step,
  :math:`R_{k+1} = R_k \\exp([\\omega_k]_\\times \\Delta t_k)` (Rodrigues' formula);
* the ordered product of the steps is a prefix scan (:func:`cumulative_product`): ``log2 K``
  vectorised matrix products instead of a Python loop per sample.
"""

from __future__ import annotations

import re

import numpy as np

from magexp.errors import MagexpError


def field_ned(total: float, declination_deg: float, inclination_deg: float) -> np.ndarray:
    """Geomagnetic field vector in the local North-East-Down frame (``D`` east of north, ``I`` below the horizontal).

    .. math:: \\mathbf F = F\\,[\\cos I\\cos D,\\ \\cos I\\sin D,\\ \\sin I]
    """
    d, i = np.deg2rad(declination_deg), np.deg2rad(inclination_deg)
    return total * np.array([np.cos(i) * np.cos(d), np.cos(i) * np.sin(d), np.sin(i)])


def random_rotations(n: int, *, rng: np.random.Generator) -> np.ndarray:
    """``n`` rotation matrices drawn uniformly (Haar measure) on SO(3).

    Uses normalised 4-D Gaussian vectors as unit quaternions (Shoemake 1992).
    """
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return quat_to_matrix(q)


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices from unit quaternions ``[w, x, y, z]`` of shape ``(n, 4)``."""
    w, x, y, z = np.moveaxis(np.asarray(q, dtype=float), -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


def _axis_rotation(angle, i: int, j: int) -> np.ndarray:
    """Active rotations by ``angle`` in the plane of axes ``i``, ``j``: the one body of :func:`rot_x`, :func:`rot_y`, :func:`rot_z`."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    r = np.zeros(a.shape + (3, 3))
    k = 3 - i - j
    r[..., k, k] = 1.0
    r[..., i, i] = c
    r[..., j, j] = c
    r[..., i, j] = -s
    r[..., j, i] = s
    return r


def rot_x(angle) -> np.ndarray:
    """Active rotation about x by ``angle`` radians (scalar or array)."""
    return _axis_rotation(angle, 1, 2)


def rot_y(angle) -> np.ndarray:
    """Active rotation about y by ``angle`` radians (scalar or array)."""
    return _axis_rotation(angle, 2, 0)


def rot_z(angle) -> np.ndarray:
    """Active rotation about z by ``angle`` radians (scalar or array)."""
    return _axis_rotation(angle, 0, 1)


def rotation_angle(r: np.ndarray) -> np.ndarray:
    """Angle (radians) of rotation matrices, ``arccos((tr R - 1) / 2)`` clipped: robust near 0 and pi."""
    tr = np.trace(r, axis1=-2, axis2=-1)
    return np.arccos(np.clip((tr - 1.0) / 2.0, -1.0, 1.0))


def ship_attitude(heading, roll, trim) -> np.ndarray:
    """Yan & Zhou 2022 eq 2, ``A = R_y(trim) R_x(roll) R_z(heading)`` (navigation -> sensor),
    angles in radians; shape ``(..., 3, 3)``.

    As printed, ``R_y`` is an active rotation and ``R_x``, ``R_z`` passive ones:
    ``A = rot_y(trim) rot_x(-roll) rot_z(-heading)``.
    """
    return rot_y(trim) @ rot_x(-np.asarray(roll, float)) @ rot_z(-np.asarray(heading, float))


# -- rotation vectors and strapdown integration ----------------------------------------------------
def skew(w: np.ndarray) -> np.ndarray:
    """Cross-product matrices ``[w]×`` of vectors ``w`` of shape ``(..., 3)``."""
    w = np.asarray(w, float)
    z = np.zeros(w.shape[:-1])
    x, y, c = w[..., 0], w[..., 1], w[..., 2]
    return np.stack([np.stack([z, -c, y], -1), np.stack([c, z, -x], -1), np.stack([-y, x, z], -1)], -2)


def exp_so3(phi: np.ndarray) -> np.ndarray:
    """Rotation matrices ``exp([φ]×)`` of rotation vectors ``φ`` (``(..., 3)``), Rodrigues' formula.

    .. math:: \\exp([\\varphi]_\\times) = I + \\frac{\\sin\\theta}{\\theta}[\\varphi]_\\times
              + \\frac{1 - \\cos\\theta}{\\theta^2}[\\varphi]_\\times^2,\\quad \\theta = \\lVert\\varphi\\rVert

    with the Taylor series of both coefficients for ``θ < 1e-4`` (exact to round-off).
    """
    phi = np.asarray(phi, float)
    theta = np.linalg.norm(phi, axis=-1)[..., None, None]
    small = theta < 1e-4
    t = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta**2 / 6.0, np.sin(t) / t)
    b = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(t)) / t**2)
    k = skew(phi)
    return np.eye(3) + a * k + b * (k @ k)


def cumulative_product(mats: np.ndarray, axis: int = 0) -> np.ndarray:
    """Inclusive ordered products ``P_k = M_0 M_1 ... M_k`` along ``axis`` of a stack ``(..., K, ..., 3, 3)``.

    Hillis-Steele prefix scan: after the pass with stride ``d`` every ``P_k`` holds the product of
    the ``min(2d, k+1)`` matrices ending at ``k``; ``ceil(log2 K)`` vectorised passes in all.
    """
    out = np.moveaxis(np.array(mats, dtype=float), axis, 0)
    d = 1
    while d < out.shape[0]:
        out[d:] = out[:-d] @ out[d:]
        d *= 2
    return np.moveaxis(out, 0, axis)


def integrate_rates(rates: np.ndarray, dt, start: np.ndarray | None = None) -> np.ndarray:
    """Body-to-nav rotations ``R_0..R_K`` from body rates ``(K, 3)`` (rad/s) held over each step.

    ``dt`` is one step length or one per step ``(K,)``. ``R_0`` is ``start`` (default identity).
    """
    rates = np.asarray(rates, float)
    steps = exp_so3(rates * np.broadcast_to(np.asarray(dt, float), rates.shape[:1])[:, None])
    first = np.eye(3) if start is None else np.asarray(start, float)
    return np.concatenate([first[None], first @ cumulative_product(steps)]) if len(steps) else first[None]


def merged_steps(gyro_times: np.ndarray, rates: np.ndarray, at: np.ndarray):
    """The zero-order-hold steps of a gyro stream on the union of its times and the times ``at``.

    Returns ``(rates_k, dt_k, index)``: the rate and length of every step of the merged grid from
    ``at[0]`` to ``at[-1]``, and for every time of ``at`` the number of steps before it. A gyro
    sample is held until the next one; times before the first sample use the first sample.
    """
    gyro_times, at = np.asarray(gyro_times, float), np.asarray(at, float)
    grid = np.union1d(gyro_times[(gyro_times > at[0]) & (gyro_times < at[-1])], at)
    held = np.clip(np.searchsorted(gyro_times, grid[:-1], side="right") - 1, 0, len(gyro_times) - 1)
    return np.asarray(rates, float)[held], np.diff(grid), np.searchsorted(grid, at)


def attitude_at(gyro_times: np.ndarray, rates: np.ndarray, at: np.ndarray, *, bias=None) -> np.ndarray:
    """Body -> start-frame rotations ``R(t)`` at the times ``at`` from a gyro stream sampled at its own times.

    The gyro is *integrated* at the magnetometer's times, not resampled: the zero-order-hold rate of
    :func:`merged_steps` is propagated exactly over every piece of the merged time grid, so an
    attitude at a time between two gyro samples includes the fraction of the step up to it.
    ``bias`` (rad/s, in the gyro's axes) is subtracted from every rate. The start frame is the body
    frame at ``at[0]`` (``R = I`` there).
    """
    r, dt, index = merged_steps(gyro_times, rates, at)
    if bias is not None:
        r = r - np.asarray(bias, float)
    return integrate_rates(r, dt)[index]


def preintegrate(gyro_times: np.ndarray, rates: np.ndarray, at: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation increments between consecutive times ``at`` and their first-order bias Jacobians.

    For the step between ``at[j]`` and ``at[j+1]`` (Forster et al. 2017, on-manifold preintegration,
    with the right Jacobian of each short gyro step taken as ``I``):

    .. math:: \\Delta R_j(\\mathbf b) \\approx \\Delta R_j\\,\\exp\\big(-[J_j\\mathbf b]_\\times\\big),\\qquad
              J_j = G_{e}^\\top \\sum_{k \\in j} G_k\\,\\delta t_k

    with ``G_k`` the product of the gyro steps from the start through step ``k``, ``e`` the last
    step of the interval. Returns ``(ΔR (M-1, 3, 3), J (M-1, 3, 3))``; with them a bias changes
    the attitude of every reading without re-integrating the gyro stream.
    """
    r, dt, index = merged_steps(gyro_times, rates, at)
    g = integrate_rates(r, dt)  # G_0 = I .. G_K
    delta = np.einsum("nji,njk->nik", g[index[:-1]], g[index[1:]])
    weighted = np.concatenate([np.zeros((1, 3, 3)), np.cumsum(g[1:] * dt[:, None, None], axis=0)])
    jac = np.einsum("nji,njk->nik", g[index[1:]], weighted[index[1:]] - weighted[index[:-1]])
    return delta, jac


def attitude_with_bias(delta: np.ndarray, jac: np.ndarray, bias: np.ndarray) -> np.ndarray:
    """Body -> start rotations of every reading for biases ``(n, 3)``: shape ``(n, M, 3, 3)``.

    ``R_0 = I`` and ``R_{j+1} = R_j ΔR_j exp(-[J_j b]×)`` (:func:`preintegrate`), a prefix scan
    over readings for every bias at once.
    """
    bias = np.atleast_2d(np.asarray(bias, float))
    steps = delta[None] @ exp_so3(-np.einsum("mij,nj->nmi", jac, bias))
    eye = np.broadcast_to(np.eye(3), (len(bias), 1, 3, 3))
    return np.concatenate([eye, cumulative_product(steps, axis=1)], axis=1)


# -- axis conventions ------------------------------------------------------------------------------
_AXIS = re.compile(r"^([+-]?)([xyz])$")


def axis_map(spec: str | None, what: str = "axes") -> np.ndarray:
    """The signed permutation ``P`` with ``v_common = P v_sensor`` from a spec such as ``"-x,y,z"``.

    Entry ``i`` of ``spec`` names the sensor axis (with its sign) that becomes common axis ``i``:
    ``"-x,y,z"`` flips x (a gyro whose x is positive clockwise), ``"y,x,-z"`` swaps x and y and
    flips z. ``None`` or ``"x,y,z"`` is the identity.
    """
    if spec is None:
        return np.eye(3)
    parts = [p.strip().lower() for p in str(spec).split(",")]
    matches = [_AXIS.match(p) for p in parts]
    if len(parts) != 3 or not all(matches) or sorted(m.group(2) for m in matches) != ["x", "y", "z"]:
        raise MagexpError(f"{what}={spec!r} is not allowed: give three signed axes using each of x, y, z once, "
                          "e.g. '-x,y,z'")
    out = np.zeros((3, 3))
    for i, m in enumerate(matches):
        out[i, "xyz".index(m.group(2))] = -1.0 if m.group(1) == "-" else 1.0
    return out
