"""The Cramér-Rao floor of the gyro-aided problem on a simulated neutral dataset, in the bench's measures.

magexp's bound (:func:`magexp.core.bounds.cramer_rao`) of :class:`magexp.problems.gyro.GyroAidedCalibration` at the truth,
for Gaussian magnetometer noise of the dataset's ``mag_noise_std``. The gyroscope enters the problem as known
rotations, so its noise is not in the bound: the floor is that of a noise-free gyroscope (any method with the noisy
one can do no better). The truth in the problem's parameters: ``S = D |m| / F`` (the problem fixes the field's
magnitude to ``F``, the sidecar's ``reference_total``), ``b = h``, the field direction of ``truth_field_start`` (the
start frame is the body frame at the first reading), the bias in °/s. The bounds, in the units of
:mod:`.measures`: hard iron ``sqrt(tr Cov(b)) / F``; gyro bias ``sqrt(tr Cov(b_g))``; soft iron
``sqrt(tr(H Cov(S) Hᵀ))`` with ``H`` the Jacobian of ``log_shape(S)`` (its RMS log-Euclidean error, by the delta
method; central differences).
"""

from __future__ import annotations

import numpy as np

from magexp.core.bounds import central_differences, cramer_rao
from magexp.perf.peers.exchange import NeutralDataset
from magexp.perf.peers.magexp_side import gyro_problem
from magexp.perf.peers.measures import log_shape


def gyro_floor(ds: NeutralDataset, n_fit: int) -> dict:
    """``{soft_iron_error, hard_iron_error, gyro_bias_error}`` floors on ``n_fit`` evenly spaced readings of ``ds``
    (``{}`` without the truth it needs).
    """
    truth = ds.truth
    if "truth_field_start" not in truth:
        return {}
    problem = gyro_problem(ds, n_fit)
    problem.dataset.noise_std = float(ds.side["mag_noise_std"])
    radius = float(ds.side["reference_total"])
    start = np.asarray(truth["truth_field_start"], float)
    s = np.asarray(truth["truth_soft_iron"], float) * np.linalg.norm(start) / radius
    theta = problem.pack_all(np.linalg.inv(s), truth["truth_hard_iron"], start,
                             np.rad2deg(truth["truth_gyro_bias"]))
    crb = cramer_rao(problem, theta)
    cov = crb["invariant_cov"]  # the problem's invariants are its parameters: [vec(S), b, a, e, b_g]
    steps = 1e-6 * np.maximum(np.abs(theta[:9]), 1e-3)
    jac = central_differences(lambda v: log_shape(v.reshape(3, 3)).ravel(), theta[:9], steps)
    with np.errstate(invalid="ignore"):
        soft = float(np.sqrt(np.trace(jac @ cov[:9, :9] @ jac.T)))
    return {"soft_iron_error": soft, "hard_iron_error": float(np.sqrt(np.trace(cov[9:12, 9:12]))) / radius,
            "gyro_bias_error": float(np.sqrt(np.trace(cov[14:17, 14:17])))}
