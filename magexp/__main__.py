"""Command line: ``magexp`` (or ``python -m magexp``).

* ``magexp scenario=... estimator=... seed=...``: one simulated run; prints its metrics and
  writes ``metrics.csv``, ``estimate.csv``, ``history.csv`` and ``config.yaml`` into a folder of
  its own (``outputs/<date>/<time>[-k]/``, or ``hydra.run.dir=<folder>``);
* ``magexp -m key=a,b other='range(3)' ...``: a sweep, expanded by Hydra's sweeper and run by
  magexp's launcher through :mod:`magexp.run.executor` (:func:`magexp.run.sweep.launch`: local processes,
  or a Dask cluster with ``hydra.launcher.executor=dask``). Every job is composed and checked
  before the first starts, every job goes through the run cache of ``make reproduce`` (a killed
  sweep resumes), and the sweep ends with ``<sweep dir>/sweep.csv``;
* ``magexp calibrate KEY=VALUE ...``: calibrate a recording (:mod:`magexp.calibration.fit`);
* ``magexp --help``, ``--version``, ``--cfg job`` (the composed config, not run).

A single run is composed once (:func:`magexp.run.compose.compose_config`) and run without Hydra's
application machinery; a sweep is handed to Hydra (its sweeper, then magexp's launcher) after
every job and the launcher's settings have been checked. Every
user mistake ends in one line on stderr and a non-zero exit, with nothing written.
"""

from __future__ import annotations

import os
import re
import shutil
import sys
import time
from pathlib import Path

from magexp.errors import MagexpError

RUN_DIR = "outputs/%Y-%m-%d/%H-%M-%S"     # a single run's folder (strftime), made unique
SWEEP_DIR = "multirun/%Y-%m-%d/%H-%M-%S"  # a sweep's folder, made unique
EXIT_BAD_INPUT, EXIT_BUG, EXIT_INTERRUPTED = 2, 3, 130
_PLAIN = re.compile(r"[A-Za-z0-9_.+\-]*")  # a value that cannot be a sweep or need Hydra's parser
#: the extra that provides a Hydra launcher (``hydra/launcher=<name>``)
LAUNCHER_EXTRAS = {"slurm": ("hydra_plugins.hydra_submitit_launcher", "cluster"),
                   "submitit_slurm": ("hydra_plugins.hydra_submitit_launcher", "cluster"),
                   "submitit_local": ("hydra_plugins.hydra_submitit_launcher", "cluster"),
                   "joblib": ("hydra_plugins.hydra_joblib_launcher", None),
                   "magexp": ("hydra_plugins.magexp_launcher", None)}

USAGE = """\
usage: magexp [KEY=VALUE ...]              one run (scenario x estimator x seed)
       magexp -m KEY=A,B KEY='range(N)' ...  a sweep: every combination, one folder each, sweep.csv
       magexp calibrate KEY=VALUE ...       calibrate a recording (magexp calibrate --help)
       magexp --cfg job [KEY=VALUE ...]     print the composed config and stop
       magexp --version | --help

examples:
  magexp scenario=ding2024_exp1 estimator=ipso seed=3
  magexp scenario=ding2024_exp2 estimator=lm scenario.noise=5 hydra.run.dir=my_run
  magexp -m estimator=pso,ipso scenario.noise=0,2,5,10 seed='range(10)'

config groups (conf/<group>/<name>.yaml):
"""


def fail(message: str, code: int = EXIT_BAD_INPUT) -> None:
    """One line on stderr, then exit."""
    print(f"error: {message}", file=sys.stderr)
    sys.exit(code)


