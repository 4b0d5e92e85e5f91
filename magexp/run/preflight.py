"""Checks made before any computation, so that a user mistake is one line and nothing is written.

* :func:`expand_sweep`: every job of a ``-m`` sweep, as Hydra's basic sweeper forms them;
* :func:`validate_runs`: every job composed (:func:`magexp.run.compose.compose_config`) and every
  distinct scenario and estimator built, so that each value is checked by its constructor
  before the first job starts; the data of each distinct scenario is checked against the
  problem's parameter count, and each run's and the whole sweep's memory and work against
  the limits of :mod:`magexp.run.budget`;
* :func:`check_output_folder`: an output folder that can be created and written.
"""

from __future__ import annotations

import itertools
import json
import os
import tempfile
from pathlib import Path

from magexp.run.budget import Tally, check_run, check_sweep
from magexp.run.compose import (GROUPS, check_choice, compose_config, options, parse_overrides,  # noqa: F401
                           resolved, target_class, yaml_value)
from magexp.errors import MagexpError, check
from magexp.run.guard import check_run_values

def expand_sweep(overrides: list[str]) -> list[list[str]]:
    """The jobs of a sweep: the cartesian product of every override's values, first key slowest
    (Hydra's basic sweeper); ``a,b``, ``range(...)``, ``choice(...)`` and, for a config group,
    ``glob(...)`` are expanded, once their count is within the runs limit (:func:`magexp.run.budget.check_sweep`)."""
    axes = []
    parsed = parse_overrides(overrides)
    check_sweep(parsed, lambda key: options(key) if key in GROUPS else [])
    for ov in parsed:
        key = ov.get_key_element()
        if ov.is_sweep_override():
            from hydra.core.override_parser.types import Glob

            try:
                glob = ov.value() if key in GROUPS and isinstance(ov.value(), Glob) else None
                values = glob.filter(options(key)) if glob else [str(v) for v in ov.sweep_string_iterator()]
            except Exception as exc:
                raise MagexpError(f"{ov.input_line} is not allowed: only a,b,... lists, range(), choice() and a "
                                  f"group's glob() can be swept ({str(exc).splitlines()[0]})") from None
        else:
            values = [ov.get_value_element_as_str()]
        axes.append([f"{key}={v}" for v in values])
    return [list(job) for job in itertools.product(*axes)]


def swept_keys(overrides: list[str]) -> list[str]:
    """The keys of ``overrides`` that take more than one value."""
    return [ov.get_key_element() for ov in parse_overrides(overrides) if ov.is_sweep_override()]


def _build(node, what):
    from magexp.run.runner import build

    return build(node, what)


def check_problem(cfg, scenario) -> None:
    """The scenario's data (seed ``cfg.seed``) give at least as many residuals as the problem has
    parameters: fewer readings than parameters is refused for every estimator."""
    import numpy as np

    from magexp.problems import make_problem
    from magexp.core.seeding import run_generators

    data_rng, _ = run_generators(cfg.seed)
    dataset = scenario.generate(rng=data_rng)
    objective = cfg.get("objective") or scenario.objective
    problem = make_problem(objective, dataset, scenario.search, **getattr(scenario, "problem_options", {}))
    centre = (np.asarray(problem.lower) + np.asarray(problem.upper)) / 2
    n_res = int(np.size(problem.residuals(centre)))
    check(n_res >= problem.n_params,
          f"scenario.n_readings={dataset.n} is not allowed with objective {objective!r}: {dataset.n} readings give "
          f"{n_res} residuals for {problem.n_params} parameters; use at least "
          f"{-(-problem.n_params * dataset.n // max(n_res, 1))} readings")


def check_seed(seed) -> None:
    from magexp.errors import check_positive_int

    check_positive_int(seed, "seed", minimum=0)


