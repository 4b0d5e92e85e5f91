"""The reference field from where and when: the IGRF or the WMM at a place and date, recorded with its inputs.

:func:`reference_field` evaluates ``model="igrf"`` (:func:`magexp.core.igrf.field_at`, ``ppigrf``'s
newest generation, IGRF-14: 1900-2030; Alken et al. 2021 for IGRF-13) or ``model="wmm"`` (the
World Magnetic Model through ``pygeomag``, the coefficients of the five-year epoch holding the
date: WMM2010, WMM2015 (the 2018 revision, ``WMM_2015v2``), WMM2020, WMM2025; 2010-2030;
Chulliat et al. 2020 for WMM2020) and returns a :class:`ReferenceField`: the vector in NED (nT),
its total, the model's name and generation, and the inputs, so that an output can record where
the reference came from (:meth:`ReferenceField.record`). ArduPilot and PX4 use the WMM onboard
(their declination and field-strength tables); the two models differ by tens of nT, far below a
magnetometer's calibration error.

:func:`field_of_recording` takes the place and date from a log's GPS
(:func:`place_of`: the ``latitude``, ``longitude``, ``altitude_km``, ``date`` a reader of
:mod:`magexp.core.readers` stores in ``Recording.meta``), each overridable by an explicit value.
:func:`total_in` gives the total in a recording's unit; a raw-count recording has no factor to nT,
so its scale is set *to* the model's total instead (``W`` maps counts to nT): the caller uses
:attr:`ReferenceField.total` (nT) as the reference and reports the calibration in nT.

Altitude: both models take the height above the WGS84 ellipsoid; logs give GPS altitude above sea
level (ULog ``alt``, DataFlash ``Alt``) or above the ellipsoid (ROS ``NavSatFix``). The difference,
the geoid height (|N| < 110 m), changes the field by under 0.01 % (the field falls off as ``r⁻³``:
3 × 0.11 km / 6371 km), so it is ignored.
"""

from __future__ import annotations

import datetime as _dt
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from pygeomag import GeoMag
from pygeomag.time import calculate_decimal_year

from magexp.errors import MagexpError
from magexp.core.igrf import check_place, field_at
from magexp.core.recordings import RAW_UNITS, UNITS, Recording

#: the models :func:`reference_field` offers
MODELS = ("igrf", "wmm")
#: WMM coefficient files shipped with pygeomag, by the first year of their epoch (each valid 5 years)
WMM_FILES = {2010: "WMM_2010.COF", 2015: "WMM_2015v2.COF", 2020: "WMM_2020.COF", 2025: "WMM.COF"}
#: the years each model covers (first, last)
SPANS = {"igrf": (1900, 2030), "wmm": (min(WMM_FILES), max(WMM_FILES) + 4)}
#: the allowed range of each number of a place: a latitude, a longitude east or west of Greenwich
#: (-180 to 360, both conventions), an altitude from the deepest ocean trench (11 km below sea level)
#: to geostationary orbit (35,786 km), beyond which the internal field of these models is not the field
PLACE_RANGES = {"latitude": (-90.0, 90.0), "longitude": (-180.0, 360.0), "altitude_km": (-11.0, 35786.0)}


@dataclass(frozen=True)
class ReferenceField:
    """The model field at one place and date.

    Attributes
    ----------
    ned : (3,) north, east, down (nT).
    model : ``igrf`` or ``wmm``.
    generation : the model and its generation, e.g. ``IGRF-14``, ``WMM-2025``.
    inputs : ``latitude``, ``longitude`` (degrees), ``altitude_km``, ``date`` (ISO) and
        ``source`` of each (``given`` or ``log GPS``).
    """

    ned: np.ndarray
    model: str
    generation: str
    inputs: dict = field(default_factory=dict)

    @property
    def total(self) -> float:
        """``|B|`` (nT)."""
        return float(np.linalg.norm(self.ned))

    @property
    def declination_deg(self) -> float:
        """``D``, degrees east of north."""
        return float(np.rad2deg(np.arctan2(self.ned[1], self.ned[0])))

    @property
    def inclination_deg(self) -> float:
        """``I``, degrees below the horizontal."""
        return float(np.rad2deg(np.arctan2(self.ned[2], np.hypot(self.ned[0], self.ned[1]))))

    def record(self) -> dict:
        """What an output records: the model, generation, inputs and the field (JSON-ready)."""
        return {"model": self.model, "generation": self.generation, **self.inputs,
                "ned_nT": [float(v) for v in self.ned], "total_nT": self.total,
                "declination_deg": self.declination_deg, "inclination_deg": self.inclination_deg}