def guarded(func, *args):
    """Call ``func(*args)`` turning every error into one line and a non-zero exit.

    :class:`MagexpError` and ``OSError`` (a file or folder the user named) exit 2; Ctrl-C exits
    130 with one line; anything else is a bug: one line and exit 3 (``MAGEXP_DEBUG=1`` shows
    the traceback).
    """
    try:
        return func(*args)
    except MagexpError as exc:
        fail(str(exc).splitlines()[0] if str(exc) else "bad input")
    except KeyboardInterrupt:
        fail("interrupted (Ctrl-C); finished runs are cached, rerun the same command to resume",
             EXIT_INTERRUPTED)
    except OSError as exc:
        fail(f"{exc.filename or ''}: {exc.strerror or exc}".lstrip(": "))
    except SystemExit:
        raise
    except Exception as exc:
        if os.environ.get("MAGEXP_DEBUG"):
            raise
        first = str(exc).splitlines()[0] if str(exc) else ""
        fail(f"unexpected {type(exc).__name__}: {first} (rerun with MAGEXP_DEBUG=1 for details)", EXIT_BUG)


# ---------------------------------------------------------------------------------------------
# outputs of one run

def print_table(rows: dict) -> None:
    """``key  value`` lines, keys aligned; floats with 6 significant digits."""
    width = max(len(k) for k in rows)
    for key, value in rows.items():
        print(f"{key:<{width}}  {value:.6g}" if isinstance(value, float) else f"{key:<{width}}  {value}")


def _write_csv(path: Path, header: list[str], rows) -> None:
    import csv

    from magexp.core.atomic import atomic_open

    with atomic_open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows(rows)


def execute(cfg, out_dir: Path, *, use_cache: bool = True) -> dict:
    """Run ``cfg`` through the run cache and write its outputs into ``out_dir`` (:func:`write_outputs`)."""
    from omegaconf import OmegaConf

    from magexp.run import cache
    from magexp.run.compose import resolved

    plain = resolved(cfg)
    key = cache.run_key(plain)
    out = cache.load(key, root=cache.CACHE) if use_cache else None
    cached = out is not None
    if out is None:
        from magexp.run.runner import run

        out = run(OmegaConf.create(plain))
        cache.store(key, out, root=cache.CACHE)  # if it cannot be kept, it is noted and written all the same
    cache.say_notes()
    return write_outputs(out, plain, out_dir, cached=cached)


def to_yaml(plain) -> str:
    """``OmegaConf.to_yaml`` of a plain container, the same text without building a config first
    (a tenth of the time: a sweep writes one per job)."""
    import yaml
    from omegaconf._utils import get_omega_conf_dumper

    return yaml.dump(plain, default_flow_style=False, allow_unicode=True, sort_keys=False,
                     Dumper=get_omega_conf_dumper())


def write_outputs(out, plain: dict, out_dir: Path, *, cached: bool) -> dict:
    """Write a run's folder: ``metrics.csv``, ``estimate.csv``, ``history.csv``, ``config.yaml``.

    ``metrics.csv`` is one row: the run's metrics, ``cached`` (whether the result came from the
    cache) and the provenance (:func:`magexp.run.provenance.provenance`); ``config.yaml`` is the
    resolved config ``plain`` the run read. Returns the metrics with ``cached``.
    """
    from magexp.core.atomic import write_text
    from magexp.run.provenance import provenance

    out_dir.mkdir(parents=True, exist_ok=True)
    metrics = {**out.metrics, "cached": cached, **provenance(plain)}
    _write_csv(out_dir / "metrics.csv", list(metrics), [list(metrics.values())])
    _write_csv(out_dir / "estimate.csv", ["parameter", "x"], zip(out.parameter_names, out.x.tolist()))
    if plain.get("write_history", True):
        _write_csv(out_dir / "history.csv", ["iteration", "nfev", "fun"],
                   zip(range(len(out.history)), out.history_nfev.tolist(), out.history.tolist()))
    write_text(out_dir / "config.yaml", to_yaml(plain))
    return {**out.metrics, "cached": cached}


def single_run(overrides: list[str], run_dir: str | None) -> None:
    """Compose once, check, create the run's own folder, run, write, print."""
    from magexp.run.preflight import check_output_folder, create_unique, first_missing, validate_runs

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


