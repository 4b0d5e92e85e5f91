"""A couple of dozen static shots (the hand-held and bench workflow, circuitpython-mag-cal's) are judged by the
held-out design that fits them (issue 40, item 2: :mod:`magexp.calibration.holdout`): each shot calibrated by
the fit without its neighbours in direction; accepted where an ellipsoid fits them, refused with the real cause
where it does not, and ``folds=0`` never claims a held-out result.

Fast tests use a synthetic sensor; the ``full`` ones make 24-shot recordings from the shared ones (24 readings
spread by direction, each averaged over a short window), written to ``tmp_path``.
"""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest

from magexp.calibration import holdout
from magexp.calibration.api import calibrate
from magexp.calibration.checks import MIN_READINGS
from magexp.core.ellipsoid import fit_sphere
from magexp.core.identifiability import fibonacci_sphere
from magexp.core.recordings import load_recording
from magexp.errors import MagexpError
from magexp.paths import SHARED_DATA

#: a soft-iron matrix (inverse of W) and hard-iron offset of the synthetic sensor, mG; field 500 mG
SOFT = np.array([[1.2, 0.05, 0.02], [0.05, 0.9, -0.04], [0.02, -0.04, 1.05]])
HARD, FIELD = np.array([80.0, -120, 40]), 500.0


def sensor(directions: np.ndarray, *, seed: int = 4, noise: float = 0.5, soft=SOFT, hard=HARD) -> np.ndarray:
    """Static shots ``soft · B + hard + noise`` of the field pointing along ``directions`` (turned at random)."""
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    b = FIELD * directions @ q.T
    return b @ soft.T + hard + rng.normal(scale=noise, size=b.shape)


def write_csv(path, readings):
    """A plain ``x,y,z`` CSV of ``readings`` (the shots a user saved)."""
    np.savetxt(path, readings, delimiter=",", header="x,y,z", comments="")
    return path


def static_shots(readings: np.ndarray, n: int = 24, window: int = 9, keep=None) -> np.ndarray:
    """``n`` static shots of a recording: readings spread by direction about the fitted sphere's centre
    (farthest-point sampling among those ``keep`` allows), each averaged with its neighbours in time over
    ``window`` readings (a hand-held shot is held still for a moment)."""
    u = readings - fit_sphere(readings)[0]
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    pool = np.flatnonzero(np.ones(len(u), bool) if keep is None else keep(u))
    chosen, gap = [pool[0]], 1.0 - u[pool] @ u[pool[0]]
    for _ in range(n - 1):
        chosen.append(pool[int(np.argmax(gap))])
        gap = np.minimum(gap, 1.0 - u[pool] @ u[chosen[-1]])
    half = window // 2
    return np.array([readings[max(i - half, 0):i + half + 1].mean(axis=0) for i in chosen])


def assert_refused_for_spread(line: str) -> None:
    """A refusal of shots in half of the sphere names that: too clumped for a held-out check, or directions
    untested (the regions check), each with its remedy, and never blames the calibration's fit."""
    clumped = "24 readings: too clumped in direction for a held-out check" in line
    assert (clumped and "spread the shots evenly over every direction" in line) or (
        "check 'regions' failed" in line and "record turns (or static shots) that point the sensor so" in line)
    assert "does not hold on readings" not in line and "region of directions held out" not in line


# -- the design -----------------------------------------------------------------------------------
def test_exclusion_radius_is_a_sixth_of_the_sphere():
    # a cap of half-angle θ covers (1 - cos θ) / 2 of the sphere: a sixth, as much as one direction region
    assert (1 - math.cos(math.radians(holdout.EXCLUSION_DEG))) / 2 == pytest.approx(1 / 6)
    u = fibonacci_sphere(6000)
    near = u @ u[0] >= math.cos(math.radians(holdout.EXCLUSION_DEG))
    assert near.mean() == pytest.approx(1 / 6, abs=0.01)


