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

import itertools
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from omegaconf import DictConfig, OmegaConf

from magexp import cache
from magexp.errors import MagexpError
from magexp.config import compose_config, yaml_value  # noqa: F401  (compose_config: re-exported)
from magexp.paths import EXPERIMENTS

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
    """Whether the run's estimator applies to its problem: :func:`magexp.estimators.base.applies_to`
    on the classes named by the config (nothing is built or simulated)."""
    from hydra.utils import get_class

    from magexp.estimators.base import applies_to
    from magexp.problems import problem_class

    objective = cfg.get("objective") or cfg.scenario.get("objective")
    if objective is None:  # the scenario class fixes it
        objective = getattr(get_class(cfg.scenario._target_), "objective", None)
    if objective is None:
        return True
    return applies_to(get_class(cfg.estimator._target_), problem_class(objective))[0]


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


def setting_of(overrides: list[str]) -> str:
    """``key=value`` pairs joined by ``;``, the scenario first, the estimator left out."""
    pairs = dict(o.split("=", 1) for o in overrides)
    first = [f"scenario={pairs.pop('scenario')}"] if "scenario" in pairs else []
    pairs.pop("estimator", None)
    return ";".join(first + [f"{k}={v}" for k, v in pairs.items()])


def shrink(cfg: DictConfig) -> DictConfig:
    """Tiny sizes for smoke tests: cap every size key the config has."""
    for key, cap in SHRINK.items():
        value = OmegaConf.select(cfg, key)
        if isinstance(value, int):
            OmegaConf.update(cfg, key, min(value, cap))
    return cfg


def _execute(resolved: dict):
    from magexp.runner import run

    return run(OmegaConf.create(resolved))


def run_many(configs: list[dict], *, jobs: int = 0, use_cache: bool = True, progress=None) -> list:
    """Run resolved configs (cached), in parallel over ``jobs`` processes (0: all cores)."""
    keys = [cache.run_key(c) for c in configs]
    outputs = [cache.load(k) if use_cache else None for k in keys]
    todo = [i for i, o in enumerate(outputs) if o is None]
    if progress:
        progress(len(configs) - len(todo))
    n_jobs = jobs if jobs > 0 else (os.cpu_count() or 1)
    if todo:
        if n_jobs == 1 or len(todo) == 1:
            for i in todo:
                outputs[i] = _execute(configs[i])
                cache.store(keys[i], outputs[i])
                if progress:
                    progress(1)
        else:
            from joblib import Parallel, delayed

            par = Parallel(n_jobs=n_jobs, return_as="generator", batch_size=1)
            for i, out in zip(todo, par(delayed(_execute)(configs[i]) for i in todo)):
                outputs[i] = out
                cache.store(keys[i], out)
                if progress:
                    progress(1)
    return outputs


@dataclass
class ArtifactRuns:
    """Every run of an artifact: ``table`` has one row per (cell, seed) with its metrics."""

    spec: DictConfig
    cells: list[dict[str, str]]
    table: pd.DataFrame
    outputs: dict  # (cell index, seed) -> RunOutput
    overrides: list[list[str]]  # per cell, the overrides that apply to it


def run_artifact(spec: DictConfig, *, seeds: int | None = None, jobs: int = 0, tiny: bool = False,
                 use_cache: bool = True) -> ArtifactRuns:
    """Run every cell of ``spec`` over its seeds."""
    n_seeds = int(seeds if seeds is not None else spec.seeds)
    if n_seeds < 1:
        raise MagexpError(f"seeds={n_seeds} is not allowed: it must be an integer >= 1")
    configs, index, settings, grid = [], [], [], []
    for cell in cells(spec):
        cfg = apply_optional(spec, compose_config(overrides_of(spec, cell)))
        if spec.skip_inapplicable and not applicable(cfg):
            continue
        ci = len(grid)
        grid.append(cell)
        settings.append(overrides_of(spec, cell, cfg))
        if tiny:
            cfg = shrink(cfg)
        for seed in range(n_seeds):
            cfg.seed = seed
            configs.append(OmegaConf.to_container(cfg, resolve=True))
            index.append((ci, seed))
    from magexp.progress import Progress

    outputs = run_many(configs, jobs=jobs, use_cache=use_cache, progress=Progress(len(configs), spec.name))
    rows = []
    for (ci, seed), out in zip(index, outputs):
        rows.append({"cell": ci, **grid[ci], "setting": setting_of(settings[ci]), **out.metrics})
    return ArtifactRuns(spec=spec, cells=grid, table=pd.DataFrame(rows), outputs=dict(zip(index, outputs)),
                        overrides=settings)


def quantiles(values) -> tuple[float, float, float]:
    """Median, 25 % and 75 % quantiles (NaN for no values)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return (np.nan, np.nan, np.nan)
    q25, q50, q75 = np.quantile(v, [0.25, 0.5, 0.75])
    return float(q50), float(q25), float(q75)
