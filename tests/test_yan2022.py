"""Yan & Zhou 2022: ship attitude, recordings, the ship problem, kf / ls / the field_kalman analysis and the artifacts."""

from __future__ import annotations

import numpy as np
import pytest
from hydra.utils import instantiate

from magexp.run.compose import options
from magexp.errors import MagexpError
from magexp.estimators.kalman import kalman_update, settled_since
from magexp.problems import make_problem
from magexp.problems.vector import state_to_theta, theta_to_state
from magexp.core.recordings import load_recording
from magexp.run.runner import build
from magexp.core.geometry import ship_attitude
from magexp.artifacts.spec import Tolerance

PAPER_MOCKUP = [0.98575, 0.08153, 0.06221, -0.06233, 0.83517, -0.02987, -0.02999, -0.07748, 1.06615,
                2011.1, -2886.8, 2054.6]
YAN_ESTIMATORS = ["kf", "ls", "yan2022_paper_mockup", "yan2022_paper_sim"]


def problem_of(make_cfg, *overrides, seed=0):
    cfg = make_cfg(*overrides)
    scenario = instantiate(cfg.scenario, _convert_="all")
    dataset = scenario.generate(rng=np.random.default_rng(seed))
    return make_problem(scenario.objective, dataset, scenario.search), instantiate(cfg.estimator, _convert_="all")


# -- eq 2 ----------------------------------------------------------------------------------------
def test_attitude_is_eq2_as_printed():
    psi, theta, phi = 0.7, -0.2, 0.1  # heading, roll, trim
    c, s = np.cos, np.sin
    ry = np.array([[c(phi), 0, s(phi)], [0, 1, 0], [-s(phi), 0, c(phi)]])
    rx = np.array([[1, 0, 0], [0, c(theta), s(theta)], [0, -s(theta), c(theta)]])
    rz = np.array([[c(psi), s(psi), 0], [-s(psi), c(psi), 0], [0, 0, 1]])
    np.testing.assert_allclose(ship_attitude(psi, theta, phi), ry @ rx @ rz, atol=1e-15)
    stack = ship_attitude(np.array([psi, 0.0]), np.array([theta, 0.0]), np.array([phi, 0.0]))
    np.testing.assert_allclose(stack[1], np.eye(3), atol=1e-15)


# -- recordings ----------------------------------------------------------------------------------
def test_table1_loads():
    rec = load_recording("yan2022_mockup.csv")
    assert rec.readings.shape == (12, 3) and rec.angles.shape == (12, 3)
    np.testing.assert_array_equal(rec.field, [34425, 1961, 35898])
    np.testing.assert_array_equal(rec.readings[0], [4206, 25290, 36913])
    np.testing.assert_allclose(rec.angles[-1], [1.57080, 0.22216, -0.02211])


GOOD = "# magexp-recording v1\n# unit: nT\n# field: 1, 2, 3\nbx,by,bz,heading,roll,trim\n1,2,3,0.1,0.2,0.3\n"


@pytest.mark.parametrize("text, message", [
    (GOOD.replace("trim", "pitch"), "missing column trim"),
    (GOOD.replace("1,2,3,0.1", "1,2,abc,0.1"), "bz='abc' is not a number"),
    (GOOD.replace("1,2,3,0.1", "1,2,nan,0.1"), "bz='nan' is not allowed"),
    (GOOD.replace("0.2,0.3", "0.2"), "line 5: 5 values, but the header has 6 columns"),
    (GOOD.replace("# magexp-recording v1", "# other v2"), "line 1, column 3: found 'o', expected '# magexp-recording v1'"),
    (GOOD.replace("# field: 1, 2, 3", "# field: 1, 2"), "field='1, 2' is not allowed"),
    (GOOD.replace("# unit: nT", "# angles: grad"), "angles='grad' is not allowed"),
])
def test_malformed_recording_is_one_line(tmp_path, text, message):
    path = tmp_path / "rec.csv"
    path.write_text(text)
    with pytest.raises(MagexpError, match=message) as err:
        load_recording(path)
    assert "\n" not in str(err.value)


