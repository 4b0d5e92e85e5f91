"""The run command: ``magexp [KEY=VALUE ...]`` (one run) and ``magexp -m ...`` (a sweep).

* ``magexp scenario=... estimator=... seed=...``: one run; prints its metrics and writes
  ``metrics.csv``, ``estimate.csv``, ``history.csv`` and ``config.yaml`` into a folder of its own
  (``outputs/<date>/<time>[-k]/``, or ``hydra.run.dir=<folder>``);
* ``magexp -m key=a,b other='range(3)' ...``: a sweep, expanded by Hydra's sweeper and run by
  magexp's launcher through :mod:`magexp.run.executor` (:func:`magexp.run.sweep.launch`: local
  processes, or a Dask cluster with ``hydra.launcher.executor=dask``). Every job is composed and
  checked before the first starts, every job goes through the run cache of ``make reproduce`` (a
  killed sweep resumes), and the sweep ends with ``<sweep dir>/sweep.csv``;
* ``magexp --help``, ``--version``, ``--cfg job`` (the composed config, not run).

A single run is composed once by Hydra (:func:`magexp.run.compose.compose_config`) and run without Hydra's
application machinery; a sweep is handed to Hydra (its sweeper, then magexp's launcher) after
every job and the launcher's settings have been checked. Every user mistake ends in one line on
stderr and a non-zero exit (:func:`magexp.errors.guarded`), with nothing written.
"""

from __future__ import annotations

import importlib.util
import shutil
import sys
import time
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import OmegaConf

from magexp.errors import MagexpError, guarded
from magexp.paths import CONF
from magexp.run.compose import GROUPS, compose_config, options, parse_overrides, register_schemas
from magexp.run.folders import (check_destination, check_output_folder, check_subdir, create_unique, first_missing,
                                removed_on_failure)
from magexp.run.flags import check_flags
from magexp.run.overrides import check_hydra_keys, check_override_targets, check_override_values
from magexp.run.hydra_cli import check_commands, check_hydra_overrides, check_package, sweep_spelling
from magexp.run.keys import check_duplicates
from magexp.run.outputs import execute, print_table
from magexp.run.preflight import check_jobs, expand_sweep, validate_runs
from magexp.run.provenance import version_line
from magexp.run.sweep import check_hydra_settings, plan_jobs

RUN_DIR = "outputs/%Y-%m-%d/%H-%M-%S"     # a single run's folder (strftime), made unique
SWEEP_DIR = "multirun/%Y-%m-%d/%H-%M-%S"  # a sweep's folder, made unique
#: the extra that provides a Hydra launcher (``hydra/launcher=<name>``)
LAUNCHER_EXTRAS = {"slurm": ("hydra_plugins.hydra_submitit_launcher", "cluster"),
                   "submitit_slurm": ("hydra_plugins.hydra_submitit_launcher", "cluster"),
                   "submitit_local": ("hydra_plugins.hydra_submitit_launcher", "cluster"),
                   "joblib": ("hydra_plugins.hydra_joblib_launcher", None),
                   "magexp": ("hydra_plugins.magexp_launcher", None)}
#: Hydra's own flags: those that stand alone, and those that take a value
HYDRA_SWITCHES = ("-m", "--multirun", "-r", "--run", "-h", "--help", "--version", "--resolve", "--info", "-i",
                  "--hydra-help")
HYDRA_OPTIONS = ("--cfg", "-c", "--package", "-p", "--config-name", "-cn", "--config-dir", "-cd",
                 "--config-path", "-cp", "--experimental-rerun", "--shell-completion", "-sc")

USAGE = """\
usage: magexp [KEY=VALUE ...]              one run (scenario x estimator x seed)
       magexp -m KEY=A,B KEY='range(N)' ...  a sweep: every combination, one folder each, sweep.csv
       magexp calibrate KEY=VALUE ...       calibrate a recording (magexp calibrate --help)
       magexp reproduce PAPER [OPTIONS]     regenerate a paper's figures and tables (magexp reproduce --help)
       magexp verify [OPTIONS]              does a reproduction agree with the committed results? (--help)
       magexp new-paper NAME                scaffold experiments/NAME/ for a paper of your own (--help)
       magexp --cfg job [KEY=VALUE ...]     print the composed config and stop
       magexp --version | --help

examples:
  magexp scenario=ding2024_exp1 estimator=ipso seed=3
  magexp scenario=ding2024_exp2 estimator=lm scenario.noise=5 hydra.run.dir=my_run
  magexp -m estimator=pso,ipso scenario.noise=0,2,5,10 seed='range(10)'

config groups (conf/<group>/<name>.yaml):
"""