def check_model(model: str, prefix: str = "field") -> str:
    """``model`` lower-cased if it is one of :data:`MODELS`, else one line."""
    text = str(model).strip().lower()
    if text not in MODELS:
        raise MagexpError(f"{prefix}.model={model!r} is not allowed: choose one of {', '.join(MODELS)}")
    return text


def check_given(place: dict, prefix: str = "field") -> None:
    """Each value of ``place`` (``model``, ``latitude``, ``longitude``, ``altitude_km``, ``date``) that is
    given (not None) checked on its own, before the log's GPS fills in the others: a value is refused
    in one line even when no field model is used (no latitude given, none in the log), not ignored.
    Numbers within :data:`PLACE_RANGES`, a date ``YYYY-MM-DD`` within the model's :data:`SPANS`.
    """
    model = check_model(place.get("model") or "igrf", prefix)
    for key, (low, high) in PLACE_RANGES.items():
        value = place.get(key)
        if value is None:
            continue
        number = value if isinstance(value, (int, float)) and not isinstance(value, bool) else float("nan")
        if not low <= number <= high:
            raise MagexpError(f"{prefix}.{key}={value!r} is not allowed: it must be a number in [{low:g}, {high:g}]")
    date = place.get("date")
    if date is not None:
        try:
            when = date if isinstance(date, _dt.date) else _dt.date.fromisoformat(str(date))
        except ValueError:
            raise MagexpError(f"{prefix}.date={date!r} is not allowed: give a date YYYY-MM-DD") from None
        first, last = SPANS[model]
        if not first <= when.year <= last:
            raise MagexpError(f"{prefix}.date={str(date)!r} is not allowed with model={model}: it covers {first} to "
                              f"{last}")


def igrf_generation() -> str:
    """``IGRF-<n>`` of the coefficient file ppigrf evaluates (its ``shc_fn``, e.g. ``IGRF14.shc``)."""
    import ppigrf  # lazy: 181 ms CPU to import (min of 5, after numpy; as in magexp.core.igrf)

    stem = Path(ppigrf.ppigrf.shc_fn).stem.upper()
    return f"IGRF-{stem.removeprefix('IGRF')}"


def wmm_field(latitude: float, longitude: float, altitude_km: float, when: _dt.datetime,
              prefix: str = "field") -> tuple[np.ndarray, str]:
    """``(NED nT, generation)`` of the WMM epoch holding ``when`` (:data:`WMM_FILES`)."""
    epoch = next((y for y in sorted(WMM_FILES, reverse=True) if y <= when.year < y + 5), None)
    if epoch is None:
        raise MagexpError(f"{prefix}.date={when.date().isoformat()!r} is not allowed for model=wmm: the WMM "
                          f"shipped covers {min(WMM_FILES)} to {max(WMM_FILES) + 5}; use model=igrf")
    if not -1.0 <= altitude_km <= 850.0:
        raise MagexpError(f"{prefix}.altitude_km={altitude_km!r} is not allowed for model=wmm: it must be within "
                          "[-1, 850] km")
    geomag = GeoMag(coefficients_file=f"wmm/{WMM_FILES[epoch]}")
    result = geomag.calculate(glat=latitude, glon=longitude, alt=altitude_km, time=calculate_decimal_year(when))
    return np.array([result.x, result.y, result.z], float), geomag.model


