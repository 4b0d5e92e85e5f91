"""Heading error in degrees (magexp/calibration/heading.py): known answers on synthetic sensors, the record
through magexp.calibrate, the export files' line, the figure's panel and gate.max_heading_deg."""

import json

import numpy as np
import pytest

import magexp
from magexp.calibration import heading
from magexp.calibration.command import main
from magexp.calibration.export import ardupilot, firmware_correction, of_calibration
from magexp.calibration.firmware import to_firmware
from magexp.calibration.result import Calibration
from magexp.core.geometry import random_rotations, rot_x, rot_z
from magexp.errors import MagexpError
from magexp.paths import SHARED_DATA

I = 60.0  # inclination of the synthetic site (deg)
S = np.array([[1.10, 0.05, -0.03], [0.05, 0.92, 0.04], [-0.03, 0.04, 1.05]])


def test_identity_correction_leaves_no_heading_error():
    err = heading.errors(np.eye(3), np.zeros(3), I)
    assert err.shape == (1, 10, heading.N_HEADINGS) and np.abs(err).max() < 1e-9


@pytest.mark.parametrize("d", [0.05, 0.2, 0.45])
def test_an_offset_along_x_gives_asin_of_offset_over_horizontal_field(d):
    """A constant vector of length d F added to a horizontal field H = F cos I turning with the heading
    turns it by at most asin(d / cos I): the raw heading error of a sensor whose only fault is an offset."""
    err = heading.raw_errors(np.eye(3), [d * 50.0, 0, 0], 50.0, I, tilt_deg=0, n_headings=36000)
    expected = np.degrees(np.arcsin(d / np.cos(np.radians(I))))
    assert abs(heading.stats(err)["level_worst_deg"] - expected) < 1e-3


def test_an_offset_beyond_the_horizontal_field_turns_the_heading_through_every_angle():
    err = heading.raw_errors(np.eye(3), [0, 0.6 * 50.0, 0], 50.0, I, tilt_deg=0)  # 0.6 > cos 60 = 0.5
    assert heading.stats(err)["level_worst_deg"] > 179


@pytest.mark.parametrize("theta", [0.5, 3.0, 4.8])
def test_a_rotation_about_the_vertical_left_out_of_the_export_is_that_many_degrees(theta):
    w = rot_z(np.radians(theta)) @ S  # W = R S, R about the sensor's z: the vertical when level
    corr = to_firmware(w, [3.0, -2.0, 1.0], "uT", "mG", symmetric=True, max_rotation_deg=5)
    assert corr.rotation_deg == pytest.approx(theta)
    s = heading.stats(heading.export_errors(corr, 50.0, I))
    assert s["level_worst_deg"] == pytest.approx(theta, abs=1e-4)
    assert s["level_rms_deg"] == pytest.approx(theta, abs=1e-4)  # every heading, either way up


def test_a_rotation_about_a_horizontal_axis_costs_more_heading_than_its_angle():
    """A tilt error e turns the heading by up to about e tan I: a rotation left out is not bounded by its angle."""
    w = rot_x(np.radians(3.0)) @ S
    corr = to_firmware(w, np.zeros(3), "uT", None, symmetric=True, max_rotation_deg=5)
    worst = heading.stats(heading.export_errors(corr, 50.0, I))["level_worst_deg"]
    assert worst == pytest.approx(np.degrees(np.arctan(np.tan(np.radians(3.0)) * np.tan(np.radians(I)))), rel=0.02)


def test_a_symmetric_export_loses_only_float32_rounding():
    corr = to_firmware(S, [30.0, -20.0, 10.0], "uT", "G", symmetric=True)
    assert heading.stats(heading.export_errors(corr, 50.0, I))["worst_deg"] < 1e-4


def test_only_the_size_of_the_inclination_matters():
    rng = np.random.default_rng(3)
    a, c = np.eye(3) + 0.05 * rng.standard_normal((3, 3)), 0.1 * rng.standard_normal(3)
    up, down = heading.stats(heading.errors(a, c, I)), heading.stats(heading.errors(a, c, -I))
    assert all(up[k] == pytest.approx(down[k], rel=1e-9) for k in up)


def test_heldout_folds_equal_to_the_full_calibration_leave_nothing_and_an_offset_fold_what_its_offset_does():
    o = np.array([5.0, -3.0, 2.0])
    assert np.abs(heading.heldout_errors(S, o, [(S, o), (S, o)], 50.0, I)).max() < 1e-9
    shifted = o - np.linalg.solve(S, [0.1 * 50.0, 0, 0])  # W_k (o - o_k) = 0.1 F along x
    err = heading.heldout_errors(S, o, [(S, o), (S, shifted)], 50.0, I, tilt_deg=0, n_headings=36000)
    assert np.abs(err[0]).max() < 1e-9
    assert np.abs(err[1]).max() == pytest.approx(np.degrees(np.arcsin(0.1 / np.cos(np.radians(I)))), abs=1e-3)


