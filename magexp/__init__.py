"""magexp: reproducible experiments on three-axis magnetometer calibration.

Data flows one way::

    scenario ──► Dataset ──► problem (vectorised cost) ──► estimator.fit ──► FitResult
             ──► metrics ──► tidy rows ──► results/<paper>/<artifact>.csv ──► figures, report
"""

__version__ = "0.1.0"
