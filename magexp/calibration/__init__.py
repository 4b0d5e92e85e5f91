"""Calibrating a user's recording: ``magexp calibrate`` and :func:`magexp.calibrate`, in three rooms.

* **The API**: :mod:`~magexp.calibration.api` (:func:`~magexp.calibration.api.calibrate`, its keyword
  parameters explicit) and :mod:`~magexp.calibration.result` (``Calibration``, what it returns, holding
  the ``Reference`` of :mod:`~magexp.calibration.inputs`).
* **The pipeline** (read → fit → checks → outputs): :mod:`~magexp.calibration.inputs` (the reference total
  field and the recording's dataset), :mod:`~magexp.calibration.fit` (the pipeline itself, the fit and the
  held-out regions), :mod:`~magexp.calibration.quality` (spread, noise, the identifiability report),
  :mod:`~magexp.calibration.models` (``model=auto``: sphere, diagonal, full or,
  with a gyroscope, gyro-aided, chosen by held-out spread), :mod:`~magexp.calibration.checks` (the acceptance
  gate: degenerate data, failed fits and implausible calibrations, refused in one line),
  :mod:`~magexp.calibration.onboard` (a log's onboard calibration), :mod:`~magexp.calibration.write` (the
  output folder and the printed summary), :mod:`~magexp.calibration.figure` (its figure) and
  :mod:`~magexp.calibration.export` (ArduPilot, PX4, ROS and C parameter files).
* **The command**: :mod:`~magexp.calibration.command` (``magexp calibrate KEY=VALUE ...``: parsing, composing,
  printing) and :mod:`~magexp.calibration.options` (the typed schema of its keys: ``--help`` and
  ``conf/calibrate.yaml`` come from it).

May import: ``core``, ``problems``, ``scenarios``, ``estimators``, ``run`` (composition, preflight,
outputs) and ``artifacts`` (the house figure style :mod:`magexp.artifacts.plots.style`).
"""
