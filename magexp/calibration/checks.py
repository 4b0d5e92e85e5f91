"""Whether readings can determine a calibration, and whether a fit did: the degenerate cases of
``magexp calibrate`` (identical readings, one attitude, one plane, too few directions, a failed fit),
each refused in one :class:`~magexp.errors.MagexpError` line that says why and what to record instead.

The measures they read (direction coverage, :data:`~magexp.core.identifiability.CELLS`) are the
core's (:mod:`magexp.core.identifiability`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from magexp.core.identifiability import CELLS
from magexp.errors import MagexpError

#: Fewest readings accepted: the 12 parameters of ``W`` and ``o`` (a scalar fit identifies 9).
MIN_READINGS = 12

#: Degenerate-data thresholds (see :func:`check_readings` and :func:`check_fit`).
MIN_DISTINCT = 12
PLANE_RATIO = 0.2    # sqrt(λ_min / λ_max) of the raw readings' covariance below it: one plane (docs/calibrate.md)
MIN_CELLS = 8        # fewer occupied cells (a quarter of the sphere): too few distinct directions
PARTIAL = 0.75       # fewer occupied cells after a failed fit: say the coverage is partial
ONE_ATTITUDE_DEG = 20.0  # every calibrated direction within this angle of their mean: one attitude
STILL = 0.05         # RMS distance of the raw readings from their centroid below this fraction of their magnitude: one attitude
RECORD = "record again while turning the sensor slowly through as many orientations as you can (a full sphere)"


def check_readings(readings: np.ndarray, name: str) -> None:
    """Fail in one line if the raw readings cannot determine a calibration: too few distinct
    readings, readings that barely move (one attitude; an offset over ~20 times the field would
    look the same), or readings in one plane."""
    ordered = readings[np.lexsort(readings.T)]  # distinct rows by a sort: np.unique(axis=0) took 70 ms on 22 k readings
    distinct = int(np.any(np.diff(ordered, axis=0) != 0, axis=1).sum()) + 1 if len(ordered) else 0
    if distinct < MIN_DISTINCT:
        raise MagexpError(f"{name}: only {distinct} distinct readings, a calibration needs at least {MIN_DISTINCT}: "
                          f"{RECORD}")
    centred = readings - readings.mean(axis=0)
    moved = float(np.sqrt((centred**2).sum(axis=1).mean()) / max(np.linalg.norm(readings, axis=1).mean(), 1e-300))
    if moved < STILL:
        raise MagexpError(f"{name}: the readings barely move (RMS distance from their centroid {100 * moved:.2g} % of "
                          f"their magnitude, under the limit {100 * STILL:g} %): one attitude cannot determine a "
                          f"calibration: {RECORD}")
    ev = np.linalg.eigvalsh(centred.T @ centred / len(readings))
    if ev[0] <= (PLANE_RATIO**2) * ev[-1]:
        raise MagexpError(f"{name}: the readings lie in one plane (thickness {np.sqrt(max(ev[0], 0) / ev[-1]):.2g} of "
                          f"their width, under the limit {PLANE_RATIO:g}: turns about one axis only), which cannot "
                          "determine the offset along its "
                          "normal nor the scale across it: also turn the sensor about a second axis")


def check_fit(name: str, estimator: str, success: bool, message: str, cover: dict, raw_cover: dict) -> None:
    """Fail in one line if the estimator failed or the calibrated directions show one attitude
    or too few distinct directions. ``raw_cover``: the coverage of the raw readings about the
    centre of their fitted sphere (what a failed fit's message quotes). Where the raw readings cover
    at least :data:`PARTIAL` of the sphere about that centre and only the fit's centre makes them look like one
    attitude or too few directions, the fit collapsed, and the line says so instead of blaming the recording."""
    who = estimator if estimator.endswith(" fit") else f"estimator={estimator!r}"
    if not success:
        why = message.splitlines()[0] if message else "no message"
        if raw_cover["coverage_cells"] < PARTIAL:
            raise MagexpError(f"{name}: {who} reports failure ({why}), nothing written: the readings "
                              f"cover {100 * raw_cover['coverage_cells']:.0f} % of the sphere, too little for W: record the "
                              "missing orientations, or fit model=sphere (offset and one scale)")
        raise MagexpError(f"{name}: {who} reports failure ({why}), nothing written: "
                          "try another estimator (ellipsoid, lm), or record more orientations")
    cells, raw_cells = round(cover["coverage_cells"] * CELLS), round(raw_cover["coverage_cells"] * CELLS)
    one = cover["direction_max_angle_deg"] < ONE_ATTITUDE_DEG
    if not (one or cells < MIN_CELLS):
        return
    where = (f"about its centre the readings point into {cells} of {CELLS} sphere cells (within "
             f"{cover['direction_max_angle_deg']:.1f} deg of one direction; limits {MIN_CELLS} cells, "
             f"{ONE_ATTITUDE_DEG:g} deg), about the centre of the sphere fitted to them into {raw_cells}")
    if raw_cover["coverage_cells"] >= PARTIAL:  # the readings cover the sphere: the fit collapsed
        raise MagexpError(f"{name}: {who} did not converge, nothing written: {where}: the fit "
                          "collapsed, not the recording; use estimator=ellipsoid (the closed-form fit) or model=full")
    if one and raw_cover["direction_max_angle_deg"] < ONE_ATTITUDE_DEG:
        raise MagexpError(f"{name}: every calibrated direction lies within {cover['direction_max_angle_deg']:.1f} deg "
                          f"of one, under the limit {ONE_ATTITUDE_DEG:g} deg (a single attitude): {RECORD}")
    raise MagexpError(f"{name}: {who}: too few distinct directions, nothing written: {where} "
                      f"({100 * raw_cover['coverage_cells']:.0f} % of the sphere, under {100 * PARTIAL:g} %): record the "
                      "missing orientations, or fit model=sphere (offset and one scale)")


#: an estimator's spread may exceed the closed-form ellipsoid fit's by this factor (:func:`check_optimum`)
OPTIMUM_FACTOR = 1.1


#: the option that sets an iterative estimator's budget, by the first of these its config has (:func:`budget_key`)
BUDGET_KEYS = ("n_iterations", "max_evaluations", "max_nfev", "max_iter")


def budget_key(estimator) -> str | None:
    """The option of ``estimator`` that gives it more iterations (:data:`BUDGET_KEYS`), or None."""
    return next((k for k in BUDGET_KEYS if hasattr(estimator, k)), None)


def estimator_failed(message: str) -> MagexpError:
    """The :class:`MagexpError` of a user's estimator that failed (:func:`magexp.calibration.model_fit.searched`),
    marked ``broken_estimator``: a broken estimator, not a model the readings cannot support, so the held-out check
    and ``model=auto`` (:func:`is_broken_estimator`) let it through instead of counting an unfit fold."""
    error = MagexpError(message)
    error.broken_estimator = True
    return error


def is_broken_estimator(error: BaseException) -> bool:
    """Whether ``error`` is :func:`estimator_failed`'s (a user's estimator failed)."""
    return bool(getattr(error, "broken_estimator", False))


def estimator_name(estimator) -> str:
    """The name of ``estimator`` for a message: its ``name``, else its class's (a user's estimator may have none)."""
    name = getattr(estimator, "name", None)
    return name if isinstance(name, str) and name else type(estimator).__name__


def check_optimum(name: str, estimator, value: float, closed_form: float | None, what: str = "spread") -> None:
    """Fail in one line if an iterative ``estimator`` stopped short of the optimum: its ``what`` (the in-sample
    spread, or the held-out spread of ``model=full``) over :data:`OPTIMUM_FACTOR` times that of the closed-form
    ellipsoid fit of the same readings (``closed_form``; None or NaN when that fit is not an ellipsoid, and
    nothing is checked). The line names the closed-form fit that reached it, not the recording, and the
    estimator's budget option (:func:`budget_key`)."""
    if closed_form is None or not np.isfinite(closed_form) or value <= OPTIMUM_FACTOR * closed_form:
        return
    mine = (f"its {what} {100 * value:.3g} % is {value / closed_form:.3g} times" if np.isfinite(value)
            else f"its fit failed for a region of directions held out ({what} NaN), against")
    key = budget_key(estimator)
    raise MagexpError(f"{name}: estimator={estimator_name(estimator)!r} did not converge, nothing written: {mine} the closed-form "
                      f"ellipsoid fit's {100 * closed_form:.3g} % (limit {OPTIMUM_FACTOR:g} times): use estimator=ellipsoid"
                      + (f", or give it a larger budget (estimator.{key}=..., now {getattr(estimator, key)})" if key else ""))


