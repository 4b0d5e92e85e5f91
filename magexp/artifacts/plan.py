"""Artifacts: a paper's figure or table as data, run and drawn by generic code.

The artifact language (keys, types, defaults) is :mod:`magexp.artifacts.spec`. Every run is
``scenario x estimator x seed`` through :func:`magexp.run.runner.run`, cached by :mod:`magexp.run.cache`;
the seeds of a cell share their data across estimators (common random numbers), and each
scenario draws from its own stream (:mod:`magexp.core.seeding`).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from hydra.utils import get_class
from omegaconf import DictConfig, OmegaConf

from magexp.artifacts.claims import matches
from magexp.artifacts.spec import load
from magexp.artifacts.paper_spec import artifact_paths, check_headlines, load_paper
from magexp.core import outcomes
from magexp.errors import MagexpError
from magexp.estimators.base import applies_to
from magexp.problems import problem_class
from magexp.run.compose import apply_overrides, compose_config
from magexp.run.executor import run_row


def load_spec(path: Path | str):
    """Read and validate an artifact YAML (:func:`magexp.artifacts.spec.load`)."""
    return load(path)


def paper_specs(paper: str) -> list:
    """Every artifact of ``paper``, in file-name order; its headlines' parts checked against their claims
    (:func:`magexp.artifacts.paper_spec.check_headlines`)."""
    specs = [load_spec(p) for p in artifact_paths(paper)]
    check_headlines(paper, load_paper(paper).headline, specs)
    return specs


def cells(spec) -> list[dict[str, str]]:
    """The grid's cells, each an ordered ``{override key: value}``.

    ``cases`` (optional): a list of override lists (e.g. a scenario with its own settings),
    each crossed with the ``grid``; the case's overrides come first.
    """
    grid = dict(spec.grid)
    keys = list(grid)
    product = [dict(zip(keys, (str(v) for v in combo))) for combo in itertools.product(*(grid[k] for k in keys))]
    cases = list(spec.cases) or [[]]
    return [{**dict(str(o).split("=", 1) for o in case), **cell} for case in cases for cell in product]


#: ``success.reference`` of data without a truth (recordings): the lowest ``success.metric`` that any
#: run of the artifact reached on the same scenario and objective (the best optimum found by any method)
BEST = "best"
#: the columns :func:`collect` adds to the runs' own (``offset_at_face`` where a config has a numeric offset
#: interval), beside ``best_<metric>`` with ``success: {reference: best}`` and each cell's settings
TABLE_COLUMNS = ("cell", "setting", "succeeded", "offset_at_face")


def best_of(table: pd.DataFrame, metric: str) -> pd.Series:
    """Per run, the lowest ``metric`` over the runs of the same scenario and objective."""
    return table[metric].astype(float).groupby([table.scenario, table.objective]).transform("min")


def succeeded(table: pd.DataFrame, success) -> pd.Series:
    """The runs table's ``succeeded`` column: :func:`magexp.core.outcomes.succeeded` of the artifact's
    rule (:class:`magexp.artifacts.spec.Success`), 1/0, NaN where the reference (the true calibration's
    value) is unknown. ``reference: best`` (:data:`BEST`): the lowest value of ``metric`` over the
    artifact's runs of the same scenario and objective.
    """
    if success.metric not in table or (success.reference not in table and success.reference != BEST):
        return pd.Series(np.nan, index=table.index)
    ref = best_of(table, success.metric) if success.reference == BEST else table[success.reference].astype(float)
    return pd.Series(outcomes.succeeded(table[success.metric], ref, success.factor, success.floor), index=table.index)


#: the offset parameters' columns of a runs table: ``I`` of the inverse parameterisation (Ding's eq 9),
#: ``b`` of the forward one (:meth:`magexp.problems.base.CalibrationProblem.parameter_names`)
OFFSET_COLUMNS = (("I1", "I2", "I3"), ("b1", "b2", "b3"))

def offset_at_face(table: pd.DataFrame, configs: list[dict]) -> pd.Series | None:
    """Per run, how many of the three offset estimates sit on a face of the search box's offset
    interval ``scenario.search.offset = [low, high]`` of that run's config (``configs[k]`` is row ``k``), by
    :func:`magexp.core.outcomes.on_face` (the tolerance of the swarm's own ``on_boundary`` count).

    A swarm that clips positions to the box (``boundary: clip``) leaves a coordinate that crossed a face
    exactly on it, and a run whose best particle has an offset there cannot reach the optimum when the
    true offset lies inside the box: the count tells such a run from one that stopped at an interior
    point. Computed from the stored estimates and the config (downstream of the run: no run changes).
    NaN where the run's config has no numeric offset interval; None when no row has one or the table
    has no offset columns.
    """
    columns = next((c for c in OFFSET_COLUMNS if all(k in table for k in c)), None)
    if columns is None or len(configs) != len(table):
        return None
    box = np.full((len(table), 2), np.nan)
    for k, cfg in enumerate(configs):
        interval = ((cfg.get("scenario") or {}).get("search") or {}).get("offset")
        if isinstance(interval, (list, tuple)) and len(interval) == 2:
            try:
                box[k] = [float(interval[0]), float(interval[1])]
            except (TypeError, ValueError):
                pass
    known = np.isfinite(box).all(axis=1)
    if not known.any():
        return None
    x = table[list(columns)].to_numpy(float)
    on = outcomes.on_face(x, box[:, :1], box[:, 1:])  # NaN box: False, and the row is NaN below
    return pd.Series(np.where(known, on.sum(axis=1), np.nan), index=table.index, name="offset_at_face")


def objective_of(cfg: dict) -> str:
    """The objective of a run's config: its own, its scenario's, else the scenario class's (imported, not built).

    Parameters
    ----------
    cfg : dict or DictConfig
        A run config, composed or resolved.

    Returns
    -------
    str
        The objective's name (empty when none is given).
    """
    scenario = cfg.get("scenario") or {}
    found = cfg.get("objective") or scenario.get("objective")
    if found is None and scenario.get("_target_"):
        found = getattr(get_class(scenario["_target_"]), "objective", None)
    return str(found or "")


def applicable(cfg: DictConfig) -> bool:
    """Whether the run's estimator applies to its problem: :func:`magexp.estimators.base.applies_to`
    on the classes named by the config (nothing is built or simulated).
    """
    objective = objective_of(cfg)
    if not objective:
        return True
    return applies_to(get_class(cfg.estimator._target_), problem_class(objective))[0]


def overrides_of(spec, cell: dict[str, str], cfg: DictConfig | None = None) -> list[str]:
    """The Hydra overrides of a cell. ``?key=value`` entries of ``base`` apply only where the
    composed config has ``key`` (e.g. a swarm size that a closed-form estimator lacks); with
    ``cfg=None`` they are left out (the plain overrides to compose with).
    """
    out = []
    for o in [str(o) for o in spec.base] + [f"{k}={v}" for k, v in cell.items()]:
        if o.startswith("?"):
            if cfg is None or OmegaConf.select(cfg, o[1:].split("=", 1)[0]) is None:
                continue
            o = o[1:]
        out.append(o)
    return out


def apply_optional(spec, cfg: DictConfig) -> DictConfig:
    """Apply the ``?key=value`` overrides of ``spec.base`` that ``cfg`` has a key for (Hydra's override step)."""
    optional = [str(o)[1:] for o in spec.base if str(o).startswith("?")]
    return apply_overrides(cfg, [o for o in optional if OmegaConf.select(cfg, o.split("=", 1)[0]) is not None])


def setting_of(overrides: list[str]) -> str:
    """``key=value`` pairs joined by ``;``, the scenario first, the estimator left out."""
    pairs = dict(o.split("=", 1) for o in overrides)
    first = [f"scenario={pairs.pop('scenario')}"] if "scenario" in pairs else []
    pairs.pop("estimator", None)
    return ";".join(first + [f"{k}={v}" for k, v in pairs.items()])


def shrink(cfg: DictConfig) -> DictConfig:
    """Tiny sizes for smoke tests: cap each key of the estimator class's ``smoke`` sizes."""
    for key, cap in getattr(get_class(cfg.estimator._target_), "smoke", {}).items():
        value = OmegaConf.select(cfg, f"estimator.{key}")
        if isinstance(value, int):
            OmegaConf.update(cfg, f"estimator.{key}", min(value, cap))
    return cfg


@dataclass
class ArtifactRuns:
    """Every run of an artifact: ``table`` has one row per (cell, seed) with its metrics."""

    spec: object  # magexp.artifacts.spec.Artifact
    cells: list[dict[str, str]]
    table: pd.DataFrame
    outputs: Mapping  # (cell index, seed) -> RunOutput, read from the run cache on access
    overrides: list[list[str]]  # per cell, the overrides that apply to it


@dataclass
class ArtifactPlan:
    """The runs of an artifact before they run: ``configs[k]`` is run ``index[k] = (cell, seed)``."""

    spec: object  # magexp.artifacts.spec.Artifact
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


def plan_artifact(spec, *, seeds: int | None = None, tiny: bool = False, seeds_for=None) -> ArtifactPlan:
    """Every run of ``spec``: each cell of its grid over its seeds; ``seeds_for(plan)``, where given, names
    the cells that get more (``{cell: seeds}``: those of a comparison's ``effect:``,
    :func:`magexp.artifacts.sample_sizes.planned_seeds`). ``seeds`` (an exploration) gives every cell that
    many and plans nothing more; so does ``tiny``.
    """
    n_seeds = int(seeds if seeds is not None else spec.seeds)
    if n_seeds < 1:
        raise MagexpError(f"seeds={n_seeds} is not allowed: it must be an integer >= 1")
    plan = ArtifactPlan(spec=spec, cells=[], overrides=[], configs=[], index=[])
    composed = []
    for cell in cells(spec):
        cfg = apply_optional(spec, compose_config(overrides_of(spec, cell)))
        if spec.skip_inapplicable and not applicable(cfg):
            continue
        plan.cells.append(cell)
        plan.overrides.append(overrides_of(spec, cell, cfg))
        composed.append(cfg)
    planned = seeds_for(plan) if seeds_for is not None and seeds is None and not tiny else {}
    for ci, cfg in enumerate(composed):
        if tiny:
            cfg = shrink(cfg)
        n = max(n_seeds, planned.get(ci, 0))
        plan.configs.extend(_per_seed(cfg, n))
        plan.index.extend((ci, seed) for seed in range(n))
    return plan


def _settings(overrides: list[str]) -> dict:
    """A cell's settings as its runs table names them: its overrides, ``estimator`` its name
    (``estimator.name`` where a case renames it)."""
    pairs = dict(o.split("=", 1) for o in overrides)
    if "estimator.name" in pairs:
        pairs["estimator"] = pairs["estimator.name"]
    return pairs


def claim_cells(plan: ArtifactPlan, claim) -> list[int]:
    """The cells of ``plan`` that a comparison claim selects (its ``cells``), or a trend (its ``where``), matched
    on the cell's overrides; a key that is no setting, a row filter such as ``succeeded``, is left out.
    """
    settings = [_settings(o) for o in plan.overrides]
    keys = {k for s in settings for k in s}
    return sorted({ci for where in (claim.cells or [claim.where]) for ci, s in enumerate(settings)
                   if matches({k: v for k, v in where.items() if k in keys}, s)})


class _ByRun(Mapping):
    """``(cell, seed) -> RunOutput`` over :class:`magexp.run.executor.Outputs` (read on access)."""

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
    metrics = outputs.metrics if hasattr(outputs, "metrics") else (lambda k: run_row(outputs[k]))
    rows = [{"cell": ci, **plan.cells[ci], "setting": setting_of(plan.overrides[ci]), **metrics(k)}
            for k, (ci, seed) in enumerate(plan.index)]
    table = pd.DataFrame(rows)
    if len(table):
        at_face = offset_at_face(table, plan.configs)
        if at_face is not None:
            table["offset_at_face"] = at_face
        success = plan.spec.success
        if success is not None and success.reference == BEST and success.metric in table:
            table[f"best_{success.metric}"] = best_of(table, success.metric)  # for claims: metric / best_metric
        table["succeeded"] = succeeded(table, success)
    return ArtifactRuns(spec=plan.spec, cells=plan.cells, table=table,
                        outputs=_ByRun(plan.index, outputs), overrides=plan.overrides)