def test_exclusion_folds_keep_exactly_the_readings_outside_the_cap():
    u = fibonacci_sphere(24)
    folds = holdout.exclusion_folds(u)
    assert len(folds) == 24 and sorted(int(h[0]) for h, _ in folds) == list(range(24))
    cos_x = math.cos(math.radians(holdout.EXCLUSION_DEG))
    for held, kept in folds:
        angles = u @ u[held[0]]
        np.testing.assert_array_equal(kept, np.flatnonzero(angles < cos_x))  # every far reading kept, no near one


def test_more_readings_are_grouped_into_bounded_folds():
    u = fibonacci_sphere(300)
    folds = holdout.exclusion_folds(u)
    assert len(folds) == holdout.MAX_EXCLUSION_FOLDS  # an iterative estimator runs at most this many fits
    held = np.concatenate([h for h, _ in folds])
    np.testing.assert_array_equal(np.sort(held), np.arange(300))  # each reading held out exactly once
    cos_x = math.cos(math.radians(holdout.EXCLUSION_DEG))
    for h, kept in folds:
        assert np.all(u[kept] @ u[h].T < cos_x)


def test_design_follows_the_size_of_the_regions():
    assert holdout.design_of(np.repeat(np.arange(6), MIN_READINGS)) == "regions"
    assert holdout.design_of(np.repeat([0, 1, 2, 4], MIN_READINGS)) == "regions"  # empty regions: the gate's
    assert holdout.design_of(np.repeat(np.arange(6), 4)) == "exclusion"


# -- a synthetic 24-shot sensor -----------------------------------------------------------------------
def test_good_24_shots_are_accepted_by_leave_one_out():
    cal = calibrate(sensor(fibonacci_sphere(24)), unit="mG")
    m = cal.metrics
    assert m["heldout_design"] == "exclusion" and m["heldout_folds"] == 24 and m["heldout_readings"] == 24
    assert m["heldout_spread"] < 0.05 * m["spread_before"] and cal.report["gate"]["passed"]
    w_true = np.linalg.inv(SOFT)  # W up to the rotation a total-field fit cannot see, and the estimated scale
    w = cal.w / np.linalg.norm(cal.w, 2)
    np.testing.assert_allclose(w.T @ w, (w_true.T @ w_true) / np.linalg.norm(w_true, 2) ** 2, atol=0.01)
    np.testing.assert_allclose(cal.offset, HARD, atol=3.0)
    assert "each of 24 readings tested by a fit without the readings within 48.2 deg" in cal.summary()
    assert "leave one out, neighbours excluded" in cal.summary()


def test_a_turned_recording_keeps_the_region_design():
    cal = calibrate(sensor(fibonacci_sphere(600)), unit="mG")
    assert cal.metrics["heldout_design"] == "regions" and cal.metrics["heldout_folds"] == 6
    assert "every region of directions tested" in cal.summary()


@pytest.mark.parametrize("n", [12, 13])
def test_too_few_shots_name_the_count_and_how_many_to_record(n):
    with pytest.raises(MagexpError) as err:
        calibrate(sensor(fibonacci_sphere(n)), unit="mG")
    line = str(err.value)
    assert f"{n} readings: too few for a held-out check" in line
    assert f"record at least {holdout.MIN_SHOTS} static shots" in line
    assert "region of directions held out" not in line and "does not hold" not in line


def test_the_advised_number_of_evenly_spread_shots_is_accepted():
    cal = calibrate(sensor(fibonacci_sphere(holdout.MIN_SHOTS)), unit="mG")
    assert cal.report["gate"]["passed"] and cal.metrics["heldout_min_kept"] >= MIN_READINGS


@pytest.mark.parametrize("model", ["auto", "full"])
def test_shots_in_one_hemisphere_are_refused_for_their_spread(model):
    with pytest.raises(MagexpError) as err:
        calibrate(static_shots(sensor(fibonacci_sphere(2000)), window=1, keep=lambda u: u[:, 2] > 0.2), unit="mG",
                  model=model)
    assert_refused_for_spread(str(err.value))


