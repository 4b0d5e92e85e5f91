"""Checks made before any computation, so that a user mistake is one line and nothing is written.

* :func:`expand_sweep`: every job of a ``-m`` sweep, the jobs magexp's sweeper launches, within the runs limit;
* :func:`validate_runs`: every job composed (:func:`magexp.run.compose.compose_config`) and every
  distinct scenario and estimator built, so that each value is checked by its constructor
  before the first job starts; the data of each distinct scenario is checked against the
  problem's parameter count, and each run's and the whole sweep's memory and work against
  the limits of :mod:`magexp.run.budget`, and each file a recording scenario reads (:func:`check_scenario_files`:
  no device or FIFO, its size within the readings limit) before it is read;
* :func:`check_jobs`: a sweep that selects no job is refused, naming the override.
"""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import numpy as np
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import Override

from magexp.core.recordings import exists, load_recording, resolve
from magexp.core.seeding import run_generators
from magexp.errors import MagexpError, check
from magexp.problems import make_problem
from magexp.paths import SHARED_DATA
from magexp.run.budget import Tally, check_run, check_sweep
from magexp.run.files import check_recording_file
from magexp.run.compose import (GROUPS, check_choice, compose_config, config_loader, options, override_value,
                                 parse_overrides, resolved)
from magexp.run.values import check_run_values
from magexp.run.hydra_cli import check_nested
from magexp.run.keys import check_seed, shape
from magexp.run.runner import build

def check_discrete(parsed: list[Override]) -> None:
    """Refuse, in one line, a swept override whose values cannot be listed (``interval(...)``: a sweep
    lists its jobs).

    Raises
    ------
    MagexpError
        One line naming the override."""
    for ov in parsed:
        if ov.is_sweep_override() and not ov.is_discrete_sweep():
            raise MagexpError(f"{ov.input_line} is not allowed: only a,b,... lists, range(), choice() and a "
                              "group's glob() can be swept")


def sweep_jobs(overrides: list[str]) -> list[list[str]]:
    """The jobs of a ``-m`` sweep: the cartesian product of every override's values, first key slowest,
    a key given twice keeping its place and its last values (Hydra's basic sweeper's order); ``a,b``,
    ``range(...)``, ``choice(...)`` and a config group's ``glob(...)`` (its options read by Hydra's
    config loader), each enumerated by Hydra's parser.

    Raises
    ------
    MagexpError
        An override whose values cannot be listed (``interval(...)``)."""
    parsed = parse_overrides(overrides, parser=OverridesParser.create(config_loader=config_loader()))
    check_discrete(parsed)
    values = {}
    for ov in parsed:
        key = ov.get_key_element()
        texts = ov.sweep_string_iterator() if ov.is_sweep_override() else [ov.get_value_element_as_str()]
        values[key] = [f"{key}={text}" for text in texts]
    return [list(job) for job in itertools.product(*values.values())]


#: the module of the swarm's coefficient schedules (:func:`check_schedules`)
SCHEDULES = "magexp.estimators.schedules."


def expand_sweep(overrides: list[str]) -> list[list[str]]:
    """The jobs of a sweep (:func:`sweep_jobs`, in the order Hydra's basic sweeper gives), once their
    count is within the runs limit (:func:`magexp.run.budget.check_sweep`)."""
    parsed = parse_overrides(overrides)
    check_discrete(parsed)
    check_nested(parsed)
    check_sweep(parsed, lambda key: options(key) if key in GROUPS else [])
    return sweep_jobs(overrides)


def swept_keys(overrides: list[str]) -> list[str]:
    """The keys of ``overrides`` that take more than one value."""
    return [ov.get_key_element() for ov in parse_overrides(overrides) if ov.is_sweep_override()]


def check_problem(cfg, scenario) -> None:
    """The scenario's data (seed ``cfg.seed``) give at least as many residuals as the problem has
    parameters: fewer readings than parameters is refused for every estimator."""

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


def validate_runs(jobs: list[list[str]], *, keep: bool = True) -> list:
    """Check every job (one line on the first bad value); return the composed configs (``keep``).

    Each distinct scenario (with its objective) is built and its data checked once, each
    distinct estimator built once. Without ``keep`` (a sweep, whose jobs Hydra composes
    itself), jobs that differ only in ``seed`` are composed once and their seeds checked
    alone, so a sweep over many seeds costs almost nothing to check."""
    _check_choices(jobs)
    configs, seen, composed, estimates = [], set(), {}, {}
    tally = Tally("the sweep" if len(jobs) > 1 else "the run")  # memory and work: magexp.run.budget
    for job in jobs:
        rest = tuple(o for o in job if o.partition("=")[0] != "seed")
        if not keep and rest in composed:
            for ov in job:
                if ov.partition("=")[0] == "seed":
                    check_seed(override_value(ov.partition("=")[2]))
            tally.add(composed[rest])
            continue
        cfg = compose_config(job)
        if any(o.partition("=")[0] == "estimator.name" for o in job):  # a config's own name is its own label
            check_label(cfg.estimator)
        composed[rest] = _check_config(cfg, seen, estimates)
        tally.add(composed[rest])
        if keep:
            configs.append(cfg)
    return configs


def _check_choices(jobs: list[list[str]]) -> None:
    """Every config-group choice of every job exists (the cheapest and most common mistake, first)."""
    for job in jobs:
        for ov in job:
            key, _, value = ov.partition("=")
            if key in GROUPS:
                check_choice(key, value)


