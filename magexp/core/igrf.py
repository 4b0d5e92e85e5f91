"""The local geomagnetic field from the International Geomagnetic Reference Field (IGRF).

:func:`field_at` evaluates the IGRF (the newest generation shipped with ``ppigrf``, IGRF-14;
Alken et al. 2021 for IGRF-13) at a geodetic latitude, longitude, altitude above the WGS84
ellipsoid and date, and gives

* the reference total field ``F = |B|`` (nT) for a scalar calibration,
* the field vector in the navigation frame, ``NED = [north, east, down]`` or
  ``ENU = [east, north, up]`` (nT), for a vector calibration,
* declination ``D = atan2(E, N)`` and inclination ``I = atan2(Z, H)``, ``H = sqrt(N² + E²)``.
"""

from __future__ import annotations

import datetime as _dt
from dataclasses import dataclass

import numpy as np

from magexp.errors import MagexpError


@dataclass(frozen=True)
class Field:
    """The IGRF field at one place and date; components in nT."""

    north: float
    east: float
    down: float

    @property
    def total(self) -> float:
        """``|B|`` (nT)."""
        return float(np.sqrt(self.north**2 + self.east**2 + self.down**2))

    @property
    def ned(self) -> np.ndarray:
        """North, east, down (nT)."""
        return np.array([self.north, self.east, self.down])

    @property
    def enu(self) -> np.ndarray:
        """East, north, up (nT)."""
        return np.array([self.east, self.north, -self.down])

    @property
    def declination_deg(self) -> float:
        """``D``, degrees east of north."""
        return float(np.rad2deg(np.arctan2(self.east, self.north)))

    @property
    def inclination_deg(self) -> float:
        """``I``, degrees below the horizontal."""
        return float(np.rad2deg(np.arctan2(self.down, np.hypot(self.north, self.east))))

    def vector(self, frame: str = "NED") -> np.ndarray:
        """The field in ``frame`` (``NED`` or ``ENU``)."""
        frames = {"NED": self.ned, "ENU": self.enu}
        if str(frame).upper() not in frames:
            raise MagexpError(f"frame={frame!r} is not allowed: choose NED or ENU")
        return frames[str(frame).upper()]


def _date(date, prefix: str = "igrf") -> _dt.datetime:
    """``date`` (a date, datetime or ``YYYY-MM-DD``) as a datetime, else one line naming ``<prefix>.date``."""
    if isinstance(date, _dt.datetime):
        return date
    if isinstance(date, _dt.date):
        return _dt.datetime(date.year, date.month, date.day)
    try:
        return _dt.datetime.fromisoformat(str(date))
    except ValueError:
        raise MagexpError(f"{prefix}.date={date!r} is not allowed: give a date YYYY-MM-DD") from None


def check_place(latitude, longitude, altitude_km=0.0, date=None, *, prefix: str = "igrf"):
    """``(latitude, longitude, altitude_km, datetime)`` checked: finite numbers, ``|latitude| <= 90``,
    a date ``YYYY-MM-DD`` (a date or datetime); one line naming ``<prefix>.<key>`` otherwise.
    """
    values = {}
    for name, value in (("latitude", latitude), ("longitude", longitude), ("altitude_km", altitude_km)):
        try:
            values[name] = float(value)
        except (TypeError, ValueError):
            values[name] = float("nan")
        if not np.isfinite(values[name]):
            raise MagexpError(f"{prefix}.{name}={value!r} is not allowed: it must be a finite number")
    if abs(values["latitude"]) > 90:
        raise MagexpError(f"{prefix}.latitude={latitude!r} is not allowed: it must be within [-90, 90]")
    return values["latitude"], values["longitude"], values["altitude_km"], _date(date, prefix)


def field_at(latitude, longitude, altitude_km=0.0, date=None, *, prefix: str = "igrf") -> Field:
    """IGRF field at a geodetic ``latitude``, ``longitude`` (degrees), ``altitude_km`` above the
    WGS84 ellipsoid, on ``date`` (``YYYY-MM-DD``, a date or datetime; within the model's 1900-2030 span).
    """
    import ppigrf  # lazy: 280 ms CPU to import (min of 5, after numpy), paid only where a place is given

    lat, lon, alt, when = check_place(latitude, longitude, altitude_km, date, prefix=prefix)
    if not 1900 <= when.year <= 2030:
        raise MagexpError(f"{prefix}.date={date!r} is not allowed: the IGRF covers 1900 to 2030")
    east, north, up = (float(np.ravel(c)[0]) for c in ppigrf.igrf(lon, lat, alt, when))
    return Field(north=north, east=east, down=-up)
