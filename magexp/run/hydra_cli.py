"""Hydra's own switches and ``hydra.*`` settings on magexp's command line (issue 41): each either does what
Hydra documents or is refused in one line before Hydra sees it, and every way a sweep is spelled is counted
before it expands.

* :func:`check_commands`: Hydra runs one of ``--run``, ``--multirun``, ``--cfg``, ``--info`` and
  ``--shell-completion``; ``--resolve`` and ``--package`` go with ``--cfg`` (:func:`check_package`: a node of
  the config shown); ``--info`` takes one of :data:`INFO_CHOICES`; ``--shell-completion`` one of
  ``install|uninstall|query=bash|fish|zsh`` (``query`` only from the shell's completion, which sets
  ``COMP_LINE``);
* :func:`check_hydra_overrides`: no interpolation in a ``hydra.*`` setting's value (resolved later, it could
  read the environment or point anywhere), but Hydra's own job keys in ``hydra.sweep.subdir``
  (:data:`JOB_KEYS`); a setting given twice is refused with every key (:func:`magexp.run.keys.check_duplicates`);
* :func:`check_hydra_node`: the ``hydra`` node Hydra composes from them: a launcher node,
  ``hydra.sweeper.max_batch_size`` null or an integer >= 1, ``hydra.job.chdir`` false (magexp's runs
  read and write by absolute paths), joblib's launcher settings bounded (:func:`check_joblib`);
* :func:`sweep_spelling`: the sweep's overrides as Hydra's sweeper forms them, ``hydra.sweeper.params``
  first and the command line's overrides replacing those of the same key, each checked as a command-line
  value, so that the sweep magexp counts and checks is the sweep that runs;
* :func:`check_nested`: a range or a list inside a list of values (``seed=range(5),7``) is refused.
"""

from __future__ import annotations

import math
import os
import re

from hydra.core.override_parser.types import ChoiceSweep, Sweep
from omegaconf import DictConfig, OmegaConf

from magexp.errors import MagexpError
from magexp.run.compose import compose_config, hydra_compose

#: Hydra's commands: one at a time (aliases map to the long name)
COMMANDS = {"--run": "--run", "-r": "--run", "--multirun": "--multirun", "-m": "--multirun", "--cfg": "--cfg",
            "-c": "--cfg", "--info": "--info", "-i": "--info", "--shell-completion": "--shell-completion",
            "-sc": "--shell-completion"}
#: what ``--info`` may show (Hydra's choices)
INFO_CHOICES = ("all", "config", "defaults", "defaults-tree", "plugins", "searchpath")
#: ``--shell-completion``'s subcommands and shells (Hydra's completion plugins)
COMPLETION = ("install", "uninstall", "query")
SHELLS = ("bash", "fish", "zsh")
#: the interpolations a sweep job's folder name may hold: Hydra's own keys of the job
JOB_KEYS = re.compile(r"\$\{hydra\.job\.(?:num|id|name|override_dirname)\}")
#: joblib's launcher settings magexp passes on (bounded by :func:`check_joblib`); the others keep Hydra's
#: defaults (``backend``: the plugin always uses loky; ``temp_folder``... would write elsewhere)
JOBLIB_SETTINGS = ("n_jobs", "verbose", "timeout", "batch_size")


def check_commands(flags: dict) -> None:
    """Hydra's switches as Hydra reads them, or one line: one command at a time, ``--resolve`` and
    ``--package`` with ``--cfg``, ``--info`` and ``--shell-completion`` with a value Hydra knows.

    Raises
    ------
    MagexpError
        One line naming the flag."""
    given = list(dict.fromkeys(COMMANDS[f] for f in flags if f in COMMANDS))
    if len(given) > 1:
        raise MagexpError(f"{given[0]} and {given[1]} are not allowed together: Hydra does one of --run, --multirun "
                          "(-m), --cfg, --info and --shell-completion (-sc) at a time")
    if "--cfg" not in given and not any(f in flags for f in ("-h", "--help", "--hydra-help")):
        _without_cfg(flags)
    info = flags.get("--info", flags.get("-i"))
    if isinstance(info, str) and info not in INFO_CHOICES:
        raise MagexpError(f"--info {info!r} is not allowed: choose one of {', '.join(INFO_CHOICES)}")
    for flag in ("--shell-completion", "-sc"):
        if flag in flags:
            _check_completion(flag, flags[flag])


