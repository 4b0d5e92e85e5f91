"""Every objective's fast swarm cost equals its direct formula, including at a noise-free optimum.

The scalar objective's check is ``test_ding_model.py::test_fast_cost_equals_direct_formula``.
Tolerance: ``rtol=1e-9`` plus ``atol=1e-9`` in the readings' unit (mG, nT), far above the
direct formula's own rounding at a perfect fit (~1e-11) and far below any noise level.
"""

import numpy as np
import pytest

from magexp.problems import make_problem
from magexp.run.runner import build

CASES = [  # (scenario, objective, problem options, noise values: paper's and noise-free)
    ("yuan2018_table2", "vector", {"parameterisation": "forward"}, ["0.45", "0"]),
    ("yuan2018_table2", "vector", {"parameterisation": "inverse"}, ["0.45", "0"]),
    ("yan2022_sim", "ship", {}, ["100", "0"]),
]


def swarm(make_cfg, scenario_name, objective, options, noise):
    """A problem with 60 readings and 40 particles: 30 uniform in the box, the truth, 9 near it."""
    overrides = [f"scenario={scenario_name}", f"scenario.noise={noise}", "scenario.n_readings=60"]
    if noise == "0":  # a perfect fit: no error on the attitudes either
        overrides += ["scenario.gyro.drift_deg_h=0"] if objective == "vector" else ["scenario.angle_noise_deg=0"]
    sc = build(make_cfg(*overrides).scenario, "scenario")
    problem = make_problem(objective, sc.generate(rng=np.random.default_rng(3)), sc.search, **options)
    rng = np.random.default_rng(4)
    truth = problem.truth_theta()
    thetas = np.vstack([problem.lower + rng.random((30, 12)) * (problem.upper - problem.lower), truth,
                        truth * (1 + 10.0 ** rng.integers(-9, -2, (9, 1)) * rng.standard_normal((9, 12)))])
    return problem, thetas


@pytest.mark.parametrize("scenario_name, objective, options, noises", CASES)
def test_fast_cost_equals_direct_formula(make_cfg, scenario_name, objective, options, noises):
    for noise in noises:
        problem, thetas = swarm(make_cfg, scenario_name, objective, options, noise)
        direct = np.array([problem.cost_direct(t) for t in thetas])
        np.testing.assert_allclose(problem.cost(thetas), direct, rtol=1e-9, atol=1e-9)
        assert problem.cost(thetas[:1]).shape == (1,)
    assert direct[30] < 1e-9 and problem.cost(thetas[30:31])[0] < 1e-9  # noise-free truth: zero to rounding


def test_ship_cost_at_the_least_squares_solution(make_cfg):
    """The floor ``rho`` of the QR form is the least-squares fit's own residual."""
    problem, _ = swarm(make_cfg, "yan2022_sim", "ship", {}, "100")
    ls = problem.least_squares()
    assert problem.cost(ls[None])[0] == pytest.approx(problem.cost_direct(ls), rel=1e-12)
    assert problem.cost(ls[None])[0] == pytest.approx(np.sqrt(problem._floor / problem._y.size), rel=1e-9)
