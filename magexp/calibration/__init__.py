"""Calibrating a user's recording: ``magexp calibrate`` and :func:`magexp.calibrate`.

Lives here: :mod:`~magexp.calibration.fit` (the fit, held-out folds, the quality report, the
``Calibration`` object and the command), :mod:`~magexp.calibration.models` (``model=auto``: sphere,
diagonal, full or, with a gyroscope, gyro-aided, chosen by held-out spread), :mod:`~magexp.calibration.checks` (the acceptance gate:
degenerate data, failed fits and implausible calibrations, refused in one line),
:mod:`~magexp.calibration.write` (the output folder and the printed summary),
:mod:`~magexp.calibration.figure` (its figure) and :mod:`~magexp.calibration.export` (ArduPilot, PX4,
ROS and C parameter files).

May import: ``core``, ``problems``, ``scenarios``, ``estimators``, ``run`` (composition, preflight,
outputs) and ``artifacts`` (the house figure style :mod:`magexp.artifacts.plots.style`).
"""