def test_shots_in_one_plane_are_refused_as_a_plane():
    flat = static_shots(sensor(fibonacci_sphere(2000)), window=1, keep=lambda u: np.abs(u[:, 2]) < 0.1)
    with pytest.raises(MagexpError, match="lie in one plane.*turn the sensor about a second axis"):
        calibrate(flat, unit="mG")


def test_a_calibration_worse_than_raw_on_unseen_directions_is_refused_as_such():
    # an already calibrated sensor: the raw spread is its noise, a full fit only adds extrapolation error
    with pytest.raises(MagexpError) as err:
        calibrate(sensor(fibonacci_sphere(24), soft=np.eye(3), hard=np.zeros(3)), unit="mG", model="full")
    line = str(err.value)
    assert "of 24 readings, each calibrated by the fit without the readings within 48.2 deg of it" in line
    assert "record more static shots" in line and "need no calibration" in line


def test_folds_0_says_not_measured_never_beats(tmp_path, cli):
    path = write_csv(tmp_path / "shots.csv", sensor(fibonacci_sphere(24)))
    done = cli("calibrate", f"data.path={path}", "data.unit=mG", "folds=0", f"out={tmp_path / 'out'}")
    assert done.returncode == 0, done.stderr
    gate_line = next(line for line in done.stdout.splitlines() if line.startswith("gate"))
    assert "not measured" in gate_line and "beats" not in done.stdout
    saved = json.loads((tmp_path / "out" / "calibration.json").read_text())
    assert saved["quality"]["gate"]["heldout"].startswith("not measured (folds=0")
    assert saved["metrics"]["heldout_design"] == "none" and "heldout_spread" not in saved["metrics"]
    assert "held out not measured" in repr(calibrate(sensor(fibonacci_sphere(24)), unit="mG", folds=0))


def test_24_shots_through_the_command_say_the_design(tmp_path, cli):
    path = write_csv(tmp_path / "shots.csv", sensor(fibonacci_sphere(24)))
    done = cli("calibrate", f"data.path={path}", "data.unit=mG", f"out={tmp_path / 'out'}")
    assert done.returncode == 0, done.stderr
    held = next(line for line in done.stdout.splitlines() if line.startswith("held-out spread"))
    assert "24 readings, each calibrated by the fit on the readings more than 48.2 deg from its direction" in held
    saved = json.loads((tmp_path / "out" / "calibration.json").read_text())
    assert saved["metrics"]["heldout_design"] == "exclusion"
    assert saved["metrics"]["heldout_exclusion_deg"] == pytest.approx(holdout.EXCLUSION_DEG)
    assert "leave one out, neighbours excluded" in saved["quality"]["gate"]["heldout"]


# -- 24-shot recordings made from the shared ones ----------------------------------------------------------
#: the shared recordings, their unit, the window each shot averages (readings) and the axis of the half-sphere
SHARED = {"hmc5883l_full-sphere_mag.csv": ("G", 9), "fxos8700_mag_readings.txt": ("uT", 1)}


def shared(name: str):
    """The shared recording ``name`` and its unit, or a skip."""
    path = SHARED_DATA / name
    if not path.is_file():
        pytest.skip(f"{path} is not present (the shared recordings are read in place)")
    unit, window = SHARED[name]
    return load_recording(path, unit=unit), unit, window


def measured(path, unit, **options):
    """``(calibration or the refusal's line, CPU-s)`` of the 24 shots at ``path``, and a line for the report."""
    start = time.process_time()
    try:
        out = calibrate(path, unit=unit, **options)
    except MagexpError as exc:
        out = str(exc)
    cpu = time.process_time() - start
    if isinstance(out, str):
        print(f"{path.name} {options}: refused ({cpu:.3f} CPU-s): {out}")
    else:
        m = out.metrics
        print(f"{path.name} {options}: accepted, model {out.model}, spread {100 * m['spread_before']:.3g} % -> "
              f"{100 * m['spread_after']:.3g} %, held out {100 * m['heldout_spread']:.3g} % "
              f"({m['heldout_design']}, {m['heldout_folds']} folds), {cpu:.3f} CPU-s")
    return out, cpu


