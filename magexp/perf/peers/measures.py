"""The measures both sides get, from an :class:`~.exchange.Estimate` and a neutral dataset.

Soft iron, compared up to scale and rotation. The gyro-aided methods cannot see the field's magnitude (MAGYC
fixes ``det D = 1``, magexp fixes ``|h|`` to the readings' sphere radius) and the total-field methods cannot see
the rotation of ``D`` (``D Q`` for any orthogonal ``Q`` fits as well); what every method estimates is the shape
``D Dᵀ`` up to scale. The error is the log-Euclidean distance between the unit-determinant shapes (MAGYC's own
``pds_geodesic_distance`` of its validation, on ``P = (D Dᵀ)^{1/2}``):

.. math:: e_{SI} = \\big\\lVert \\log \\hat P - \\log P \\big\\rVert_F,\\qquad
          \\log P = \\tfrac12 \\log(D D^\\top) - \\tfrac16 \\operatorname{tr}\\log(D D^\\top)\\, I

(about the relative error of ``P`` when small). A method without a soft iron (sphere fit, SAR) is taken as
``D = I``. Hard iron: ``|ĥ - h|`` over the readings' sphere radius (the sidecar's ``reference_total``). Gyro bias:
``|b̂ - b|`` in deg/s. Spread of the calibrated total field ``|D^{-1}(r - h)|``: std / mean
(:func:`magexp.core.identifiability.spread`), scale-free.

Consistency with the gyroscope (recordings, no truth): each calibrated direction ``u_k`` is carried ``HORIZON_S``
forward by the gyroscope (less the method's bias, or the rest recording's mean rate for a method that estimates
none), ``û_{k+n} = R_{k+n}ᵀ R_k u_k``, and compared with the calibrated ``u_{k+n}``: the median angle (°). A
calibration whose directions turn as the gyroscope says scores near the noise; a wrong soft iron or axis map does not.

A run *succeeds* on simulated data when its soft-iron error is at most :data:`SOFT_TOL`, its hard-iron error at
most :data:`HARD_TOL` of the field and, where it estimates one, its gyro-bias error at most :data:`BIAS_TOL`
(documented defaults: a calibration off by more leaves heading errors of degrees).
"""

from __future__ import annotations

import numpy as np

from magexp.core.geometry import attitude_at
from magexp.perf.peers.exchange import Estimate, NeutralDataset
from magexp.core.identifiability import spread

SOFT_TOL = 0.05  # log-Euclidean distance of the unit-determinant shapes (about 5 %)
HARD_TOL = 0.05  # fraction of the field
BIAS_TOL = 0.1  # deg/s
HORIZON_S = 1.0  # s, the gyro-consistency horizon


def log_shape(d: np.ndarray) -> np.ndarray:
    """``log P`` of the unit-determinant ``P = (D Dᵀ)^{1/2} / det(...)^{1/3}`` (module docstring)."""
    vals, vecs = np.linalg.eigh(d @ d.T)
    logs = 0.5 * np.log(np.maximum(vals, 1e-300))
    logs = logs - logs.mean()
    return (vecs * logs) @ vecs.T


def soft_iron_error(estimate: np.ndarray | None, truth: np.ndarray) -> float:
    """:math:`e_{SI}` of the module docstring (the identity for a method without a soft iron)."""
    est = np.eye(3) if estimate is None else estimate
    return float(np.linalg.norm(log_shape(est) - log_shape(truth)))


def calibrated(est: Estimate, mag: np.ndarray) -> np.ndarray:
    """``D^{-1} (r - h)`` of every reading."""
    d = np.eye(3) if est.soft_iron is None else est.soft_iron
    return np.linalg.solve(d, (mag - est.hard_iron).T).T


def field_spread(est: Estimate, mag: np.ndarray) -> float:
    """Spread of the calibrated total field (std / mean)."""
    return spread(np.linalg.norm(calibrated(est, mag), axis=1))


def gyro_consistency(est: Estimate, ds: NeutralDataset, bias: np.ndarray) -> float:
    """Median angle (°) between the calibrated directions and the gyroscope's prediction ``HORIZON_S`` ahead
    (module docstring); ``bias`` (rad/s) is subtracted from the rates.
    """
    rot = attitude_at(ds.t[:-1], ds.gyro[1:] - bias, ds.t)  # body -> start frame at every reading
    n = int(np.searchsorted(ds.t, ds.t[0] + HORIZON_S))
    if n < 1 or n >= len(ds.t):
        return float("nan")
    u = calibrated(est, ds.mag)
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    start = np.einsum("kij,kj->ki", rot[:-n], u[:-n])  # in the start frame
    predicted = np.einsum("kji,kj->ki", rot[n:], start)
    cos = np.clip(np.einsum("ki,ki->k", predicted, u[n:]), -1.0, 1.0)
    return float(np.rad2deg(np.median(np.arccos(cos))))


def simulated(est: Estimate, ds: NeutralDataset) -> dict:
    """Errors against the truth, the success flag, the in-sample spread and the time."""
    if est.error:
        return {"failed": 1.0, "success": 0.0}
    radius = float(ds.side["reference_total"])
    out = {"soft_iron_error": soft_iron_error(est.soft_iron, ds.truth["truth_soft_iron"]),
           "hard_iron_error": float(np.linalg.norm(est.hard_iron - ds.truth["truth_hard_iron"]) / radius),
           "spread_after": field_spread(est, ds.mag), "seconds": est.seconds, "failed": 0.0}
    ok = out["soft_iron_error"] <= SOFT_TOL and out["hard_iron_error"] <= HARD_TOL
    if est.gyro_bias is not None:
        out["gyro_bias_error"] = float(np.rad2deg(np.linalg.norm(est.gyro_bias - ds.truth["truth_gyro_bias"])))
        ok = ok and out["gyro_bias_error"] <= BIAS_TOL
    out["success"] = float(ok)
    if np.isfinite(est.own_output_spread):
        out["own_output_spread"] = est.own_output_spread
    return out


def recorded(est: Estimate, fit_on: NeutralDataset, held_out: NeutralDataset | None, rest: np.ndarray) -> dict:
    """Spread in sample and on ``held_out``, the gyro bias (deg/s) and its distance from the rest recording's."""
    if est.error:
        return {"failed": 1.0}
    out = {"spread_in_sample": field_spread(est, fit_on.mag), "seconds": est.seconds, "failed": 0.0,
           "gyro_consistency": gyro_consistency(est, fit_on, rest if est.gyro_bias is None else est.gyro_bias)}
    if held_out is not None:
        out["spread_held_out"] = field_spread(est, held_out.mag)
    if est.gyro_bias is not None:
        bias = np.rad2deg(est.gyro_bias)
        out.update({f"gyro_bias_{a}": float(v) for a, v in zip("xyz", bias)})
        out["gyro_bias_vs_rest"] = float(np.linalg.norm(bias - np.rad2deg(rest)))
    if np.isfinite(est.own_output_spread):
        out["own_output_spread"] = est.own_output_spread
    return out
