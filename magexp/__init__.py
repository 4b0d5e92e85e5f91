"""magexp: reproducible experiments on three-axis magnetometer calibration.

Data flows one way::

    scenario ──► Dataset ──► problem (vectorised cost) ──► estimator.fit ──► FitResult
             ──► metrics ──► tidy rows ──► results/<paper>/<artifact>.csv ──► figures, report

The public API::

    from magexp import calibrate, Calibration, FitResult

* :func:`calibrate` (:func:`magexp.calibration.api.calibrate`): calibrate readings, a DataFrame or a recording;
* :class:`Calibration` (:class:`magexp.calibration.result.Calibration`): what it returns;
* :class:`FitResult` (:class:`magexp.estimators.result.FitResult`): what every estimator's ``fit`` returns
  (the estimators themselves: :mod:`magexp.estimators`).

Importing magexp changes nothing in the importing process (no environment variable, no thread
setting): the commands set one BLAS thread for themselves (:mod:`magexp.run.threads`).
"""

from magexp._version import __version__

#: the names of the public API, each imported on its first use (below)
__all__ = ["__version__", "calibrate", "Calibration", "FitResult"]


def __getattr__(name: str):
    """The public API's ``name``, imported on first use (PEP 562) and kept. Measured saving: ``import magexp``
    takes 0.03 s CPU alone and 0.37 s with the calibration API (median of 5, ``/usr/bin/time``), which every
    command would pay (``python -m magexp`` imports this package first) and a run's workers too.

    Parameters
    ----------
    name : str
        ``calibrate``, ``Calibration`` or ``FitResult``.

    Returns
    -------
    object
        The function or class.

    Raises
    ------
    AttributeError
        For any other name.
    """
    if name == "calibrate":
        from magexp.calibration.api import calibrate as value
    elif name == "Calibration":
        from magexp.calibration.result import Calibration as value
    elif name == "FitResult":
        from magexp.estimators.result import FitResult as value
    else:
        raise AttributeError(f"module 'magexp' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The module's names with the public API's (:data:`__all__`)."""
    return sorted({*globals(), *__all__})
