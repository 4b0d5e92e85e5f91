"""Exports (magexp.calibration.export) applied with each firmware's own correction equation, written
here from the firmware sources independently of export.py, give magexp's calibrated readings back."""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest
import yaml

from magexp.errors import MagexpError
from magexp.core.geometry import random_rotations, rot_z
from magexp.paths import SHARED_DATA

from magexp.calibration import export as ex
from magexp.calibration import firmware as fw

#: the test's own unit table: mGauss per unit (1 G = 1000 mG = 1e5 nT)
MG_PER = {"nT": 0.01, "uT": 10.0, "mG": 1.0, "G": 1000.0, "T": 1e7}
#: the relative agreement the exports must reach (float64 values in the files)
RTOL = 1e-6


def parse_ardupilot(text: str) -> dict:
    return {k: float(v) for k, v in (ln.split(",") for ln in text.splitlines() if ln and not ln.startswith("#"))}


def ardupilot_correct_field(raw_mg: np.ndarray, p: dict) -> np.ndarray:
    """AP_Compass_Backend::correct_field: mag += offsets; mag *= scale (if 0.85 <= scale <= 1.4); mag = mat * mag."""
    dia = np.array([p["COMPASS_DIA_X"], p["COMPASS_DIA_Y"], p["COMPASS_DIA_Z"]])
    odi = np.array([p["COMPASS_ODI_X"], p["COMPASS_ODI_Y"], p["COMPASS_ODI_Z"]])
    mat = np.array([[dia[0], odi[0], odi[1]], [odi[0], dia[1], odi[2]], [odi[1], odi[2], dia[2]]])
    scale = p.get("COMPASS_SCALE", 1.0)
    scale = scale if 0.85 <= scale <= 1.4 else 1.0
    ofs = np.array([p["COMPASS_OFS_X"], p["COMPASS_OFS_Y"], p["COMPASS_OFS_Z"]])
    return (scale * (raw_mg + ofs)) @ mat.T


def parse_px4(text: str) -> dict:
    rows = [ln.split("\t") for ln in text.splitlines() if ln and not ln.startswith("#")]
    assert all(len(r) == 5 and r[4] == "9" for r in rows)  # vehicle, component, name, value, REAL32
    return {r[2]: float(r[3]) for r in rows}


def px4_correct(raw_g: np.ndarray, p: dict, n: int = 0, rotation=np.eye(3)) -> np.ndarray:
    """calibration::Magnetometer::Correct: _rotation * (_scale * (data - _offset)), _scale from SCALE and ODIAG."""
    g = lambda k: p[f"CAL_MAG{n}_{k}"]  # noqa: E731
    scale = np.array([[g("XSCALE"), g("XODIAG"), g("YODIAG")], [g("XODIAG"), g("YSCALE"), g("ZODIAG")],
                      [g("YODIAG"), g("ZODIAG"), g("ZSCALE")]])
    off = np.array([g("XOFF"), g("YOFF"), g("ZOFF")])
    return (raw_g - off) @ scale.T @ np.asarray(rotation).T


def relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.linalg.norm(a - b, axis=1) / np.linalg.norm(b, axis=1)))


def synthetic(unit: str, seed: int = 3):
    """A symmetric positive-definite W, an offset and raw readings around it, in ``unit``."""
    rng = np.random.default_rng(seed)
    size = {"nT": 5e4, "uT": 50.0, "mG": 500.0, "G": 0.5, "T": 5e-5, "counts": 2000.0}[unit]
    q = random_rotations(1, rng=rng)[0]
    w = q @ np.diag(rng.uniform(0.8, 1.25, 3)) @ q.T
    offset = rng.uniform(-0.6, 0.6, 3) * size
    raw = offset + rng.standard_normal((300, 3)) * size
    return w, offset, raw


@pytest.mark.parametrize("unit", ["nT", "uT", "mG", "G", "counts"])
def test_ardupilot_and_px4_give_magexp_back(unit):
    w, offset, raw = synthetic(unit)
    b = (raw - offset) @ w.T
    counts_nt = 0.25 if unit == "counts" else None  # nT per count of the driver
    mg = MG_PER[unit] if unit != "counts" else counts_nt * MG_PER["nT"]
    ap = ex.render("ardupilot", w, offset, unit, counts_nt=counts_nt)
    err_ap = relative(ardupilot_correct_field(raw * mg, parse_ardupilot(ap.text)), b * mg)
    p4 = ex.render("px4", w, offset, unit, counts_nt=counts_nt)
    err_px4 = relative(px4_correct(raw * mg / 1000, parse_px4(p4.text)), b * mg / 1000)
    f32 = {k: float(np.float32(v)) for k, v in parse_ardupilot(ap.text).items()}  # as the firmware stores them
    err_f32 = relative(ardupilot_correct_field(raw * mg, f32), b * mg)
    print(f"{unit}: ArduPilot {err_ap:.2g}, PX4 {err_px4:.2g}, ArduPilot with float32 parameters {err_f32:.2g}")
    assert err_ap < RTOL and err_px4 < RTOL and err_f32 < 1e-5


