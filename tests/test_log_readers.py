"""The log readers (magexp.core.readers: ulog, dataflash, _logs): the real PX4 and ArduPilot samples, the attitude
conversions, and the one-line refusals (ROS bags: test_rosbag_reader.py)."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from magexp.calibration.command import main as calibrate_main
from magexp.core.logfiles import angles_from_attitude, attitude_at, euler_quaternions
from magexp.errors import MagexpError
from magexp.core.geometry import quat_to_matrix, random_rotations, rotation_angle, ship_attitude
from magexp.paths import SHARED_DATA
from magexp.core.recordings import detect, load_recording

ULOG, ULOG_SMALL, DATAFLASH = (SHARED_DATA / n for n in ("px4_sample.ulg", "px4_sample_log_small.ulg",
                                                         "ardupilot_test.bin"))
needs = lambda path: pytest.mark.skipif(not path.is_file(), reason=f"{path} is not present")  # noqa: E731


# -- attitude conversions ------------------------------------------------------------------------
def test_angles_reproduce_every_rotation():
    a = random_rotations(500, rng=np.random.default_rng(1))
    back = ship_attitude(*angles_from_attitude(a).T)
    assert np.max(np.abs(back - a)) < 1e-12


def test_slerp_is_exact_at_samples_and_halfway_between():
    q = np.array([[1.0, 0, 0, 0], [np.cos(0.5), 0, 0, np.sin(0.5)]])  # 0 and 1 rad about z
    r = attitude_at(np.array([0.0, 2.0]), q, np.array([0.0, 1.0, 2.0, 3.0]))
    assert np.allclose(rotation_angle(r), [0.0, 0.5, 1.0, 1.0], atol=1e-12)  # held after the last sample
    assert r[1][1, 0] == pytest.approx(np.sin(0.5))  # about +z


def test_euler_quaternions_are_zyx():
    roll, pitch, yaw = 0.3, -0.2, 1.1
    rz = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    ry = np.array([[np.cos(pitch), 0, np.sin(pitch)], [0, 1, 0], [-np.sin(pitch), 0, np.cos(pitch)]])
    rx = np.array([[1, 0, 0], [0, np.cos(roll), -np.sin(roll)], [0, np.sin(roll), np.cos(roll)]])
    assert np.allclose(quat_to_matrix(euler_quaternions([roll], [pitch], [yaw]))[0], rz @ ry @ rx, atol=1e-12)


@pytest.mark.parametrize("name, key", [("a.ulg", "ulog"), ("a.bin", "dataflash"), ("a.bag", "rosbag"),
                                       ("a.mcap", "rosbag"), ("a.db3", "rosbag")])
def test_auto_detects_the_logs(tmp_path, name, key):
    assert detect(tmp_path / name) == key


def test_a_missing_extra_names_the_pip_install(monkeypatch, tmp_path, capsys):
    for module in ("pyulog", "pyulog.core"):  # import pyulog fails (even after an earlier test imported it)
        monkeypatch.setitem(sys.modules, module, None)
    path = tmp_path / "flight.ulg"
    path.write_bytes(b"ULog\x01\x12\x35")
    with pytest.raises(MagexpError, match=r"pip install 'magexp\[ulog\]'") as err:
        load_recording(path)
    assert "\n" not in str(err.value)
    assert calibrate_main([f"data.path={path}", f"out={tmp_path / 'out'}"]) == 2
    assert "magexp[ulog]" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("name", ["junk.ulg", "junk.bin", "junk.mcap"])
def test_a_damaged_log_is_one_line(tmp_path, name):
    path = tmp_path / name
    path.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(MagexpError) as err:
        load_recording(path)
    assert name in str(err.value) and "\n" not in str(err.value)


# -- PX4 ULog -------------------------------------------------------------------------------------
@needs(ULOG)
def test_px4_sample_undoes_the_onboard_offsets():
    from pyulog import ULog

    rec = load_recording(ULOG)
    ulog = ULog(str(ULOG), ["sensor_combined", "vehicle_attitude"])
    d = ulog.get_dataset("sensor_combined").data
    t = d["timestamp"].astype(np.int64) + d["magnetometer_timestamp_relative"]
    fresh = np.concatenate([[True], np.diff(t) != 0])
    logged = np.column_stack([d[f"magnetometer_ga[{i}]"] for i in range(3)])[fresh]
    p = ulog.initial_parameters
    off = np.array([p[f"CAL_MAG0_{a}OFF"] for a in "XYZ"])
    # B = R S (r - OFF): S = I (SCALE 1), R the board's level adjustment Rz(z) Ry(y) Rx(x) (SENS_BOARD_ROT = 0)
    x, y, z = np.deg2rad([p["SENS_BOARD_X_OFF"], p["SENS_BOARD_Y_OFF"], p["SENS_BOARD_Z_OFF"]])
    rx = np.array([[1, 0, 0], [0, np.cos(x), -np.sin(x)], [0, np.sin(x), np.cos(x)]])
    ry = np.array([[np.cos(y), 0, np.sin(y)], [0, 1, 0], [-np.sin(y), 0, np.cos(y)]])
    rz = np.array([[np.cos(z), -np.sin(z), 0], [np.sin(z), np.cos(z), 0], [0, 0, 1]])
    print(f"px4_sample: {rec.n} readings at {1 / np.median(np.diff(rec.times)):.0f} Hz, meta {rec.meta}")
    assert (rec.n, rec.unit, rec.meta["source"], p["SENS_BOARD_ROT"]) == (6759, "G", "sensor_combined", 0)
    np.testing.assert_allclose((rec.readings - off) @ (rz @ ry @ rx).T, logged, rtol=0, atol=1e-6)
    assert np.all(np.diff(rec.times) > 0) and rec.gyro_stream[1].shape == (17070, 3)
    a = ulog.get_dataset("vehicle_attitude").data  # the sample nearest each reading, from pyulog directly
    t_att = (a["timestamp"].astype(np.int64) - ulog.start_timestamp) / 1e6
    k = np.clip(np.searchsorted(t_att, rec.times), 1, len(t_att) - 1)
    k -= rec.times - t_att[k - 1] < t_att[k] - rec.times
    body_to_ned = quat_to_matrix(np.column_stack([a[f"q[{i}]"] for i in range(4)])[k])
    error = np.rad2deg(rotation_angle(rec.attitude() @ body_to_ned))  # nav->body @ body->nav = I
    assert np.median(error) < 0.01 and np.max(error) < 2.0  # interpolated between samples ~10 ms apart


@needs(ULOG_SMALL)
def test_px4_small_log_has_gps():
    rec = load_recording(ULOG_SMALL)
    assert (rec.n, rec.meta["source"], rec.meta["calibration_slot"]) == (319, "vehicle_magnetometer", "1")
    assert float(rec.meta["latitude"]) == pytest.approx(63.41705, abs=1e-4)
    assert float(rec.meta["longitude"]) == pytest.approx(10.40822, abs=1e-4)
    assert rec.meta["date"] == "2021-04-21"


@needs(ULOG_SMALL)
@pytest.mark.parametrize("edit, message", [
    ("drop", "has no CAL_MAGn_ID in the log's parameters: its onboard calibration cannot be undone"),
    ("change", "CAL_MAG1_XOFF changes at 2.982 s, while the magnetometer is logged"),
], ids=["dropped", "changed"])
def test_an_onboard_calibration_that_cannot_be_undone_is_one_line(tmp_path, edit, message):
    """The small log rewritten by pyulog without its CAL_MAG parameters, or with one changed mid-log."""
    from pyulog import ULog

    from magexp.core.readers.ulog import read_ulog

    ulog = ULog(str(ULOG_SMALL), ["vehicle_magnetometer"])
    if edit == "drop":
        for key in [k for k in ulog.initial_parameters if k.startswith("CAL_MAG")]:
            del ulog.initial_parameters[key]
    else:
        ulog.changed_parameters.append((ulog.start_timestamp + 3_000_000, "CAL_MAG1_XOFF", 0.05))
    path = tmp_path / "edited.ulg"
    ulog.write_ulog(str(path))
    with pytest.raises(MagexpError, match=message) as err:
        load_recording(path)
    assert "\n" not in str(err.value)
    kept = read_ulog(path, undo=False)  # the readings as logged
    logged = ulog.get_dataset("vehicle_magnetometer").data
    np.testing.assert_array_equal(kept.readings[:, 0], logged["magnetometer_ga[0]"])
    assert kept.meta["corrected"] == "kept as logged (undo=False)"


@pytest.mark.parametrize("path, reason", [
    (ULOG, "cover 66 % of the sphere"),  # ±22° of roll, 28° of heading: too little for W
    (ULOG_SMALL, "barely move"),  # on the ground: one attitude
    (DATAFLASH, "8 readings is not allowed"),  # one second of log
], ids=["px4_sample", "px4_small", "ardupilot"])
def test_the_samples_are_refused_in_one_line(path, reason):
    if not path.is_file():
        pytest.skip(f"{path} is not present")
    from magexp.calibration.fit import calibrate_recording
    from magexp.estimators.ellipsoid import EllipsoidFit  # magexp calibrate's default estimator

    with pytest.raises(MagexpError, match=reason) as err:
        calibrate_recording(load_recording(path), EllipsoidFit(name="ellipsoid"), folds=0,
                            rng=np.random.default_rng(0))
    assert path.name in str(err.value) and "\n" not in str(err.value)


# -- ArduPilot DataFlash ------------------------------------------------------------------------
def test_a_dataflash_log_without_mag_is_one_line(tmp_path):
    """A DataFlash log written here (FMT records, then IMU messages), with no MAG: refused in one line."""
    import struct

    fmt = lambda t, n, f, c: b"\xa3\x95\x80" + struct.pack("<BB4s16s64s", t, 3 + struct.calcsize("<" + {  # noqa: E731
        "BBnNZ": "BB4s16s64s", "Qfff": "Qfff"}[f]), n, f.encode(), c.encode())
    data = fmt(128, b"FMT", "BBnNZ", "Type,Length,Name,Format,Columns") + fmt(129, b"IMU", "Qfff", "TimeUS,GyrX,GyrY,GyrZ")
    data += b"".join(b"\xa3\x95\x81" + struct.pack("<Qfff", 1000 * k, 0.1, 0.2, 0.3) for k in range(50))
    path = tmp_path / "imu_only.bin"
    path.write_bytes(data)
    with pytest.raises(MagexpError, match="imu_only.bin: no MAG messages of compass instance 0") as err:
        load_recording(path)
    assert "\n" not in str(err.value)


@needs(DATAFLASH)
def test_a_unit_other_than_the_logs_is_one_line():
    with pytest.raises(MagexpError, match=r"data.unit='uT' is not allowed for ardupilot_test.bin: DataFlash MAG is in mG"):
        load_recording(DATAFLASH, unit="uT")


@needs(DATAFLASH)
def test_ardupilot_raw_reproduces_the_logged_field_through_correct_field():
    """ArduPilot's correct_field (AP_Compass_Backend.cpp), written here from the source, applied to
    the reader's raw readings with the log's PARM values gives MAG back (logged as whole mGauss)."""
    from pymavlink import DFReader

    rec = load_recording(DATAFLASH)
    reader = DFReader.DFReader_binary(str(DATAFLASH), zero_time_base=False)
    params, logged = {}, []
    while (m := reader.recv_match(type=["PARM", "MAG"])) is not None:
        if m.get_type() == "PARM":
            params[m.Name] = m.Value
        else:
            logged.append([m.MagX, m.MagY, m.MagZ])
    dia = [params[f"COMPASS_DIA_{a}"] for a in "XYZ"]
    odi = [params[f"COMPASS_ODI_{a}"] for a in "XYZ"]
    mat = np.array([[dia[0], odi[0], odi[1]], [odi[0], dia[1], odi[2]], [odi[1], odi[2], dia[2]]])
    ofs = np.array([params[f"COMPASS_OFS_{a}"] for a in "XYZ"])
    field = (rec.readings + ofs) @ mat.T  # no COMPASS_SCALE in ArduPlane 3.8, no motor compensation
    print(f"ardupilot_test: {rec.n} readings over {np.ptp(rec.times):.2f} s, |raw| {np.linalg.norm(rec.readings, axis=1)}")
    assert rec.n == 8 and rec.unit == "mG"
    np.testing.assert_allclose(field, logged, atol=1e-6)
    assert rec.meta["date"] == "2017-10-29" and float(rec.meta["latitude"]) == pytest.approx(-35.36263, abs=1e-4)
    assert rec.angles is not None and rec.gyro_stream[1].shape == (45, 3)
