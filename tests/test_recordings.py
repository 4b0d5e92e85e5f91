"""Readers of every recorded format, axis maps, and attitude maths (prefix scan, gyro integrated at
the readings' times, preintegrated bias Jacobians)."""

from pathlib import Path

import numpy as np
import pytest

from magexp.errors import MagexpError
from magexp.core.geometry import (attitude_at, attitude_with_bias, axis_map, cumulative_product, exp_so3,
                             integrate_rates, preintegrate)
from magexp.paths import DATA, SHARED_DATA
from magexp.core.readers import names
from magexp.core.recordings import detect, load_recording, resolve

needs_data = pytest.mark.skipif(not SHARED_DATA.is_dir(), reason=f"{SHARED_DATA} is not present")


def test_prefix_scan_equals_the_ordered_product():
    rng = np.random.default_rng(0)
    mats = exp_so3(rng.normal(0, 1, (37, 3)))
    expected = [mats[0]]
    for m in mats[1:]:
        expected.append(expected[-1] @ m)
    np.testing.assert_allclose(cumulative_product(mats), expected, atol=1e-13)


def test_integration_at_other_times_is_exact_for_a_constant_rate():
    gyro_t = np.linspace(0, 2, 41)  # 20 Hz
    rates = np.tile([0.0, 0.0, 0.5], (41, 1))  # 0.5 rad/s about z
    at = np.array([0.013, 0.4, 1.2345, 1.9])  # not on the gyro's grid
    r = attitude_at(gyro_t, rates, at)
    angles = np.arctan2(r[:, 1, 0], r[:, 0, 0])
    np.testing.assert_allclose(angles, 0.5 * (at - at[0]), atol=1e-12)


def test_preintegrated_bias_jacobian_matches_reintegration():
    rng = np.random.default_rng(1)
    gyro_t = np.sort(rng.uniform(0, 4, 400))
    rates = rng.normal(0, 1.5, (400, 3))
    at = np.sort(rng.uniform(0.05, 3.95, 80))
    bias = np.array([0.06, -0.04, 0.05])  # ~3 deg/s
    exact = attitude_at(gyro_t, rates, at, bias=bias)
    delta, jac = preintegrate(gyro_t, rates, at)
    approx = attitude_with_bias(delta, jac, bias[None])[0]
    unbiased = attitude_with_bias(delta, jac, np.zeros((1, 3)))[0]
    np.testing.assert_allclose(unbiased, attitude_at(gyro_t, rates, at), atol=1e-12)
    err = np.abs(approx - exact).max()
    assert err < 5e-3 < np.abs(unbiased - exact).max()  # first order in the bias, far better than ignoring it


def test_integrate_rates_with_a_start():
    start = exp_so3(np.array([0.1, 0.2, 0.3]))
    out = integrate_rates(np.zeros((3, 3)), 0.1, start)
    np.testing.assert_allclose(out, np.broadcast_to(start, (4, 3, 3)))


def test_axis_maps():
    np.testing.assert_array_equal(axis_map("-x,y,z") @ [1, 2, 3], [-1, 2, 3])
    np.testing.assert_array_equal(axis_map("y, x, -z") @ [1, 2, 3], [2, 1, -3])
    np.testing.assert_array_equal(axis_map(None), np.eye(3))
    for bad in ("x,x,z", "x,y", "a,b,c", "x,y,z,x"):
        with pytest.raises(MagexpError, match="is not allowed: give three signed axes"):
            axis_map(bad)


def test_two_stream_and_named_column_files(tmp_path):
    (tmp_path / "s_mag.csv").write_text("t_s,mx_G,my_G,mz_G\n" + "".join(f"{0.1 * k:.3f},{k},{-k},{k % 3}\n" for k in range(20)))
    (tmp_path / "s_imu.csv").write_text("t_s,gx_dps,gy_dps,gz_dps,ax_g,ay_g,az_g\n"
                                        + "".join(f"{0.07 * k:.3f},0,0,90,0,0,1\n" for k in range(40)))
    rec = load_recording(tmp_path / "s", gyro_axes="x,y,-z")
    assert detect(tmp_path / "s_mag.csv") == "two-stream" and rec.unit == "G" and rec.n == 20
    att = rec.attitude()  # -90 deg/s about z after the map: nav -> body is the inverse turn
    ang = np.rad2deg(np.arctan2(att[:, 0, 1], att[:, 0, 0]))
    np.testing.assert_allclose(ang[:5], [0, -9, -18, -27, -36], atol=1e-9)
    head = "Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),Magnetometer X (uT),Magnetometer Y (uT),Magnetometer Z (uT)\n"
    rows = "".join(f"{0.01 * k},1,0,0,{k // 3},{2},{3}\n" for k in range(30))  # the magnetometer updates every 3rd row
    (tmp_path / "x.csv").write_text(head + rows)
    rec = load_recording(tmp_path / "x.csv")
    assert rec.meta["format"] == "named-columns" and rec.n == 10 and rec.unit == "uT"
    np.testing.assert_allclose(rec.reading_times(), 0.03 * np.arange(10), atol=1e-12)
    assert len(rec.gyro_stream[0]) == 30
    (tmp_path / "q.csv").write_text("Fs,50.00\nInitialization time,60\nmx,my,mz\n" + "1,2,3\n" * 12)
    rec = load_recording(tmp_path / "q.csv")
    assert rec.unit == "counts" and rec.meta["fs"] == "50.00" and rec.reading_times()[-1] == pytest.approx(0.22)


