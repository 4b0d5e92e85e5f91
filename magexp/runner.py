"""Run one configuration: scenario x estimator x seed -> metrics and history."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from hydra.utils import instantiate
from omegaconf import DictConfig

from magexp.errors import MagexpError
from magexp.metrics import evaluate
from magexp.estimators.base import check_applies
from magexp.problems import make_problem, problem_class
from magexp.seeding import run_generators, scenario_stream


@dataclass
class RunOutput:
    """What one run produced: flat metrics, the convergence history and the estimate."""

    metrics: dict
    history: np.ndarray
    history_nfev: np.ndarray
    x: np.ndarray
    parameter_names: list[str] = field(default_factory=list)
    trace: dict = field(default_factory=dict)
    readings: np.ndarray | None = None
    calibrated: np.ndarray | None = None
    reference_norm: np.ndarray | None = None
    truth_x: np.ndarray | None = None  # the true parameter vector (simulations)


def build(node, what: str):
    """Instantiate a ``_target_`` node with plain-Python arguments, one-line errors."""
    try:
        return instantiate(node, _convert_="all")
    except MagexpError:
        raise
    except Exception as exc:  # hydra wraps constructor errors
        cause = exc
        while cause.__cause__ is not None:
            cause = cause.__cause__
        if isinstance(cause, MagexpError):
            raise cause from None
        raise MagexpError(f"{what} could not be built: {str(cause).splitlines()[0]}") from None


def run(cfg: DictConfig) -> RunOutput:
    """Simulate (or load) the scenario, fit the estimator, evaluate the result."""
    scenario = build(cfg.scenario, f"scenario {cfg.scenario.get('name')!r}")
    estimator = build(cfg.estimator, f"estimator {cfg.estimator.get('name')!r}")
    objective = cfg.get("objective") or scenario.objective
    check_applies(estimator, problem_class(objective), f"scenario {scenario.name!r}")  # before any data
    data_rng, est_rng = run_generators(cfg.seed, stream=scenario_stream(cfg.scenario))
    dataset = scenario.generate(rng=data_rng)
    problem = make_problem(objective, dataset, scenario.search, **getattr(scenario, "problem_options", {}))
    start = time.perf_counter()
    result = estimator.fit(problem, rng=est_rng)
    wall = time.perf_counter() - start
    if cfg.get("analysis"):  # an analysis step on the fitted result (conf/analysis/*.yaml)
        result = build(cfg.analysis, f"analysis {cfg.analysis.get('name')!r}")(problem, result)
    metrics = {"scenario": scenario.name, "estimator": estimator.name, "objective": objective,
               "seed": int(cfg.seed), **evaluate(problem, result), "wall_time": wall}
    return RunOutput(metrics=metrics, history=np.asarray(result.history), history_nfev=np.asarray(result.history_nfev),
                     x=np.asarray(result.x), parameter_names=problem.parameter_names(), trace=result.trace,
                     readings=dataset.readings, calibrated=problem.calibrate(result.x),
                     reference_norm=np.asarray(dataset.reference_norm), truth_x=problem.truth_theta())
