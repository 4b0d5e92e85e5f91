"""How good a fit is: the spread of the total field before and after and the readings' own noise
(:func:`quality`, :func:`noise_of`), the standard errors, conditioning and undetermined combinations of the
reported parameters (:func:`report_of`) and what the gyro-aided model reports beside them
(:func:`gyro_extras`). A stage of the pipeline (:mod:`magexp.calibration.fit`); the refusals are
:mod:`magexp.calibration.checks`'.
"""

from __future__ import annotations

import numpy as np

from magexp.core.identifiability import identifiability, spread
from magexp.core.metrics import total_field_rms
from magexp.problems.symmetric import UPPER, expand
from magexp.scenarios.search import centroid_radius

#: How each objective's ``W`` is reported.
FORMS = {"scalar": "symmetric positive-definite polar factor (W = Q P, reported P = (W^T W)^(1/2)): a total-field "
                   "fit cannot see a rotation of W",
         "vector": "as fitted (the vector objective determines the rotation)",
         "sphere": "s I (model=sphere: offset and one scale only)",
         "diagonal": "diag(w1, w2, w3) (model=diagonal: offset and one scale per axis)",
         "gyro": "as fitted (model=gyro: the gyro-aided fit determines the rotation into the gyroscope's axes)"}


#: readings whose mean step from one to the next is below this fraction of their radius are a time series
#: (:func:`noise_of`): the noise of neighbours is the sensor's; a shuffled set's steps are about 1.3 radii
SERIES_STEP = 0.25


def noise_of(raw: np.ndarray, calibrated: np.ndarray) -> float:
    """The readings' own noise in the calibrated magnitude: the RMS of its second differences over
    ``sqrt(6)`` (white noise of variance ``σ²`` has second differences of variance ``6 σ²``; a
    calibration error varies slowly with the attitude and cancels there). 0 when the readings are not
    a time series (their mean step over :data:`SERIES_STEP` of the raw radius), where neighbours are
    not close in time. The gate's RMS check discounts it (:func:`magexp.calibration.checks.gate`): a
    noisy sensor (the QMC5883L log: 6.04 % of 6.27 %) is not a bad calibration.

    .. math:: \\hat\\sigma = \\sqrt{\\tfrac{1}{6}\\,\\overline{(|B|_{i+1} - 2|B|_i + |B|_{i-1})^2}}"""
    if len(raw) < 3 or np.linalg.norm(np.diff(raw, axis=0), axis=1).mean() > SERIES_STEP * centroid_radius(raw):
        return 0.0
    return float(np.sqrt(np.mean(np.diff(np.linalg.norm(calibrated, axis=1), 2) ** 2) / 6))


def quality(raw: np.ndarray, calibrated: np.ndarray, reference: np.ndarray) -> dict:
    """Magnitude statistics before and after, the RMS against the reference and the readings' noise (:func:`noise_of`).
    """
    before, after = np.linalg.norm(raw, axis=1), np.linalg.norm(calibrated, axis=1)
    return {"mean_before": float(before.mean()), "std_before": float(before.std()), "spread_before": spread(before),
            "rms_before": total_field_rms(raw, reference),
            "mean_after": float(after.mean()), "std_after": float(after.std()), "spread_after": spread(after),
            "rms_after": total_field_rms(calibrated, reference), "noise_after": noise_of(raw, calibrated)}



def report_of(objective: str, w, o, problem, model: str = "full", extra=()) -> dict:
    """Standard errors, conditioning, undetermined combinations (:func:`magexp.core.identifiability.identifiability`)
    of the reported parameters, over the residuals of the fit's own ``problem``
    (:meth:`~magexp.problems.base.CalibrationProblem.residual_stack`): ``[s, o]`` (``W = s I``) for the
    sphere model, the 6 upper entries of the symmetric ``W`` and ``o`` for the scalar objective,
    ``[vec W, o]`` for the vector one, ``[vec W, o]`` and ``extra`` (the field direction and gyro bias
    of the fit) for the gyro-aided model."""
    if model == "sphere":
        theta = np.concatenate([[w[0, 0]], o])
        names = ["s", "o1", "o2", "o3"]
        to_problem = lambda t: problem.pack(t[0] * np.eye(3), t[1:])  # noqa: E731
    elif model == "diagonal":
        theta = np.concatenate([np.diag(w), o])
        names = ["W11", "W22", "W33", "o1", "o2", "o3"]
        to_problem = lambda t: problem.pack(np.diag(t[:3]), t[3:])  # noqa: E731
    elif objective == "scalar":
        theta = np.concatenate([w.ravel()[UPPER], o])  # the 6 upper entries of the symmetric W, then o
        names = [f"W{p // 3 + 1}{p % 3 + 1}" for p in UPPER] + ["o1", "o2", "o3"]
        to_problem = lambda t: problem.pack(expand(t)[0, :9].reshape(3, 3), t[6:])  # noqa: E731
    else:
        theta = np.concatenate([w.ravel(), o, extra])
        names = ([f"W{i + 1}{j + 1}" for i in range(3) for j in range(3)] + ["o1", "o2", "o3"]
                 + problem.parameter_names()[12:])
        to_problem = lambda t: np.concatenate([problem.pack(t[:9].reshape(3, 3), t[9:12]), t[12:]])  # noqa: E731
    out = identifiability(lambda thetas: problem.residual_stack(thetas, of=to_problem), theta, names)
    se = out["standard_errors"]
    if model == "sphere":
        out["W_standard_errors"] = (np.eye(3) * se["s"]).tolist()
    elif model == "diagonal":
        out["W_standard_errors"] = np.diag([se["W11"], se["W22"], se["W33"]]).tolist()
    else:
        out["W_standard_errors"] = [[se[f"W{min(i, j) + 1}{max(i, j) + 1}"] if objective == "scalar"
                                     else se[f"W{i + 1}{j + 1}"] for j in range(3)] for i in range(3)]
    out["offset_standard_errors"] = [se["o1"], se["o2"], se["o3"]]
    out["w_form"] = FORMS[model if model in FORMS else objective]
    out["model"] = model
    return out



def gyro_extras(model: str, problem, result) -> dict:
    """What the gyro-aided model reports beside ``W`` and ``o`` (nothing for the others): the field
    direction (rad) and the gyroscope's bias (deg/s) it fitted, and ``vector_rms``, the RMS of
    ``R_jᵀ h - W (r_j - o)`` over the readings the fit used (against the field the gyroscope carries to
    each reading; the recording's unit)."""
    if model != "gyro":
        return {}
    x = result.x
    residual = problem.residual_swarm(x[None])[0]
    return {"field_azimuth": float(x[12]), "field_elevation": float(x[13]),
            "gyro_bias_deg_s": [float(v) for v in x[14:17]],
            "vector_rms": float(np.sqrt(np.mean(np.sum(residual**2, axis=1))))}