def _without_cfg(flags: dict) -> None:
    """Refuse ``--resolve`` and ``--package`` without ``--cfg`` (Hydra's: they change what ``--cfg`` prints)."""
    if "--resolve" in flags:
        raise MagexpError("--resolve is not allowed without --cfg: it resolves the interpolations of the config "
                          "--cfg prints (magexp --cfg job --resolve)")
    for flag in ("--package", "-p"):
        if flag in flags:
            raise MagexpError(f"{flag} {flags[flag]!r} is not allowed without --cfg: it names the part of the config "
                              "--cfg prints (magexp --cfg job --package scenario)")


def _check_completion(flag: str, value: str) -> None:
    """``--shell-completion`` with ``install|uninstall|query=bash|fish|zsh``; ``query`` only where the
    shell's completion sets ``COMP_LINE``."""
    command, _, shell = str(value).partition("=")
    if command not in COMPLETION or shell not in SHELLS:
        raise MagexpError(f"{flag} {value!r} is not allowed: give {'|'.join(COMPLETION)}={'|'.join(SHELLS)}, e.g. "
                          f"eval \"$(magexp {flag} install=bash)\"")
    if command == "query" and "COMP_LINE" not in os.environ:
        raise MagexpError(f"{flag} {value!r} is not allowed here: the shell's completion runs it (it reads "
                          f"COMP_LINE); install it with eval \"$(magexp {flag} install={shell})\"")


def check_package(flags: dict, user: list[str], hydra_overrides: list[str]) -> None:
    """``--package`` (``-p``) naming a node of the config ``--cfg kind`` prints (Hydra prints only a node), else
    one line naming the nodes there are.

    Raises
    ------
    MagexpError
        A package that is not a node of that config."""
    package, kind = flags.get("--package", flags.get("-p")), flags.get("--cfg") or flags.get("-c")
    if package is None or not kind or package == "_global_":  # _global_: Hydra's name of the whole config
        return
    if kind == "job":
        cfg = compose_config(user)
    else:
        cfg = hydra_compose(tuple([*user, *hydra_overrides]), with_hydra=True)
        if kind == "hydra":
            cfg = OmegaConf.masked_copy(cfg, ["hydra"])
    node = OmegaConf.select(cfg, package, default=None, throw_on_missing=False) if package else None
    if not isinstance(node, DictConfig):
        nodes = [k for k, v in cfg.items_ex(resolve=False) if isinstance(v, DictConfig)]
        raise MagexpError(f"--package {package!r} is not allowed with --cfg {kind}: it is not a node of that config; "
                          f"choose one of {', '.join(nodes)} (or a node inside one, e.g. {nodes[0]}.<key>)")


def check_hydra_overrides(hydra_overrides: list[str]) -> None:
    """No ``${...}`` in a ``hydra.*`` setting's value but Hydra's own job keys in ``hydra.sweep.subdir``
    (:data:`JOB_KEYS`).

    Raises
    ------
    MagexpError
        One line naming the setting."""
    for ov in hydra_overrides:
        key, _, value = ov.partition("=")
        name = key.lstrip("+~")
        if "${" not in value or (name == "hydra.sweep.subdir" and "${" not in JOB_KEYS.sub("", value)):
            continue
        allowed = ("a job's folder may hold ${hydra.job.num}, ${hydra.job.id}, ${hydra.job.name} or "
                   "${hydra.job.override_dirname}" if name == "hydra.sweep.subdir" else "give the value itself")
        raise MagexpError(f"{name}={value!r} is not allowed: interpolations (${{...}}) are not read in hydra.* "
                          f"settings (resolved later they could read the environment or point anywhere); {allowed}")


def check_hydra_node(node) -> None:
    """The ``hydra`` node Hydra composes from a sweep's settings: a launcher node, the sweeper's
    ``max_batch_size`` null or an integer >= 1, ``hydra.job.chdir`` false, joblib's settings bounded.

    Raises
    ------
    MagexpError
        One line naming the setting."""
    launcher = node.get("launcher")
    if not isinstance(launcher, DictConfig):
        raise MagexpError(f"hydra.launcher={'null' if launcher is None else launcher!r} is not allowed: choose a "
                          "launcher with hydra/launcher=<name> and set its keys (hydra.launcher.jobs=4)")
    batch = node.sweeper.get("max_batch_size")
    if batch is not None and (isinstance(batch, bool) or not isinstance(batch, int) or batch < 1):
        raise MagexpError(f"hydra.sweeper.max_batch_size={batch!r} is not allowed: it must be an integer >= 1 (the "
                          "jobs launched together) or null (all at once)")
    if node.job.get("chdir"):
        raise MagexpError("hydra.job.chdir=true is not allowed: magexp's runs read and write by absolute paths and "
                          "write each job's files into its own folder already (hydra.sweep.subdir)")
    if "joblib" in str(node.launcher.get("_target_", "")):
        check_joblib(node.launcher)


