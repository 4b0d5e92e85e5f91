"""Artifacts: a paper's figure or table as data, run and drawn by generic code.

An artifact is ``experiments/<paper>/<stem>.yaml``::

    name: ding2024_fig5          # <firstauthor><year>_<fig|table><N>
    paper: ding2024
    title: ...
    kind: convergence            # convergence | field | table | ... (magexp.kinds)
    seeds: 10
    base: [scenario=ding2024_exp1, estimator.n_iterations=800]   # Hydra overrides for every run
    grid: {estimator: [pso, ipso], scenario.noise: [0, 2, 5, 10]}  # cartesian product
    plot: {panels: scenario.noise, hue: estimator}
    summarise: [{quantity: final_rms, metric: fun}]               # one summary row per cell
    ratios: [{quantity: improvement_ratio, metric: fun, numerator: {estimator: pso}, denominator: {estimator: ipso}}]
    reported:                                                     # the paper's numbers
      - {quantity: final_rms, match: {estimator: ipso, scenario.noise: 2}, value: 0.58}
    tolerance: {rel: 0.15}        # default; an entry may give its own ({rel: x}, {abs: x} or {below: x})
    # parameter tables: summarise [{mode: parameters}] gives one row per estimated parameter
    # (median over seeds beside the truth); a reported entry may be a whole column:
    #   - {quantities: [S11, S12], match: {estimator: rdpso}, values: [-1.6013, 0.4010], tolerance: {abs: 0.01}}
    notes: ...                    # why we differ, shown in the report

Every run is ``scenario x estimator x seed`` through :func:`magexp.runner.run`,
cached by :mod:`magexp.cache`, and the seeds of a cell share their data across
estimators (common random numbers).
"""

from __future__ import annotations

import copy
import functools
import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from omegaconf import DictConfig, OmegaConf

from magexp.errors import MagexpError
from magexp.executor import run_many  # its home is magexp.executor; importable from here too
from magexp.paths import CONF, EXPERIMENTS

SHRINK = {"estimator.n_iterations": 6, "estimator.n_particles": 6, "estimator.n_steps": 12, "estimator.max_nfev": 50}


def load_spec(path: Path | str) -> DictConfig:
    """Read an artifact YAML, with defaults filled in."""
    path = Path(path)
    if not path.exists():
        raise MagexpError(f"artifact {str(path)!r} does not exist")
    spec = OmegaConf.load(path)
    defaults = OmegaConf.create({"seeds": 10, "base": [], "grid": {}, "cases": [], "skip_inapplicable": False, "plot": {}, "summarise": [], "ratios": [],
                                 "reported": [], "tolerance": {"rel": 0.15}, "notes": "", "caption": ""})
    spec = OmegaConf.merge(defaults, spec)
    spec.name = spec.get("name") or path.stem
    return spec


def paper_specs(paper: str) -> list[DictConfig]:
    """Every artifact of ``paper``, in file-name order."""
    folder = EXPERIMENTS / paper
    if not folder.is_dir():
        known = sorted(p.name for p in EXPERIMENTS.iterdir() if p.is_dir())
        raise MagexpError(f"paper={paper!r} is not allowed: choose one of {', '.join(known)}")
    return [load_spec(p) for p in sorted(folder.glob(f"{paper}_*.yaml"))]


def cells(spec: DictConfig) -> list[dict[str, str]]:
    """The grid's cells, each an ordered ``{override key: value}``.

    ``cases`` (optional): a list of override lists (e.g. a scenario with its own settings),
    each crossed with the ``grid``; the case's overrides come first.
    """
    grid = OmegaConf.to_container(spec.grid)
    keys = list(grid)
    product = [dict(zip(keys, (str(v) for v in combo))) for combo in itertools.product(*(grid[k] for k in keys))]
    cases = OmegaConf.to_container(spec.cases) if spec.get("cases") else [[]]
    return [{**dict(str(o).split("=", 1) for o in case), **cell} for case in cases for cell in product]


def applicable(cfg: DictConfig) -> bool:
    """Whether the run's estimator applies to its objective (estimators may declare ``objectives``)."""
    import importlib

    module, _, cls = cfg.estimator._target_.rpartition(".")
    objectives = getattr(getattr(importlib.import_module(module), cls), "objectives", None)
    objective = cfg.get("objective") or cfg.scenario.get("objective")
    if objective is None:  # the scenario class fixes it
        module, _, cls = cfg.scenario._target_.rpartition(".")
        objective = getattr(getattr(importlib.import_module(module), cls), "objective", None)
    return objectives is None or objective is None or objective in objectives


