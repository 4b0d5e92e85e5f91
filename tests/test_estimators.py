"""The estimator contract, estimators chosen by capability, and the linear estimators on every linear problem."""

import numpy as np
import pytest
from hydra.utils import instantiate
from omegaconf import OmegaConf

from magexp.artifacts.plan import shrink
from magexp.run.compose import options
from magexp.errors import MagexpError
from magexp.estimators.base import Estimator, applies_to
from magexp.estimators.result import FitResult
from magexp.problems import make_problem, problem_class
from magexp.problems.base import LinearProblem, Problem
from magexp.run.runner import run

SCENARIOS = options("scenario")
ESTIMATORS = options("estimator")


def build_problem(make_cfg, *overrides, seed=0):
    cfg = make_cfg(*overrides)
    sc = instantiate(cfg.scenario, _convert_="all")
    est = instantiate(cfg.estimator, _convert_="all")
    objective = cfg.get("objective") or sc.objective
    prob = make_problem(objective, sc.generate(rng=np.random.default_rng(seed)), sc.search,
                        **getattr(sc, "problem_options", {}))
    return prob, est


def first_applicable(make_cfg, est):
    for name in SCENARIOS:
        sc = instantiate(make_cfg(f"scenario={name}").scenario, _convert_="all")
        if applies_to(est, problem_class(sc.objective))[0]:
            return sc
    pytest.skip(f"{est.name} applies to no scenario")


@pytest.mark.parametrize("name", ESTIMATORS)
def test_estimator_contract(make_cfg, name):
    """Every estimator config (docs/extending.md, "The estimator contract"): builds, follows the protocol
    (name, needs, iterative, label, smoke, references), fits the first scenario it applies to at its smoke
    sizes (FitResult with finite x, fun = the objective at x, a non-increasing history ending at fun), and
    an iterative one stops when its callback asks."""
    cfg = make_cfg(f"estimator={name}")
    est = instantiate(cfg.estimator, _convert_="all")
    assert est.name == name and isinstance(est, Estimator)
    assert isinstance(est.label, str) and isinstance(est.references, str) and est.references
    assert all(isinstance(cap, int) and cap > 0 and isinstance(cfg.estimator[key], int) for key, cap in est.smoke.items())
    est = instantiate(shrink(cfg).estimator, _convert_="all")  # the sizes of a --tiny run
    assert all(OmegaConf.select(cfg, f"estimator.{key}") <= cap for key, cap in est.smoke.items())
    sc = first_applicable(make_cfg, est)
    prob = make_problem(sc.objective, sc.generate(rng=np.random.default_rng(0)), sc.search,
                        **getattr(sc, "problem_options", {}))
    assert isinstance(prob, Problem)
    res = est.fit(prob, rng=np.random.default_rng(1))
    assert isinstance(res, FitResult)
    assert res.x.shape == (prob.n_params,) and np.all(np.isfinite(res.x))
    assert res.fun == pytest.approx(prob.cost_direct(res.x), rel=1e-6, abs=1e-9)
    assert len(res.history) == len(res.history_nfev) >= 1
    if getattr(est, "monotone_history", True):
        assert np.all(np.diff(res.history) <= 1e-12 * np.abs(res.history[:-1]) + 1e-15)
        assert res.history[-1] == pytest.approx(res.fun, rel=1e-6, abs=1e-9)
    if est.iterative:
        seen = []

        def callback(t, x, fun):
            seen.append(t)
            assert x.shape == (prob.n_params,)
            return True

        stopped = est.fit(prob, rng=np.random.default_rng(1), callback=callback)
        assert seen == [1], "the callback is called after the first iteration and stops the run"
        assert stopped.nit == 1 and np.all(np.isfinite(stopped.x))