def test_a_relative_path_resolves_against_the_working_folder_first(tmp_path, monkeypatch):
    """A relative file or two-stream stem found from the working folder is read there (also
    through ``..``); only a path found nowhere there is looked up in data/ (issue 31)."""
    work, beside = tmp_path / "clone", tmp_path / "shared"
    work.mkdir(), beside.mkdir()
    (beside / "s_mag.csv").write_text("t_s,mx_G,my_G,mz_G\n" + "".join(f"{0.1 * k:.3f},{k},{-k},1\n" for k in range(20)))
    (beside / "s_imu.csv").write_text("t_s,gx_dps,gy_dps,gz_dps\n" + "".join(f"{0.1 * k:.3f},0,0,0\n" for k in range(20)))
    (work / "yan2022_mockup.csv").write_text("1 2 3\n" * 12)  # the name of a file shipped in data/
    monkeypatch.chdir(work)
    assert resolve("../shared/s") == resolve("../shared/s_mag.csv").with_name("s")
    assert load_recording("../shared/s").n == 20 and load_recording("../shared/s").meta["format"] == "two-stream"
    assert load_recording("yan2022_mockup.csv", unit="nT").meta["format"].startswith("plain")  # the working folder's
    (work / "yan2022_mockup.csv").unlink()
    assert load_recording("yan2022_mockup.csv").path == DATA / "yan2022_mockup.csv"  # found nowhere here: data/'s
    with pytest.raises(MagexpError, match="does not exist"):
        load_recording("../shared/t")


@pytest.mark.parametrize("text, message", [
    ("t_s,mx_furlong,my_furlong,mz_furlong\n0,1,2,3\n", "unit suffix 'furlong' is not allowed"),
    ("t_s,mx_G,my_G,mz_G\n0,1,2,3\n0,1,2,3\n", "times must increase"),
    ("t_s,mx_G,my_G,mz_G\n0,1,x,3\n", "line 2: column 3='x' is not a number"),
    ("t_s,mx_G,mx_G,mz_G\n0,1,2,3\n", "column 'mx_g' is duplicated"),
])
def test_bad_stream_files_are_one_line(tmp_path, text, message):
    (tmp_path / "b_mag.csv").write_text(text)
    (tmp_path / "b_imu.csv").write_text("t_s,gx_dps,gy_dps,gz_dps\n0,0,0,0\n1,0,0,0\n")
    with pytest.raises(MagexpError, match=message) as err:
        load_recording(tmp_path / "b_mag.csv")
    assert "\n" not in str(err.value)


def test_unknown_format_is_one_line(tmp_path):
    (tmp_path / "a.txt").write_text("1 2 3\n")
    with pytest.raises(MagexpError, match="data.format='nope' is not allowed: choose one of auto, " + ", ".join(names())):
        load_recording(tmp_path / "a.txt", unit="uT", format="nope")


@needs_data
@pytest.mark.parametrize("name, fmt, n, unit", [
    ("fxos8700_mag_readings.txt", "plain 3 columns", 324, "uT"),
    ("hmc5883l_full-sphere", "two-stream", 8190, "G"),
    ("xio_fusion_sensor_data.csv", "named-columns", None, "uT"),
    ("qmc5883l_noisy_raw_data.csv", "header-counts", 22743, "counts"),
])
def test_every_shared_recording_loads(name, fmt, n, unit):
    rec = load_recording(SHARED_DATA / name, unit="uT" if name.startswith("fxos") else None)
    assert rec.meta["format"] == fmt and rec.unit == unit and np.all(np.isfinite(rec.readings))
    assert n is None or rec.n == n
    if fmt in ("two-stream", "named-columns"):
        att = rec.attitude()
        np.testing.assert_allclose(att @ att.transpose(0, 2, 1), np.broadcast_to(np.eye(3), att.shape), atol=1e-9)


@needs_data
def test_rest_recording_gyro_bias_is_a_few_deg_per_second():
    rec = load_recording(SHARED_DATA / "hmc5883l_unmoved-10min")
    bias = np.rad2deg(rec.gyro_stream[1].mean(axis=0))
    print("rest gyro bias (deg/s):", bias.round(3))
    assert 1.0 < np.linalg.norm(bias) < 10.0