# ---------------------------------------------------------------------------------------------
# sweeps (Hydra's sweeper; magexp's launcher, or another of Hydra's)

def sweep_job(cfg) -> dict:
    """Hydra's task function of one sweep job under Hydra's own launchers (``hydra/launcher=basic|joblib|
    slurm``): the cached run into the job's folder. magexp's launcher runs its jobs itself."""
    from hydra.core.hydra_config import HydraConfig

    return guarded(execute, cfg, Path(HydraConfig.get().runtime.output_dir))


def check_launcher(hydra_overrides: list[str]) -> None:
    """A launcher whose plugin is not installed: one line with the ``pip install`` to run."""
    import importlib.util

    for ov in hydra_overrides:
        key, _, value = ov.partition("=")
        if key.lstrip("+") == "hydra/launcher":
            module, extra = LAUNCHER_EXTRAS.get(value, (None, None))
            if module is None:
                from magexp.paths import CONF

                names = sorted({*LAUNCHER_EXTRAS, *(p.stem for p in (CONF / "hydra" / "launcher").glob("*.yaml")),
                                "basic"})
                if value not in names:
                    raise MagexpError(f"hydra/launcher={value!r} is not allowed: choose one of {', '.join(names)}")
            elif importlib.util.find_spec(module) is None:
                hint = f"pip install 'magexp[{extra}]'" if extra else f"pip install {module.split('.')[-1]}"
                raise MagexpError(f"hydra/launcher={value} needs a plugin that is not installed: run {hint}")


def sweep(user: list[str], hydra_overrides: list[str]) -> None:
    """Check every job, create the sweep's own folder, then hand the sweep to Hydra."""
    import hydra

    from magexp.run.preflight import check_output_folder, create_unique, expand_sweep, validate_runs
    from magexp.run.compose import register_schemas
    from magexp.run.guard import check_jobs, check_subdir, removed_on_failure
    from magexp.paths import CONF

    check_launcher(hydra_overrides)
    from magexp.run.sweep import check_hydra_settings

    for ov in hydra_overrides:  # each job's folder inside the sweep's
        if ov.startswith("hydra.sweep.subdir="):
            check_subdir(ov.partition("=")[2])
    check_hydra_settings([o for o in hydra_overrides if not o.startswith("hydra.sweep.dir=")])
    jobs = expand_sweep(user)
    check_jobs(user, jobs)
    validate_runs(jobs, keep=False)
    explicit = [o for o in hydra_overrides if o.startswith("hydra.sweep.dir=")]
    if explicit:
        folder, created = check_output_folder(explicit[-1].partition("=")[2], "hydra.sweep.dir"), None
    else:
        folder = Path(time.strftime(SWEEP_DIR))
        check_output_folder(folder, "sweep folder")
        folder, created = create_unique(folder)
        hydra_overrides = [*hydra_overrides, f"hydra.sweep.dir={folder}"]
    register_schemas()
    app = hydra.main(version_base=None, config_path=str(CONF), config_name="config")(sweep_job)
    sys.argv = [sys.argv[0], "-m", *user, *hydra_overrides]
    with removed_on_failure(folder, created):  # a failed or interrupted sweep leaves nothing behind
        app()


def hand_to_hydra(args: list[str]) -> None:
    """Anything this CLI does not handle itself (``--cfg hydra``, ``--info``...): Hydra's app."""
    import hydra

    from magexp.run.compose import register_schemas
    from magexp.paths import CONF

    register_schemas()
    app = hydra.main(version_base=None, config_path=str(CONF), config_name="config")(sweep_job)
    sys.argv = [sys.argv[0], *args]
    app()


# ---------------------------------------------------------------------------------------------