# -- the acceptance gate ---------------------------------------------------------------------------
#: The gate's default thresholds (``gate.*`` in ``conf/calibrate.yaml``; :func:`gate`).
GATE = {
    "heldout_vs_raw": 1.0,   # the held-out spread must be below this times the raw spread
    "max_anisotropy": 3.0,   # largest / smallest singular value of W (real sensors up to 2.25: docs/calibrate.md)
    "scale_range": (0.2, 5.0),  # each singular value of W / (reference / raw radius): ArduPilot's diagonal range
    "radius_mG": (150.0, 950.0),  # the raw readings' sphere radius (ArduPilot's accepted field radius)
    "radius_vs_reference": (0.5, 2.0),  # the raw radius / the reference total, when a reference is given
    "max_rms_mG": 16.0,      # RMS of |calibrated| - reference (ArduPilot's COMPASS_CAL_FIT default)
    "max_rms_fraction": 0.032,  # the same, relative to the reference, for a raw-count unit (16 / 500 mG)
    "min_region": 0.005,     # each of the 6 regions of directions holds at least this fraction of the readings
    "max_heading_deg": 10.0,  # level worst heading error left, held out (14 CFR 25.1327(b), 29.1327(b): 10 deg on any heading)
}
#: what to record instead, by failed check
ADVICE = {
    "heldout": "the calibration does not hold on readings it was not fitted to: record more orientations "
               "(turn about every axis)",
    "heldout_shots": "the calibration does not hold on directions it was not fitted to: record more static shots, "
                     "spread evenly over every direction and away from iron, or fit fewer parameters (model=sphere "
                     "or diagonal); raw readings already as consistent as the sensor's noise need no calibration",
    "anisotropy": "no magnetometer measured stretches one axis that much (at most 2.25, a QMC5883L: "
                  "docs/calibrate.md): check data.mag_axes and that no iron is fixed beside the sensor; "
                  "gate.max_anisotropy=<limit> accepts it",
    "scale": "W's scale is implausible for a magnetometer: record turns about every axis",
    "radius": "the readings' radius is not an Earth field: check data.unit and that the readings are raw",
    "rms": "the calibrated total still varies more than the readings' noise explains: record slowly, away from "
           "iron and motors",
    "heading": "the compass would be off by more than the limit on some heading: record more orientations "
               "(turn about every axis); gate.max_heading_deg=<degrees> sets the limit",
    "regions": "no held-out check could test the calibration on attitudes there, and it is untested where the data "
               "stop: record turns (or static shots) that point the sensor so",
}


