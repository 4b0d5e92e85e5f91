"""Every config composes and instantiates; every artifact is well formed (the estimator contract: test_estimators.py)."""

import numpy as np
import pytest
from hydra.utils import instantiate
from omegaconf import OmegaConf

from magexp.artifacts.plan import cells, load_spec, overrides_of
from magexp.run.compose import options
from magexp.paths import EXPERIMENTS
from magexp.artifacts.kinds import kind
from magexp.artifacts.claims import matches
from magexp.artifacts.summary import reported_entries

SCENARIOS = options("scenario")
ARTIFACTS = sorted(EXPERIMENTS.glob("*/*_*.yaml"))


@pytest.mark.parametrize("name", SCENARIOS)
def test_scenario_composes_generates_and_names_itself(make_cfg, name):
    cfg = make_cfg(f"scenario={name}")
    sc = instantiate(cfg.scenario, _convert_="all")
    assert sc.name == name
    ds = sc.generate(rng=np.random.default_rng(0))
    assert ds.readings.ndim == 2 and ds.readings.shape[1] == 3 and np.all(np.isfinite(ds.readings))
    assert ds.reference_norm.shape == (ds.n,)


def test_run_seed_reproducibility(make_cfg):
    from magexp.run.runner import run

    a = run(make_cfg("estimator=ipso", "seed=4", "estimator.n_iterations=50"))
    b = run(make_cfg("estimator=ipso", "seed=4", "estimator.n_iterations=50"))
    c = run(make_cfg("estimator=ipso", "seed=5", "estimator.n_iterations=50"))
    np.testing.assert_array_equal(a.history, b.history)
    np.testing.assert_array_equal(a.x, b.x)
    assert not np.array_equal(a.readings, c.readings)
    # common random numbers: the data of a seed does not depend on the estimator
    d = run(make_cfg("estimator=lm", "seed=4"))
    np.testing.assert_array_equal(a.readings, d.readings)


@pytest.mark.parametrize("path", ARTIFACTS, ids=lambda p: p.stem)
def test_artifact_spec_is_well_formed(path):
    """Its name, paper, kind and cells; every paper number lands on a cell (that every cell composes
    and runs: tests/test_artifacts.py, whose smoke runs plan every cell of every artifact)."""
    spec = load_spec(path)
    assert spec.name == path.stem and spec.paper == path.parent.name
    kind(spec.kind)
    grid = cells(spec)
    assert grid, "an artifact needs at least one cell"
    settings = [dict(o.split("=", 1) for o in overrides_of(spec, cell)) for cell in grid]
    per_parameter = any(s.mode == "parameters" for s in spec.summarise)
    quantities = {s.quantity for s in spec.summarise if s.quantity} | {r.quantity for r in spec.ratios}
    for entry in reported_entries(spec):  # every paper number lands on a cell
        assert per_parameter or entry["quantity"] in quantities, entry
        assert any(matches(entry.get("match", {}), s) for s in settings), entry


# --- the one composer (magexp.run.compose) -------------------------------------------------------

@pytest.mark.parametrize("overrides", [[], ["scenario=yuan2018_mode3", "estimator=rdpso"], ["estimator=kf"],
                                       ["scenario=yan2022_mockup", "estimator=ls", "seed=4"],
                                       ["scenario=ding2024_exp2", "scenario.noise=5", "estimator.n_particles=7"]])
def test_compose_config_equals_hydras_compose(overrides):
    from magexp.run.compose import compose_config, hydra_compose

    expected = OmegaConf.to_container(hydra_compose(tuple(overrides)), resolve=True)
    for _ in range(2):  # composed by Hydra, then its group choices composed already in this process
        cfg = compose_config(overrides)
        assert OmegaConf.to_container(cfg, resolve=True) == expected
        cfg.seed = 99  # the caller's own copy
    assert compose_config(overrides).seed != 99


def test_a_typo_names_the_key_and_the_keys_that_exist():
    from magexp.run.compose import compose_config
    from magexp.errors import MagexpError

    with pytest.raises(MagexpError) as info:
        compose_config(["scenario=yuan2018_mode1", "scenario.gyro.drift_deg=3"])
    msg = str(info.value)
    assert "\n" not in msg and "'drift_deg'" in msg and "scenario.gyro has no key" in msg
    assert "drift_deg_h" in msg and "noise_deg_s" in msg


def test_schema_types_are_checked_at_compose_time():
    """The schema refuses a value of the wrong type before any constructor runs."""
    from magexp.run.compose import compose_config
    from magexp.errors import MagexpError

    with pytest.raises(MagexpError, match="scenario.n_readings=many"):
        compose_config(["scenario.n_readings=many"])
    with pytest.raises(MagexpError, match="scenario.rotation.rate_deg_s=fast"):
        compose_config(["scenario=yuan2018_mode2", "scenario.rotation.rate_deg_s=fast"])


def test_yuan_scenarios_inherit_one_base():
    from magexp.paths import CONF
    from magexp.run.compose import compose_config
    from magexp.scenarios.yuan import YuanScenarioConf

    names = [n for n in SCENARIOS if n.startswith("yuan2018_")]
    assert {"yuan2018_mode3_xz", "yuan2018_mode3_yz"} <= set(names)  # yuan2018_ext_turns: "any two axes"
    base = OmegaConf.load(CONF / "scenario" / "base" / "yuan2018.yaml")
    for name in names:
        own = OmegaConf.load(CONF / "scenario" / f"{name}.yaml")
        assert "base/yuan2018@_here_" in [str(d).split("#")[0].strip() for d in own.defaults]
        assert "search" not in own  # the box lives in the base
        cfg = compose_config([f"scenario={name}"])
        assert OmegaConf.get_type(cfg.scenario) is YuanScenarioConf
        assert cfg.scenario.search == base.search and cfg.scenario.name == name
    assert compose_config(["scenario=yuan2018_mode3"]).scenario.rotation.mode == "mode3"
    for name, axes in (("yuan2018_mode3_xz", ["x", "z"]), ("yuan2018_mode3_yz", ["y", "z"])):
        turns = compose_config([f"scenario={name}", "scenario.rotation.partial_arc_deg=90"]).scenario.rotation.segments
        assert [t.axis for t in turns] == axes and [float(t.arc_deg) for t in turns] == [90.0, 90.0]
    assert compose_config(["scenario=yuan2018_adis16488"]).scenario.gyro.noise_deg_s == 0.16


def test_calibration_keys_are_unknown_to_a_simulation_run():
    from magexp.run.compose import compose_config
    from magexp.errors import MagexpError

    for override in ("task=calibrate", "data.path=x.csv", "out=folder"):
        with pytest.raises(MagexpError, match="magexp calibrate"):
            compose_config([override])


def test_an_artifact_is_composed_once_per_cell_as_hydra_composes_each_run():
    """Every run an artifact plans is ``hydra.compose`` of its cell's overrides (the ``?key=value`` ones
    where the cell's config has the key) with its seed: one compose per cell, the seed set per run."""
    from magexp.artifacts.plan import paper_specs, plan_artifact
    from magexp.run.compose import hydra_compose, resolved

    spec = next(s for s in paper_specs("yuan2018") if s.name == "yuan2018_table4")  # 4 cells, 2 sets of choices
    plan = plan_artifact(spec, seeds=2)
    assert len(plan.configs) == 2 * len(plan.cells) == 8
    assert all("estimator.n_particles=80" in o for o in plan.overrides)  # its ?key=value, both swarms have it
    for (ci, seed), cfg in zip(plan.index, plan.configs):
        assert cfg == resolved(hydra_compose((*plan.overrides[ci], f"seed={seed}")))
