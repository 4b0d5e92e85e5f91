"""The calibration models ``magexp calibrate`` fits, and ``model=auto``: the one the data support.

Models of ``B = W (r - o)``, simplest first (:data:`ORDER`):

``sphere``
    ``W = s I``: the offset and one scale (4 numbers), closed form (:func:`magexp.scenarios.search.fit_sphere`,
    Pratt 1987). What readings covering part of the sphere can still determine.
``diagonal``
    ``W = diag(w1, w2, w3)``: the offset and one scale per axis (6 numbers), closed form
    (:func:`fit_diagonal`): the axis-aligned ellipsoid ``a x² + b y² + c z² + 2 (d x + e y + f z) + g = 0``
    as the null vector of its design matrix, then :func:`magexp.core.ellipsoid.quadric_calibration`.
    This is ``magcal``'s ``diag`` model.
``full``
    ``W`` symmetric (a scalar fit cannot see a rotation; 9 numbers) and the offset, fitted by the
    configured estimator (``estimator=ellipsoid`` by default).
``gyro``
    The gyro-aided vector model of Yuan 2018 (eq 8, :mod:`magexp.problems.gyro`): the whole ``W``
    (9 numbers, its rotation into the gyroscope's axes included) and the offset, with the field
    direction in the first reading's frame and the gyroscope's bias (5 more) fitted beside them,

    .. math:: \\min \\sum_j \\lVert R_j(\\mathbf b_g)^\\top \\mathbf h - W(\\mathbf r_j - \\mathbf o)\\rVert^2,

    ``R_j`` the gyroscope's rates (less the bias) integrated to reading ``j``. Only for a recording with
    a gyroscope; fitted by Levenberg-Marquardt from the problem's two-stage start (the ellipsoid fit,
    then the rotation, field direction and bias: :meth:`~magexp.problems.gyro.GyroAidedCalibration.initial_estimate`),
    whatever ``estimator`` is (the swarm and ellipsoid estimators do not fit it).

``model=auto`` (:func:`select`) fits each model in turn and measures its held-out spread (the
readings cut into six regions of directions, each calibrated by the fit on the others: see
:func:`magexp.calibration.fit.heldout`). The simplest model is the start; a richer one replaces the
current choice only if its held-out spread is below the current one's times ``1 - margin``
(``auto_margin``, default :data:`MARGIN` = 0.1: a richer model must cut the held-out spread by at
least a tenth; a documented default, as ``magcal`` gives none). A model whose fit fails is skipped.
The choice, the reason and every candidate's held-out spread go into the output
(``quality.model_selection``). ``gyro`` is a candidate where the recording has a gyroscope
(:func:`candidates`): its held-out spread is measured the same way (magnitudes of held-out regions, which
no rotation changes), so it is chosen only where the attitude the gyroscope adds makes the magnitudes of
readings the fit has not seen more consistent. Its folds stop once the least pooled spread the remaining folds
could give (:func:`spread_bound`) is not below the current choice's times ``1 - margin`` (:func:`stopped`): it
cannot win, its spread is recorded as a lower bound, and the choice is the one the whole check would make. A
fold whose offset collapses the readings' directions (:func:`collapsed`) is a failed fold.

A vector (attitude-aided) objective fits ``full`` only: it determines the whole ``W``.
"""

from __future__ import annotations

import numpy as np

from magexp.calibration.checks import CELLS, MIN_CELLS, ONE_ATTITUDE_DEG, is_broken_estimator
from magexp.core.ellipsoid import LINEAR_TWICE, normalise, quadratic_features, quadric_calibration
from magexp.core.identifiability import coverage
from magexp.errors import MagexpError
from magexp.core.ellipsoid import fit_sphere

#: the models, simplest first (parameters of W and o: 4, 6, 9, 12), and ``auto``
ORDER = ("sphere", "diagonal", "full", "gyro")
MODELS = (*ORDER, "auto")
#: the models only a recording with a gyroscope supports
NEEDS_GYRO = ("gyro",)
#: default parsimony margin of ``model=auto`` (module docstring)
MARGIN = 0.1
#: the columns of :func:`magexp.core.ellipsoid.quadratic_features` an axis-aligned ellipsoid uses
DIAGONAL_COLUMNS = [0, 1, 2, 6, 7, 8, 9]


def fit_diagonal(readings: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray] | None:
    """``(W, o)`` of the axis-aligned ellipsoid through ``readings`` mapped onto the sphere of
    ``radius`` (``W`` diagonal); None if the fit is not an ellipsoid (module docstring)."""
    c, s, u = normalise(readings)
    design = (quadratic_features(u) * LINEAR_TWICE)[:, DIAGONAL_COLUMNS]
    p7 = np.linalg.svd(design, full_matrices=False)[2][-1]
    p = np.concatenate([p7[:3], np.zeros(3), p7[3:]])
    return quadric_calibration(p, c, s, radius)


