"""Yuan 2018 motion, gyro and scenario generation."""

import numpy as np
import pytest

from magexp.errors import MagexpError
from magexp.core.geometry import exp_so3, integrate_rates, rot_x, rotation_angle
from magexp.scenarios.motion import Gyro, Trajectory, even_subsample


def test_constant_rate_integration_is_exact_without_drift():
    dt, w, k = 0.01, np.deg2rad(36.0), 1000
    rates = np.tile([w, 0.0, 0.0], (k, 1))
    out = integrate_rates(Gyro(drift_deg_h=0.0).measure(rates, rng=np.random.default_rng(0)), dt)
    expected = rot_x(w * dt * np.arange(k + 1))
    assert np.max(np.abs(out - expected)) < 1e-12


def test_gyro_at_rest_error_is_drift_times_duration():
    dt, k, drift = 0.01, 3000, 25.0
    out = integrate_rates(Gyro(drift_deg_h=drift).measure(np.zeros((k, 3)), rng=np.random.default_rng(0)), dt)
    angle = np.rad2deg(rotation_angle(out[-1]))
    assert angle == pytest.approx(drift / 3600.0 * k * dt, rel=0.01)


def test_exp_so3_small_and_large_angles_are_rotations():
    r = exp_so3(np.array([[1e-9, 0, 0], [0.3, -1.2, 2.0]]))
    assert np.allclose(r @ np.swapaxes(r, 1, 2), np.eye(3), atol=1e-14)
    assert np.allclose(np.linalg.det(r), 1.0)


def test_modes_and_subsample():
    assert len(Trajectory(mode="mode1").rates()) == 3000
    assert len(Trajectory(mode="mode4").rates()) == 1000
    full = integrate_rates(Trajectory(mode="mode2").rates(), 0.01)
    assert np.allclose(full[-1], np.eye(3), atol=1e-9)  # two full turns return to the start
    half = integrate_rates(Trajectory(mode="mode3", partial_arc_deg=90).rates(), 0.01)
    assert np.rad2deg(rotation_angle(half[-1])) == pytest.approx(120.0)  # Rx(90) Ry(90): 120 deg
    idx = even_subsample(3000, 30)
    assert idx[0] == 0 and idx[-1] == 2999 and len(np.unique(idx)) == 30


@pytest.mark.parametrize("kwargs", [{"mode": "mode9"}, {"mode": None, "segments": [{"axis": "w", "arc_deg": 90}]},
                                    {"rate_deg_s": 0}, {"sample_period": -0.01}])
def test_bad_trajectory(kwargs):
    with pytest.raises(MagexpError):
        Trajectory(**kwargs)


@pytest.mark.parametrize("kwargs", [{"drift_deg_h": -1}, {"noise_deg_s": float("nan")}, {"drift_axis": [0, 0, 0]}])
def test_bad_gyro(kwargs):
    with pytest.raises(MagexpError):
        Gyro(**kwargs)


def test_too_many_readings():
    with pytest.raises(MagexpError):
        even_subsample(10, 11)