def validate_runs(jobs: list[list[str]], *, keep: bool = True) -> list:
    """Check every job (one line on the first bad value); return the composed configs (``keep``).

    Each distinct scenario (with its objective) is built and its data checked once, each
    distinct estimator built once. Without ``keep`` (a sweep, whose jobs Hydra composes
    itself), jobs that differ only in ``seed`` are composed once and their seeds checked
    alone, so a sweep over many seeds costs almost nothing to check.
    """
    for job in jobs:  # group choices first: the cheapest and most common mistake
        for ov in job:
            key, _, value = ov.partition("=")
            if key in GROUPS:
                check_choice(key, value)
    configs, seen, composed, estimates = [], set(), {}, {}
    tally = Tally("the sweep" if len(jobs) > 1 else "the run")  # memory and work: magexp.run.budget
    for job in jobs:
        rest = tuple(o for o in job if o.partition("=")[0] != "seed")
        if not keep and rest in composed:
            for ov in job:
                if ov.partition("=")[0] == "seed":
                    check_seed(yaml_value(ov.partition("=")[2]))
            tally.add(composed[rest])
            continue
        cfg = compose_config(job)
        check_seed(cfg.seed)
        plain = resolved(cfg)
        check_run_values(plain)
        s_key = json.dumps([plain["scenario"], plain.get("objective")], sort_keys=True, default=str)
        e_key = json.dumps(plain["estimator"], sort_keys=True, default=str)
        if (s_key, e_key) not in estimates:  # its memory and work first: nothing built for a run refused
            estimates[s_key, e_key] = check_run(plain)
        composed[rest] = estimates[s_key, e_key]
        tally.add(composed[rest])
        if e_key not in seen:
            _build(cfg.estimator, f"estimator {cfg.estimator.get('name')!r}")
            seen.add(e_key)
        if s_key not in seen:
            scenario = _build(cfg.scenario, f"scenario {cfg.scenario.get('name')!r}")
            check_problem(cfg, scenario)
            seen.add(s_key)
        if keep:
            configs.append(cfg)
    return configs


def check_output_folder(folder: Path | str, what: str = "output folder", *, canonical: bool = False) -> Path:
    """Fail unless ``folder`` is (or can be created as) a writable directory a command may write
    (:func:`magexp.run.guard.check_destination`: not empty, not a root, not inside ``results/`` unless
    ``canonical``); create nothing."""
    from magexp.run.guard import check_destination

    check_destination(folder, what, canonical=canonical)
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise MagexpError(f"{what} {str(folder)!r} is a file, not a folder: name a folder")
    probe = folder
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise MagexpError(f"{what} {str(folder)!r} cannot be created: {str(probe)!r} is a file")
    try:  # a real probe (permissions alone say nothing for root or a read-only mount)
        fd, tmp = tempfile.mkstemp(dir=probe, prefix=".magexp-probe-")
        os.close(fd)
        os.unlink(tmp)
    except OSError as exc:
        raise MagexpError(f"{what} {str(folder)!r} is not writable: {str(probe)!r}: {exc.strerror}") from None
    return folder


def first_missing(folder: Path) -> Path | None:
    """The highest of ``folder`` and its parents that does not exist yet (None if ``folder`` exists):
    removing it after a failure leaves no trace of the folders made for it."""
    if folder.exists():
        return None
    top = folder
    while not top.parent.exists():
        top = top.parent
    return top


def create_unique(folder: Path | str) -> tuple[Path, Path]:
    """Create ``folder`` exclusively; if it exists, ``folder-2``, ``folder-3``...: two runs started
    in the same second never share a folder. Returns ``(folder, top)``, ``top`` the highest
    folder this call created (remove it to leave no trace)."""
    folder = Path(folder)
    top = first_missing(folder)
    folder.parent.mkdir(parents=True, exist_ok=True)
    for k in itertools.count(1):
        candidate = folder if k == 1 else folder.with_name(f"{folder.name}-{k}")
        try:
            candidate.mkdir()
            return candidate, (top if top != folder else candidate)
        except FileExistsError:
            continue