def single_run(overrides: list[str], run_dir: str | None) -> None:
    """Compose once, check, create the run's own folder, run, write, print."""
    (cfg,) = validate_runs([overrides])
    folder = Path(run_dir) if run_dir else Path(time.strftime(RUN_DIR))
    check_output_folder(folder, "run folder")
    if run_dir:
        created = first_missing(folder)
        folder.mkdir(parents=True, exist_ok=True)
    else:
        folder, created = create_unique(folder)
    try:
        metrics = execute(cfg, folder)
    except BaseException:
        if created is not None:  # leave nothing half-written behind
            shutil.rmtree(created, ignore_errors=True)
        raise
    print_table({**metrics, "written to": str(folder)})


def sweep_job(cfg) -> dict:
    """Hydra's task function of one sweep job under Hydra's own launchers (``hydra/launcher=basic|joblib|
    slurm``): the cached run into the job's folder. magexp's launcher runs its jobs itself."""
    return guarded(execute, cfg, Path(HydraConfig.get().runtime.output_dir))


def check_launcher(hydra_overrides: list[str]) -> None:
    """A launcher whose plugin is not installed: one line with the ``pip install`` to run."""
    for ov in hydra_overrides:
        key, _, value = ov.partition("=")
        if key.lstrip("+") != "hydra/launcher":
            continue
        module, extra = LAUNCHER_EXTRAS.get(value, (None, None))
        if module is None:
            names = sorted({*LAUNCHER_EXTRAS, *(p.stem for p in (CONF / "hydra" / "launcher").glob("*.yaml")),
                            "basic"})
            if value not in names:
                raise MagexpError(f"hydra/launcher={value!r} is not allowed: choose one of {', '.join(names)}")
        elif importlib.util.find_spec(module) is None:
            hint = f"pip install 'magexp[{extra}]'" if extra else f"pip install {module.split('.')[-1]}"
            raise MagexpError(f"hydra/launcher={value} needs a plugin that is not installed: run {hint}")


def hydra_app(args: list[str]) -> None:
    """Run Hydra's application on ``args`` (``sys.argv`` as Hydra reads it), :func:`sweep_job` per job."""
    register_schemas()
    app = hydra.main(version_base=None, config_path=str(CONF), config_name="config")(sweep_job)
    sys.argv = [sys.argv[0], *args]
    app()


def sweep(user: list[str], hydra_overrides: list[str]) -> None:
    """Check every job, create the sweep's own folder, then hand the sweep to Hydra."""
    check_launcher(hydra_overrides)
    for ov in hydra_overrides:  # each job's folder inside the sweep's
        if ov.startswith("hydra.sweep.subdir="):
            check_subdir(ov.partition("=")[2])
    node = check_hydra_settings([o for o in hydra_overrides if not o.startswith("hydra.sweep.dir=")])
    user = check_override_values(sweep_spelling(node, user))  # hydra.sweeper.params counted and checked too
    hydra_overrides = [o for o in hydra_overrides if o.partition("=")[0].lstrip("+") != "hydra.sweeper.params"]
    jobs = expand_sweep(user)
    check_jobs(user, jobs)
    validate_runs(jobs, keep=False)
    explicit = [o for o in hydra_overrides if o.startswith("hydra.sweep.dir=")]
    if explicit:
        folder, created = check_output_folder(folder_of(explicit[-1]), "hydra.sweep.dir"), None
    else:
        folder = Path(time.strftime(SWEEP_DIR))
        check_output_folder(folder, "sweep folder")
        folder, created = create_unique(folder)
        hydra_overrides = [*hydra_overrides, f"hydra.sweep.dir={folder}"]
    plan_jobs(user, jobs)  # the jobs checked are the jobs launched: the sweep expanded once
    with removed_on_failure(folder, created):  # a failed or interrupted sweep leaves nothing behind
        hydra_app(["-m", *user, *hydra_overrides])


def print_help() -> None:
    """Print ``magexp run --help``: the usage and each config group's choices."""
    lines = [USAGE]
    for group in GROUPS:
        lines.append(f"  {group}: {', '.join(options(group))}")
    lines.append("\nany value can be overridden (scenario.noise=5, estimator.n_particles=30, seed=3); "
                 "`magexp --cfg job KEY=VALUE ...` shows every key.")
    print("\n".join(lines))


def split_args(args: list[str]) -> tuple[list[str], list[str], dict]:
    """``(user overrides, hydra overrides, flags)``; flags maps ``--name`` to its value."""
    user, hyd, flags = [], [], {}
    it = iter(args)
    for arg in it:
        if arg.startswith("--") and "=" in arg and arg.partition("=")[0] in (*HYDRA_OPTIONS, "--info"):  # --cfg=job
            flags[arg.partition("=")[0]] = arg.partition("=")[2]
        elif arg in ("--info", "-i") and _next_is(args, arg):  # an optional value, as Hydra's argparse reads it
            flags[arg] = next(it)
        elif arg in HYDRA_SWITCHES:
            flags[arg] = True
        elif arg in HYDRA_OPTIONS:
            value = next(it, None)
            if value is None:
                raise MagexpError(f"{arg} needs a value")
            flags[arg] = value
        elif arg.startswith("-") and "=" not in arg:
            raise MagexpError(f"option {arg!r} is not allowed: see magexp --help")
        elif arg.lstrip("+~").startswith("hydra"):
            hyd.append(arg)
        else:
            user.append(arg)
    return user, hyd, flags