def test_a_field_unit_other_than_the_readings_scales_the_matrix():
    """Counts calibrated to a model's total in nT (W maps counts to nT): the firmware field is in mGauss."""
    w, offset, raw = synthetic("counts")
    w_nt = w * 50000.0 / 2000.0  # counts -> nT
    ap = ex.render("ardupilot", w_nt, offset, "counts", field_unit="nT", counts_nt=0.3)
    b_mg = (raw - offset) @ w_nt.T * MG_PER["nT"]
    assert relative(ardupilot_correct_field(raw * 0.3 * MG_PER["nT"], parse_ardupilot(ap.text)), b_mg) < RTOL


def test_a_real_calibration_round_trips():
    path = SHARED_DATA / "fxos8700_mag_readings.txt"
    if not path.is_file():
        pytest.skip(f"{path} is not present")
    from magexp.calibration.fit import calibrate_recording
    from magexp.estimators.ellipsoid import EllipsoidFit
    from magexp.core.recordings import load_recording

    cal = calibrate_recording(load_recording(path, unit="uT"), EllipsoidFit(), folds=0, rng=np.random.default_rng(0))
    raw, b = cal.recording.readings, cal.calibrated
    ap = ex.render("ardupilot", cal.w, cal.offset, cal.unit)
    p4 = ex.render("px4", cal.w, cal.offset, cal.unit)
    errors = (relative(ardupilot_correct_field(raw * 10, parse_ardupilot(ap.text)), b * 10),
              relative(px4_correct(raw / 100, parse_px4(p4.text)), b / 100))
    print(f"fxos8700 (ellipsoid, {cal.recording.n} readings): ArduPilot {errors[0]:.2g}, PX4 {errors[1]:.2g}")
    assert max(errors) < RTOL


def test_a_rotation_in_w_is_refused_or_exported_as_s():
    w, offset, raw = synthetic("uT")
    r = rot_z(np.deg2rad(5.0))
    for target in ("ardupilot", "px4"):
        with pytest.raises(MagexpError, match=r"W turns the field by 5.00 deg") as err:
            ex.render(target, r @ w, offset, "uT")
        assert "\n" not in str(err.value)
    ap = ex.render("ardupilot", r @ w, offset, "uT", max_rotation_deg=6)
    firmware = ardupilot_correct_field(raw * 10, parse_ardupilot(ap.text))
    assert relative(firmware, (raw - offset) @ w.T * 10) < RTOL  # S(r - o) = R^T B
    assert "R turns by 5 deg" in ap.text
    mirrored = np.diag([1.0, 1.0, -1.0]) @ w
    with pytest.raises(MagexpError, match="mirrors an axis"):
        ex.render("px4", mirrored, offset, "uT")


def test_px4_takes_its_own_rotation_out_of_w():
    """A vector calibration of readings PX4 rotates after S (board yaw 180°, 2° level adjustment):
    W = R S; exported with rotation=R, Correct (with that R) gives magexp's field back."""
    from magexp.core.readers.ulog import onboard_rotation

    r = onboard_rotation({"CAL_MAG1_ROT": -1, "SENS_BOARD_ROT": 4, "SENS_BOARD_X_OFF": 2.0}, 1)
    w, offset, raw = synthetic("G")
    out = ex.render("px4", r @ w, offset, "G", instance=1, rotation=r)
    err = relative(px4_correct(raw, parse_px4(out.text), 1, r), (raw - offset) @ (r @ w).T)
    print(f"PX4 with its rotation: {err:.2g}")
    assert err < RTOL
    with pytest.raises(MagexpError, match="W turns the field by"):
        ex.render("px4", r @ w, offset, "G")  # without it, R is far from the identity


@pytest.mark.parametrize("options, message", [
    ({"unit": "counts"}, "counts_nt=<nT per count"),
    ({"unit": "uT", "instance": 3}, "instance=3 is not allowed"),
    ({"unit": "uT", "counts_nt": -1, "field_unit": "counts"}, "counts_nt=-1 is not allowed"),
])
def test_bad_export_options_are_one_line(options, message):
    w, offset, _ = synthetic("uT")
    with pytest.raises(MagexpError, match=message) as err:
        ex.render("ardupilot", w, offset, **options)
    assert "\n" not in str(err.value)
    with pytest.raises(MagexpError, match="export='qgc' is not allowed"):
        ex.render("qgc", w, offset, "uT")