def test_missing_recording_is_one_line(tmp_path):
    with pytest.raises(MagexpError, match="does not exist") as err:
        load_recording(tmp_path / "absent.csv")
    assert "\n" not in str(err.value)


def test_degrees_are_converted(tmp_path):
    path = tmp_path / "rec.csv"
    path.write_text(GOOD.replace("# unit: nT", "# angles: deg").replace("0.1,0.2,0.3", "90,0,180"))
    np.testing.assert_allclose(load_recording(path).angles, [[np.pi / 2, 0, np.pi]])


# -- the problem -----------------------------------------------------------------------------------
def test_cost_is_vectorised_and_matches_direct(make_cfg):
    problem, _ = problem_of(make_cfg, "scenario=yan2022_sim")
    thetas = problem.truth_theta() + np.random.default_rng(1).normal(0, [1e-3] * 9 + [10] * 3, (5, 12))
    np.testing.assert_allclose(problem.cost(thetas), [problem.cost_direct(t) for t in thetas], rtol=1e-12)
    assert problem.residuals(thetas[0]).shape == (36,)
    c, y = problem.design()
    assert c.shape == (12, 4) and y.shape == (12, 3)
    np.testing.assert_allclose(state_to_theta(theta_to_state(thetas)), thetas)
    assert problem.parameter_names()[:3] == ["K11", "K12", "K13"] and problem.parameter_names()[-1] == "Bp3"


def test_calibrate_returns_the_ship_frame_field(make_cfg):
    problem, _ = problem_of(make_cfg, "scenario=yan2022_sim", "scenario.noise=0", "scenario.angle_noise_deg=0")
    np.testing.assert_allclose(problem.calibrate(problem.truth_theta()), problem.dataset.field_body_true, atol=1e-8)


# -- the filter kernel -----------------------------------------------------------------------------
def test_kalman_update_by_hand():
    # s = 1, c = 2: R = 1 + 0.5, m = 1.5*2 / (2*1.5*2 + 1) = 3/7, x = (1 - 6/7) x0 + 3/7 y
    x, p = kalman_update(np.array([[1.0, -1.0]]), np.array([[1.0]]), np.array([[2.0]]), np.array([[4.0, 2.0]]),
                         np.array([[0.5]]), 1.0)
    np.testing.assert_allclose(x, [[1 / 7 + 12 / 7, -1 / 7 + 6 / 7]])
    np.testing.assert_allclose(p, [[(1 - 6 / 7) * 1.5]])


def test_settled_since():
    assert settled_since(np.array([True, True, False, False])) == 2
    assert settled_since(np.array([False, True, False])) == 2
    assert settled_since(np.array([True, False, True])) == -1
    assert settled_since(np.array([False, False])) == 0


# -- estimators ------------------------------------------------------------------------------------
def test_noiseless_simulation_recovers_truth_to_round_off(make_cfg):
    exact = ("scenario=yan2022_sim", "scenario.noise=0", "scenario.angle_noise_deg=0")
    problem, ls = problem_of(make_cfg, *exact, "estimator=ls")
    truth = problem.truth_theta()
    x = ls.fit(problem, rng=None).x
    assert np.abs(x[:9] - truth[:9]).max() < 1e-12 and np.abs(x[9:] - truth[9:]).max() < 1e-9
    # an uninformative prior: the default P(0) is forgotten only as 1/passes (1e-6 after 50 passes)
    problem, kf = problem_of(make_cfg, *exact, "estimator=kf", "estimator.p0=1e9")
    x = kf.fit(problem, rng=None).x
    assert np.abs(x[:9] - truth[:9]).max() < 1e-12 and np.abs(x[9:] - truth[9:]).max() < 1e-8


