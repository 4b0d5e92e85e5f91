"""Plans read, not composed: an artifact's plan is composed once per content of what it is composed from.

Planning an artifact (:func:`magexp.artifacts.sample_sizes.plan_with_effects`) composes each distinct set
of its group choices through Hydra once per process, applies each cell's overrides and resolves every
run's config: the CPU a warm ``make reproduce`` (every run cached) spends before it reads a single run.
The plan is deterministic: the same configs, artifacts, code and libraries give the same runs. So a plan
is keyed by

* the content of every file of ``conf/`` and ``experiments/`` (the configs composed, the artifact, its
  siblings whose families size its seeds),
* magexp's source (every ``magexp/**/*.py``: a schema, a scenario's ``Config`` or the composer),
* the versions of Python, Hydra and OmegaConf,
* the artifact (``repr`` of the validated :class:`magexp.artifacts.spec.Artifact`, its file) and the
  ``seeds`` and ``tiny`` asked for,

and the cache keeps under that key the plan's cells, overrides and resolved configs as a run cache entry
(:func:`magexp.run.cache.pack`: JSON and a digest, never code). A changed file gives another key: a plan is
never stale, only composed again. The cache lives beside the run cache (``<run cache>-plans``), never in
``results/``; where it cannot be written the plan is composed each time.
"""

from __future__ import annotations

import hashlib
import json
import sys
from functools import lru_cache
from pathlib import Path

import hydra
import omegaconf

from magexp import paths
from magexp.artifacts.memo import beside_cache, source_digest
from magexp.artifacts.plan import ArtifactPlan
from magexp.artifacts.sample_sizes import plan_with_effects
from magexp.run.cache import write
from magexp.run.entries import InvalidEntry, pack, read
from magexp.run.runkeys import files_digest

#: the kind of a plan's entry (:func:`magexp.run.cache.pack`)
KIND = "ArtifactPlan"


def root() -> Path:
    """The plan cache: beside the run cache, never inside it (:func:`magexp.artifacts.memo.beside_cache`)."""
    return beside_cache("plans")


@lru_cache(maxsize=1)
def inputs_digest() -> str:
    """The digest of everything a plan is composed from but the artifact itself (module docstring)."""
    h = hashlib.sha256(source_digest().encode())
    for folder in (paths.CONF, paths.EXPERIMENTS):
        h.update(files_digest(sorted(p for p in folder.rglob("*") if p.is_file()), folder).digest())
    h.update(f"{sys.version} {hydra.__version__} {omegaconf.__version__}".encode())
    return h.hexdigest()


def key(spec, seeds: int | None, tiny: bool) -> str:
    """The key of ``spec``'s plan for ``seeds`` and ``tiny`` (module docstring)."""
    h = hashlib.sha256(inputs_digest().encode())
    h.update(json.dumps([repr(spec), str(getattr(spec, "path", None)), seeds, tiny]).encode())
    return h.hexdigest()[:32]


def entry(k: str) -> Path:
    """Where the plan of key ``k`` is kept."""
    return root() / k[:2] / f"{k}.plan"


def packed(plan: ArtifactPlan) -> dict:
    """The plan as data: each distinct config once (its ``seed`` left as None) and, per run, that config's
    index and its seed (a cell's seeds share one config)."""
    distinct: dict[str, int] = {}
    configs, runs = [], []
    for cfg in plan.configs:
        text = json.dumps({**cfg, "seed": None})
        if text not in distinct:
            distinct[text] = len(configs)
            configs.append({**cfg, "seed": None})
        runs.append([distinct[text], cfg.get("seed")])
    return {"cells": plan.cells, "overrides": plan.overrides, "index": plan.index, "configs": configs, "runs": runs}


def unpacked(spec, value: dict) -> ArtifactPlan:
    """The :class:`ArtifactPlan` of ``spec`` that :func:`packed` gave ``value``."""
    configs = value["configs"]
    return ArtifactPlan(spec=spec, cells=value["cells"], overrides=value["overrides"],
                        configs=[{**configs[at], "seed": seed} for at, seed in value["runs"]],
                        index=[tuple(pair) for pair in value["index"]])


def _same(plan: ArtifactPlan, again: ArtifactPlan) -> bool:
    """Whether ``again`` (a plan read back) holds ``plan``'s runs to the type and key order (a config
    JSON cannot hold, e.g. a tuple or an integer key, is never kept)."""
    parts = (lambda p: (p.cells, p.overrides, p.index, p.configs))
    return parts(plan) == parts(again) and json.dumps(parts(plan)) == json.dumps(parts(again))


def planned(spec, *, seeds: int | None = None, tiny: bool = False, fresh: bool = False) -> ArtifactPlan:
    """:func:`magexp.artifacts.sample_sizes.plan_with_effects` of ``spec``, ``seeds`` and ``tiny``, read from the plan
    cache when it holds it, else composed and kept there; ``fresh`` (``--force``) composes it all the same."""
    k = key(spec, seeds, tiny)
    if not fresh:
        try:
            return unpacked(spec, read(entry(k), k, KIND))
        except (OSError, InvalidEntry, KeyError, TypeError, ValueError, IndexError):
            pass  # absent or not a plan: composed again, and replaced
    plan = plan_with_effects(spec, seeds=seeds, tiny=tiny)
    value = packed(plan)
    if _same(plan, unpacked(spec, json.loads(json.dumps(value)))):
        try:
            write(entry(k), pack(k, KIND, value), root())
        except OSError:  # a read-only cache folder: composed each time
            pass
    return plan
