"""Calibrating a user's recording: ``magexp calibrate`` and :func:`magexp.calibrate`.

Lives here: :mod:`~magexp.calibration.fit` (the fit, held-out folds, the quality report, the command),
:mod:`~magexp.calibration.checks` (degenerate data and failed fits, refused in one line),
:mod:`~magexp.calibration.write` (the output folder and the printed summary), :mod:`~magexp.calibration.figure`
(its figure).

May import: ``core``, ``problems``, ``estimators``, ``run`` (composition and preflight) and the house
figure style :mod:`magexp.artifacts.plots.style`.
"""
