"""What the bench runs on (:mod:`magexp.perf.bench`): its problems, swarms and estimators, composed by the project's one composer."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from magexp.core.seeding import run_generators
from magexp.problems import make_problem
from magexp.run.compose import compose_config
from magexp.run.runner import build


SIZES = [(300, 50), (30_000, 500)]  # (readings, particles)


BUDGET_PARTICLES, BUDGET_ITERATIONS = 50, 800  # every iterative peer: 50 x 801 cost evaluations


def compose(overrides: list[str]):
    """The run config of ``overrides`` (the project's one composer)."""
    return compose_config(overrides)


def ding_problem(n_readings: int, seed: int = 0, *overrides: str):
    """Ding 2024 simulation 1 with ``n_readings`` readings (data of ``seed``) and its scenario."""
    cfg = compose(["scenario=ding2024_exp1", f"scenario.n_readings={n_readings}", *overrides])
    scenario = build(cfg.scenario, "scenario")
    dataset = scenario.generate(rng=run_generators(seed)[0])
    return make_problem(scenario.objective, dataset, scenario.search), scenario


def vector_problem(n_readings: int):
    """A vector problem (Yuan 2018 eq 8) of any size: Ding's readings with their true body-frame field as the
    reference vectors (identity attitudes: only shapes matter; Yuan's trajectories are too short for 3e4 readings).
    """
    problem, scenario = ding_problem(n_readings)
    ds = problem.dataset
    ds = replace(ds, attitude=np.broadcast_to(np.eye(3), (ds.n, 3, 3)), field_nav=ds.field_body_true)
    return make_problem("vector", ds, scenario.search, parameterisation="inverse")


def swarm_in_box(problem, n_particles: int, seed: int = 0) -> np.ndarray:
    """``n_particles`` positions drawn uniformly in the problem's box."""
    rng = np.random.default_rng(seed)
    return problem.lower + rng.random((n_particles, problem.n_params)) * (problem.upper - problem.lower)


def swarm_estimator(name: str, n_particles: int = BUDGET_PARTICLES, n_iterations: int = BUDGET_ITERATIONS):
    """The configured swarm estimator ``name`` with the given population and iterations."""
    cfg = compose([f"estimator={name}", f"estimator.n_particles={n_particles}",
                   f"estimator.n_iterations={n_iterations}"])
    return build(cfg.estimator, "estimator")