def fit_sphere_model(readings: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """``(s I, centre)`` of the sphere through ``readings`` scaled onto ``radius``."""
    centre, fitted = fit_sphere(readings)
    return np.eye(3) * radius / fitted, centre


#: a gyroscope axis is clipped where its largest ``|rate|``, at least :data:`CLIP_RATE` rad/s (115 deg/s, under
#: the smallest common full scale of 125 deg/s), recurs on :data:`CLIP_COUNT` readings or more: a rate that
#: varies does not repeat its extreme exactly; the HMC5883L full sphere's MPU-6050 sits at 250.13 deg/s
#: (32767 / 131 LSB) on 22 readings, every other shared recording's gyroscope reaches its extreme once
CLIP_COUNT = 3
CLIP_RATE = 2.0
#: readings within this fraction of the largest ``|rate|`` are at it (a 16-bit range is asymmetric by one count:
#: the MPU-6050's +250.137 and -250.130 deg/s)
CLIP_TOLERANCE = 1e-3


def clipped(rates: np.ndarray) -> list[tuple[str, float, int]]:
    """``(axis, limit in deg/s, readings there)`` of each clipped axis of the gyroscope's ``rates`` (rad/s)."""
    out = []
    for k, axis in enumerate("xyz"):
        size = np.abs(rates[:, k])
        top = float(size.max(initial=0.0))
        count = int(np.count_nonzero(size >= top * (1 - CLIP_TOLERANCE)))
        if top >= CLIP_RATE and count >= CLIP_COUNT:
            out.append((axis, float(np.degrees(top)), count))
    return out


def gyro_unusable(stream) -> str | None:
    """Why the gyro-aided model cannot succeed on the gyroscope ``stream`` (``(times, rates)``,
    :meth:`~magexp.core.recordings.Recording.gyro_rates`), or None: a clipped axis (:func:`clipped`)
    loses the rotation beyond its limit, so the attitude it integrates is wrong from the first clip on."""
    if stream is None:
        return "the recording has no gyroscope"
    clips = clipped(np.asarray(stream[1], float))
    if not clips:
        return None
    where = ", ".join(f"g{axis} at ±{limit:.4g} deg/s on {count} readings" for axis, limit, count in clips)
    return f"the gyroscope saturates ({where}): the rotation beyond its range is lost"


def collapsed(readings: np.ndarray, offset: np.ndarray) -> bool:
    """Whether a fit collapsed: about its ``offset`` the ``readings`` point one way (within
    :data:`~magexp.calibration.checks.ONE_ATTITUDE_DEG`) or into fewer than
    :data:`~magexp.calibration.checks.MIN_CELLS` cells, where about the centre of their sphere they do not
    (:func:`magexp.calibration.checks.check_fit`'s refusal of the whole fit, asked of a fold). An offset far
    outside the readings makes every ``W (r - o)`` nearly one vector, whose magnitudes agree on any held-out
    region: the gyro-aided fit of a recording whose attitude barely turns (``R_jᵀ h`` nearly constant) does so."""
    def narrow(cover):
        return cover["direction_max_angle_deg"] < ONE_ATTITUDE_DEG or round(cover["coverage_cells"] * CELLS) < MIN_CELLS

    return narrow(coverage(readings - offset)) and not narrow(coverage(readings - fit_sphere(readings)[0]))


#: the closed-form models: ``readings, radius -> (W, o)`` or None
CLOSED_FORM = {"sphere": fit_sphere_model, "diagonal": fit_diagonal}


def check_model(model: str, objective: str, *, gyro: bool = True) -> str:
    """``model`` if it is one of :data:`MODELS`, fits ``objective`` and (``gyro``: the recording has a
    gyroscope) the data, else one line."""
    if model not in MODELS:
        raise MagexpError(f"model={model!r} is not allowed: choose one of {', '.join(MODELS)}")
    if (model in CLOSED_FORM or model in NEEDS_GYRO) and objective != "scalar":
        raise MagexpError(f"model={model!r} is not allowed with objective {objective!r}: choose full, or "
                          f"{model} with the scalar objective")
    if model in NEEDS_GYRO and not gyro:
        raise MagexpError(f"model={model!r} is not allowed: the recording has no gyroscope (gx, gy, gz columns "
                          "with sample_time, or a log's gyro stream); choose auto, sphere, diagonal or full")
    return model


def candidates(objective: str, *, gyro: bool = False) -> tuple[str, ...]:
    """The models ``auto`` tries, simplest first: all of :data:`ORDER` for the scalar objective
    (``gyro`` only with a gyroscope), ``full`` for the vector one (it determines the whole ``W``)."""
    if objective != "scalar":
        return ("full",)
    return tuple(m for m in ORDER if gyro or m not in NEEDS_GYRO)


def check_margin(margin) -> float:
    """``auto_margin`` as a float in ``[0, 1)``, else one line."""
    try:
        value = float(margin)
    except (TypeError, ValueError):
        value = float("nan")
    if not 0.0 <= value < 1.0:
        raise MagexpError(f"auto_margin={margin!r} is not allowed: it must be a number in [0, 1) (the fraction of "
                          "the simpler model's held-out spread a richer model must cut)")
    return value


def select(heldout_of, objective: str, margin: float = MARGIN, *, gyro: bool = False,
           dropped: dict | None = None, bounded: bool = False) -> tuple[str, dict]:
    """The model ``auto`` chooses, and the record of the choice."""
    tried = candidates(objective, gyro=gyro)
    spreads, stopped, chosen, why = {}, [], None, ""
    for name in tried:
        beat = None if chosen is None else (1 - margin) * spreads[chosen]
        value, cut = _measured(heldout_of, name, beat, bounded)
        spreads[name] = value
        stopped += [name] if cut else []
        if value is None or cut:
            continue
        if chosen is None:
            chosen, why = name, f"{name}: the simplest model that fits"
        elif value < beat:
            why = (f"{name}: held-out spread {100 * value:.3g} % beats {chosen}'s {100 * spreads[chosen]:.3g} % by "
                   f"more than the margin {100 * margin:g} %")
            chosen = name
    dropped = dict(dropped or {})
    if chosen is None:
        raise MagexpError("model=auto: no model could be fitted with a region of directions held out (" + ", ".join(tried) + " "
                          "all failed): record again while turning the sensor through as many orientations as you can")
    return chosen, {"chosen": chosen, "why": f"{why} ({candidates_text(chosen, spreads, dropped, stopped)})",
                    "margin": margin, "heldout_spread": spreads, "dropped": dropped, "stopped": stopped}


def _measured(heldout_of, name: str, beat, bounded: bool) -> tuple:
    """``(held-out spread or None, stopped)`` of ``name`` by :func:`select`'s ``heldout_of``."""
    try:
        value, cut = heldout_of(name, beat) if bounded else (heldout_of(name), False)
        value = float(value)
    except MagexpError as exc:
        if is_broken_estimator(exc):  # a broken estimator, not a model the readings cannot support
            raise
        value, cut = float("nan"), False
    return (value if np.isfinite(value) else None), bool(cut)


def spread_bound(done: np.ndarray, rest: int) -> float:
    """The least pooled spread (std / mean) of the magnitudes ``done`` and ``rest`` more of any positive values.

    With the rest's mean ``x`` (their own scatter only adds), the pooled variance is
    ``(n_d v + n_d n_r (m - x)² / N) / N`` over the mean ``(n_d m + n_r x) / N`` (``m``, ``v``: the mean and
    variance of ``done``); its ratio is least at ``x = m (1 + v / m²)``, where it is evaluated."""
    n_d, m, v = len(done), float(np.mean(done)), float(np.var(done))
    n = n_d + rest
    x = m * (1 + v / m**2)
    variance = (n_d * v + n_d * rest / n * (m - x) ** 2) / n
    return float(np.sqrt(variance) / ((n_d * m + rest * x) / n))


def stopped(pooled: list, total: int, beat: float | None, folds: int) -> dict | None:
    """The record of a held-out check stopped early (:func:`magexp.calibration.fit.heldout`), or None to go on:
    the folds ``pooled`` so far (their magnitudes) of ``folds`` holding ``total`` readings cannot, whatever
    the rest give, pool below ``beat`` (:func:`spread_bound`)."""
    if beat is None or len(pooled) == folds:
        return None
    done = np.concatenate(pooled)
    low = spread_bound(done, total - len(done))
    if low < beat:
        return None
    return {"heldout_spread": low, "heldout_stopped": True, "heldout_folds_done": len(pooled), "heldout_folds": folds}


def candidates_text(chosen: str, spreads: dict, dropped: dict, stopped=()) -> str:
    """Every candidate of :func:`select`, the chosen first: its held-out spread (at least, where its folds
    stopped once it could not win), that its fit failed with a region held out, or why it was dropped before any fit."""
    def one(name):
        value = spreads[name]
        if value is None:
            return f"{name}: its fit failed with a region of directions held out"
        if name in stopped:
            return f"{name} at least {100 * value:.3g} % (its folds stopped once it could not win)"
        return f"{name} {100 * value:.3g} %"
    held = [one(chosen)] + [one(n) for n in spreads if n != chosen]
    return "held out: " + ", ".join(held) + "".join(f"; {n} not fitted: {why}" for n, why in dropped.items())