def print_help() -> None:
    from magexp.run.compose import GROUPS, options

    lines = [USAGE]
    for group in GROUPS:
        lines.append(f"  {group}: {', '.join(options(group))}")
    lines.append("\nany value can be overridden (scenario.noise=5, estimator.n_particles=30, seed=3); "
                 "`magexp --cfg job KEY=VALUE ...` shows every key.")
    print("\n".join(lines))


def calibrate(argv: list[str]) -> None:
    """``magexp calibrate ...``: :func:`magexp.calibration.fit.main`."""
    try:
        from magexp.calibration.fit import main as calibration_main
    except ModuleNotFoundError as exc:
        if exc.name != "magexp.calibration.fit":
            raise
        raise MagexpError("the calibrate command is not available in this build: magexp.calibration.fit is missing") \
            from None
    code = calibration_main(argv)
    sys.exit(code or 0)


def split_args(args: list[str]) -> tuple[list[str], list[str], dict]:
    """``(user overrides, hydra overrides, flags)``; flags maps ``--name`` to its value."""
    user, hyd, flags = [], [], {}
    it = iter(args)
    for arg in it:
        if arg in ("-m", "--multirun", "-h", "--help", "--version", "--resolve", "--info", "--hydra-help"):
            flags[arg] = True
        elif arg in ("--cfg", "-c", "--package", "-p", "--config-name", "-cn", "--config-dir", "-cd",
                     "--config-path", "-cp", "--experimental-rerun", "--shell-completion", "-sc"):
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


def run_command(args: list[str]) -> None:
    from magexp.run.guard import check_destination, check_flags, check_override_values

    user, hyd, flags = split_args(args)
    user = check_override_values(user)
    check_flags(flags)
    if flags.get("-h") or flags.get("--help"):
        return print_help()
    if flags.get("--version"):
        from magexp.run.provenance import version_line

        return print(version_line())
    cfg_flag = flags.get("--cfg") or flags.get("-c")
    multirun = flags.get("-m") or flags.get("--multirun")
    others = {k: v for k, v in flags.items() if k not in ("-m", "--multirun", "--cfg", "-c", "--resolve")}
    if cfg_flag == "job" and not others and not multirun:
        from omegaconf import OmegaConf

        from magexp.run.compose import compose_config

        cfg = compose_config(user)
        return print(OmegaConf.to_yaml(cfg, resolve=bool(flags.get("--resolve"))), end="")
    if cfg_flag or others:
        from magexp.run.preflight import expand_sweep, validate_runs

        validate_runs(expand_sweep(user)[:1], keep=False)
        return hand_to_hydra(args)
    if multirun:
        return sweep(user, hyd)
    run_dirs = [o.partition("=")[2] for o in hyd if o.startswith("hydra.run.dir=")]
    for run_dir in run_dirs:  # not empty, not a root, not inside results/
        check_destination(run_dir, "hydra.run.dir")
    if len(run_dirs) != len(hyd):
        rest = [o for o in hyd if not o.startswith("hydra.run.dir=")]
        check_launcher(rest)
        raise MagexpError(f"{rest[0]} is not allowed for a single run: hydra.* settings other than hydra.run.dir "
                          "apply to -m sweeps")
    from magexp.run.preflight import expand_sweep

    plain = all(_PLAIN.fullmatch(ov.partition("=")[2]) for ov in user)  # nothing Hydra's parser must read
    if not plain and len(expand_sweep(user)) > 1:
        raise MagexpError("a value list (a,b or range()) needs -m: magexp -m " + " ".join(user))
    single_run(user, run_dirs[-1] if run_dirs else None)


def main(argv: list[str] | None = None) -> None:
    """Entry point of ``magexp`` / ``python -m magexp``."""
    args = list(sys.argv[1:] if argv is None else argv)
    if argv is None:  # a closed pipe (magexp --help | head) ends quietly, as for any Unix tool
        import signal

        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    if args and args[0] == "calibrate":
        return guarded(calibrate, args[1:])
    guarded(run_command, args)


if __name__ == "__main__":
    main()