def reference_field(latitude, longitude, altitude_km=0.0, date=None, *, model: str = "igrf",
                    sources: dict | None = None, prefix: str = "field") -> ReferenceField:
    """The ``model`` field at geodetic ``latitude``, ``longitude`` (degrees), ``altitude_km`` above
    the WGS84 ellipsoid, on ``date`` (``YYYY-MM-DD``, a date or datetime).
    """
    model = check_model(model, prefix)
    lat, lon, alt, when = check_place(latitude, longitude, altitude_km, date, prefix=prefix)
    if model == "igrf":
        ned, generation = field_at(lat, lon, alt, when, prefix=prefix).ned, igrf_generation()
    else:
        ned, generation = wmm_field(lat, lon, alt, when, prefix)
    sources = sources or {}
    inputs = {"latitude": lat, "longitude": lon, "altitude_km": alt, "date": when.date().isoformat(),
              "sources": {k: sources.get(k, "given") for k in ("latitude", "longitude", "altitude_km", "date")}}
    return ReferenceField(ned=ned, model=model, generation=generation, inputs=inputs)


def place_of(rec: Recording) -> dict:
    """``{latitude, longitude, altitude_km, date}`` a log's reader stored in ``rec.meta`` (those present)."""
    out = {}
    for key in ("latitude", "longitude", "altitude_km"):
        if key in rec.meta:
            out[key] = float(rec.meta[key])
    if "date" in rec.meta:
        out["date"] = rec.meta["date"]
    return out


def field_of_recording(rec: Recording, *, model: str = "igrf", latitude=None, longitude=None, altitude_km=None,
                       date=None, prefix: str = "field") -> ReferenceField:
    """The ``model`` field where and when ``rec`` was recorded: each of ``latitude``,
    ``longitude``, ``altitude_km``, ``date`` as given, else from the log's GPS (:func:`place_of`);
    ``altitude_km`` defaults to 0.
    """
    logged = place_of(rec)
    given = {"latitude": latitude, "longitude": longitude, "altitude_km": altitude_km, "date": date}
    values, sources = {}, {}
    for key, value in given.items():
        if value is not None:
            values[key], sources[key] = value, "given"
        elif key in logged:
            values[key], sources[key] = logged[key], "log GPS"
        elif key == "altitude_km":
            values[key], sources[key] = 0.0, "default 0"
        else:
            raise MagexpError(f"{prefix}.{key}=None is not allowed for {rec.name}: the recording has no GPS "
                              f"{'date' if key == 'date' else 'position'}, give {prefix}.{key}=<"
                              f"{'YYYY-MM-DD' if key == 'date' else 'degrees'}>")
    return reference_field(values["latitude"], values["longitude"], values["altitude_km"], values["date"],
                           model=model, sources=sources, prefix=prefix)


def gps_field(rec: Recording, model: str = "igrf") -> ReferenceField | None:
    """The ``model`` field at the log's GPS place and date (:func:`field_of_recording`), or None without a GPS
    place and date (or with one the model refuses): the site of a calibration's heading error
    (:mod:`magexp.calibration.heading`) where no field model gave the reference.
    """
    if not {"latitude", "longitude", "date"} <= set(place_of(rec)):
        return None
    try:
        return field_of_recording(rec, model=model)
    except MagexpError:
        return None


def field_in(reference: ReferenceField, unit: str) -> np.ndarray:
    """The model's NED vector in ``unit`` (a key of :data:`magexp.core.recordings.UNITS`): a log's
    ``Recording.field`` for the vector objective (its attitudes are NED). A raw unit (``counts``)
    has no factor: one line saying to calibrate to the model's field in nT instead.
    """
    if unit in RAW_UNITS or unit not in UNITS:
        raise MagexpError(f"unit {unit!r} has no known factor to nT: calibrate to the model's total "
                          f"{reference.total:.1f} nT itself (W then maps {unit} to nT)")
    return reference.ned / UNITS[unit]


def total_in(reference: ReferenceField, unit: str) -> float:
    """The model's total in ``unit`` (:func:`field_in`'s norm; the same refusal for ``counts``)."""
    return float(np.linalg.norm(field_in(reference, unit)))