def _cores() -> int:
    """The cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def check_joblib(launcher) -> None:
    """joblib's launcher settings: ``n_jobs`` -1 (all cores) or 1 to the cores (or -2 to -cores, all
    but some), ``verbose`` an integer >= 0, ``timeout`` null or a number > 0, ``batch_size`` auto or an
    integer >= 1; the others (:data:`JOBLIB_SETTINGS`) as Hydra sets them.

    Raises
    ------
    MagexpError
        One line naming the setting."""
    defaults = hydra_compose(("hydra/launcher=joblib",), with_hydra=True).hydra.launcher
    for key in launcher:
        if key not in JOBLIB_SETTINGS and launcher.get(key) != defaults.get(key):
            raise MagexpError(f"hydra.launcher.{key}={launcher.get(key)!r} is not allowed with hydra/launcher=joblib: "
                              f"magexp sets only {', '.join(f'hydra.launcher.{k}' for k in JOBLIB_SETTINGS)}")
    _joblib_values(launcher)


def _joblib_values(launcher) -> None:
    """Refuse joblib's ``n_jobs``, ``verbose``, ``timeout`` or ``batch_size`` out of range (:func:`check_joblib`)."""
    n, cores = launcher.get("n_jobs"), _cores()
    if isinstance(n, bool) or not isinstance(n, int) or n == 0 or not -cores <= n <= cores:
        raise MagexpError(f"hydra.launcher.n_jobs={n!r} is not allowed: this machine gives {cores} cores; give 1 to "
                          f"{cores}, or -1 (all cores) to -{cores}")
    verbose, timeout, batch = launcher.get("verbose"), launcher.get("timeout"), launcher.get("batch_size")
    if isinstance(verbose, bool) or not isinstance(verbose, int) or verbose < 0:
        raise MagexpError(f"hydra.launcher.verbose={verbose!r} is not allowed: it must be an integer >= 0")
    if timeout is not None and not (isinstance(timeout, (int, float)) and math.isfinite(timeout) and timeout > 0):
        raise MagexpError(f"hydra.launcher.timeout={timeout!r} is not allowed: it must be a number > 0 or null")
    if batch != "auto" and not (str(batch).isdigit() and int(batch) >= 1):
        raise MagexpError(f"hydra.launcher.batch_size={batch!r} is not allowed: it must be auto or an integer >= 1")


def sweep_spelling(node, user: list[str]) -> list[str]:
    """The sweep's overrides as Hydra's basic sweeper forms them: ``hydra.sweeper.params`` (each
    ``key: values`` as ``key=values``) first, the command line's ``user`` overrides after, one of the same key
    replacing the param in its place.

    Raises
    ------
    MagexpError
        A param that is not ``key: values`` of a config key (a ``hydra.*`` key, a node, null or an interpolation)."""
    params = OmegaConf.to_container(node.sweeper, resolve=False).get("params") or {}
    if not isinstance(params, dict):
        raise MagexpError(f"hydra.sweeper.params={params!r} is not allowed: give {{key: values}}, e.g. "
                          "'hydra.sweeper.params={seed: \"range(3)\"}'")
    spelled = {}
    for key, value in params.items():
        text = f"hydra.sweeper.params.{key}={value!r}"
        if str(key).lstrip("+~").startswith("hydra") or not str(key).strip():
            raise MagexpError(f"{text} is not allowed: a param sweeps a key of the run's config (seed, scenario.noise, "
                              "estimator...), not a hydra.* setting")
        if isinstance(value, (dict, list)) or value is None:
            raise MagexpError(f"{text} is not allowed: give the values as Hydra's sweep syntax in a string, e.g. "
                              f"{key}: \"1,2\" or \"range(3)\"")
        if "${" in str(value):
            raise MagexpError(f"{text} is not allowed: interpolations (${{...}}) are not read in a job's values; give "
                              "the values themselves")
        spelled[str(key)] = f"{key}={value}"
    for ov in user:
        spelled[ov.partition("=")[0]] = ov
    return list(spelled.values())


def check_nested(parsed) -> None:
    """Refuse a sweep inside a list of values (``seed=range(5),7``): Hydra cannot expand it.

    Raises
    ------
    MagexpError
        One line naming the override."""
    for ov in parsed:
        value = ov.value()
        if isinstance(value, ChoiceSweep) and any(isinstance(v, Sweep) for v in value.list):
            raise MagexpError(f"{ov.input_line} is not allowed: a range() or list inside a list of values is not "
                              "expanded; write one list (seed=0,1,2,3,4,7) or one range()")