@pytest.mark.full
def test_24_shots_of_the_hmc5883l_full_sphere_are_accepted(tmp_path):
    rec, unit, window = shared("hmc5883l_full-sphere_mag.csv")
    path = write_csv(tmp_path / "hmc5883l_24_shots.csv", static_shots(rec.readings, window=window))
    cal, cpu = measured(path, unit)
    whole = calibrate(rec, unit=unit)  # the turned recording, by regions: the 24 shots reach its calibration
    assert not isinstance(cal, str) and cal.report["gate"]["passed"] and cal.metrics["heldout_design"] == "exclusion"
    assert cal.metrics["heldout_spread"] < 0.1 * cal.metrics["spread_before"]
    assert cal.metrics["heldout_spread"] < 1.5 * whole.metrics["heldout_spread"]
    assert cpu < 1.0


@pytest.mark.full
def test_24_shots_of_the_fxos8700_are_accepted_with_the_full_model(tmp_path):
    rec, unit, window = shared("fxos8700_mag_readings.txt")
    path = write_csv(tmp_path / "fxos8700_24_shots.csv", static_shots(rec.readings, window=window))
    cal, _ = measured(path, unit, model="full")
    assert not isinstance(cal, str) and cal.report["gate"]["passed"] and cal.metrics["heldout_design"] == "exclusion"
    assert cal.metrics["heldout_spread"] < 0.25 * cal.metrics["spread_before"]
    auto, _ = measured(path, unit)  # reported: auto's choice on these shots (the report of issue 40, item 2)
    if isinstance(auto, str):  # where auto's simpler model is refused, only for its residual, never the design
        assert "check 'rms' failed" in auto and "held-out" not in auto


@pytest.mark.full
@pytest.mark.parametrize("name", sorted(SHARED))
def test_24_shots_in_one_half_of_the_sphere_are_refused_for_their_spread(tmp_path, name):
    rec, unit, window = shared(name)
    shots = static_shots(rec.readings, window=window, keep=lambda u: u[:, 2] > 0.2)
    path = write_csv(tmp_path / f"{name}_24_half.csv", shots)
    for model in ("auto", "full"):
        line, _ = measured(path, unit, model=model)
        assert isinstance(line, str)
        assert_refused_for_spread(line)


@pytest.mark.full
@pytest.mark.parametrize("name", sorted(SHARED))
def test_24_shots_about_one_axis_are_refused_as_a_plane(tmp_path, name):
    rec, unit, window = shared(name)
    shots = static_shots(rec.readings, window=window, keep=lambda u: np.abs(u[:, 2]) < 0.1)
    line, _ = measured(write_csv(tmp_path / f"{name}_24_plane.csv", shots), unit)
    assert isinstance(line, str) and "lie in one plane" in line and "second axis" in line


def test_a_calibration_saved_before_the_designs_still_says_regions():
    cal = calibrate(sensor(fibonacci_sphere(600)), unit="mG")
    del cal.metrics["heldout_design"]  # as calibration.json was written before issue 40
    assert "every region of directions tested" in cal.summary()
    assert "6 regions of directions, each calibrated by the fit on the others" in cal.summary()


def test_a_long_recording_with_a_sparse_region_keeps_the_region_design():
    labels = np.repeat(np.arange(6), [holdout.MAX_EXCLUSION_READINGS] + [MIN_READINGS] * 4 + [3])
    assert holdout.design_of(labels) == "regions"  # the 3 readings stay in every fit; the gate's min_region refuses
    assert [int(labels[h[0]]) for h, _ in holdout.region_folds(labels)] == [0, 1, 2, 3, 4]