def _check_config(cfg, seen: set, estimates: dict):
    """Check one composed job: its seed and values, its memory and work (once per scenario and
    estimator), and build its estimator and scenario the first time each is ``seen``; returns the
    run's estimate (:func:`magexp.run.budget.check_run`)."""
    check_seed(cfg.seed)
    plain = resolved(cfg)
    check_run_values(plain)
    check_schedules(plain.get("estimator") or {})
    s_key = json.dumps([plain["scenario"], plain.get("objective")], sort_keys=True, default=str)
    e_key = json.dumps(plain["estimator"], sort_keys=True, default=str)
    if s_key not in seen:
        check_scenario_files(plain["scenario"])  # before its size is estimated or the scenario reads them
    if (s_key, e_key) not in estimates:  # its memory and work first: nothing built for a run refused
        estimates[s_key, e_key] = check_run(plain)
    if e_key not in seen:
        build(cfg.estimator, f"estimator {cfg.estimator.get('name')!r}")
        seen.add(e_key)
    if s_key not in seen:
        check_window(plain["scenario"])  # after the file gate: it reads the recording's times
        scenario = build(cfg.scenario, f"scenario {cfg.scenario.get('name')!r}")
        check_problem(cfg, scenario)
        seen.add(s_key)
    return estimates[s_key, e_key]


#: a recording scenario's keys naming a file it reads when built, and the folder a relative one is read from
#: (None: :func:`magexp.core.recordings.resolve`'s, the working folder then ``data/``)
SCENARIO_FILES = {"file": SHARED_DATA, "rest_file": SHARED_DATA, "path": None}


def check_scenario_files(scenario: dict) -> None:
    """Refuse, before the scenario is built, a file it would read that is a device, a FIFO or a socket, or too big
    for the readings or memory limit (:func:`magexp.run.files.check_recording_file`, as ``magexp calibrate``'s).

    Raises
    ------
    MagexpError
        One line naming the key."""
    for key, folder in SCENARIO_FILES.items():
        value = scenario.get(key)
        if isinstance(value, str) and value:
            path = resolve(value) if folder is None else (Path(value) if Path(value).is_absolute() else folder / value)
            check_recording_file(path, f"scenario.{key}", scenario.get("format") if key != "path" else "auto")


def check_window(scenario: dict) -> None:
    """A recording scenario's ``window`` (null: the whole recording) refused unless it is ``[start, end]`` seconds,
    ``0 <= start < end``, of a recording that has reading times (read here, before the scenario cuts it).

    Raises
    ------
    MagexpError
        One line naming ``scenario.window``."""
    window, file = scenario.get("window"), scenario.get("file")
    if window is None or not isinstance(file, str):
        return
    if shape(window) != (2,) or not 0 <= window[0] < window[1]:
        raise MagexpError(f"scenario.window={window!r} is not allowed: give [start, end] seconds from the first "
                          "reading, 0 <= start < end (null: the whole recording)")
    path = Path(file) if Path(file).is_absolute() else SHARED_DATA / file
    options = {k: scenario.get(k) for k in ("unit", "format", "mag_axes", "gyro_axes")}
    if exists(path) and load_recording(path, **options).reading_times() is None:
        raise MagexpError(f"scenario.window={window!r} is not allowed: {file} has no reading times to cut "
                          "(scenario.window=null)")


def check_schedules(node: dict, prefix: str = "estimator") -> None:
    """Every value of a coefficient schedule under ``node`` (:mod:`magexp.estimators.schedules`) a finite
    number, named by its whole key (``estimator.velocity.c1.start``): the schedule knows only its own
    part's name (``start``)."""
    schedule = str(node.get("_target_", "")).startswith(SCHEDULES)
    for key, value in node.items():
        if isinstance(value, dict):
            check_schedules(value, f"{prefix}.{key}")
        elif schedule and key != "_target_":
            number = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
            check(number, f"{prefix}.{key}={value!r} is not allowed: it must be a finite number")


def check_label(estimator) -> None:
    """An estimator's ``name`` labels its metrics in every table: set to the name of another estimator
    config whose class differs (``estimator=lm estimator.name=ipso``: ``lm`` labelled ``ipso``) is refused; a
    name of its own (``estimator.name=ipso_w``, an ablation's variant) is the caller's label."""
    name, target = estimator.get("name"), estimator.get("_target_")
    if isinstance(name, str) and name in options("estimator"):
        theirs = compose_config([f"estimator={name}"]).estimator.get("_target_")
        if theirs != target:
            raise MagexpError(f"estimator.name={name!r} is not allowed for {str(target).rpartition('.')[2]}: it is the "
                              f"label of conf/estimator/{name}.yaml ({str(theirs).rpartition('.')[2]}); choose "
                              f"estimator={name}, or a name of its own")


def check_jobs(overrides: list[str], jobs: list) -> None:
    """A sweep with no job (``estimator=glob(zzz*)``, ``seed=range(0,0)``) is refused, naming the
    override that selects nothing (and, for a config group, the options there are)."""
    if jobs:
        return

    empty = next((ov for ov in overrides if not expand_sweep([ov])), " ".join(overrides))
    key = empty.partition("=")[0]
    hint = f" (options: {', '.join(options(key))})" if key in GROUPS else ""
    raise MagexpError(f"{empty} is not allowed: it selects no value, so the sweep has no job{hint}")
