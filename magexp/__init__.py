"""magexp: reproducible experiments on three-axis magnetometer calibration.

Data flows one way::

    scenario ──► Dataset ──► problem (vectorised cost) ──► estimator.fit ──► FitResult
             ──► metrics ──► tidy rows ──► results/<paper>/<artifact>.csv ──► figures, report

Importing magexp changes nothing in the importing process (no environment variable, no thread
setting): the commands set one BLAS thread for themselves (:mod:`magexp.run.threads`).
"""

__version__ = "0.1.0"


def calibrate(readings, **options):
    """Calibrate readings: see :func:`magexp.calibration.fit.calibrate` (imported on first use)."""
    from magexp.calibration.fit import calibrate as _calibrate

    return _calibrate(readings, **options)
