"""The Python API of the calibration: ``magexp.calibrate(readings, unit="uT", estimator="lm")``.

:func:`calibrate` takes readings as they come (an ``(N, 3)`` array, a DataFrame, a recording's path or a
:class:`~magexp.core.recording.Recording`), runs the pipeline (:func:`magexp.calibration.fit.calibrate_recording`)
and returns a :class:`~magexp.calibration.result.Calibration`. Its keyword defaults are the command's
(:data:`magexp.calibration.options.DEFAULTS`, the one home of both).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from magexp.calibration.fit import calibrate_recording, numpy_path
from magexp.calibration.inputs import readings_array
from magexp.run.named import estimator_named
from magexp.calibration.options import DEFAULTS, ESTIMATOR
from magexp.calibration.result import Calibration
from magexp.core.limits import check_limits
from magexp.core.recording import Recording, check_unit
from magexp.core.textfiles import check_unique
from magexp.core.readers.header_row import MAG_COLUMNS
from magexp.core.recordings import load_recording, resolve
from magexp.core.seeding import run_generators
from magexp.errors import MagexpError
from magexp.run.keys import check_seed
from magexp.problems.kernels import numpy_only
from magexp.run.files import check_recording_file
from magexp.run.compose import options


def frame_readings(frame) -> np.ndarray:
    """The ``(N, 3)`` readings of a DataFrame: its ``bx, by, bz`` (or ``mx, my, mz``, ``x, y, z``:
    :data:`~magexp.core.readers.header_row.MAG_COLUMNS`) columns, else its three numeric columns."""
    cols = [str(c).strip().lower() for c in frame.columns]
    check_unique(cols, "readings")
    pick = next((names for names in MAG_COLUMNS if all(n in cols for n in names)), None)
    chosen = frame.iloc[:, [cols.index(n) for n in pick]] if pick else frame.select_dtypes("number")
    if chosen.shape[1] != 3:
        raise MagexpError(f"readings with columns {list(frame.columns)} are not allowed: give bx, by, bz "
                          "(or x, y, z), or exactly three numeric columns")
    return chosen.to_numpy(float)


def as_recording(readings, *, unit: str | None = None) -> Recording:
    """A :class:`Recording` from an ``(N, 3)`` array, a DataFrame (columns ``bx, by, bz`` or
    ``x, y, z``, else its three numeric columns), a path or a Recording."""
    if isinstance(readings, Recording):
        return readings
    if isinstance(readings, (str, Path)):
        if not str(readings).strip():
            raise MagexpError(f"readings={str(readings)!r} is not allowed: give a recording's path, an (N, 3) array "
                              "or a DataFrame")
        check_recording_file(resolve(readings), "readings")  # no device or FIFO, within the limits: before it is read
        return load_recording(readings, unit=unit)
    pandas = sys.modules.get("pandas")  # a DataFrame exists only if pandas is loaded: not importing it saves
    if pandas is not None and isinstance(readings, pandas.DataFrame):  # 240 ms (-X importtime) per calibration
        readings = frame_readings(readings)
    values = readings_array(readings)
    if values.ndim != 2 or values.shape[1] != 3:
        raise MagexpError(f"readings of shape {values.shape} are not allowed: give an (N, 3) array")
    if not np.all(np.isfinite(values)):
        raise MagexpError("readings with NaN or infinite values are not allowed: every value must be finite")
    if unit is None:
        raise MagexpError("unit=None is not allowed: name the unit of the readings (nT, uT, mG, G, T or counts)")
    return Recording(readings=values, angles=None, field=None, unit=check_unit(unit, "unit"),
                     meta={"format": "array", "name": "readings"})


def check_arguments(seed, reference_total, estimator_options: dict) -> int:
    """Refuse, in one line, the arguments of :func:`calibrate` no later check reads as the command does: a seed
    that is not an integer in ``[0, MAX_SEED]`` (:func:`~magexp.run.keys.check_seed`), a reference
    total that is not a number (a string, a bool), an estimator option ``name`` (the estimator is
    ``estimator=``); returns the seed as an int."""
    seed = check_seed(seed)
    if reference_total is not None and (isinstance(reference_total, (bool, str, bytes)) or
                                        not isinstance(reference_total, (int, float, np.number))):
        raise MagexpError(f"reference_total={reference_total!r} is not allowed: give a number > 0 (the readings' "
                          "unit) or None")
    if "name" in estimator_options:
        raise MagexpError(f"name={estimator_options['name']!r} is not allowed as an estimator option: choose the "
                          "estimator with estimator=...")
    return seed


def calibrate(readings, *, unit: str | None = None, estimator=ESTIMATOR, objective: str = DEFAULTS.objective,
              reference_total=None, folds: int = DEFAULTS.folds, seed: int = DEFAULTS.seed, checks: bool = True,
              model: str = DEFAULTS.model, accept: bool = DEFAULTS.accept, gate=None,
              auto_margin: float = DEFAULTS.auto_margin, compiled: bool | None = None,
              **estimator_options) -> Calibration:
    """Calibrate readings from a notebook: ``magexp.calibrate(readings, unit="uT", estimator="lm")``.

    Fits the calibration ``B_i = W (r_i - o)`` of raw readings ``r_i`` (Ding 2024 eq 9, ``W = M^-1`` and
    ``o = I``; Yuan 2018's ``W = S^-1``, ``o = b``) by minimising, with ``objective="scalar"``, the total-field
    RMS against the reference ``B_a`` (Ding 2024 eqs 17-18)

    .. math:: \\mathrm{RMS} = \\sqrt{\\tfrac1N \\sum_i (\\lVert W (\\mathbf r_i - \\mathbf o) \\rVert - B_a)^2}

    or, with ``objective="vector"``, the vector misfit to the attitudes' reference vectors (Yuan 2018 eq 8)

    .. math:: F = \\sum_i \\lVert C_i^b \\mathbf H_i - W (\\mathbf r_i - \\mathbf o) \\rVert

    with the model ``model=auto`` chooses by held-out spread (:mod:`magexp.calibration.models`), then checks
    it (the acceptance gate, :func:`magexp.calibration.checks.gate`).

    Parameters
    ----------
    readings : array_like, DataFrame, str, Path or Recording
        ``(N, 3)`` raw readings, a DataFrame (``bx, by, bz`` / ``mx, my, mz`` / ``x, y, z`` columns, else
        its three numeric columns), a recording's path in any format of
        :mod:`magexp.core.readers`, or a loaded :class:`~magexp.core.recording.Recording`.
    unit : str or None
        Unit of an array or DataFrame (``nT, uT, mG, G, T, counts``); of a path, as ``data.unit``.
    estimator : str or estimator
        A name of ``conf/estimator/*.yaml`` (``ellipsoid``, ``lm``, ``ipso``, ...) or an object with a
        ``fit(problem, rng=...)`` method.
    objective : str
        ``scalar`` (total field) or ``vector`` (needs attitudes and ``# field:``).
    reference_total : float or None
        The reference total field (the readings' unit); None: the recording's, else estimated
        (:func:`magexp.calibration.fit.reference_of`).
    folds : int
        The held-out check: 0 none; 2 or more, each region of directions calibrated by the fit on the others (a few
        static shots: each reading by the fit without its neighbours, :mod:`magexp.calibration.holdout`).
    seed : int
        The estimator's random generator derives from it (:func:`magexp.core.seeding.run_generators`).
    checks : bool
        Refuse degenerate data, failed fits and calibrations failing the gate; False measures them anyway.
    model : str
        ``auto``, ``sphere``, ``diagonal``, ``full`` or ``gyro`` (:mod:`magexp.calibration.models`).
    accept : bool
        Keep a calibration that fails the acceptance gate, its failures recorded in ``report["gate"]``.
    gate : dict or None
        ``gate.*`` thresholds overriding :data:`magexp.calibration.checks.GATE`.
    auto_margin : float
        ``model=auto``: a richer model must cut the simpler one's held-out spread by this fraction.
    compiled : bool or None
        The kernels' path: False numpy; True the compiled (numba) kernels where installed and not turned off
        by ``MAGEXP_NUMBA=0``; None (default) the compiled ones for an iterative estimator, numpy for a
        closed form, whose few residual evaluations do not repay loading numba
        (:func:`magexp.calibration.fit.numpy_path`).
    **estimator_options
        Overrides of the estimator config (e.g. ``n_iterations=200``).

    Returns
    -------
    Calibration
        ``.w`` (canonical form), ``.offset``, ``.calibrated``, ``.metrics`` (spread before, after,
        held out; coverage), ``.report`` (standard errors, conditioning, undetermined combinations, the gate).

    Raises
    ------
    MagexpError
        One line for bad input (any argument above, a seed outside ``[0, MAX_SEED]`` (:data:`magexp.run.keys.MAX_SEED`), an unreadable
        recording), degenerate data, a failed estimator or, with ``checks``, a calibration failing the gate.

    See Also
    --------
    magexp.calibration.result.Calibration.load : read back a saved calibration.

    References
    ----------
    Ding Xuezhen, *Integrated calibration of sensor errors with improved PSO algorithm*, Digital Ocean &
    Underwater Warfare 7(3):285-292, 2024 (eqs 9, 17, 18).

    Yuan Yujia, Wang Wei, Chen Xingbang, *Particle swarm optimization with MEMS gyro-aided for magnetometer
    calibration*, Navigation Positioning & Timing 5(6):92-98, 2018 (eqs 1, 8).
    """
    check_limits()
    rec = as_recording(readings, unit=unit)
    if not isinstance(estimator, str) and not callable(getattr(estimator, "fit", None)):
        raise MagexpError(f"estimator={estimator!r} is not allowed: give an estimator's name ("
                          f"{', '.join(options('estimator'))}) or an object with a fit(problem, rng=...) method")
    seed = check_arguments(seed, reference_total, estimator_options)
    est = estimator_named(estimator, **estimator_options) if isinstance(estimator, str) else estimator
    _, rng = run_generators(seed)
    with numpy_only(numpy_path(compiled, est)):
        cal = calibrate_recording(rec, est, objective=objective, reference_total=reference_total, folds=folds,
                                  rng=rng, checks=checks, model=model, accept=accept, gate_overrides=gate,
                                  auto_margin=auto_margin)
    cal.seed = seed
    cal.config = {"readings": str(readings) if isinstance(readings, (str, Path)) else type(readings).__name__,
                  "unit": unit, "estimator": est.name if hasattr(est, "name") else str(estimator),
                  "objective": objective, "reference_total": None if reference_total is None else
                  float(np.mean(cal.reference.total)), "folds": folds, "seed": seed, "checks": checks, "model": model,
                  "accept": accept, "gate": dict(gate or {}), "auto_margin": auto_margin,
                  **({} if compiled is None else {"compiled": compiled}), **estimator_options}
    return cal
