"""What a log's firmware already did (issue 33 item 6): the onboard calibration a PX4 ULog or ArduPilot
DataFlash log carries, which its reader undid (:mod:`magexp.core.logfiles`), and how good it was.

The reader keeps the readings as logged (after the onboard calibration) beside the raw ones (columns
:data:`magexp.core.logfiles.LOGGED`). The onboard calibration was fitted before the log was recorded, so every
reading of the log is held out from it: the spread of the logged magnitudes is its held-out spread, set beside
the raw readings' spread and magexp's own held-out spread (:func:`magexp.calibration.fit.heldout`). The
printed report, ``calibration.json`` (``quality.onboard_calibration``) and a refusal say it.
"""

from __future__ import annotations

import functools
import re
from contextlib import contextmanager

import numpy as np

from magexp.core.identifiability import spread
from magexp.core.logfiles import LOGGED
from magexp.core.recording import Recording
from magexp.errors import MagexpError


def parameters_of(rec: Recording) -> str:
    """The firmware and parameters of ``rec``'s onboard calibration (``PX4 CAL_MAG0_*``, ``ArduPilot
    COMPASS_OFS_*, ...``), from what its reader recorded (``meta``)."""
    if rec.meta.get("format") == "ulog":
        return f"PX4 CAL_MAG{rec.meta.get('calibration_slot', '0')}_*"
    instance = re.search(r"instance (\d+)", rec.meta.get("source", ""))
    suffix = "" if instance is None or instance[1] == "0" else str(int(instance[1]) + 1)
    return (f"ArduPilot COMPASS_OFS{suffix}_*, COMPASS_DIA{suffix}_*, COMPASS_ODI{suffix}_*, "
            f"COMPASS_SCALE{suffix}")


def onboard_of(rec: Recording, heldout_spread: float | None) -> dict:
    """``{"onboard_calibration": {...}}`` of a log whose reader undid an onboard calibration, else ``{}``:
    its firmware and parameters, that it was undone and how (the reader's equation), and the spreads of
    the readings as logged (its held-out spread), raw, and held out from magexp's calibration
    (``heldout_spread``; None when not measured)."""
    if not all(c in rec.columns for c in LOGGED):
        return {}
    logged = np.column_stack([rec.columns[c] for c in LOGGED])
    return {"onboard_calibration": {
        "parameters": parameters_of(rec), "undone": True, "how": rec.meta.get("corrected", ""),
        "spread_as_logged": spread(np.linalg.norm(logged, axis=1)),
        "spread_raw": spread(np.linalg.norm(rec.readings, axis=1)),
        "heldout_spread_magexp": None if heldout_spread is None or not np.isfinite(heldout_spread)
        else float(heldout_spread)}}


def onboard_line(record: dict | None) -> str:
    """The report's line of :func:`onboard_of`'s record ('' without one)."""
    if not record:
        return ""
    held = record["heldout_spread_magexp"]
    return (f"{SAID}{record['parameters']}) was undone, the readings are raw: spread as "
            f"logged (onboard-corrected) {100 * record['spread_as_logged']:.3g} %, raw {100 * record['spread_raw']:.3g} "
            "%, magexp's calibration held out " + ("not measured" if held is None else f"{100 * held:.3g} %"))


#: how every :func:`onboard_line` starts (a refusal that says it already is not told again)
SAID = "the log's onboard calibration ("


@contextmanager
def saying_onboard(rec: Recording, heldout_spread: float | None = None):
    """Within the block, a refusal (:class:`~magexp.errors.MagexpError`) of a log whose onboard calibration was
    undone ends with :func:`onboard_line`: what the firmware already did, and how good it was (once)."""
    try:
        yield
    except MagexpError as exc:
        note = onboard_line(onboard_of(rec, heldout_spread).get("onboard_calibration"))
        if not note or SAID in str(exc):
            raise
        raise MagexpError(f"{exc}; {note}") from None


def says_onboard(calibrate):
    """``calibrate(rec, ...)`` whose every refusal of a log says what its firmware already did (:func:`saying_onboard`).
    """
    @functools.wraps(calibrate)
    def wrapped(rec: Recording, *args, **kwargs):
        with saying_onboard(rec):
            return calibrate(rec, *args, **kwargs)
    return wrapped