def _pair(value, key: str) -> tuple[float, float]:
    """``(low, high)`` of a range threshold ``gate.<key>`` with ``0 <= low < high``, else one line."""
    try:
        low, high = (float(v) for v in value)
    except (TypeError, ValueError):
        low, high = float("nan"), float("nan")
    if not (0 <= low < high):
        raise MagexpError(f"gate.{key}={value!r} is not allowed: give [low, high] with 0 <= low < high")
    return low, high


def gate_thresholds(overrides=None) -> dict:
    """:data:`GATE` with ``overrides`` (a mapping of ``gate.*``), each checked; unknown keys refused."""
    out = dict(GATE)
    if overrides is not None and not isinstance(overrides, Mapping):
        raise MagexpError(f"gate={overrides!r} is not allowed: give a mapping of the gate's keys to thresholds "
                          f"({', '.join(GATE)})")
    for key, value in dict(overrides or {}).items():
        if key not in GATE:
            raise MagexpError(f"gate.{key}={value!r} is not allowed: the gate's keys are {', '.join(GATE)}")
        if isinstance(GATE[key], tuple):
            out[key] = _pair(value, key)
        else:
            try:
                out[key] = float(value)
            except (TypeError, ValueError):
                out[key] = float("nan")
            if not out[key] > 0:
                raise MagexpError(f"gate.{key}={value!r} is not allowed: it must be a number > 0")
    return out


