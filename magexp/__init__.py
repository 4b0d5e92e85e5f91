"""magexp: reproducible experiments on three-axis magnetometer calibration.

Data flows one way::

    scenario ──► Dataset ──► problem (vectorised cost) ──► estimator.fit ──► FitResult
             ──► metrics ──► tidy rows ──► results/<paper>/<artifact>.csv ──► figures, report
"""

import os as _os

# Deterministic numbers: one BLAS thread (the matrices here are small, so threads buy nothing,
# and a threaded reduction order can move a flat direction of a fit in its last digits).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_var, "1")

__version__ = "0.1.0"


def calibrate(readings, **options):
    """Calibrate readings: see :func:`magexp.calibration.fit.calibrate` (imported on first use)."""
    from magexp.calibration.fit import calibrate as _calibrate

    return _calibrate(readings, **options)
