"""IGRF field against published values (NOAA NCEI geomagnetic calculator)."""

import numpy as np
import pytest

from magexp.errors import MagexpError
from magexp.core.igrf import field_at

# NOAA NCEI Geomagnetic Calculator (https://www.ngdc.noaa.gov/geomag/calculators/magcalc.shtml),
# model IGRF2020, calculator version 0.5.1.11, date 2022.75890 (2022-10-05), 5 km above the WGS84
# ellipsoid, as published in ppigrf's test data (klaundal/ppigrf, test/data/2022-10-05/b_e.csv,
# b_n.csv, b_z.csv; b_z is downward). Values in nT: (latitude, longitude, north, east, down).
NOAA = [
    (80.0, -100.0, 1688.7, -903.2, 56738.2),
    (80.0, 0.0, 6513.9, 11.0, 54611.6),
    (80.0, 100.0, 1587.2, 1087.3, 58629.6),
]


@pytest.mark.parametrize("lat, lon, north, east, down", NOAA)
def test_igrf_matches_noaa_within_50_nt(lat, lon, north, east, down):
    f = field_at(lat, lon, 5.0, "2022-10-05")
    print(f"({lat}, {lon}): NED {f.ned.round(1)} vs NOAA {[north, east, down]}")
    np.testing.assert_allclose(f.ned, [north, east, down], atol=50.0)
    assert abs(f.total - np.linalg.norm([north, east, down])) < 50.0
    np.testing.assert_allclose(f.vector("ENU"), [east, north, -down], atol=50.0)
    assert f.declination_deg == pytest.approx(np.rad2deg(np.arctan2(east, north)), abs=1.0)


@pytest.mark.parametrize("args, message", [
    ((91.0, 0.0, 0.0, "2020-01-01"), "latitude=91.0 is not allowed"),
    ((10.0, "east", 0.0, "2020-01-01"), "longitude='east' is not allowed"),
    ((10.0, 0.0, 0.0, "yesterday"), "date='yesterday' is not allowed"),
    ((10.0, 0.0, 0.0, "1850-01-01"), "1900 to 2030"),
])
def test_bad_place_or_date_is_one_line(args, message):
    with pytest.raises(MagexpError, match=message) as err:
        field_at(*args)
    assert "\n" not in str(err.value)
