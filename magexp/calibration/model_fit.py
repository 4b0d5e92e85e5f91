"""One fit of one calibration model to one recording (:func:`fit_model`): the objective's problem in its own
parameterisation, its search box (:func:`search_box_of`) and the estimator that searches it
(``model=gyro``: :func:`gyro_estimator`, whatever ``estimator`` is), or a closed form (:func:`closed_form`:
``sphere`` and ``diagonal``, :data:`magexp.calibration.models.CLOSED_FORM`). The pipeline
(:func:`magexp.calibration.fit.calibrate_recording`) runs it on the whole recording and on each held-out fold
(:func:`fold_fit`).

A scalar calibration's ``W`` is returned in canonical form (:func:`magexp.core.identifiability.canonical`: a
total-field fit cannot see a rotation of ``W``); with an estimated reference the scale is free, and ``W`` is
rescaled so that the mean calibrated magnitude is the reference.
"""

from __future__ import annotations

import numpy as np

from magexp.calibration import models as models_
from magexp.calibration.box import calibration_box
from magexp.calibration.checks import estimator_failed, estimator_name
from magexp.calibration.inputs import Reference, gyro_dataset, recording_dataset
from magexp.core.dataset import Dataset
from magexp.core.identifiability import canonical
from magexp.core.recording import Recording
from magexp.errors import MagexpError
from magexp.estimators.lm import LevenbergMarquardt
from magexp.estimators.result import FitResult
from magexp.problems import make_problem
from magexp.scenarios.search import search_box

#: The estimator of ``model=gyro`` (:mod:`magexp.calibration.models`): Levenberg-Marquardt from the gyro-aided
#: problem's closed-form start, whatever ``estimator`` is, its Jacobian from one stacked evaluation
#: (:func:`magexp.core.marquardt.stacked_jacobian`); at most 200 residual evaluations at a tolerance of
#: 1e-10 (documented defaults: a good recording converges well within them; one whose gyroscope does not
#: carry the attitude, e.g. a saturated one, stops there instead of running 2000 evaluations per fold).
GYRO_ESTIMATOR = {"name": "lm", "max_nfev": 200, "tol": 1e-10, "jacobian": "stacked", "solver": "numpy"}


def gyro_estimator():
    """The estimator of ``model=gyro``: :class:`~magexp.estimators.lm.LevenbergMarquardt` with :data:`GYRO_ESTIMATOR`
    (built directly: composing ``conf/estimator/lm.yaml`` for each of a held-out check's folds cost 0.17 CPU-s a fold;
    the numpy solver spares the 0.45-0.5 CPU-s import of ``scipy.optimize``)."""
    return LevenbergMarquardt(**GYRO_ESTIMATOR)


def fit_model(rec: Recording, estimator, objective: str, reference: Reference, rng, model: str = "full",
              dataset: Dataset | None = None) -> tuple:
    """One fit of ``model`` to ``rec`` (module docstring): ``W`` canonical for a scalar objective, rescaled to the
    reference when it is estimated."""
    if model == "gyro":  # its own problem and estimator (magexp.calibration.models)
        objective, dataset, estimator = "gyro", gyro_dataset(rec, reference), gyro_estimator()
    dataset = recording_dataset(rec, reference, objective) if dataset is None else dataset
    box = search_box_of(rec.readings, float(np.mean(reference.total)), estimator, objective, model)
    problem = make_problem(objective, dataset, box,  # each objective's own parameterisation; gyro from the closed form
                           **({"start": "projected"} if model == "gyro" else {}))
    if model in models_.CLOSED_FORM:
        w, o, calibrated, result = closed_form(rec, model, reference)
        return w, o, calibrated, problem, result, box
    result, (w, o) = searched(estimator, problem, rng)
    who = "the gyro fit (model=gyro)" if model == "gyro" else f"estimator={estimator_name(estimator)!r}"
    if not np.all(np.isfinite(w)) or not np.all(np.isfinite(o)):
        raise MagexpError(f"{rec.name}: {who} gave a non-finite calibration, nothing written: "
                          "try estimator=ellipsoid or estimator=lm")
    if not abs(np.linalg.det(w)) > 0:
        raise MagexpError(f"{rec.name}: {who} gave a singular W (it maps every reading onto a plane), nothing "
                          "written: try estimator=ellipsoid or estimator=lm")
    if objective == "scalar":
        w = canonical(w)
    calibrated = (rec.readings - o) @ w.T
    if reference.estimated:  # the scale is free: the mean calibrated magnitude is the reference
        w = w * reference.total[0] / np.linalg.norm(calibrated, axis=1).mean()
        calibrated = (rec.readings - o) @ w.T
    return w, o, calibrated, problem, result, box