def test_the_format_modules_are_the_registry_and_name_the_reader_the_cache_keys_on(tmp_path):
    """Every module of magexp/core/readers/ not starting with ``_`` is a format (listed in ``PRIORITY`` order),
    and :func:`magexp.core.readers.reader_of` names its ``read`` (what the run cache keys a run on), a real
    function; ``auto`` tries the suffixes, then the paths, then the first lines in that order."""
    import pkgutil

    from magexp.core import readers

    listed = {m.name for m in pkgutil.iter_modules(readers.__path__) if not m.name.startswith("_")}
    assert {m.__name__.rpartition(".")[2] for m in readers.formats()} == listed
    assert [m.PRIORITY for m in readers.formats()] == sorted(m.PRIORITY for m in readers.formats())
    assert len({m.PRIORITY for m in readers.formats()}) == len(listed)  # no two tried at once
    for module in readers.formats():
        assert callable(module.read) and module.NAME in readers.names()
        name = readers.reader_of(tmp_path / "x", module.NAME)
        owner, _, function = name.rpartition(".")
        assert owner == module.__name__ and getattr(module, function) is module.read
    assert readers.reader_of(Path("x.ulg")) == "magexp.core.readers.ulog.read_ulog"
    assert readers.by_suffix(Path("a.MCAP")) == "rosbag" and readers.by_suffix(Path("a.csv")) is None
    for head, fmt in [("# magexp-recording v1\n", "magexp-v1"), ("Fs,100\n", "header-counts"),
                      ("Time (s),Magnetometer X (uT)\n", "named-columns"), ("t,mx,my,mz\n", "header-row"),
                      ("1 2 3\n", "plain"), ("hello\n", "magexp-v1"), ("mx_uT,Gyroscope X (deg/s)\n", "named-columns"),
                      ("fs, x, y, z\n", "header-counts")]:
        (tmp_path / "r.csv").write_text(head)
        assert readers.detect(tmp_path / "r.csv") == fmt, head
    (tmp_path / "x_mag.csv").write_text("1 2 3\n")  # the name wins over the first line
    assert readers.detect(tmp_path / "x_mag.csv") == readers.detect(tmp_path / "x") == "two-stream"


def test_no_reader_imports_the_loader():
    """The readers import :mod:`magexp.core.recording` (the type), never :mod:`magexp.core.recordings` (the
    loader, which names them): no cycle, hidden or not."""
    import ast

    import magexp.core.readers

    folder = Path(magexp.core.readers.__file__).parent
    for path in [*folder.glob("*.py"), folder.parent / "recording.py"]:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                assert node.module != "magexp.core.recordings", path
            elif isinstance(node, ast.Import):
                assert all(a.name != "magexp.core.recordings" for a in node.names), path


def test_one_path_from_a_recording_to_a_dataset(tmp_path):
    """The scenario's gyro dataset is :func:`magexp.core.recording.recording_dataset` of its readings: the
    readings kept, their reference, the gyroscope preintegrated between their times (the calibration's path)."""
    from magexp.core.geometry import preintegrate
    from magexp.core.recording import Recording, evenly_spaced, recording_dataset
    from magexp.scenarios.recording import RecordingScenario
    from magexp.scenarios.search import centroid_radius

    t = np.arange(200) * 0.02
    u = np.column_stack([np.cos(t), np.sin(t) * np.cos(3 * t), np.sin(t) * np.sin(3 * t)])
    rows = np.column_stack([t, 40 * u + [3, -2, 1], np.full((200, 3), 0.1)])
    path = tmp_path / "rec.csv"
    path.write_text("t,mx_uT,my_uT,mz_uT,gx,gy,gz\n" + "\n".join(",".join(f"{v:.6f}" for v in r) for r in rows) + "\n")
    scenario = RecordingScenario(name="s", file=str(path), objective="gyro", folds=0, n_readings=20)
    data = scenario.generate()
    rec = load_recording(path)
    keep = evenly_spaced(rec.n, 20)
    assert keep[0] == 0 and keep[-1] == 199 and len(keep) == 20 and np.all(np.diff(keep) > 0)
    direct = recording_dataset(rec, centroid_radius(rec.readings[keep]), "gyro", keep=keep)
    assert np.array_equal(data.readings, direct.readings) and np.array_equal(data.reference_norm, direct.reference_norm)
    for got, want in zip(data.extra["preintegration"], preintegrate(*rec.gyro_rates(), rec.reading_times()[keep])):
        assert np.array_equal(got, want)
    assert np.array_equal(evenly_spaced(5, None), np.arange(5)) and np.array_equal(evenly_spaced(5, 9), np.arange(5))
    with pytest.raises(MagexpError, match="objective='gyro' is not allowed for readings: it has no gyroscope"):
        recording_dataset(Recording(readings=rec.readings, angles=None, field=None, unit="uT"), 40.0, "gyro")
