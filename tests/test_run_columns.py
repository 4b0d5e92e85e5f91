"""The columns a run writes are declared beside their writers (:mod:`magexp.artifacts.run_columns`): every
estimator config on every objective at smoke sizes writes only declared columns, and each declared column is
written by some run; the spec check knows a metric a new estimator declares before any run."""

import pytest
from hydra.utils import get_class
from omegaconf import OmegaConf

from magexp import paths

from magexp.artifacts.plan import objective_of, shrink
from magexp.artifacts.run_columns import run_columns
from magexp.core.recordings import exists
from magexp.errors import MagexpError
from magexp.estimators.base import applies_to
from magexp.problems import problem_class
from magexp.run.compose import compose_config, options
from magexp.run.executor import run_row
from magexp.run.runner import run_batch

#: one small scenario per objective (and per kind of dataset: simulated, recorded, a ship's, a gyro-aided one)
SCENARIOS = {
    "scalar": ["scenario=ding2024_exp1", "scenario.n_readings=40"],
    "vector": ["scenario=yuan2018_mode1", "scenario.n_readings=20"],
    "vector_ls": ["scenario=yuan2018_mode1", "scenario.n_readings=20", "+objective=vector_ls"],
    "ship": ["scenario=yan2022_sim"],
    "ship_analysis": ["scenario=yan2022_mockup", "+analysis=field_kalman", "analysis.n_steps=12"],
    "recording": ["scenario=real_qmc5883l", "scenario.n_readings=60"],
    "gyro": ["scenario=real_hmc5883l_full_sphere", "scenario.n_readings=40"],
}


def _absent(cfg: dict) -> bool:
    """Whether the recording ``cfg``'s scenario reads is absent (the recordings of others are never shipped)."""
    file = cfg["scenario"].get("file")
    return file is not None and not exists(paths.SHARED_DATA / file)


def _configs() -> list[dict]:
    """Every estimator config on each scenario of :data:`SCENARIOS` it applies to, at its smoke sizes (a scenario
    whose recording is absent left out, as a reproduction skips it); each config composed once."""
    estimators = [OmegaConf.to_container(shrink(compose_config([f"estimator={name}"])).estimator, resolve=True)
                  for name in options("estimator")]
    out = []
    for scenario in SCENARIOS.values():
        base = OmegaConf.to_container(compose_config([*scenario, "seed=0"]), resolve=True)
        if _absent(base):
            continue
        problem = problem_class(objective_of(base))
        out += [{**base, "estimator": est} for est in estimators if applies_to(get_class(est["_target_"]), problem)[0]]
    return out


@pytest.fixture(scope="module")
def smoke_runs() -> list[tuple[dict, set]]:
    """``[(config, written columns)]`` of every smoke run (a run its estimator refuses at smoke sizes, in one
    line, left out: ``de``'s two populations exceed its smoke budget on the 17 parameters of ``gyro``)."""
    runs = []
    for cfg in _configs():
        try:
            runs.append((cfg, set(run_row(next(run_batch([cfg]))))))
        except MagexpError:
            continue
    return runs


def test_a_swarm_run_on_a_simulation_writes_only_declared_columns():
    """The fast case of the two below: one swarm run (its own ``on_boundary``, the core's, the problem's and
    its estimates) writes only declared columns, and its declared ``on_boundary`` among them."""
    cfg = OmegaConf.to_container(shrink(compose_config([*SCENARIOS["scalar"], "estimator=pso", "seed=0"])), resolve=True)
    written = set(run_row(next(run_batch([cfg]))))
    assert "on_boundary" in written and not written - run_columns(cfg), sorted(written - run_columns(cfg))


@pytest.mark.full  # every estimator on seven scenarios: 6 s
def test_a_run_writes_only_declared_columns(smoke_runs):
    """Each smoke run's row (its metrics and estimates) holds only columns its config declares."""
    assert len({cfg["estimator"]["name"] for cfg, _ in smoke_runs}) == len(options("estimator"))
    for cfg, written in smoke_runs:
        undeclared = written - run_columns(cfg)
        assert not undeclared, (cfg["scenario"]["name"], cfg["estimator"]["name"], sorted(undeclared))


@pytest.mark.full
def test_every_declared_column_is_written_by_some_run(smoke_runs):
    """No declaration names a column no run writes (each conditional one is written where its condition holds:
    a truth, a bound, a held-out block, a rest recording, a gauge-fixed fit, an analysis step)."""
    if any(_absent(OmegaConf.to_container(compose_config(s), resolve=True)) for s in SCENARIOS.values()):
        pytest.skip(f"a recording is not in {paths.SHARED_DATA}: its columns cannot be written")
    declared = set().union(*(run_columns(cfg) for cfg, _ in smoke_runs))
    written = set().union(*(w for _, w in smoke_runs))
    assert declared - written == set()
