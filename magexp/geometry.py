"""Rotations and the geomagnetic field.

All rotation matrices act on column vectors; stacks of them have shape
``(n, 3, 3)``. Angles in configs are degrees unless a name says otherwise.
"""

from __future__ import annotations

import numpy as np


def field_ned(total: float, declination_deg: float, inclination_deg: float) -> np.ndarray:
    """Geomagnetic field vector in the local North-East-Down frame.

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
    """Angle (radians) of rotation matrices, robust near 0 and pi."""
    tr = np.trace(r, axis1=-2, axis2=-1)
    return np.arccos(np.clip((tr - 1.0) / 2.0, -1.0, 1.0))
