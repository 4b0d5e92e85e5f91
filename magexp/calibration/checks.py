"""Whether readings can determine a calibration, and whether a fit did: the degenerate cases of
``magexp calibrate`` (identical readings, one attitude, one plane, too few directions, a failed fit),
each refused in one :class:`~magexp.errors.MagexpError` line that says why and what to record instead.

The measures they read (direction coverage, :data:`~magexp.core.identifiability.CELLS`) are the
core's (:mod:`magexp.core.identifiability`).
"""

from __future__ import annotations

import numpy as np

from magexp.core.identifiability import CELLS
from magexp.errors import MagexpError

#: Degenerate-data thresholds (see :func:`check_readings` and :func:`check_fit`).
MIN_DISTINCT = 12
PLANE_RATIO = 0.02   # sqrt(λ_min / λ_max) of the raw readings' covariance below it: one plane
MIN_CELLS = 8        # fewer occupied cells (a quarter of the sphere): too few distinct directions
PARTIAL = 0.75       # fewer occupied cells after a failed fit: say the coverage is partial
ONE_ATTITUDE_DEG = 20.0  # every calibrated direction within this angle of their mean: one attitude
STILL = 0.05         # RMS distance of the raw readings from their centroid below this fraction of their magnitude: one attitude
RECORD = "record again while turning the sensor slowly through as many orientations as you can (a full sphere)"


def check_readings(readings: np.ndarray, name: str) -> None:
    """Fail in one line if the raw readings cannot determine a calibration: too few distinct
    readings, readings that barely move (one attitude; an offset over ~20 times the field would
    look the same), or readings in one plane."""
    distinct = len(np.unique(readings, axis=0))
    if distinct < MIN_DISTINCT:
        raise MagexpError(f"{name}: only {distinct} distinct readings, a calibration needs at least {MIN_DISTINCT}: "
                          f"{RECORD}")
    centred = readings - readings.mean(axis=0)
    moved = float(np.sqrt((centred**2).sum(axis=1).mean()) / max(np.linalg.norm(readings, axis=1).mean(), 1e-300))
    if moved < STILL:
        raise MagexpError(f"{name}: the readings barely move (RMS distance from their centroid {100 * moved:.2g} % of "
                          f"their magnitude): one attitude cannot determine a calibration: {RECORD}")
    ev = np.linalg.eigvalsh(centred.T @ centred / len(readings))
    if ev[0] <= (PLANE_RATIO**2) * ev[-1]:
        raise MagexpError(f"{name}: the readings lie in one plane (thickness {np.sqrt(max(ev[0], 0) / ev[-1]):.2g} of "
                          "their width: turns about one axis only), which cannot determine the offset along its "
                          "normal nor the scale across it: also turn the sensor about a second axis")


def check_fit(name: str, estimator: str, success: bool, message: str, cover: dict, raw_cover: dict) -> None:
    """Fail in one line if the estimator failed or the calibrated directions show one attitude
    or too few distinct directions. ``raw_cover``: the coverage of the raw readings about the
    centre of their fitted sphere (what a failed fit's message quotes)."""
    if not success:
        why = message.splitlines()[0] if message else "no message"
        if raw_cover["coverage_cells"] < PARTIAL:
            raise MagexpError(f"{name}: estimator={estimator!r} reports failure ({why}), nothing written: the readings "
                              f"cover {100 * raw_cover['coverage_cells']:.0f} % of the sphere, too little for W: record the "
                              "missing orientations, or fit model=sphere (offset and one scale)")
        raise MagexpError(f"{name}: estimator={estimator!r} reports failure ({why}), nothing written: "
                          "try another estimator (ellipsoid, lm), or record more orientations")
    if cover["direction_max_angle_deg"] < ONE_ATTITUDE_DEG:
        raise MagexpError(f"{name}: every calibrated direction lies within {cover['direction_max_angle_deg']:.1f} deg "
                          f"of one (a single attitude): {RECORD}")
    cells = round(cover["coverage_cells"] * CELLS)
    if cells < MIN_CELLS:
        raise MagexpError(f"{name}: the readings point into only {cells} of {CELLS} sphere cells (too few distinct "
                          f"directions): {RECORD}")