def searched(estimator, problem, rng) -> tuple:
    """``(result, (W, o))`` of ``estimator.fit(problem, rng=rng)``. A user's estimator (one not of magexp) that
    fails, or returns something other than a :class:`~magexp.estimators.result.FitResult` of the problem's
    parameters, is refused in one line naming it (its own exception is the line's ``__cause__``); magexp's own
    estimators raise as they do (a failure of theirs is a bug, not bad input)."""
    if type(estimator).__module__.split(".")[0] == "magexp":
        result = estimator.fit(problem, rng=rng)
        return result, tuple(a[0] for a in problem.unpack(result.x))
    who = f"estimator={estimator_name(estimator)!r}"
    try:
        result = estimator.fit(problem, rng=rng)
    except MagexpError:
        raise
    except Exception as exc:  # a user's code: whatever it raises is its failure, named
        first = (str(exc).splitlines() or [""])[0][:200]
        raise estimator_failed(f"{who} failed: its fit raised {type(exc).__name__}: {first}") from exc
    if not isinstance(result, FitResult):
        raise estimator_failed(f"{who} is not allowed: its fit returned {type(result).__name__}, not a FitResult "
                          "(magexp.estimators.result.FitResult)")
    _check_outcome(result, who)
    try:
        x = np.asarray(result.x, float).reshape(1, problem.n_params)
    except (TypeError, ValueError) as exc:
        raise estimator_failed(f"{who} is not allowed: its FitResult.x is not the problem's {problem.n_params} "
                          f"numbers ({type(exc).__name__})") from exc
    return result, tuple(a[0] for a in problem.unpack(x))


def _check_outcome(result: FitResult, who: str) -> None:
    """Refuse a user's :class:`FitResult` whose ``fun``, ``nit``, ``nfev``, ``success`` or ``message`` is of a wrong type."""
    kinds = {"fun": (float, int, np.floating, np.integer), "nit": (int, np.integer), "nfev": (int, np.integer),
             "success": (bool, np.bool_), "message": (str,)}
    for key, kind in kinds.items():
        value = getattr(result, key)
        if not isinstance(value, kind) or (key != "success" and isinstance(value, (bool, np.bool_))) or (
                key in ("nit", "nfev") and value < 0):
            raise estimator_failed(f"{who} is not allowed: its FitResult.{key}={value!r} is not "
                              f"{'an integer >= 0' if key in ('nit', 'nfev') else kind[0].__name__}")


def search_box_of(readings: np.ndarray, radius: float, estimator, objective: str, model: str):
    """The box of a fit (module docstring): an iterative estimator's scalar ``model=full`` search, the box centred
    on the closed-form ellipsoid fit (:func:`magexp.calibration.box.calibration_box`); any other fit, the
    readings' range (:func:`magexp.scenarios.search.search_box`; ``S = W^-1`` for the vector objectives), which
    a closed form or a start from it does not search."""
    searched = getattr(estimator, "iterative", True) and model not in models_.CLOSED_FORM
    if objective == "scalar" and searched:
        return calibration_box(readings, radius)
    return search_box(readings, radius, forward=objective != "scalar")


def closed_form(rec: Recording, model: str, reference: Reference) -> tuple:
    """A closed-form model's fit (:data:`magexp.calibration.models.CLOSED_FORM`), with the
    :class:`~magexp.estimators.result.FitResult` an estimator would give."""
    radius = float(np.mean(reference.total))
    fitted = models_.CLOSED_FORM[model](rec.readings, radius)
    if fitted is None:
        raise MagexpError(f"{rec.name}: model={model!r}: the readings do not lie on an axis-aligned ellipsoid, "
                          "nothing written: try model=sphere, or record more orientations")
    w, centre = fitted
    result = FitResult(x=np.concatenate([w.ravel(), centre]), fun=float("nan"), nit=1, nfev=1,
                       history=np.zeros(1), history_nfev=np.ones(1), success=True,
                       message=f"closed-form {model} fit (no estimator)")
    calibrated = (rec.readings - centre) @ w.T
    if reference.estimated and model != "sphere":  # the scale is free: the mean calibrated magnitude is the reference
        w = w * reference.total[0] / np.linalg.norm(calibrated, axis=1).mean()
        calibrated = (rec.readings - centre) @ w.T
    return w, centre, calibrated, result


def fold_fit(train: Recording, estimator, objective: str, reference: Reference, rng, model: str) -> tuple:
    """A held-out fold's fit: a closed form directly (no problem or search box: 19 of them took 0.2 CPU-s on the
    QMC5883L's 22 744 readings), else :func:`fit_model`."""
    if model in models_.CLOSED_FORM:
        w, o, _, result = closed_form(train, model, reference)
        return w, o, result
    w, o, _, _, result, _ = fit_model(train, estimator, objective, reference, rng, model)
    return w, o, result