def sensor(n=400, seed=5, offset=(14.0, -9.0, 6.0), noise=0.05):
    """Readings of a sensor with soft iron ``S^-1`` and ``offset`` turned through every orientation (uT)."""
    rng = np.random.default_rng(seed)
    field = random_rotations(n, rng=rng) @ np.array([20.0, 0.0, 45.0])
    return field @ np.linalg.inv(S).T + np.asarray(offset) + noise * rng.standard_normal((n, 3))


@pytest.fixture(scope="module")
def cal():
    return magexp.calibrate(sensor(), unit="uT", model="full")


def test_calibrate_reports_heading_raw_calibrated_and_exported(cal):
    h = cal.report["heading"]
    assert h["inclination_deg"] == heading.DEFAULT_INCLINATION_DEG and "default" in h["inclination_source"]
    expected_raw = heading.stats(heading.raw_errors(cal.w, cal.offset, float(np.mean(cal.reference.total)),
                                                    heading.DEFAULT_INCLINATION_DEG))
    assert h["raw"] == pytest.approx(expected_raw)
    assert h["raw"]["level_worst_deg"] > 20  # an offset of 18 uT against a horizontal field of 25 uT
    assert h["calibrated"]["folds"] == len(cal.heldout_fits) == 6
    assert 0 < h["calibrated"]["level_worst_deg"] < 1  # 0.05 uT noise on 400 readings
    assert h["exported"]["worst_deg"] < 1e-3 and h["exported"]["rotation_left_out_deg"] == 0
    assert "heading error" in cal.summary() and "calibrated (held out)" in cal.summary()


def test_heading_record_round_trips_and_an_older_file_without_it_still_reads(cal, tmp_path):
    path = cal.save(tmp_path / "calibration.json")
    assert Calibration.load(path).report["heading"] == json.loads(json.dumps(cal.report["heading"]))
    data = json.loads(path.read_text())
    del data["quality"]["heading"]
    (tmp_path / "old.json").write_text(json.dumps(data))
    old = Calibration.load(tmp_path / "old.json")
    assert "heading error" not in old.summary() and "offset" in old.summary()


def test_export_files_state_the_heading_error(cal):
    out = of_calibration(cal, "px4")
    assert "heading error these parameters leave" in out.text and "heading error of the calibration (held out)" \
        in out.text
    w = rot_z(np.radians(2.0)) @ S
    rendered = ardupilot(w, [1.0, 2.0, 3.0], "uT", max_rotation_deg=3, site=(50.0, (I, "test site")))
    line = next(t for t in rendered.text.splitlines() if "heading error" in t)
    assert "worst 2 deg" in line and "test site" in line


@pytest.mark.full
def test_figure_has_the_heading_panel(cal):
    fig = cal.plot()
    panel = fig.axes[-1]
    assert panel.get_xlabel() == "heading (deg)" and panel.get_yscale() == "log"
    assert [t.get_text().split(":")[0] for t in panel.get_legend().get_texts()] == \
        ["raw", "calibrated (held out)", "as exported"]


def test_folds_zero_says_not_measured(tmp_path):
    c = magexp.calibrate(sensor(n=200), unit="uT", model="full", folds=0)
    assert c.report["heading"]["calibrated"] == {"not_measured": "no held-out check (folds=0)"}
    assert "not measured (no held-out check (folds=0))" in c.summary()


def test_gate_in_degrees_refuses_in_one_line(tmp_path, capsys):
    path = tmp_path / "mine.csv"
    np.savetxt(path, sensor(n=300), delimiter=",")
    out = tmp_path / "out"
    code = main([f"data.path={path}", "data.unit=uT", "model=full", "gate.max_heading_deg=0.01", f"out={out}"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "check 'heading' failed" in err[0] and "over the limit 0.01 deg" in err[0]
    assert not out.exists()
    with pytest.raises(MagexpError, match=r"gate.max_heading_deg=-1 is not allowed"):
        magexp.calibrate(sensor(n=200), unit="uT", gate={"max_heading_deg": -1})


def test_firmware_correction_of_a_mirrored_w_is_the_refusal(cal):
    mirrored = Calibration(**{**cal.__dict__, "w": -cal.w})
    assert "mirrors an axis" in firmware_correction(mirrored)


@pytest.mark.full
@pytest.mark.skipif(not (SHARED_DATA / "px4_sample_log_small.ulg").is_file(), reason="shared recordings absent")
def test_a_logs_gps_gives_the_inclination():
    c = magexp.calibrate(SHARED_DATA / "px4_sample_log_small.ulg", checks=False)
    h = c.report["heading"]
    assert "at the log's GPS" in h["inclination_source"] and 70 < h["inclination_deg"] < 80  # Trondheim