def test_applies_to_reads_capabilities_not_names(make_cfg):
    kf = instantiate(make_cfg("estimator=kf").estimator, _convert_="all")
    for objective, ok in (("scalar", False), ("vector", True), ("ship", True)):
        assert applies_to(kf, problem_class(objective))[0] is ok
    ok, reason = applies_to(kf, problem_class("scalar"))
    assert "needs a linear design" in reason and "\n" not in reason
    assert not applies_to(instantiate(make_cfg("estimator=ellipsoid").estimator), problem_class("vector"))[0]
    assert applies_to(instantiate(make_cfg("estimator=lm").estimator), problem_class("ship"))[0]
    assert not applies_to(instantiate(make_cfg("estimator=yan2022_paper_sim").estimator), problem_class("vector"))[0]


def test_vector_and_ship_problems_share_the_linear_model(make_cfg):
    vec, _ = build_problem(make_cfg, "scenario=yuan2018_mode1", "estimator=ls")
    ship, _ = build_problem(make_cfg, "scenario=yan2022_sim", "estimator=ls")
    assert isinstance(vec, LinearProblem) and isinstance(ship, LinearProblem)
    # Yuan's forward model B = S u + b: least squares on noise-free data is the truth
    clean, _ = build_problem(make_cfg, "scenario=yuan2018_mode1", "scenario.noise=0", "scenario.gyro.drift_deg_h=0",
                             "estimator=ls")
    np.testing.assert_allclose(clean.least_squares(), clean.truth_theta(), atol=1e-9)
    # the inverse parameterisation gets the same fit in its own parameters
    inv = make_problem("vector", vec.dataset, instantiate(make_cfg("scenario=yuan2018_mode1").scenario).search,
                       parameterisation="inverse")
    s = vec.least_squares()[:9].reshape(3, 3)
    np.testing.assert_allclose(inv.least_squares()[:9], np.linalg.inv(s).ravel(), rtol=1e-10)


@pytest.mark.parametrize("scenario, estimator", [
    ("yuan2018_mode1", "kf"), ("yuan2018_mode1", "ekf"), ("yan2022_sim", "ekf"), ("yan2022_sim", "kf")])
def test_filters_agree_with_least_squares_on_every_linear_problem(make_cfg, scenario, estimator):
    """With constant parameters (Q = 0) a filter over reused rows is recursive least squares: its
    offset ends within 1 % of the reading noise of the least-squares one (the prior is forgotten
    as 1/passes; the offset's Cramér-Rao bound is ~0.3x the noise here)."""
    kw = ["estimator.n_steps=3000"] if estimator == "kf" else []
    prob, est = build_problem(make_cfg, f"scenario={scenario}", f"estimator={estimator}", *kw)
    x = est.fit(prob, rng=None).x
    ls = prob.least_squares()
    assert np.max(np.abs(x[9:] - ls[9:])) < 0.01 * prob.dataset.noise_std
    assert np.max(np.abs(x[:9] - ls[:9])) < 1e-4
    # and the least-squares fit is at the truth within a few bounds (it is the efficient estimate)
    assert np.linalg.norm(ls[9:] - prob.truth_theta()[9:]) < 5 * max(prob.dataset.noise_std, 1e-9)


def test_task_run_refuses_an_estimator_that_does_not_apply(make_cfg):
    for est in ("kf", "ekf", "ls"):
        with pytest.raises(MagexpError, match="needs a linear design"):
            run(make_cfg("scenario=ding2024_exp1", f"estimator={est}"))
    with pytest.raises(MagexpError, match="total field"):
        run(make_cfg("scenario=yan2022_sim", "estimator=ellipsoid"))


@pytest.mark.slow
def test_cli_runs_kf_on_yuan_and_ekf_on_yan_and_refuses_kf_on_ding(tmp_path, cli):
    def run(*args):
        return cli(*args, f"hydra.run.dir={tmp_path}/run", cwd=tmp_path)

    assert run("scenario=yuan2018_mode1", "estimator=kf").returncode == 0
    assert run("scenario=yan2022_sim", "estimator=ekf").returncode == 0
    bad = run("scenario=ding2024_exp1", "estimator=kf")
    assert bad.returncode != 0 and len(bad.stderr.strip().splitlines()) == 1
    assert "needs a linear design" in bad.stderr
