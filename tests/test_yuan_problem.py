"""The vector objective (Yuan 2018 eq 8), the RDPSO kernel, the EKF and every new config."""

import numpy as np
import pytest

from magexp.errors import MagexpError
from magexp.estimators.ekf import ExtendedKalmanFilter
from magexp.estimators.rdpso import RandomDriftVelocity, ThermalCoefficient, drift_factors, random_drift
from magexp.estimators.velocity import ALL
from magexp.problems import make_problem
from magexp.run.runner import build, run
from magexp.core.seeding import run_generators

YUAN_SCENARIOS = ["yuan2018_table2", "yuan2018_mode1", "yuan2018_mode2", "yuan2018_mode3", "yuan2018_mode4",
                  "yuan2018_changing_field", "yuan2018_drift", "yuan2018_adis16488"]


def problem_of(make_cfg, *overrides, objective="vector"):
    cfg = make_cfg(*overrides)
    scenario = build(cfg.scenario, "scenario")
    dataset = scenario.generate(rng=run_generators(0)[0])
    return make_problem(objective, dataset, scenario.search, **scenario.problem_options)


def test_vector_objective_zero_at_truth_and_vectorised(make_cfg):
    p = problem_of(make_cfg, "scenario=yuan2018_table2", "scenario.noise=0", "scenario.gyro.drift_deg_h=0")
    truth = p.truth_theta()
    assert p.cost_direct(truth) < 1e-9 and p.cost(truth[None])[0] < 1e-9
    thetas = truth + np.random.default_rng(1).normal(0, 0.05, (7, 12))
    assert np.allclose(p.cost(thetas), [p.cost_direct(t) for t in thetas], rtol=1e-10)
    assert np.allclose(p.residuals(truth), 0.0, atol=1e-9)


def test_changing_field_reference(make_cfg):
    p = problem_of(make_cfg, "scenario=yuan2018_changing_field", "scenario.noise=0", "scenario.gyro.drift_deg_h=0")
    norms = p.dataset.reference_norm
    assert norms[-1] / norms[0] == pytest.approx(1.5) and p.cost_direct(p.truth_theta()) < 1e-9


def test_random_drift_velocity_by_hand():
    x = np.array([[0.0, 1.0], [2.0, -1.0], [1.0, 3.0]])
    pbest = np.array([[1.0, 1.0], [2.0, 0.0], [0.0, 2.0]])  # M = [1, 1]; the global best: particle 0, [1, 1]
    u = np.array([[np.exp(-1.0), 1.0], [np.exp(-2.0), np.exp(-0.5)], [1.0, np.exp(-1.0)]])
    s = np.array([[0.9, 0.1], [0.2, 0.6], [0.7, 0.3]])
    r = drift_factors(np.stack([np.full((3, 2), 0.5), np.full((3, 2), 0.25), s, 1.0 - u])[None])[0]
    assert np.allclose(r[3], [[1.0, 0.0], [2.0, 0.5], [0.0, 1.0]])  # ln(1/u); φ = ±ln(1/u), + where s > 0.5 (eq 14)
    v = random_drift(ALL, ALL, x, None, pbest, 0, pbest.mean(axis=0), r, (0.5, 2.0, 4.0))
    # particle 0: 0.5*|1-0|*1 + 1*(1-0) + 1*(1-0) = 2.5 ; 0.5*|1-1|*0 + 0 + 0 = 0
    # particle 1: 0.5*|1-2|*(-2) + 1*(2-2) + 1*(1-2) = -2 ; 0.5*|1+1|*0.5 + 1*(0+1) + 1*(1+1) = 3.5
    # particle 2: 0.5*|1-1|*0 + 1*(0-1) + 1*(1-1) = -1 ; 0.5*|1-3|*(-1) + 1*(2-3) + 1*(1-3) = -4
    assert np.allclose(v, [[2.5, 0.0], [-2.0, 3.5], [-1.0, -4.0]])


def test_thermal_coefficient_as_printed():
    a = ThermalCoefficient()
    assert a(0, 1000) == pytest.approx(0.9) and a(1000, 1000) == pytest.approx(0.42)
    np.testing.assert_allclose(RandomDriftVelocity().schedule(np.array([0, 1000]), 1000), [[0.9, 1.45, 1.45],
                                                                                             [0.42, 1.45, 1.45]])


def test_ekf_converges_without_noise(make_cfg):
    p = problem_of(make_cfg, "scenario=yuan2018_mode1", "scenario.noise=0", "scenario.gyro.drift_deg_h=0")
    res = ExtendedKalmanFilter(n_steps=300).fit(p, rng=np.random.default_rng(0))
    assert np.max(np.abs(res.x - p.truth_theta())) < 1e-3
    assert len(res.history) == 301 and res.history[-1] < 1e-1 * res.history[0]


def test_lm_problem_start_recovers_truth(make_cfg):
    p = problem_of(make_cfg, "scenario=yuan2018_mode3", "scenario.noise=0", "scenario.gyro.drift_deg_h=0")
    assert np.allclose(p.initial_estimate(), p.truth_theta(), atol=1e-8)


#: the first scenario's tiny run in make test, the others' in make test-full (each one composed and generated in
#: make test: tests/test_configs.py)
@pytest.mark.parametrize("scenario", [YUAN_SCENARIOS[0], *(pytest.param(name, marks=pytest.mark.full)
                                                          for name in YUAN_SCENARIOS[1:])])
def test_every_yuan_scenario_runs_tiny(make_cfg, scenario):
    cfg = make_cfg(f"scenario={scenario}", "estimator=rdpso", "estimator.n_particles=6", "estimator.n_iterations=4")
    out = run(cfg)
    assert out.metrics["scenario"] == scenario and np.isfinite(out.metrics["fg"]) and len(out.x) == 12


@pytest.mark.parametrize("estimator", ["rdpso", "pso", "ekf", "lm", "ellipsoid", "ipso"])
@pytest.mark.parametrize("objective", ["scalar", "vector"])
def test_every_estimator_with_either_objective(make_cfg, estimator, objective):
    """Each estimator runs with each objective it applies to, and is refused in one line otherwise
    (``ekf`` needs the vector problem's linear design, ``ellipsoid`` the scalar one's total field)."""
    over = ["estimator.n_particles=6", "estimator.n_iterations=4"] if estimator in ("rdpso", "pso", "ipso") else []
    cfg = make_cfg("scenario=yuan2018_mode1", f"estimator={estimator}", f"objective={objective}", *over)
    if (estimator, objective) in (("ekf", "scalar"), ("ellipsoid", "vector")):
        with pytest.raises(MagexpError, match="needs") as err:
            run(cfg)
        assert "\n" not in str(err.value)
        return
    out = run(cfg)
    assert np.isfinite(out.metrics["fun"]) and out.metrics["objective"] == objective


@pytest.mark.parametrize("override", ["scenario.rotation.mode=mode7", "scenario.gyro.drift_deg_h=-1",
                                      "scenario.noise=-0.1", "scenario.n_readings=100000",
                                      "scenario.field_scale=[1.0,-1.0]", "estimator.form=sideways"])
def test_bad_inputs_are_one_line_errors(make_cfg, override):
    est = "estimator=ekf" if override.startswith("estimator") else "estimator=rdpso"
    cfg = make_cfg("scenario=yuan2018_mode1", est, override)
    with pytest.raises(MagexpError):
        if override.startswith("estimator"):
            build(cfg.estimator, "estimator")
        else:
            build(cfg.scenario, "scenario").generate(rng=np.random.default_rng(0))