def gate(w: np.ndarray, metrics: dict, *, raw_radius: float, reference: float, estimated: bool, to_mg,
         thresholds: dict | None = None) -> list[dict]:
    """The acceptance gate: the checks a calibration fails, each ``{check, value, threshold, line}``; ``metrics``
    its spreads, ``raw_radius`` and ``reference`` in the recording's unit, ``to_mg`` mGauss per unit (None for
    counts: absolute checks skipped, the RMS checked relative to the reference), ``estimated`` no reference given.

    Checks (thresholds in :data:`GATE`): the held-out spread below ``heldout_vs_raw`` times the raw
    spread; ``W``'s singular values ``σ`` with ``σ_max / σ_min <= max_anisotropy`` and each
    ``σ / (reference / raw_radius)`` within ``scale_range``; the raw radius within ``radius_mG``
    and, with a given reference, ``raw_radius / reference`` within ``radius_vs_reference``; the RMS of
    ``|B| - reference``, less the readings' own noise (``metrics["noise_after"]``), at most ``max_rms_mG`` (or
    ``max_rms_fraction`` of the reference for counts); each
    of the six regions of directions (``metrics["direction_regions"]``, :func:`magexp.calibration.fit.regions`)
    holding at least ``min_region`` of the readings: a region below it was never held out, so the
    calibration is untested on attitudes there; the level worst heading error it leaves on directions it was
    not fitted to (``metrics["heading_left_deg"]``, :func:`magexp.calibration.heading.worst_left`) at most
    ``max_heading_deg`` (default 10°: the deviation 14 CFR 25.1327(b) and 29.1327(b) allow a
    compensated aircraft compass, in level flight, on any heading).
    """
    t = GATE if thresholds is None else thresholds
    failed = []

    def fail(check, value, threshold, text, advice=None):
        reason = f"check {check!r} failed: {text}"
        advice = ADVICE[check] if advice is None else advice
        failed.append({"check": check, "value": value, "threshold": threshold, "reason": reason,
                       "line": f"{reason}: {advice}" if advice else reason})

    held, raw = metrics.get("heldout_spread"), metrics["spread_before"]
    if held is not None and not (held < t["heldout_vs_raw"] * raw):
        fail("heldout", held, t["heldout_vs_raw"] * raw, *_heldout_text(held, raw, metrics))
    sigma = np.linalg.svd(w, compute_uv=False)
    if sigma[0] > t["max_anisotropy"] * sigma[-1]:
        fail("anisotropy", float(sigma[0] / sigma[-1]), t["max_anisotropy"],
             f"W's singular values {sigma[0]:.3g}/{sigma[-1]:.3g} = {sigma[0] / sigma[-1]:.3g} exceed the limit "
             f"{t['max_anisotropy']:g}")
    scaled = sigma * raw_radius / reference
    low, high = t["scale_range"]
    if scaled.min() < low or scaled.max() > high:
        fail("scale", [float(v) for v in scaled], [low, high],
             f"W's scale {scaled.min():.3g}..{scaled.max():.3g} leaves [{low:g}, {high:g}]")
    if to_mg is not None:
        low, high = t["radius_mG"]
        if not low <= raw_radius * to_mg <= high:
            fail("radius", raw_radius * to_mg, [low, high],
                 f"radius {raw_radius * to_mg:.4g} mGauss outside [{low:g}, {high:g}]")
    if not estimated:
        low, high = t["radius_vs_reference"]
        if not low <= raw_radius / reference <= high:
            fail("radius", raw_radius / reference, [low, high],
                 f"radius {raw_radius:.4g} is {raw_radius / reference:.3g} times the reference {reference:.4g} "
                 f"(allowed [{low:g}, {high:g}])")
    for check in (_rms_check(metrics["rms_after"], reference, to_mg, t, metrics.get("noise_after", 0.0)),
                  _region_check(metrics, t), _heading_check(metrics, t)):
        if check:
            fail(*check)
    return failed


