"""The whole route a user takes: a log (an MCAP bag written by rosbags) with attitudes and GPS ->
the WMM field at its place and date -> a vector calibration -> ArduPilot parameters that, applied
with ArduPilot's correct_field, give magexp's calibrated field back."""

from __future__ import annotations

import numpy as np

from magexp.calibration.fit import calibrate_recording
from magexp.core.field_model import field_in, field_of_recording, reference_field
from magexp.estimators.lm import LevenbergMarquardt
from magexp.core.geometry import random_rotations, rot_x
from magexp.core.recordings import load_recording
from tests.test_export import ardupilot_correct_field, parse_ardupilot, relative
from tests.test_rosbag_reader import ALT, LAT, LON, write_bag

from magexp.calibration import export as ex
from magexp.calibration import firmware as fw


def test_a_bag_calibrated_to_the_wmm_field_exports_to_ardupilot(tmp_path):
    rng = np.random.default_rng(11)
    field_ned = reference_field(LAT, LON, ALT / 1e3, "2025-06-15", model="wmm").ned  # the bag's place and date
    q = random_rotations(1, rng=rng)[0]
    w_true = rot_x(np.deg2rad(0.4)) @ q @ np.diag([1.08, 0.93, 1.02]) @ q.T  # soft iron, 0.4° misalignment
    o_true = np.array([12.0, -30.0, 21.0])  # µT
    path = tmp_path / "flight"
    readings = write_bag(path, "mcap", random_rotations(60, rng=rng), field_ned, w_true, o_true)  # r = W⁻¹ B + o
    rec = load_recording(path)
    np.testing.assert_allclose(rec.readings, readings, rtol=1e-12)
    reference = field_of_recording(rec, model="wmm")
    assert reference.generation == "WMM-2025" and reference.inputs["sources"]["latitude"] == "log GPS"
    rec.field = field_in(reference, rec.unit)
    cal = calibrate_recording(rec, LevenbergMarquardt(), objective="vector", folds=0, rng=np.random.default_rng(0))
    print(f"W error {np.max(np.abs(cal.w - w_true)):.2g}, offset error {np.max(np.abs(cal.offset - o_true)):.2g} uT")
    assert np.allclose(cal.w, w_true, atol=1e-6) and np.allclose(cal.offset, o_true, atol=1e-4)
    out = ex.render("ardupilot", cal.w, cal.offset, cal.unit)  # R of 0.4°: within the 1° the export accepts
    firmware = ardupilot_correct_field(rec.readings * 10, parse_ardupilot(out.text))  # µT -> mGauss
    rotation, _ = fw.polar(cal.w)
    assert relative(firmware, cal.calibrated @ rotation * 10) < 1e-6  # the firmware's field: Rᵀ B
