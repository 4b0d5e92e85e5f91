"""A recording as a scenario like any other: ``scenario=real_<recording>`` (``conf/scenario/real_*.yaml``).

:class:`RecordingScenario` loads a file of any format of :mod:`magexp.core.readers` (from
:data:`magexp.paths.SHARED_DATA`, i.e. ``$MAGEXP_DATA`` or ``../shared/data``), optionally cuts a
time ``window``, and gives the :class:`~magexp.core.dataset.Dataset` of one objective (by
:func:`magexp.core.recording.recording_dataset`, the path ``magexp calibrate`` takes too):

* ``scalar``: the readings, ``n_readings`` evenly spaced ones for the fit; the block of fold
  ``heldout_fold`` of ``folds`` contiguous blocks is held out (``dataset.extra["heldout"]``) and
  the metrics report its spread under the fitted calibration (:func:`magexp.core.identifiability.recording_metrics`);
* ``gyro``: ``n_readings`` evenly spaced readings of the window and the gyroscope preintegrated
  between them (:func:`magexp.core.geometry.preintegrate`) for :class:`magexp.problems.gyro.GyroAidedCalibration`.

There is no truth: the reference total is the radius of the sphere fitted to the readings
(:func:`magexp.scenarios.search.centroid_radius`), the search box comes from the data
(:func:`magexp.scenarios.search.search_box`): ``box: auto`` is ``aligned`` for the scalar objective
and ``signed`` (Yuan 2018's widths about zero for ``S`` and about the sphere centre for ``b``) for the
gyro-aided one, whose ``S`` holds the unknown rotation or axis flip between the magnetometer's and
the gyroscope's axes. A seed changes nothing in the data (a recording is
what it is); it seeds the estimator only.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from magexp.core.dataset import Dataset
from magexp.core.identifiability import RECORDING_METRICS
from magexp.core.recording import evenly_spaced, recording_dataset
from magexp.core.recordings import exists, load_recording
from magexp.errors import MagexpError, check, check_nonnegative, check_positive_int
from magexp.paths import SHARED_DATA
from magexp.scenarios.motion import GYRO_RANGE_DEG_S
from magexp.scenarios.search import BOXES, centroid_radius, search_box

OBJECTIVES = ("scalar", "gyro")
#: the box of ``box: auto`` per objective: the scalar objective leaves W's orientation
#: free (the aligned box holds the symmetric member of the optimum's orbit); the gyro-aided one fixes
#: it to the gyroscope's axes, which may be rotated or flipped against the magnetometer's
AUTO_BOX = {"scalar": "aligned", "gyro": "signed"}


class RecordingScenario:
    """A scenario read from a recorded file (``conf/scenario/real_*.yaml``): its keys are the constructor's.

    Parameters
    ----------
    name : str
        The scenario's name.
    file : str
        The recording, relative to the shared data folder (or absolute).
    objective : str
        ``scalar`` or ``gyro``.
    unit, format, mag_axes, gyro_axes
        As :func:`magexp.core.recordings.load_recording`.
    window : list of float or None
        ``[start, end]`` seconds from the first reading (None: all).
    n_readings : int or None
        Readings used by the fit, evenly spaced (None: all).
    folds, heldout_fold : int
        Contiguous blocks, and the one held out of the fit (scalar; folds 0: none).
    bias_bound_deg_s : float
        Half-width of the gyro-bias search interval (gyro).
    rest_file : str or None
        A recording of the same gyroscope at rest (gyro): its mean rate, in the same axes, is reported
        beside the estimated bias (``gyro_bias_rest_*``, ``gyro_bias_difference``).
    box : str
        ``aligned``, ``signed`` or ``auto`` (:data:`AUTO_BOX`); the shapes are those of
        :func:`magexp.scenarios.search.search_box`.
    matrix_bound, offset_width : float
        The widths of the ``signed`` box (Yuan 2018 Table 1: 3; the offset within the readings' range when
        ``offset_width`` is None, else within that fraction of the readings' sphere radius of its centre,
        Yuan's 100 mG of 527 mG being 0.19).
    """

    #: the columns its runs write beside the problem's: a recording's spread and coverage
    #: (:func:`magexp.core.identifiability.recording_metrics`, on its dataset's ``all_readings`` and ``heldout``)
    METRICS = RECORDING_METRICS

    def __init__(self, *, name: str, file: str, objective: str = "scalar", unit: str | None = None,
                 format: str = "auto", mag_axes: str | None = None, gyro_axes: str | None = None,
                 window: list[float] | None = None, n_readings: int | None = None, folds: int = 5,
                 heldout_fold: int = 0, bias_bound_deg_s: float = 10.0, rest_file: str | None = None,
                 box: str = "auto", matrix_bound: float = 3.0, offset_width: float | None = None):
        if objective not in OBJECTIVES:
            raise MagexpError(f"scenario.objective={objective!r} is not allowed: choose one of {', '.join(OBJECTIVES)}")
        self.name, self.file, self.objective = name, file, objective
        self.load_options = {"unit": unit, "format": format, "mag_axes": mag_axes, "gyro_axes": gyro_axes}
        self.window = window
        self.rest_file = rest_file
        self.n_readings = None if n_readings is None else check_positive_int(n_readings, "scenario.n_readings", 12)
        self.folds = check_positive_int(folds, "scenario.folds", minimum=0)
        self.heldout_fold = check_positive_int(heldout_fold, "scenario.heldout_fold", minimum=0)
        if self.folds and not 0 <= self.heldout_fold < self.folds:
            raise MagexpError(f"scenario.heldout_fold={heldout_fold!r} is not allowed: choose 0 to {self.folds - 1}")
        if box not in ("auto", *BOXES):
            raise MagexpError(f"scenario.box={box!r} is not allowed: choose one of auto, {', '.join(BOXES)}")
        self.box_options = {"shape": AUTO_BOX[objective] if box == "auto" else box,
                            "matrix_bound": matrix_bound, "offset_width": offset_width}
        bound = check_nonnegative(bias_bound_deg_s, "scenario.bias_bound_deg_s")
        check(0 < bound <= GYRO_RANGE_DEG_S, f"scenario.bias_bound_deg_s={bias_bound_deg_s!r} is not allowed: it must "
                                             f"be > 0 and <= {GYRO_RANGE_DEG_S:g} (a gyroscope's widest range, deg/s)")
        self.problem_options = {"bias_bound_deg_s": bound} if objective == "gyro" else {}
        self._data = None

    def recording(self, file=None):
        """The loaded recording (``file``, default the scenario's), cut to the window."""
        file = file or self.file
        path = Path(file) if Path(file).is_absolute() else SHARED_DATA / file
        if not exists(path):
            raise MagexpError(f"scenario.file={file!r} is not allowed: {path} does not exist "
                              "(set MAGEXP_DATA to the folder of the recordings)")
        rec = load_recording(path, **self.load_options)
        if self.window is not None and file == self.file:
            t = rec.reading_times()
            t0, t1 = (float(v) for v in self.window)
            keep = np.flatnonzero((t - t[0] >= t0) & (t - t[0] <= t1))
            if len(keep) < 12:
                raise MagexpError(f"scenario.window={list(self.window)} is not allowed: it holds {len(keep)} readings")
            rec = rec.subset(keep)
        return rec

    def _prepare(self):
        """Load the recording once: its folds, held-out block, dataset and search box."""
        rec = self.recording()
        n = rec.n
        heldout = np.zeros(n, bool)
        if self.objective == "scalar" and self.folds > n:
            raise MagexpError(f"scenario.folds={self.folds} is not allowed: the recording holds {n} readings; give "
                              f"at most {n} blocks (0: none)")
        if self.objective == "scalar" and self.folds > 1:
            edges = np.linspace(0, n, self.folds + 1).astype(int)
            heldout[edges[self.heldout_fold]:edges[self.heldout_fold + 1]] = True
        fit = np.flatnonzero(~heldout)
        fit = fit[evenly_spaced(len(fit), self.n_readings)]
        radius = centroid_radius(rec.readings[fit])
        extra = {"heldout": rec.readings[heldout], "all_readings": rec.readings}
        if self.objective == "gyro":
            if rec.gyro_rates() is None:
                raise MagexpError(f"scenario {self.name!r}: objective 'gyro' needs a gyroscope, {rec.name} has none")
            if self.rest_file:
                rest = self.recording(self.rest_file).gyro_rates()
                extra["rest_gyro_bias_deg_s"] = np.rad2deg(rest[1].mean(axis=0))
        self.search = search_box(rec.readings[fit], radius, forward=True, **self.box_options)
        self._data = recording_dataset(rec, radius, self.objective, keep=fit, meta={"scenario": self.name},
                                       extra=extra)

    @property
    def search(self):
        """The search box, derived from the readings (:meth:`_prepare`)."""
        if self._data is None:
            self._prepare()
        return self._search

    @search.setter
    def search(self, box):
        """Set the search box (the one :meth:`_prepare` derives from the readings)."""
        self._search = box

    def generate(self, *, rng: np.random.Generator | None = None) -> Dataset:
        """The recording's dataset (loaded and prepared once, then shared)."""
        if self._data is None:
            self._prepare()
        return self._data