def test_kf_converges_to_ls_on_the_mockup(make_cfg):
    problem, kf = problem_of(make_cfg, "scenario=yan2022_mockup", "estimator=kf")
    result = kf.fit(problem, rng=None)
    ls = problem.least_squares()
    assert np.abs(result.x[:9] - ls[:9]).max() < 1e-4 and np.abs(result.x[9:] - ls[9:]).max() < 1.0
    assert result.metrics["steps_to_ls"] == 96
    assert result.trace["x"].shape == (601, 12) and len(result.history) == 601
    np.testing.assert_array_equal(result.trace["x"][0], np.zeros(12))


def test_paper_solution_fits_table1_worse_than_ls(make_cfg):
    problem, paper = problem_of(make_cfg, "scenario=yan2022_mockup", "estimator=yan2022_paper_mockup")
    np.testing.assert_array_equal(paper.fit(problem, rng=None).x, PAPER_MOCKUP)
    assert problem.cost_direct(np.array(PAPER_MOCKUP)) == pytest.approx(453.77, abs=0.01)
    assert problem.cost_direct(problem.least_squares()) == pytest.approx(399.62, abs=0.01)


@pytest.mark.parametrize("name", YAN_ESTIMATORS)
def test_every_yan_estimator_fits_the_mockup(make_cfg, name):
    problem, est = problem_of(make_cfg, "scenario=yan2022_mockup", f"estimator={name}")
    assert est.name == name
    result = est.fit(problem, rng=np.random.default_rng(0))
    assert result.x.shape == (12,) and np.isfinite(result.fun) and len(result.history) >= 1


def test_field_kalman_analysis_recomputes_the_field(make_cfg):
    from magexp.run.runner import run

    out = run(make_cfg("scenario=yan2022_mockup", "estimator=kf", "+analysis=field_kalman"))
    assert out.trace["be"].shape == (601, 3)
    assert out.metrics["be_rms"] < out.metrics["be_direct_rms"] < 500
    # with exact data and parameters, both recover Be to round-off
    m = run(make_cfg("scenario=yan2022_sim", "scenario.noise=0", "scenario.angle_noise_deg=0", "estimator=kf",
                     "estimator.p0=1e9", "+analysis=field_kalman")).metrics
    assert m["be_direct_rms"] < 1e-6 and m["be_rms"] < 1e-3


def test_yan_configs_compose_and_bad_values_are_one_line(make_cfg):
    assert {"yan2022_sim", "yan2022_mockup"} <= set(options("scenario"))
    assert set(YAN_ESTIMATORS) <= set(options("estimator"))
    with pytest.raises(MagexpError, match="estimator.n_steps"):
        build(make_cfg("estimator=kf", "estimator.n_steps=0").estimator, "kf")
    with pytest.raises(MagexpError, match="scenario.noise"):
        build(make_cfg("scenario=yan2022_sim", "scenario.noise=-1").scenario, "yan2022_sim")
    from magexp.estimators.kalman import FieldKalmanFilter

    for bad in (0.0, -1.0):  # the analysis filter refuses a zero or negative noise variance as kf does
        with pytest.raises(MagexpError, match=r"analysis\.sigma2"):
            FieldKalmanFilter(sigma2=bad)
    with pytest.raises(MagexpError, match="does not exist"):
        build(make_cfg("scenario=yan2022_mockup", "scenario.path=nowhere.csv").scenario, "yan2022_mockup")


def test_same_seed_same_numbers(make_cfg):
    a, kf = problem_of(make_cfg, "scenario=yan2022_sim", "estimator=kf", seed=5)
    b, _ = problem_of(make_cfg, "scenario=yan2022_sim", "estimator=kf", seed=5)
    np.testing.assert_array_equal(kf.fit(a, rng=None).x, kf.fit(b, rng=None).x)


def test_abs_and_factor_tolerances():
    assert Tolerance(abs=1e-3).holds(1.0005, 1.0) and not Tolerance(abs=1e-3).holds(1.002, 1.0)
    assert Tolerance(factor=3).holds(2.9e-4, 1e-4) and not Tolerance(factor=3).holds(5e-3, 1e-4)