def test_ardupilot_warns_outside_its_ranges_and_names_the_instance():
    w, offset, _ = synthetic("G")
    out = ex.render("ardupilot", w * 8, offset, "G")  # diagonals near 8 > 5; offsets up to 300 mG
    assert any("COMPASS_DIA_X" in text for text in out.warnings) and "# WARNING" in out.text
    third = ex.render("ardupilot", w, offset, "G", instance=2).values
    assert "COMPASS_OFS3_X" in third and "COMPASS_SCALE3" in third and "COMPASS_OFS_X" not in third


def test_ros_yaml_parses_and_applies_in_tesla():
    w, offset, raw = synthetic("uT")
    rot = rot_z(0.3)  # ROS holds the full W: a rotation is kept
    out = ex.render("ros", rot @ w, offset, "uT", notes={"recording": "a: b # c"})
    node = yaml.safe_load(out.text)["/**"]["ros__parameters"]["magnetometer_calibration"]
    assert node["unit"] == "T"
    b_t = (raw * 1e-6 - np.array(node["offset"])) @ np.array(node["matrix"]).reshape(3, 3).T
    assert relative(b_t, (raw - offset) @ (rot @ w).T * 1e-6) < RTOL


def test_c_header_compiles_and_applies():
    w, offset, raw = synthetic("uT")
    out = ex.render("c", w, offset, "uT", name="imu_mag")
    assert "static const float IMU_MAG_MATRIX[3][3]" in out.text
    b = (raw - offset) @ w.T
    numbers = [float(v.rstrip("f")) for v in re.findall(r"-?[\d.]+(?:e-?\d+)?f\b", out.text)]  # the literals
    assert len(numbers) == 12 + 1  # offset, matrix, and the 0.0f of the function
    assert np.allclose(numbers[:3], offset, rtol=1e-8) and np.allclose(numbers[3:12], w.ravel(), rtol=1e-8)
    cc = shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler: the header's numbers parse, its syntax is not checked")
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "imu_mag.h").write_text(out.text)
        rows = ",".join("{%r,%r,%r}" % tuple(map(float, r)) for r in raw[:20])
        (Path(tmp) / "main.c").write_text(
            '#include <stdio.h>\n#include "imu_mag.h"\n#include "imu_mag.h"\n'  # twice: the include guard
            f"static const float R[20][3] = {{{rows}}};\n"
            "int main(void) { float out[3]; int k; for (k = 0; k < 20; ++k) { imu_mag_apply(R[k], out);"
            ' printf("%.9g %.9g %.9g\\n", out[0], out[1], out[2]); } return 0; }\n')
        subprocess.run([cc, "-std=c99", "-Wall", "-Werror", "-o", f"{tmp}/main", f"{tmp}/main.c"], check=True)
        got = np.loadtxt(subprocess.run([f"{tmp}/main"], check=True, capture_output=True, text=True).stdout.splitlines())
    print(f"C header (float32): {relative(got, b[:20]):.2g}")
    assert relative(got, b[:20]) < 1e-5  # float32 arithmetic


def test_write_never_overwrites(tmp_path):
    w, offset, _ = synthetic("uT")
    first = ex.write(ex.render("px4", w, offset, "uT"), tmp_path)
    assert first == tmp_path / ex.FILE_NAMES["px4"] and first.read_text().startswith("# magexp")
    with pytest.raises(MagexpError, match="exists already") as err:
        ex.write(ex.render("px4", w, offset, "uT"), first)
    assert "\n" not in str(err.value)
    with pytest.raises(MagexpError, match="does not exist"):
        ex.write(ex.render("c", w, offset, "uT"), tmp_path / "missing" / "x.h")


def parse_orientation_px4(text: str) -> tuple[dict, dict]:
    """``(real parameters, integer parameters)`` of a QGroundControl file (type 9 REAL32, type 6 INT32)."""
    rows = [ln.split("\t") for ln in text.splitlines() if ln and not ln.startswith("#")]
    return ({r[2]: float(r[3]) for r in rows if r[4] == "9"}, {r[2]: int(r[3]) for r in rows if r[4] == "6"})