def _heldout_text(held: float, raw: float, metrics: dict) -> tuple[str, str | None]:
    """``(why, advice)`` of a failed held-out check (:func:`gate`): its spread against the raw one, by the design
    that measured it, or, with no spread, the cause :mod:`magexp.calibration.holdout` found (its own remedy)."""
    if not np.isfinite(held):
        return (metrics.get("heldout_failure")
                or "no held-out spread could be measured: record more orientations (turn about every axis)"), ""
    if metrics.get("heldout_design") == "exclusion":
        return (f"held-out spread {100 * held:.3g} % of {metrics['heldout_readings']} readings, each calibrated by the "
                f"fit without the readings within {metrics['heldout_exclusion_deg']:.1f} deg of it, is not below the raw "
                f"{100 * raw:.3g} %", ADVICE["heldout_shots"])
    return f"held-out spread {100 * held:.3g} % is not below the raw {100 * raw:.3g} %", None


def _heading_check(metrics: dict, t: dict) -> tuple | None:
    """``(check, value, threshold, text)`` when the level worst heading error the calibration leaves
    (``metrics["heading_left_deg"]``: :func:`magexp.calibration.heading.worst_left`) exceeds ``max_heading_deg``."""
    left, limit = metrics.get("heading_left_deg"), t.get("max_heading_deg", GATE["max_heading_deg"])
    if left is None or left <= limit:
        return None
    return ("heading", left, limit, f"it leaves a heading error of up to {left:.3g} deg (level, held out), over "
                                    f"the limit {limit:g} deg")


def _region_check(metrics: dict, t: dict) -> tuple | None:
    """``(check, value, threshold, text)`` when a region of directions holds less than ``min_region`` of the
    readings (:func:`gate`; the regions of :func:`magexp.calibration.fit.regions`), naming its half-axis."""
    regions = metrics.get("direction_regions")
    if regions is None or min(regions) >= t["min_region"]:
        return None
    empty = [k for k, f in enumerate(regions) if f < t["min_region"]]
    where = " and ".join("[" + ", ".join(f"{v:.2f}" for v in metrics["region_axes"][k]) + "]" for k in empty)
    return ("regions", 6 - len(empty), 6,
            f"the readings' directions reach {6 - len(empty)} of the 6 regions about their principal axes (under "
            f"{100 * t['min_region']:g} % of them toward {where}, in the sensor's axes, about the fitted centre)")


def _rms_check(rms: float, reference: float, to_mg, t: dict, noise: float = 0.0) -> tuple | None:
    """``(check, value, threshold, text)`` when the residual RMS, less the readings' own noise ``noise``
    (the RMS of the calibrated magnitudes' reading-to-reading noise, :func:`magexp.calibration.quality.noise_of`;
    ``sqrt(rms² - noise²)``: what a calibration could still remove), exceeds its threshold (:func:`gate`)."""
    left = float(np.sqrt(max(rms**2 - noise**2, 0.0)))
    if to_mg is not None and left * to_mg > t["max_rms_mG"]:
        return "rms", left * to_mg, t["max_rms_mG"], (f"residual RMS {rms * to_mg:.3g} mGauss, {left * to_mg:.3g} without "
                                                      f"the readings' noise {noise * to_mg:.3g}, exceeds the limit "
                                                      f"{t['max_rms_mG']:g}")
    if to_mg is None and left > t["max_rms_fraction"] * reference:
        return ("rms", left / reference, t["max_rms_fraction"],
                f"residual RMS {100 * rms / reference:.3g} % of the reference, {100 * left / reference:.3g} % without "
                f"the readings' noise {100 * noise / reference:.3g} %, exceeds the limit {100 * t['max_rms_fraction']:g} %")
    return None


def refuse(name: str, failed: list[dict]) -> None:
    """Raise the gate's one line: every failed check, then how to override."""
    raise MagexpError(f"{name}: calibration refused, nothing written: " + "; ".join(f["line"] for f in failed)
                      + "; accept=true writes it anyway, with these failures recorded")
