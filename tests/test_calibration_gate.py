"""The acceptance gate (a bad calibration is refused with every reason, or written only with accept=true and
its failures recorded) and model=auto (the model the held-out spread supports, with a parsimony margin)."""

import json

import numpy as np
import pytest

import magexp
from magexp.calibration.checks import GATE, gate, gate_thresholds
from magexp.calibration.command import main
from magexp.calibration.models import fit_diagonal, select
from magexp.core.geometry import random_rotations
from magexp.core.identifiability import coverage
from magexp.errors import MagexpError
from magexp.paths import SHARED_DATA

HMC = "hmc5883l_rotate-ccw-around-{}"


def needs(name):
    present = (SHARED_DATA / name).is_file() or (SHARED_DATA / f"{name}_mag.csv").is_file()
    return pytest.mark.skipif(not present, reason=f"{SHARED_DATA / name} is not present")


def _refused(tmp_path, capsys, *args):
    code = main([*args, f"out={tmp_path / 'out'}"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert not (tmp_path / "out").exists()  # nothing written as good
    return err[0]


# the silent cases of issue 21, each refused with its reasons -----------------------------------------
@needs(HMC.format("z"))
@pytest.mark.parametrize("model", ["auto", "full", "sphere"])
def test_rotate_about_z_is_refused_as_one_plane(tmp_path, capsys, model):
    """Was: exit 0, W33 = 37.9, spread 8.98 % -> 16.77 % (24.6 % held out). A turn about one axis, by
    hand: its raw readings' thickness is 0.051 of their width (the plane threshold, 0.2, sits between
    the single-axis turns' 0.051-0.079 and the multi-axis recordings' 0.48-0.82: docs/calibrate.md)."""
    line = _refused(tmp_path, capsys, f"data.path={SHARED_DATA / HMC.format('z')}", "estimator=ellipsoid",
                    f"model={model}")
    assert "one plane (thickness 0.051" in line and "second axis" in line


@needs(HMC.format("z"))
def test_rotate_about_z_gate_lists_every_failure_when_measured():
    cal = magexp.calibrate(SHARED_DATA / HMC.format("z"), model="full", checks=False)
    failed = {f["check"] for f in cal.report["gate"]["failed"]}
    assert {"heldout", "anisotropy", "scale"} <= failed
    raw = coverage(cal.recording.readings - cal.offset)  # the raw directions about the fitted centre
    assert cal.metrics["coverage_cells"] == raw["coverage_cells"] < coverage(cal.calibrated)["coverage_cells"]


@pytest.mark.parametrize("axis, thickness", [("x", "0.057"), ("y", "0.079")])
def test_a_turn_about_one_axis_is_refused_whatever_the_model(tmp_path, capsys, axis, thickness):
    """Was (issue 33): rotate-ccw-around-y accepted with model=full (held out 0.98 % in time blocks, YSCALE
    1.52), making the sensor's full-sphere recording 20.8 % against 13.6 % raw; rotate-ccw-around-x
    accepted with the gyro model (4.83 % on the full sphere, ten times the full-sphere calibration's)."""
    if not (SHARED_DATA / f"{HMC.format(axis)}_mag.csv").is_file():
        pytest.skip(f"{HMC.format(axis)} is not present")
    for model in ("full", "gyro", "auto"):
        line = _refused(tmp_path, capsys, f"data.path={SHARED_DATA / HMC.format(axis)}", f"model={model}",
                        "accept=true")
        assert f"one plane (thickness {thickness}" in line and "second axis" in line


@needs("xio_fusion_sensor_data.csv")
def test_xio_sphere_recipe_is_refused_heldout_worse_than_raw(tmp_path, capsys):
    """Was: model=sphere, 5.64 % held out against 4.80 % raw, "success". Half a sphere: the region of
    directions toward +z is empty, so the calibration is untested there."""
    line = _refused(tmp_path, capsys, f"data.path={SHARED_DATA / 'xio_fusion_sensor_data.csv'}", "model=sphere")
    assert "is not below the raw 4.8 %" in line and "reach 5 of the 6 regions" in line  # z stays negative


@needs("px4_sample.ulg")
def test_px4_sample_sphere_is_refused_radius_and_heldout(tmp_path, capsys):
    """Was: radius 0.077 G against a 0.48 G field, 121 % held out."""
    line = _refused(tmp_path, capsys, f"data.path={SHARED_DATA / 'px4_sample.ulg'}", "model=sphere")
    assert "held-out spread" in line and "mGauss outside [150, 950]" in line


@needs("xio_fusion_sensor_data.csv")
def test_accept_writes_the_failures_into_calibration_json(tmp_path, capsys):
    out = tmp_path / "out"
    code = main([f"data.path={SHARED_DATA / 'xio_fusion_sensor_data.csv'}", "model=sphere", "accept=true",
                 f"out={out}"])
    assert code == 0
    record = json.loads((out / "calibration.json").read_text())["quality"]["gate"]
    assert record["accepted_anyway"] and not record["passed"]
    assert [f["check"] for f in record["failed"]] == ["heldout", "regions", "heading"]  # 12.8 deg held out


# the gate on synthetic readings ---------------------------------------------------------------------
M = np.array([[1.10, 0.05, -0.03], [0.05, 0.92, 0.04], [-0.03, 0.04, 1.05]])
OFFSET = np.array([12.0, -7.0, 4.0])


def readings(n=600, noise=0.05, seed=1, m=M):
    rng = np.random.default_rng(seed)
    u = random_rotations(n, rng=rng)[:, :, 0]
    return 50.0 * u @ m.T + OFFSET + rng.normal(0, noise, (n, 3))


def test_a_good_full_sphere_passes_the_gate_and_auto_chooses_full():
    cal = magexp.calibrate(readings(), unit="uT", reference_total=50.0)
    assert cal.report["gate"]["passed"] and cal.report["model"] == "full"
    assert "beats" in cal.report["model_selection"]["why"]


def test_auto_keeps_the_sphere_when_richer_models_do_not_beat_it_by_the_margin():
    cal = magexp.calibrate(readings(m=np.eye(3)), unit="uT", reference_total=50.0)
    assert cal.report["model"] == "sphere"
    assert set(cal.report["model_selection"]["heldout_spread"]) == {"sphere", "diagonal", "full"}


def test_diagonal_fit_recovers_a_diagonal_w():
    d = np.diag([1.2, 0.9, 1.05])
    w, o = fit_diagonal(readings(noise=0.0, m=np.linalg.inv(d)), 50.0)
    assert np.allclose(w, d, rtol=1e-9) and np.allclose(o, OFFSET, atol=1e-9)


def test_select_parsimony_margin():
    spreads = {"sphere": 0.010, "diagonal": 0.0095, "full": 0.008}
    assert select(spreads.get, "scalar", 0.1)[0] == "full"       # 0.008 < 0.9 * 0.010
    assert select(spreads.get, "scalar", 0.25)[0] == "sphere"    # neither cuts it by a quarter
    assert select({"full": 0.01}.get, "vector")[0] == "full"


def test_gate_radius_and_rms_in_physical_units():
    metrics = {"spread_before": 0.1, "heldout_spread": 0.01, "rms_after": 0.2}  # 0.2 uT = 2 mG
    assert gate(np.eye(3), metrics, raw_radius=50.0, reference=50.0, estimated=False, to_mg=10.0) == []
    bad = gate(np.eye(3), metrics, raw_radius=7.7, reference=48.0, estimated=False, to_mg=10.0)
    assert [f["check"] for f in bad] == ["scale", "radius", "radius"]
    loose = gate_thresholds({"radius_mG": [10, 1000], "radius_vs_reference": [0.1, 2], "scale_range": [0.1, 10]})
    assert gate(np.eye(3), metrics, raw_radius=7.7, reference=48.0, estimated=False, to_mg=10.0,
                thresholds=loose) == []
    counts = gate(np.eye(3), {**metrics, "rms_after": 5.0}, raw_radius=100.0, reference=100.0, estimated=True,
                  to_mg=None)
    assert [f["check"] for f in counts] == ["rms"] and GATE["max_rms_fraction"] < 0.05


@pytest.mark.parametrize("overrides, message", [({"nope": 1}, "gate's keys"), ({"max_anisotropy": -1}, "> 0"),
                                                ({"radius_mG": [5, 1]}, "low < high")])
def test_bad_gate_keys_are_one_line(overrides, message):
    with pytest.raises(MagexpError, match=message):
        gate_thresholds(overrides)


@pytest.mark.full  # 30 s: every model on every HMC5883L recording (make test-full)
@needs("hmc5883l_full-sphere")
def test_no_accepted_hmc5883l_calibration_makes_another_recording_worse_than_raw():
    """Issue 33's cross-table (magexp.perf.crosstable): each calibration accepted from an HMC5883L recording,
    applied to every other one that turns, is no worse than raw; at rest (unmoved-10min, the one
    single-attitude target) the spread is the raw scatter carried through W, to first order."""
    from magexp.perf.crosstable import recordings, rows, worse

    table = rows(recordings())
    accepted = {(r["source"], r["model"], r["estimator"]) for r in table if r["calibrated"] is not None}
    assert ("full-sphere", "auto", "ellipsoid") in accepted
    assert not any(r["source"].startswith("rotate-ccw") for r in table if r["calibrated"] is not None)
    assert {r["target"] for r in table if r["single_attitude"]} == {"unmoved-10min"}
    assert not [r for r in table if worse(r)]
    for r in table:
        if r["calibrated"] is not None and r["single_attitude"]:
            assert r["calibrated"] == pytest.approx(r["carried_noise"], rel=1e-3), r