def overrides_of(spec: DictConfig, cell: dict[str, str], cfg: DictConfig | None = None) -> list[str]:
    """The Hydra overrides of a cell. ``?key=value`` entries of ``base`` apply only where the
    composed config has ``key`` (e.g. a swarm size that a closed-form estimator lacks); with
    ``cfg=None`` they are left out (the plain overrides to compose with)."""
    out = []
    for o in [str(o) for o in spec.base] + [f"{k}={v}" for k, v in cell.items()]:
        if o.startswith("?"):
            if cfg is None or OmegaConf.select(cfg, o[1:].split("=", 1)[0]) is None:
                continue
            o = o[1:]
        out.append(o)
    return out


def apply_optional(spec: DictConfig, cfg: DictConfig) -> DictConfig:
    """Apply the ``?key=value`` overrides of ``spec.base`` that ``cfg`` has a key for."""
    for o in spec.base:
        o = str(o)
        if o.startswith("?"):
            key, value = o[1:].split("=", 1)
            if OmegaConf.select(cfg, key) is not None:
                OmegaConf.update(cfg, key, yaml_value(value))
    return cfg


@functools.lru_cache(maxsize=1)
def _override_parser():
    from hydra.core.override_parser.overrides_parser import OverridesParser

    return OverridesParser.create()


def yaml_value(text: str):
    """A command-line value typed as Hydra's override grammar types it (``2`` -> int,
    ``1e-06`` -> float, ``[1,2]`` -> list, ``null`` -> None, ``a`` -> str)."""
    return _override_parser().parse_overrides([f"k={text}"])[0].value()


def setting_of(overrides: list[str]) -> str:
    """``key=value`` pairs joined by ``;``, the scenario first, the estimator left out."""
    pairs = dict(o.split("=", 1) for o in overrides)
    first = [f"scenario={pairs.pop('scenario')}"] if "scenario" in pairs else []
    pairs.pop("estimator", None)
    return ";".join(first + [f"{k}={v}" for k, v in pairs.items()])


def _hydra_compose(overrides: tuple[str, ...]) -> DictConfig:
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra

    if GlobalHydra.instance().is_initialized():
        return compose("config", overrides=list(overrides))
    with initialize_config_dir(config_dir=str(CONF), version_base=None):
        return compose("config", overrides=list(overrides))


@functools.lru_cache(maxsize=256)
def _group_node(group: str, choice: str | None) -> DictConfig:
    """The config with one group choice (Hydra compose, once per choice)."""
    return _hydra_compose(() if choice is None else (f"{group}={choice}",))


GROUPS = ("scenario", "estimator")


def compose_config(overrides: list[str]) -> DictConfig:
    """The run config for ``overrides``, as Hydra would compose it.

    Each config-group choice (``scenario=...``, ``estimator=...``) is composed once and
    cached (a Hydra compose costs about 0.3 s); the nodes are grafted onto the primary config
    and the plain ``key=value`` overrides applied with OmegaConf (struct mode: an unknown key
    is an error, as with Hydra).
    """
    choices = {g: None for g in GROUPS}
    values = []
    for o in overrides:
        key, _, value = o.partition("=")
        if key in GROUPS:
            choices[key] = value
        elif key.startswith(("+", "~", "hydra")) or "/" in key:
            return _hydra_compose(tuple(overrides))  # anything else: Hydra itself
        else:
            values.append((key, value))
    cfg = copy.deepcopy(_group_node("scenario", None))
    OmegaConf.set_struct(cfg, False)
    for group, choice in choices.items():
        if choice is not None:
            cfg[group] = copy.deepcopy(_group_node(group, choice)[group])
    OmegaConf.set_struct(cfg, True)
    for key, value in values:
        if OmegaConf.select(cfg, key, default="__missing__") == "__missing__":
            raise MagexpError(f"bad override {key}={value}: the key {key!r} is not in the config")
        OmegaConf.update(cfg, key, yaml_value(value), merge=False)
    return cfg


def shrink(cfg: DictConfig) -> DictConfig:
    """Tiny sizes for smoke tests: cap every size key the config has."""
    for key, cap in SHRINK.items():
        value = OmegaConf.select(cfg, key)
        if isinstance(value, int):
            OmegaConf.update(cfg, key, min(value, cap))
    return cfg