def ardupilot_with_orientation(raw_mg: np.ndarray, p: dict) -> np.ndarray:
    """AP_Compass_Backend: rotate_field (``COMPASS_ORIENT``, an external compass) before correct_field."""
    turned = raw_mg @ fw.standard_rotation(int(p["COMPASS_ORIENT"])).T
    return ardupilot_correct_field(turned, p)


@pytest.mark.parametrize("n", [2, 8, 17, 28, 40])
def test_a_rotation_near_a_standard_one_is_exported_as_the_orientation(n):
    """W = R_n R_e S (R_e 0.4 deg): both firmwares get orientation n and S; their field is magexp's up to R_e."""
    w, offset, raw = synthetic("G")
    small = rot_z(np.deg2rad(0.4))
    turned = fw.standard_rotation(n) @ small @ w
    b = (raw - offset) @ turned.T
    ap = ex.render("ardupilot", turned, offset, "G", orient=True)
    p = parse_ardupilot(ap.text)
    assert p["COMPASS_ORIENT"] == n and "orientation" in ap.text
    real, ints = parse_orientation_px4(ex.render("px4", turned, offset, "G", orient=True).text)
    assert ints == {"CAL_MAG0_ROT": n}
    err_ap = relative(ardupilot_with_orientation(raw * 1000, p), b * 1000)
    err_px4 = relative(px4_correct(raw, real, 0, fw.standard_rotation(n)), b)
    assert max(err_ap, err_px4) < 1.01 * np.deg2rad(0.4)  # the residual left out, nothing more
    exact = ex.render("ardupilot", fw.standard_rotation(n) @ w, offset, "G", orient=True)
    assert relative(ardupilot_with_orientation(raw * 1000, parse_ardupilot(exact.text)),
                    (raw - offset) @ (fw.standard_rotation(n) @ w).T * 1000) < RTOL


def test_every_standard_rotation_is_its_own_nearest_and_a_far_one_names_a_key_that_works():
    for n in fw.STANDARD_ROTATIONS:
        index, residual = fw.nearest_orientation(fw.standard_rotation(n))
        assert residual < 1e-6 and np.allclose(fw.standard_rotation(index), fw.standard_rotation(n))
    w, offset, _ = synthetic("G")
    turned = fw.standard_rotation(6) @ rot_z(np.deg2rad(3.0)) @ w
    with pytest.raises(MagexpError, match=r"3.00 deg from the nearest .* \(6: roll 0, pitch 0, yaw 270\)") as err:
        ex.render("px4", turned, offset, "G", orient=True)
    key = re.search(r"max_rotation_deg=([0-9.]+)", str(err.value)).group(1)
    assert "\n" not in str(err.value) and float(key) >= 3.0
    assert "CAL_MAG0_ROT\t6\t6" in ex.render("px4", turned, offset, "G", orient=True, max_rotation_deg=float(key)).text


def test_a_gyro_calibration_of_a_turned_magnetometer_exports_its_orientation():
    """The tumbling IMU of test_calibration_gyro_model with its magnetometer mounted yaw 90 deg: the gyro-aided
    fit's W = R_2 S⁻¹; S⁻¹'s own rotation (3.8 deg) is over the default limit, so PX4's export names
    max_rotation_deg; with it, both files carry orientation 2 and reproduce the calibrated field."""
    from tests.test_calibration_gyro_model import tumbling
    import magexp

    rec = tumbling()
    rec = type(rec)(**{**rec.__dict__, "readings": (rec.readings - rec.readings.mean(0)) @ fw.standard_rotation(2)
                       + rec.readings.mean(0)})
    cal = magexp.calibrate(rec, model="gyro")
    assert ex.orientable(cal)
    with pytest.raises(MagexpError, match=r"nearest of the firmware's standard orientations \(2:") as err:
        ex.of_calibration(cal, "px4")  # ArduPilot takes it as its custom rotation (test_calibration_gyro_auto)
    limit = float(re.search(r"max_rotation_deg=([0-9.]+)", str(err.value)).group(1))
    p = parse_ardupilot(ex.of_calibration(cal, "ardupilot", max_rotation_deg=limit).text)
    real, ints = parse_orientation_px4(ex.of_calibration(cal, "px4", max_rotation_deg=limit).text)
    assert p["COMPASS_ORIENT"] == 2 and ints == {"CAL_MAG0_ROT": 2}
    raw, b = rec.readings, cal.calibrated
    assert relative(ardupilot_with_orientation(raw * 1000, p), b * 1000) < 1.01 * np.deg2rad(limit)
    assert relative(px4_correct(raw, real, 0, fw.standard_rotation(2)), b) < 1.01 * np.deg2rad(limit)
