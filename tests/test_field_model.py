"""The reference field from where and when (magexp.core.field_model): WMM against NOAA's published
test values, IGRF against WMM, the generation and inputs recorded, and the one-line refusals."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from magexp.core.field_model import field_in, field_of_recording, reference_field, total_in
from magexp.errors import MagexpError
from magexp.core.recordings import Recording

# NOAA NCEI, WMM2025 test values (WMM2025_TEST_VALUES.txt, published with the model; as shipped in
# Mayitzin/ahrs, ahrs/utils/WMM2025/): decimal year, height above WGS84 (km), latitude, longitude,
# X (north), Y (east), Z (down), nT.
WMM2025 = [
    (dt.datetime(2025, 1, 1), 0.0, 80.0, 0.0, 6521.6, 145.9, 54791.5),
    (dt.datetime(2025, 1, 1), 100.0, -80.0, 240.0, 5907.6, 14780.3, -49540.7),
    (dt.datetime(2027, 7, 2, 12), 0.0, 0.0, 120.0, 39701.6, -167.4, -10381.8),
    (dt.datetime(2027, 7, 2, 12), 100.0, 80.0, 0.0, 6196.7, 233.8, 52670.5),
]


@pytest.mark.parametrize("when, alt, lat, lon, x, y, z", WMM2025)
def test_wmm_matches_noaa_test_values(when, alt, lat, lon, x, y, z):
    f = reference_field(lat, lon, alt, when, model="wmm")
    assert f.generation == "WMM-2025"
    np.testing.assert_allclose(f.ned, [x, y, z], atol=0.2)  # published to 0.1 nT


@pytest.mark.parametrize("date, generation, lat, lon", [("2012-06-01", "WMM-2010", 63.4, 10.4),
                                                        ("2017-10-29", "WMM-2015v2", -35.4, 149.2),
                                                        ("2021-04-21", "WMM-2020", 47.6, -122.3),
                                                        ("2026-03-01", "WMM-2025", -70.0, 30.0)])
def test_igrf_and_wmm_agree_and_name_their_generation(date, generation, lat, lon):
    """Two independent models of the same field: within 150 nT a component (a sign, unit or frame
    error would be thousands)."""
    wmm, igrf = (reference_field(lat, lon, 0.1, date, model=m) for m in ("wmm", "igrf"))
    assert np.max(np.abs(wmm.ned - igrf.ned)) < 150.0, (wmm.ned, igrf.ned)
    assert (wmm.generation, igrf.generation) == (generation, "IGRF-14")


def test_the_record_holds_model_generation_and_inputs():
    f = reference_field(63.41705, 10.40822, 0.064, "2021-04-21", model="WMM")
    rec = f.record()
    assert rec["model"] == "wmm" and rec["generation"] == "WMM-2020" and rec["date"] == "2021-04-21"
    assert (rec["latitude"], rec["longitude"], rec["altitude_km"]) == (63.41705, 10.40822, 0.064)
    assert rec["total_nT"] == pytest.approx(np.linalg.norm(rec["ned_nT"]))
    assert rec["declination_deg"] == pytest.approx(np.rad2deg(np.arctan2(f.ned[1], f.ned[0])))
    assert rec["sources"]["date"] == "given"


def log(meta: dict) -> Recording:
    return Recording(readings=np.ones((3, 3)), angles=None, field=None, unit="mG", meta=meta)


def test_the_log_gps_gives_place_and_date_and_explicit_values_win():
    rec = log({"latitude": "-35.3626", "longitude": "149.1653", "altitude_km": "0.589", "date": "2017-10-29"})
    f = field_of_recording(rec, model="igrf")
    assert f.inputs["sources"] == {k: "log GPS" for k in ("latitude", "longitude", "altitude_km", "date")}
    assert total_in(f, "mG") == pytest.approx(f.total / 100)
    np.testing.assert_allclose(field_in(f, "uT"), f.ned / 1000)
    g = field_of_recording(rec, model="igrf", date="2020-01-01")
    assert g.inputs["date"] == "2020-01-01" and g.inputs["sources"]["date"] == "given" and g.total != f.total
    h = field_of_recording(log({}), latitude=10, longitude=20, date="2020-01-01")
    assert h.inputs["sources"]["altitude_km"] == "default 0"


@pytest.mark.parametrize("call, message", [
    (lambda: field_of_recording(log({})), r"field.latitude=None is not allowed for readings: the recording has no GPS"),
    (lambda: field_of_recording(log({"latitude": "1", "longitude": "2"})), r"field.date=None is not allowed"),
    (lambda: reference_field(10, 20, 0, "2020-01-01", model="emm"), r"field.model='emm' is not allowed"),
    (lambda: reference_field(95, 20, 0, "2020-01-01"), r"field.latitude=95 is not allowed"),
    (lambda: reference_field(10, 20, 0, "2008-01-01", model="wmm"), r"covers 2010 to 2030; use model=igrf"),
    (lambda: reference_field(10, 20, 0, "soon", model="wmm"), r"field.date='soon' is not allowed"),
    (lambda: total_in(reference_field(10, 20, 0, "2020-01-01"), "counts"), r"calibrate to the model's total"),
])
def test_bad_inputs_are_one_line(call, message):
    with pytest.raises(MagexpError, match=message) as err:
        call()
    assert "\n" not in str(err.value)
