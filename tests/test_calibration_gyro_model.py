"""``model=gyro`` of ``magexp calibrate`` and its place in ``model=auto`` (issue 21: the gyro-aided model
where a gyroscope exists, chosen by held-out spread with the parsimony rule)."""

import numpy as np
import pytest

import magexp
from magexp import Calibration
from magexp.calibration.models import candidates, select
from magexp.core.geometry import attitude_at
from magexp.core.recordings import Recording
from magexp.errors import MagexpError

#: the magnetometer: readings = S R_jᵀ h + o (S with a rotation of a few degrees), so the calibration is W = S⁻¹
S = np.array([[1.05, 0.06, -0.02], [-0.03, 0.95, 0.04], [0.02, -0.05, 1.02]])
O = np.array([0.05, -0.1, 0.02])
H = 0.5 * np.array([0.3, -0.4, -0.866]) / np.linalg.norm([0.3, -0.4, -0.866])
BIAS_DEG = np.array([2.5, -0.5, 1.2])


def tumbling(seconds=30.0, noise=1e-4, seed=0, gyro=True) -> Recording:
    """A tumbling IMU: the gyroscope at 100 Hz (rate + bias), the magnetometer at 77 Hz on its own clock."""
    rng = np.random.default_rng(seed)
    t_g = np.arange(0, seconds, 0.01)
    rates = 1.5 * np.sin(2 * np.pi * np.array([0.11, 0.07, 0.05]) * t_g[:, None] + np.array([0.0, 1.0, 2.0]))
    t_m = np.arange(0.003, seconds - 0.01, 1 / 77)
    readings = np.einsum("ij,nkj,k->ni", S, attitude_at(t_g, rates, t_m), H) + O + rng.normal(0, noise, (len(t_m), 3))
    stream = (t_g, rates + np.deg2rad(BIAS_DEG)) if gyro else None
    return Recording(readings=readings, angles=None, field=None, unit="G", reference_total=0.5,
                     times=t_m, gyro_stream=stream, meta={"name": "tumbling"})


def test_the_gyro_model_recovers_the_whole_w_its_rotation_included_and_the_gyro_bias(tmp_path):
    cal = magexp.calibrate(tumbling(), model="gyro")
    back = Calibration.load(cal.save(tmp_path / "gyro.json"))
    assert back.model == "gyro" and np.array_equal(back.apply(cal.recording.readings), cal.calibrated)
    assert cal.model == "gyro" and cal.report["gate"]["passed"]
    np.testing.assert_allclose(cal.w, np.linalg.inv(S), atol=2e-3)  # not the symmetric factor: the rotation too
    np.testing.assert_allclose(cal.offset, O, atol=2e-3)
    np.testing.assert_allclose(cal.report["gyro_bias_deg_s"], BIAS_DEG, atol=0.05)
    assert cal.report["vector_rms"] < 1e-3 and (cal.estimator, cal.objective) == ("lm", "gyro")
    assert set(cal.report["standard_errors"]) >= {"W12", "W21", "gyro_bias_x"}


def test_auto_tries_the_gyro_model_where_a_gyroscope_exists_and_records_its_heldout_spread():
    with_gyro = magexp.calibrate(tumbling(), model="auto")
    spreads = with_gyro.report["model_selection"]["heldout_spread"]
    assert list(spreads) == ["sphere", "diagonal", "full", "gyro"] and spreads["gyro"] < 1e-3
    without = magexp.calibrate(tumbling(gyro=False), model="auto")
    assert "gyro" not in without.report["model_selection"]["heldout_spread"]


def test_the_gyro_model_wins_only_by_the_margin():
    spreads = {"sphere": 0.05, "diagonal": 0.03, "full": 0.010, "gyro": 0.0085}
    assert candidates("scalar", gyro=True)[-1] == "gyro" and "gyro" not in candidates("scalar")
    assert select(spreads.get, "scalar", 0.1, gyro=True)[0] == "gyro"  # 0.0085 < 0.9 * 0.010
    assert select(spreads.get, "scalar", 0.2, gyro=True)[0] == "full"  # not by a fifth
    assert select(spreads.get, "scalar", 0.1)[0] == "full"             # no gyroscope: not a candidate


@pytest.mark.parametrize("objective", ["scalar", "vector"])
def test_the_gyro_model_without_a_gyroscope_is_one_line(objective):
    with pytest.raises(MagexpError, match="gyro") as err:
        magexp.calibrate(tumbling(gyro=False), model="gyro", objective=objective)
    assert "\n" not in str(err.value)


def test_the_stacked_jacobian_is_scipys_forward_difference_from_one_call():
    from scipy.optimize._numdiff import approx_derivative

    from magexp.calibration.inputs import gyro_dataset
    from magexp.calibration.inputs import Reference
    from magexp.estimators.lm import LevenbergMarquardt
    from magexp.core.marquardt import stacked_jacobian
    from magexp.problems import make_problem
    from magexp.scenarios.search import SearchBox

    rec = tumbling(seconds=10.0)
    problem = make_problem("gyro", gyro_dataset(rec, Reference(np.full(rec.n, 0.5), "test")),
                           SearchBox((0.5, 1.5), (-0.5, 0.5), (-1.0, 1.0)))
    theta = problem.initial_estimate()
    calls = []
    swarm = problem.residual_swarm
    problem.residual_swarm = lambda t: calls.append(len(t)) or swarm(t)
    jac = stacked_jacobian(problem)(theta)
    assert calls == [18] and jac.shape == (problem.residuals(theta).size, 17)
    np.testing.assert_allclose(jac, approx_derivative(problem.residuals, theta, method="2-point"), rtol=1e-6, atol=1e-6)
    with pytest.raises(MagexpError, match="estimator.jacobian='3-point' is not allowed"):
        LevenbergMarquardt(jacobian="3-point")


def test_a_model_whose_fit_reports_failure_on_a_fold_is_skipped_by_auto():
    """A fit that stops without converging (e.g. the gyro fit of a saturated gyroscope at its evaluation
    cap) does not support its model: ``auto`` records it as not fitted, whatever its held-out spread."""
    from magexp.estimators.ellipsoid import EllipsoidFit

    class Unconverged(EllipsoidFit):
        def fit(self, problem, **kwargs):
            result = super().fit(problem, **kwargs)
            result.success = problem.dataset.readings.shape[0] == rec.n  # fails on every fold, not on all
            return result

    rec = tumbling(gyro=False)
    cal = magexp.calibrate(rec, estimator=Unconverged(), model="auto", accept=True)
    spreads = cal.report["model_selection"]["heldout_spread"]
    assert spreads["full"] is None and spreads["sphere"] is not None and cal.model != "full"
    assert magexp.calibrate(rec, estimator=EllipsoidFit(), model="auto").report["model_selection"][
        "heldout_spread"]["full"] is not None