def _next_is(args: list[str], arg: str) -> bool:
    """Whether an argument that is not a flag follows ``arg`` in ``args`` (its optional value)."""
    i = args.index(arg)
    return i + 1 < len(args) and not args[i + 1].startswith("-")


def run_one(user: list[str], hyd: list[str]) -> None:
    """One run: ``hydra.run.dir`` is the only Hydra setting it takes; a value list needs ``-m``."""
    run_dirs = [folder_of(o) for o in hyd if o.startswith("hydra.run.dir=")]
    for run_dir in run_dirs:  # not empty, not a root, not inside results/
        check_destination(run_dir, "hydra.run.dir")
    if len(run_dirs) != len(hyd):
        rest = [o for o in hyd if not o.startswith("hydra.run.dir=")]
        check_launcher(rest)
        raise MagexpError(f"{rest[0]} is not allowed for a single run: hydra.* settings other than hydra.run.dir "
                          "apply to -m sweeps")
    if any(ov.is_sweep_override() for ov in parse_overrides(user)) and len(expand_sweep(user)) > 1:
        raise MagexpError("a value list (a,b or range()) needs -m: magexp -m " + " ".join(user))
    single_run(user, run_dirs[-1] if run_dirs else None)


FOLDER_KEYS = ("hydra.run.dir", "hydra.sweep.dir")  # the output folders a command line may name


def folder_overrides(hyd: list[str]) -> list[str]:
    """``hyd`` with each output folder override (:data:`FOLDER_KEYS`, also as ``+key`` / ``++key``) as
    ``key=value``, its folder read as Hydra's parser reads it, or one line: an interpolation
    (``${oc.env:...}``, ``${hydra:...}``, resolved only later, could point into ``results/`` or name a
    folder literally ``${...}``), a deletion, or a value Hydra cannot read as one path (an ``=``, a
    comma, a space...), with how to quote it."""
    out = []
    for ov in hyd:
        key, _, value = ov.partition("=")
        name = key.lstrip("+~")
        if name not in FOLDER_KEYS:
            out.append(ov)
            continue
        if key.startswith("~"):
            raise MagexpError(f"{ov} is not allowed: name a folder ({name}=<folder>)")
        if "${" in value:
            raise MagexpError(f"{name}={value!r} is not allowed: interpolations (${{...}}) are not read in an "
                              "output folder (resolved later they could point anywhere); give the folder itself")
        try:
            parsed = parse_overrides([f"{name}={value}"])[0]
            folder = parsed.value() if not parsed.is_sweep_override() else None
        except MagexpError:
            folder = None
        if not isinstance(folder, str):
            quoted = value.replace("'", "\\'")
            raise MagexpError(f"{name}={value!r} is not allowed as written: Hydra reads an '=', ',', space, quote or "
                              f"bracket in it; quote the folder for Hydra, e.g. \"{name}='{quoted}'\"")
        out.append(f"{name}={value}")
    return out


def folder_of(ov: str) -> str:
    """The folder of a checked output folder override (:func:`folder_overrides`)."""
    return parse_overrides([ov])[0].value()


def run_command(args: list[str]) -> None:
    """``magexp ARGS``: help, version, the composed config, Hydra's own flags, a sweep, or one run."""
    user, hyd, flags = split_args(args)
    check_duplicates(user + hyd)  # Hydra would keep the last silently
    check_flags(flags)
    check_commands(flags)
    check_hydra_keys(hyd)  # no code from an override: before anything reads them
    check_override_targets(user + hyd)
    checked = folder_overrides(hyd)
    check_hydra_overrides(checked)
    args = [dict(zip(hyd, checked)).get(a, a) for a in args]
    hyd = checked
    user = check_override_values(user)
    if flags.get("-h") or flags.get("--help"):
        return print_help()
    if flags.get("--version"):
        return print(version_line())
    cfg_flag = flags.get("--cfg") or flags.get("-c")
    multirun = flags.get("-m") or flags.get("--multirun")
    others = {k: v for k, v in flags.items() if k not in ("-m", "--multirun", "--cfg", "-c", "--resolve", "-r", "--run")}
    check_package(flags, user, hyd)
    if cfg_flag == "job" and not others and not multirun:
        return print(OmegaConf.to_yaml(compose_config(user), resolve=bool(flags.get("--resolve"))), end="")
    if cfg_flag or others:
        validate_runs(expand_sweep(user)[:1], keep=False)
        return hydra_app(args)
    if multirun:
        return sweep(user, hyd)
    return run_one(user, hyd)