@dataclass
class ArtifactRuns:
    """Every run of an artifact: ``table`` has one row per (cell, seed) with its metrics."""

    spec: DictConfig
    cells: list[dict[str, str]]
    table: pd.DataFrame
    outputs: Mapping  # (cell index, seed) -> RunOutput, read from the run cache on access
    overrides: list[list[str]]  # per cell, the overrides that apply to it


@dataclass
class ArtifactPlan:
    """The runs of an artifact before they run: ``configs[k]`` is run ``index[k] = (cell, seed)``."""

    spec: DictConfig
    cells: list[dict[str, str]]
    overrides: list[list[str]]
    configs: list[dict]
    index: list[tuple[int, int]]


def _per_seed(cfg: DictConfig, n_seeds: int) -> list[dict]:
    """The resolved config of each seed: resolved once per cell when no value interpolates another."""
    if "${" not in str(OmegaConf.to_container(cfg, resolve=False)):
        base = OmegaConf.to_container(cfg, resolve=True)
        return [{**base, "seed": seed} for seed in range(n_seeds)]
    out = []
    for seed in range(n_seeds):
        cfg.seed = seed
        out.append(OmegaConf.to_container(cfg, resolve=True))
    return out


def plan_artifact(spec: DictConfig, *, seeds: int | None = None, tiny: bool = False) -> ArtifactPlan:
    """Every run of ``spec``: each cell of its grid over its seeds (``seeds`` overrides the spec's)."""
    n_seeds = int(seeds if seeds is not None else spec.seeds)
    if n_seeds < 1:
        raise MagexpError(f"seeds={n_seeds} is not allowed: it must be an integer >= 1")
    plan = ArtifactPlan(spec=spec, cells=[], overrides=[], configs=[], index=[])
    for cell in cells(spec):
        cfg = apply_optional(spec, compose_config(overrides_of(spec, cell)))
        if spec.skip_inapplicable and not applicable(cfg):
            continue
        ci = len(plan.cells)
        plan.cells.append(cell)
        plan.overrides.append(overrides_of(spec, cell, cfg))
        if tiny:
            cfg = shrink(cfg)
        plan.configs.extend(_per_seed(cfg, n_seeds))
        plan.index.extend((ci, seed) for seed in range(n_seeds))
    return plan


class _ByRun(Mapping):
    """``(cell, seed) -> RunOutput`` over :class:`magexp.executor.Outputs` (read on access)."""

    def __init__(self, index: list[tuple[int, int]], outputs):
        self._at = {key: k for k, key in enumerate(index)}
        self._outputs = outputs

    def __getitem__(self, key):
        return self._outputs[self._at[key]]

    def __iter__(self):
        return iter(self._at)

    def __len__(self) -> int:
        return len(self._at)


def collect(plan: ArtifactPlan, outputs) -> ArtifactRuns:
    """The :class:`ArtifactRuns` of ``plan`` from its outputs (in ``plan.configs`` order)."""
    metrics = outputs.metrics if hasattr(outputs, "metrics") else (lambda k: outputs[k].metrics)
    rows = [{"cell": ci, **plan.cells[ci], "setting": setting_of(plan.overrides[ci]), **metrics(k)}
            for k, (ci, seed) in enumerate(plan.index)]
    return ArtifactRuns(spec=plan.spec, cells=plan.cells, table=pd.DataFrame(rows),
                        outputs=_ByRun(plan.index, outputs), overrides=plan.overrides)


def run_artifact(spec: DictConfig, *, seeds: int | None = None, jobs: int = 0, tiny: bool = False,
                 use_cache: bool = True, executor=None) -> ArtifactRuns:
    """Run every cell of ``spec`` over its seeds."""
    from magexp.progress import Progress

    plan = plan_artifact(spec, seeds=seeds, tiny=tiny)
    outputs = run_many(plan.configs, jobs=jobs, use_cache=use_cache, executor=executor,
                       progress=Progress(len(plan.configs), spec.name))
    return collect(plan, outputs)


def quantiles(values) -> tuple[float, float, float]:
    """Median, 25 % and 75 % quantiles (NaN for no values)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return (np.nan, np.nan, np.nan)
    q25, q50, q75 = np.quantile(v, [0.25, 0.5, 0.75])
    return float(q50), float(q25), float(q75)
