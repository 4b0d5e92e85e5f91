"""The acceptance gate (a bad calibration is refused with every reason, or written only with accept=true and
its failures recorded) and model=auto (the model the held-out spread supports, with a parsimony margin)."""

import json

import numpy as np
import pytest

import magexp
from magexp.calibration.checks import GATE, gate, gate_thresholds
from magexp.calibration.fit import main
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
@pytest.mark.parametrize("model", [
    # auto fits every candidate on every fold first (the gyro model's too: about 5 s), make test-full; the
    # refusal for too few sphere cells in make test: test_calibration_quality.py's few_directions case
    pytest.param("auto", marks=pytest.mark.full), "full"])
def test_rotate_about_z_with_ellipsoid_is_refused(tmp_path, capsys, model):
    """Was: exit 0, W33 = 37.9, spread 8.98 % -> 16.77 % (24.6 % held out). The raw directions about the
    fitted centre fill a few cells of the sphere (a turn about one axis): refused."""
    line = _refused(tmp_path, capsys, f"data.path={SHARED_DATA / HMC.format('z')}", "estimator=ellipsoid",
                    f"model={model}")
    if model == "auto":  # the sphere, the simplest model: its centre shows the raw directions of one turn
        assert "sphere cells" in line and "record again" in line
    else:
        assert "calibration refused" in line and "held-out spread 24.6 % is not below the raw 8.98 %" in line


@needs(HMC.format("z"))
def test_rotate_about_z_gate_lists_every_failure_when_measured():
    cal = magexp.calibrate(SHARED_DATA / HMC.format("z"), model="full", checks=False)
    failed = {f["check"] for f in cal.report["gate"]["failed"]}
    assert {"heldout", "anisotropy", "scale"} <= failed
    raw = coverage(cal.recording.readings - cal.offset)  # the raw directions about the fitted centre
    assert cal.metrics["coverage_cells"] == raw["coverage_cells"] < coverage(cal.calibrated)["coverage_cells"]


@needs(HMC.format("x"))
def test_rotate_about_x_full_is_refused_for_its_anisotropy(tmp_path, capsys):
    """Was: W11 = 4.16, spread 1.0 % in sample and 7.75 % held out, exit 0."""
    line = _refused(tmp_path, capsys, f"data.path={SHARED_DATA / HMC.format('x')}", "model=full")
    assert "calibration refused" in line and "singular values" in line and "accept=true" in line


@needs(HMC.format("x"))
def test_rotate_about_x_auto_chooses_the_gyro_model_and_names_what_it_leaves_undetermined():
    """Of the total-field models the sphere wins (the full W overfits one plane); with the gyroscope's
    attitude the gyro-aided model beats it by far, and the report names the combination a turn about x
    leaves undetermined (Yuan's mode 4: the offset along x trades with the column of W along it)."""
    cal = magexp.calibrate(SHARED_DATA / HMC.format("x"), accept=True)
    sel = cal.report["model_selection"]
    spreads = sel["heldout_spread"]
    assert sel["chosen"] == "gyro" and cal.report["model"] == "gyro" and "gyro" in sel["why"]
    assert spreads["full"] > spreads["sphere"] and spreads["gyro"] < 0.5 * spreads["sphere"]
    assert cal.metrics["heldout_spread"] < cal.metrics["spread_before"]  # held out better than raw
    assert "o1" in cal.report["weakest_combinations"][0]["combination"]


@needs("xio_fusion_sensor_data.csv")
def test_xio_sphere_recipe_is_refused_heldout_worse_than_raw(tmp_path, capsys):
    """Was: model=sphere, 5.64 % held out against 4.80 % raw, "success"."""
    line = _refused(tmp_path, capsys, f"data.path={SHARED_DATA / 'xio_fusion_sensor_data.csv'}", "model=sphere")
    assert "held-out spread 5.64 % is not below the raw 4.8 %" in line


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
    assert [f["check"] for f in record["failed"]] == ["heldout"]


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
