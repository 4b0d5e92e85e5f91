"""The side of the calibration tools pilots use, run in their own environment (``.peers/tools-venv``, ``make
peers-tools``), never in magexp's: ``magcal`` 1.0.1 (PyPI, a calibration CLI for drones and robots) and
``circuitpython-mag-cal`` 1.4.1 (``mag_cal``). This file imports numpy, the standard library and those two only.

``python tools_side.py IN.npz OUT.json``
    ``IN.npz`` holds ``mag`` (N, 3) raw readings and ``labels`` (N,) their region of directions
    (:func:`magexp.calibration.fit.regions`); ``folds`` (K,) the regions held out one at a time. For each tool
    and each fit (``all`` the readings, then each fold: the readings outside that region), it writes
    ``{"W", "o", "error", "seconds"}`` to ``OUT.json``, ``B = W (r - o)``, or the tool's own refusal (the
    exception's text) in ``error``. ``seconds``: the process time of the fit alone.

Each tool is called as its own documentation shows, its default method:

* ``magcal``: ``MagnetometerCalibrator().calibrate("ellipsoid")`` on ``raw_data`` (what ``magcal from-file``
  runs); ``B = T (r - c)`` with ``center`` ``c`` (the data mean) and ``transform_matrix`` ``T``;
* ``mag_cal``: ``Sensor().fit_ellipsoid(data)``, ``Sensor.apply``: ``B = (r - c) T``, so ``W = Tᵀ``.
"""

from __future__ import annotations

import contextlib
import io
import json
import sys
import time
from importlib.metadata import version

import numpy as np
from mag_cal import Sensor
from magcal.core import MagnetometerCalibrator  # it imports pyplot (and pyserial): run with MPLBACKEND=Agg (tools.py)


def load() -> dict:
    """The tools' fit functions (their modules are imported with this file, before any timing)."""
    def fit_magcal(data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(W, o)`` of magcal's ellipsoid method (module docstring); its refusal raised as it raises it."""
        cal = MagnetometerCalibrator()
        cal.raw_data = data.tolist()
        with contextlib.redirect_stdout(io.StringIO()):  # it prints its own progress and quality
            params = cal.calibrate("ellipsoid")
        return np.asarray(params["transform_matrix"], float), np.asarray(params["center"], float)

    def fit_mag_cal(data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(W, o)`` of circuitpython-mag-cal's ``Sensor.fit_ellipsoid`` (module docstring)."""
        sensor = Sensor("+X+Y+Z")
        sensor.fit_ellipsoid(data.copy())
        return np.asarray(sensor.transform, float).T, np.asarray(sensor.centre, float).ravel()

    return {"magcal": fit_magcal, "circuitpython-mag-cal": fit_mag_cal}


def one(fit, data: np.ndarray) -> dict:
    """One fit's answer: ``W``, ``o``, ``seconds``, or the tool's ``error``."""
    start = time.process_time()
    try:
        w, o = fit(data)
    except Exception as exc:  # the tool's own refusal, whatever it raises
        return {"W": None, "o": None, "error": f"{type(exc).__name__}: {exc}"[:300],
                "seconds": time.process_time() - start}
    seconds = time.process_time() - start
    return {"W": np.real(w).tolist(), "o": np.real(o).tolist(), "error": None, "seconds": seconds}


def main(argv: list[str]) -> int:
    """Fit every tool on the readings of ``source`` and on each fold's complement; the answers to ``out``."""
    source, out = argv
    with np.load(source, allow_pickle=False) as npz:
        mag, labels, folds = (np.asarray(npz[k]) for k in ("mag", "labels", "folds"))
    answer = {"format": "magexp-tools-exchange v1", "versions": {}, "fits": {}}
    for name, fit in load().items():
        fits = {"all": one(fit, mag.astype(float))}
        for k in folds.tolist():
            fits[str(k)] = one(fit, mag[labels != k].astype(float))
        answer["fits"][name] = fits
    answer["versions"] = {"magcal": version("magcal"), "circuitpython-mag-cal": version("circuitpython-mag-cal")}
    with open(out, "w") as f:
        json.dump(answer, f, allow_nan=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
