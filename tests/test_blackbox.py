"""CMA-ES and differential evolution on the swarms' cost, box and budget: they reach the floor
on Ding's simulation 1, a seed gives the same run, ``callback`` stops a run, the budget holds."""

import numpy as np
import pytest

from magexp.errors import MagexpError
from magexp.estimators.cmaes import CMAES
from magexp.estimators.de import DifferentialEvolution
from magexp.estimators.lm import LevenbergMarquardt
from magexp.problems import make_problem
from magexp.run.compose import compose_config
from magexp.run.runner import build


@pytest.fixture(scope="module")
def ding1():
    """Ding 2024 simulation 1 (A = 2 nT, 300 readings) and the least-squares optimum of its RMS."""
    cfg = compose_config(["scenario=ding2024_exp1", "scenario.noise=2"])  # the scenario schemas registered
    sc = build(cfg.scenario, "scenario")
    problem = make_problem("scalar", sc.generate(rng=np.random.default_rng(0)), sc.search)
    return problem, LevenbergMarquardt().fit(problem).fun


ESTIMATORS = [CMAES(max_evaluations=8000), DifferentialEvolution(max_evaluations=20000, popsize=5)]
#: the whole runs: cma's in make test-full, de's (the cheaper) in make test
WHOLE_RUNS = [pytest.param(e, id=e.name, marks=[pytest.mark.full] if e.name == "cmaes" else []) for e in ESTIMATORS]


@pytest.mark.parametrize("estimator", WHOLE_RUNS)
def test_reaches_the_least_squares_optimum(ding1, estimator):
    problem, optimum = ding1
    result = estimator.fit(problem, rng=np.random.default_rng(1))
    assert result.nfev <= estimator.max_evaluations and result.nfev == result.history_nfev[-1]
    assert problem.cost_direct(result.x) <= 1.01 * optimum
    assert result.fun == pytest.approx(problem.cost_direct(result.x), rel=1e-9)
    assert np.all(np.diff(result.history) <= 0) and result.history[-1] == result.fun
    assert np.all(result.x >= problem.lower) and np.all(result.x <= problem.upper)


@pytest.mark.parametrize("estimator", WHOLE_RUNS)
def test_same_seed_same_run(ding1, estimator):
    problem, _ = ding1
    short = type(estimator)(max_evaluations=2000)
    a, b, c = (short.fit(problem, rng=np.random.default_rng(s)) for s in (7, 7, 8))
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.history, b.history)
    assert not np.array_equal(a.x, c.x)


@pytest.mark.parametrize("estimator", ESTIMATORS, ids=lambda e: e.name)
def test_callback_stops_the_run(ding1, estimator):
    problem, _ = ding1
    seen = []

    def stop_at_three(t, x, f):
        seen.append((t, f))
        np.testing.assert_array_equal(problem.cost(x[None]), [f])
        return t == 3

    result = estimator.fit(problem, rng=np.random.default_rng(0), callback=stop_at_three)
    assert [t for t, _ in seen] == [1, 2, 3] and result.nit == 3 and len(result.history) == 4
    assert result.message == "stopped by callback"


def test_bad_settings_fail_in_one_line(ding1):
    with pytest.raises(MagexpError, match="estimator.start='middle'"):
        CMAES(start="middle")
    with pytest.raises(MagexpError, match="estimator.sigma0"):
        CMAES(sigma0=0)
    with pytest.raises(MagexpError, match="estimator.max_evaluations=100 is not allowed"):
        DifferentialEvolution(max_evaluations=100).fit(ding1[0], rng=np.random.default_rng(0))
    with pytest.raises(MagexpError, match="could not run"):
        DifferentialEvolution(strategy="best9bin").fit(ding1[0], rng=np.random.default_rng(0))
