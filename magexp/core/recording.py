"""A recording once read, whatever its format: the :class:`Recording` every reader returns, its units, and
the one path from a recording to the :class:`~magexp.core.dataset.Dataset` a problem is built on
(:func:`recording_dataset`: shared by :class:`magexp.scenarios.recording.RecordingScenario` and
``magexp calibrate``).

The readers (:mod:`magexp.core.readers`) and the loader that picks one (:mod:`magexp.core.recordings`)
import this module; it imports neither.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from magexp.core.dataset import Dataset
from magexp.core.geometry import attitude_at, preintegrate, ship_attitude
from magexp.errors import MagexpError

#: Allowed units of the readings and their factor to nT.
UNITS = {"nT": 1.0, "uT": 1e3, "mG": 100.0, "G": 1e5, "T": 1e9}
#: Raw sensor units without a known factor to nT (a calibration then reports in them).
RAW_UNITS = ("counts",)
_ALIASES = {"µt": "uT", "μt": "uT"}


@dataclass
class Recording:
    """A loaded recording.

    Attributes
    ----------
    readings : (N, 3) sensor readings ``[bx, by, bz]`` in ``unit``.
    angles : (N, 3) ``[heading, roll, trim]`` in radians (converted if the file says ``deg``),
        or None if the file has no attitude columns.
    field : (3,) ambient field in the navigation frame, or None if the file gives none.
    unit : unit of ``readings``, ``field`` and the reference totals (a key of :data:`UNITS`).
    meta : every metadata line as ``{key: text}``.
    columns : every column as ``{name: (N,) array}``.
    total : (N,) reference total field per reading (``total`` column), or None.
    reference_total : the ``# reference_total:`` value, or None.
    gyro : (N, 3) gyro rates in rad/s per reading (``gx, gy, gz`` columns), or None.
    sample_time : seconds between readings (with ``gyro``), or None.
    times : (N,) time of every reading in seconds, or None.
    gyro_stream : ``(times (K,), rates (K, 3) rad/s in the common axes)`` of a gyroscope with
        its own timestamps, or None.
    """

    readings: np.ndarray
    angles: np.ndarray | None
    field: np.ndarray | None
    unit: str
    meta: dict = field(default_factory=dict)
    columns: dict = field(default_factory=dict)
    total: np.ndarray | None = None
    reference_total: float | None = None
    gyro: np.ndarray | None = None
    sample_time: float | None = None
    path: Path | None = None
    times: np.ndarray | None = None
    gyro_stream: tuple | None = None

    @property
    def n(self) -> int:
        """The number of readings."""
        return int(self.readings.shape[0])

    @property
    def name(self) -> str:
        """The file's name, else ``meta['name']``, else ``readings``: how messages name it."""
        return self.path.name if self.path is not None else self.meta.get("name", "readings")

    def gyro_rates(self) -> tuple[np.ndarray, np.ndarray] | None:
        """``(times, rates)`` of the gyroscope and the reading times, or None without one."""
        if self.gyro_stream is not None:
            return self.gyro_stream
        if self.gyro is not None:
            return np.arange(self.n) * self.sample_time, self.gyro
        return None

    def reading_times(self) -> np.ndarray | None:
        """The readings' times (s): the recorded ones, else ``sample_time`` steps from 0."""
        if self.times is not None:
            return self.times
        return None if self.sample_time is None else np.arange(self.n) * self.sample_time

    def attitude(self, *, bias=None) -> np.ndarray | None:
        """Navigation -> sensor rotations ``(N, 3, 3)`` from the angles, else from the gyroscope
        integrated at the reading times (the sensor frame at the first reading is the navigation
        frame; ``bias`` rad/s subtracted), else None.
        """
        if self.angles is not None:
            return ship_attitude(*self.angles.T)
        stream = self.gyro_rates()
        if stream is None:
            return None
        return np.transpose(attitude_at(*stream, self.reading_times(), bias=bias), (0, 2, 1))

    def subset(self, index) -> "Recording":
        """The readings ``index`` (a slice or index array), with their attitudes' sources."""
        pick = lambda a: None if a is None else np.asarray(a)[index]  # noqa: E731
        times = self.reading_times()
        return replace(self, readings=self.readings[index], angles=pick(self.angles), total=pick(self.total),
                       columns={k: v[index] for k, v in self.columns.items()}, gyro=None, sample_time=None,
                       times=pick(times), gyro_stream=self.gyro_rates())

def check_unit(unit: str, what: str) -> str:
    """``unit`` spelled as in :data:`UNITS`, or a one-line error naming ``what``."""
    text = str(unit).strip()
    text = _ALIASES.get(text.lower(), text)
    if text not in UNITS and text not in RAW_UNITS:
        raise MagexpError(f"{what}={unit!r} is not allowed: choose one of {', '.join((*UNITS, *RAW_UNITS))}")
    return text



#: the objectives a recording's :class:`~magexp.core.dataset.Dataset` serves (:func:`recording_dataset`)
OBJECTIVES = ("scalar", "vector", "gyro")


def evenly_spaced(n: int, count: int | None) -> np.ndarray:
    """Indices of ``count`` of ``n`` readings evenly spaced in order, first and last included."""
    if count is None or count >= n:
        return np.arange(n)
    return np.round(np.linspace(0, n - 1, count)).astype(int)


def recording_dataset(rec: Recording, reference_norm, objective: str = "scalar", *, keep=None,
                      meta: dict | None = None, extra: dict | None = None) -> Dataset:
    """The :class:`~magexp.core.dataset.Dataset` of the readings ``keep`` (None: all) of ``rec`` for ``objective``:
    ``scalar``, ``vector`` (with :meth:`Recording.attitude`) or ``gyro`` (with the gyroscope preintegrated between the
    kept readings, ``extra["preintegration"]``); ``reference`` is one total or one per reading."""
    if objective not in OBJECTIVES:
        raise MagexpError(f"objective={objective!r} is not allowed: choose one of {', '.join(OBJECTIVES)}")
    keep = slice(None) if keep is None else keep
    reference = np.asarray(reference_norm, float)
    reference = np.full(rec.n, reference) if reference.ndim == 0 else reference
    extra = dict(extra or {})
    attitude = field_nav = None
    if objective == "vector":
        attitude = rec.attitude()
        if attitude is None or rec.field is None:
            raise MagexpError(f"objective='vector' is not allowed for {rec.name}: it needs attitudes "
                              "(heading, roll, trim or gx, gy, gz columns) and a '# field:' line; use objective=scalar")
        attitude = attitude[keep]
        field_nav = np.broadcast_to(rec.field, attitude.shape[:1] + (3,)).copy()
    elif objective == "gyro":
        stream, times = rec.gyro_rates(), rec.reading_times()
        if stream is None or times is None:
            raise MagexpError(f"objective='gyro' is not allowed for {rec.name}: it has no gyroscope")
        extra["preintegration"] = preintegrate(*stream, times[keep])
    return Dataset(readings=rec.readings[keep], reference_norm=reference[keep], field_nav=field_nav,
                   attitude=attitude, unit=rec.unit,
                   meta={"recording": str(rec.path) if rec.path is not None else rec.name, **rec.meta, **(meta or {})},
                   extra=extra)
