"""The held-out check's designs: which readings each fold of :func:`magexp.calibration.fit.heldout` holds out,
how the held-out magnitudes are pooled, and what the output says was measured.

A calibration must hold on directions it was not fitted to (a fit is always good on its own readings).
Both designs fit the model on some readings and calibrate others whose *directions* the fit has not seen;
``heldout_spread`` is the spread ``std / mean`` of the pooled held-out magnitudes ``|W_k (r_i - o_k)|``.

**Direction regions** (``heldout_design = "regions"``). The readings' directions ``u_i`` about the centre of
the sphere fitted to them are cut into six regions, one about each half-axis ``±v_k`` of their principal axes
(:func:`magexp.core.identifiability.direction_regions`); each occupied region is calibrated by the fit on the
other five. Used when every occupied region holds at least :data:`~magexp.calibration.checks.MIN_READINGS`
readings (a fold must be large enough for its spread to mean something): six fits, the design of a recording
in which the sensor was turned. Over :data:`MAX_EXCLUSION_READINGS` readings it is used whatever the regions
hold, a smaller region's readings staying in every fit (the gate refuses such a region as untested).

**Neighbours excluded** (``heldout_design = "exclusion"``). A recording of a couple of dozen static shots (the
common hand-held or bench workflow: circuitpython-mag-cal's, MotionCal's fixed points) has about four readings
per region, so no region could be a fold. Each reading ``i`` is held out in turn, and its fit leaves out with it
every reading within :data:`EXCLUSION_DEG` of its direction,

.. math:: \\mathcal T_i = \\{ j : \\mathbf u_j \\cdot \\mathbf u_i < \\cos\\theta_x \\},

so the fit never sees a neighbouring shot and the held-out reading lies in a gap of the fit's directions, as a
region does in the first design. :math:`\\theta_x = \\arccos(2/3) = 48.19°` is the half-angle of the spherical cap
of solid angle :math:`4\\pi/6` (a cap of half-angle ``θ`` covers ``(1 - cos θ) / 2`` of the sphere): the gap
about each held-out reading is as large as one of the six regions, so both designs test the same
extrapolation. The pooled magnitudes are the N readings', each by a fit that had not seen its sixth of the
sphere. Cost: one fit per fold; with more than :data:`MAX_EXCLUSION_FOLDS` readings the held-out readings are
grouped into that many folds, by the nearest of as many directions spread by farthest-point sampling, and each
fold's fit leaves out every reading within :data:`EXCLUSION_DEG` of any of its readings, so an iterative
estimator runs at most that many fits at its budget (a closed-form one takes milliseconds for all of them).

A fold whose fit keeps fewer than :data:`~magexp.calibration.checks.MIN_READINGS` readings, or whose fit fails,
gives no held-out spread (NaN); the record then says why in ``heldout_failure`` (too few readings, or shots
too clumped in direction, with what to record), which the gate quotes (:mod:`magexp.calibration.checks`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from magexp.calibration.checks import GATE, MIN_READINGS
from magexp.calibration.models import ORDER
from magexp.core.ellipsoid import fit_sphere
from magexp.core.identifiability import spread
from magexp.errors import MagexpError, check_positive_int

#: Angular exclusion radius of the neighbours-excluded design (module docstring): ``arccos(2/3)`` in degrees,
#: the half-angle of a cap holding a sixth of the sphere, as much as one of the six direction regions.
EXCLUSION_DEG = math.degrees(math.acos(2.0 / 3.0))
#: Most folds of the neighbours-excluded design: one per reading up to a couple of dozen static shots (the
#: common workflow), grouped beyond that so that an iterative estimator runs at most this many fits.
MAX_EXCLUSION_FOLDS = 24
#: Most readings held out by the neighbours-excluded design: beyond ``MIN_READINGS / gate.min_region`` (its default
#: 0.005, :data:`magexp.calibration.checks.GATE`) a region of fewer than :data:`MIN_READINGS` readings is refused by
#: the gate as untested anyway, and the design's ``N x (readings per fold)`` direction products stay small.
MAX_EXCLUSION_READINGS = round(MIN_READINGS / GATE["min_region"])
#: The key of :func:`measure`'s record holding each fold's ``(W_k, o_k)`` (for the heading error,
#: :mod:`magexp.calibration.heading`; the pipeline takes it out of the metrics).
FITS = "heldout_fits"
#: Fewest shots, spread evenly, for which each fit keeps :data:`MIN_READINGS` readings beyond the exclusion cap
#: (a sixth of them left out with the held-out one): ``ceil(MIN_READINGS / (5/6)) + 1``.
MIN_SHOTS = math.ceil(MIN_READINGS / (5.0 / 6.0)) + 1

#: A fit of the readings kept (an index array) -> ``(W, o)``, or None when it fails.
FitOn = Callable[[np.ndarray], "tuple[np.ndarray, np.ndarray] | None"]


def _directions(readings: np.ndarray) -> np.ndarray:
    """Unit directions of ``readings`` about the centre of the sphere fitted to them."""
    centred = readings - fit_sphere(readings)[0]
    return centred / np.maximum(np.linalg.norm(centred, axis=1, keepdims=True), 1e-300)


def design_of(labels: np.ndarray) -> str:
    """``"exclusion"`` when an occupied region of ``labels`` (0-5) holds fewer than :data:`MIN_READINGS` readings
    and there are at most :data:`MAX_EXCLUSION_READINGS` readings, else ``"regions"`` (module docstring)."""
    counts = np.bincount(labels, minlength=6)
    small = np.any((counts > 0) & (counts < MIN_READINGS))
    return "exclusion" if small and len(labels) <= MAX_EXCLUSION_READINGS else "regions"


def exclusion_folds(u: np.ndarray, exclusion_deg: float = EXCLUSION_DEG,
                    max_folds: int = MAX_EXCLUSION_FOLDS) -> list[tuple[np.ndarray, np.ndarray]]:
    """``[(held out, kept)]`` index arrays of the neighbours-excluded design: one reading per fold up to
    ``max_folds`` readings, else the readings nearest each of ``max_folds`` farthest-point directions; a fold
    keeps the readings more than ``exclusion_deg`` from every reading it holds out."""
    n = len(u)
    if n <= max_folds:
        groups = np.arange(n)
    else:  # farthest-point centres: a loop over folds, each step vectorised over the readings
        chosen, gap = [0], 1.0 - u @ u[0]
        for _ in range(max_folds - 1):
            chosen.append(int(np.argmax(gap)))
            gap = np.minimum(gap, 1.0 - u @ u[chosen[-1]])
        groups = np.argmax(u @ u[chosen].T, axis=1)
    cos_x = math.cos(math.radians(exclusion_deg))
    folds = []
    for g in np.unique(groups):
        held = np.flatnonzero(groups == g)
        near = (u @ u[held].T).max(axis=1) >= cos_x
        folds.append((held, np.flatnonzero(~near)))
    return folds


def region_folds(labels: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """``[(held out, kept)]`` of the direction-regions design: each region of at least :data:`MIN_READINGS`
    readings against the others (a smaller one's readings, in a recording over :data:`MAX_EXCLUSION_READINGS`,
    stay in every fit: the gate's ``min_region`` check refuses it as untested)."""
    tested = np.flatnonzero(np.bincount(labels, minlength=6) >= MIN_READINGS)
    return [(np.flatnonzero(labels == k), np.flatnonzero(labels != k)) for k in tested]


def measure(readings: np.ndarray, labels: np.ndarray, fit_on: FitOn, model: str = "full", stop=None) -> dict:
    """The held-out record of the design :func:`design_of` picks: each fold's held-out readings calibrated by
    ``fit_on`` of its kept ones, pooled (module docstring)."""
    design = design_of(labels)
    folds = region_folds(labels) if design == "regions" else exclusion_folds(_directions(readings))
    record = {"heldout_design": design, "heldout_folds": len(folds),
              "heldout_readings": int(sum(len(h) for h, _ in folds)),
              "heldout_min_kept": int(min((len(k) for _, k in folds), default=0))}
    if design == "exclusion":
        record["heldout_exclusion_deg"] = EXCLUSION_DEG
    failure = _too_few(readings, folds, design) or _too_few_regions(folds, design)
    pooled, per_fold, fits = [], [], []
    for held, kept in ([] if failure else folds):
        fitted = fit_on(kept)
        if fitted is None:
            failure = _fold_failed(readings, held, kept, design, model)
            break
        w, o = fitted
        fits.append(fitted)
        pooled.append(np.linalg.norm((readings[held] - o) @ w.T, axis=1))
        per_fold.append(spread(pooled[-1]))
        cut = None if stop is None else stop(pooled, record["heldout_readings"], len(folds))
        if cut:
            return {**record, **cut}
    if failure:
        return {**record, "heldout_spread": float("nan"), "heldout_failure": failure}
    record["heldout_spread"] = spread(np.concatenate(pooled))
    record[FITS] = fits
    if design == "regions":
        record["heldout_spread_max_fold"] = float(np.max(per_fold))
    return record


def _too_few_regions(folds: list, design: str) -> str | None:
    """The failure of a regions design with fewer than two regions to hold out, else None."""
    if design != "regions" or len(folds) >= 2:
        return None
    return (f"fewer than two of the six regions of directions about the readings' principal axes hold {MIN_READINGS} "
            "readings, so none can be held out: turn the sensor through as many orientations as you can")


def _too_few(readings: np.ndarray, folds: list, design: str) -> str | None:
    """Why a fold's fit would keep fewer than :data:`MIN_READINGS` readings (count or clumping), else None."""
    if design != "exclusion":
        return None
    n = len(readings)
    worst = min(range(len(folds)), key=lambda f: len(folds[f][1]))
    kept = len(folds[worst][1])
    if kept >= MIN_READINGS:
        return None
    what = (f"with each reading left out, every reading within {EXCLUSION_DEG:.1f} deg of its direction is left "
            f"out of its fit too, and {kept} remain for reading {int(folds[worst][0][0]) + 1} (a fit needs "
            f"{MIN_READINGS})")
    if n < MIN_SHOTS:
        return (f"{n} readings: too few for a held-out check: {what}: record at least {MIN_SHOTS} static shots spread "
                "evenly over every direction (or turn the sensor through every orientation while recording)")
    return (f"{n} readings: too clumped in direction for a held-out check: {what}: spread the shots evenly over "
            "every direction (point each axis of the sensor up and down, and the directions between)")


def _fold_failed(readings: np.ndarray, held: np.ndarray, kept: np.ndarray, design: str, model: str) -> str:
    """Why a fold's fit failed: its kept readings cannot determine ``model`` without the held-out directions."""
    simpler = list(ORDER[:ORDER.index(model)]) if model in ORDER else []
    instead = f", or choose a simpler model ({' or '.join(f'model={m}' for m in simpler)})" if simpler else ""
    if design == "regions":
        return (f"no calibration (model={model}) could be fitted to the {len(kept)} readings outside one region of "
                f"directions ({len(held)} held out): the others cannot determine it without that region: record turns "
                f"that point the sensor between its regions{instead}")
    return (f"{len(readings)} readings: no calibration (model={model}) could be fitted to the {len(kept)} readings "
            f"more than {EXCLUSION_DEG:.1f} deg from reading {int(held[0]) + 1}'s direction: without its neighbours "
            f"the shots cannot determine it: add shots in the directions between{instead}")


def describe(metrics: dict, *, gate: bool = False) -> str:
    """What the held-out check measured, in words: the design, its folds and what each fit left out; with
    ``gate``, the held-out part of a passed gate's line (what beat raw), or that nothing was held out."""
    design = metrics.get("heldout_design") or ("regions" if "heldout_spread" in metrics else "none")  # saved before
    folds = metrics.get("heldout_folds", 0)
    if design == "regions":
        return ("held out beats raw, every region of directions tested" if gate else
                f"{folds} regions of directions, each calibrated by the fit on the others (held-out design: "
                "direction regions)")
    if design == "exclusion":
        n, radius = metrics["heldout_readings"], metrics["heldout_exclusion_deg"]
        if gate:
            return (f"held out beats raw, each of {n} readings tested by a fit without the readings within "
                    f"{radius:.1f} deg of it")
        one = folds == n
        each = "each" if one else f"in {folds} groups of nearby readings, each group"
        return (f"{n} readings, {each} calibrated by the fit on the readings more than {radius:.1f} deg from its "
                f"direction (held-out design: {'leave one out' if one else 'leave a group out'}, neighbours excluded)")
    if gate:
        return f"held-out spread not measured (folds={folds}), untested on directions it was not fitted to"
    return f"not measured (folds={folds}: no held-out check)"


def check_folds(folds) -> int:
    """The held-out check's folds: an integer >= 0 (0 or 1: no held-out check)."""
    if isinstance(folds, str):
        raise MagexpError(f"folds={folds!r} is not allowed: it must be an integer >= 0 (0: no held-out check)")
    return check_positive_int(folds, "folds", minimum=0)
