"""What a command line's ``KEY=VALUE`` overrides may say, checked before Hydra reads them.

* :func:`check_override_values`: command-line values are values (no ``${...}`` interpolation,
  which would read other keys, the environment or files), a key is set and never added or deleted,
  and a value Hydra's lexer cannot read (``data.unit=µT``) is quoted for it;
* :func:`check_hydra_keys`, :func:`check_override_targets`: no code from an override. A command line
  changes only the ``hydra.*`` settings of :data:`HYDRA_KEYS`; a ``_target_`` it sets is checked by
  :func:`magexp.run.targets.check_target` (which the runner also applies to every node it builds)
  before Hydra reads it.

Every refusal is a :class:`~magexp.errors.MagexpError` of one line that names the override and what
is allowed.
"""

from __future__ import annotations

from magexp import paths
from magexp.errors import MagexpError
from magexp.run.targets import check_target, check_targets


def check_override_values(overrides: list[str]) -> list[str]:
    """The ``KEY=VALUE`` overrides, checked and ready for Hydra's parser.

    A key is set, never added (``+key=``) or deleted (``~key``): the objects a config builds take
    the keys it has; only a config group the primary config leaves out is added, with one of its
    choices (``+analysis=field_kalman``). A value holding ``${`` is refused (an interpolation reads other keys, the environment or
    files: a command-line value must be the value itself); ``hydra.*`` settings keep theirs
    (``hydra.sweep.subdir=${hydra.job.num}``). A plain value with characters outside ASCII
    (``data.unit=µT``), which Hydra's lexer cannot read, is quoted for it."""
    out = []
    for ov in overrides:
        key, sep, value = ov.partition("=")
        if key.startswith("+") and _addable_group(key[1:]):
            choices = sorted(p.stem for p in (paths.CONF / key[1:]).glob("*.yaml"))
            if value not in choices:
                raise MagexpError(f"{ov} is not allowed: choose one of {', '.join(choices)}")
            out.append(ov)
            continue
        if key.startswith(("+", "~")) and not key.lstrip("+~").startswith("hydra"):
            raise MagexpError(f"{ov} is not allowed: an override sets a key the config has (magexp --cfg job lists "
                              f"them); adding (+) or deleting (~) a key would be ignored or break the run")
        if sep and "${" in value and not key.lstrip("+~").startswith("hydra"):
            raise MagexpError(f"{ov} is not allowed: interpolations (${{...}}) are not read from the command line; "
                              f"give the value itself, e.g. {key}=2")
        if sep and not value.isascii() and not any(c in value for c in "'\"[]{}(),\\ "):
            ov = f"{key}='{value}'"
        out.append(ov)
    return out


def _addable_group(name: str) -> bool:
    """Whether ``name`` is a config group of ``conf/`` that the primary config leaves out, so a run
    adds it with ``+name=choice`` (``+analysis=field_kalman``: an analysis step after the fit)."""
    return name.isidentifier() and name not in ("scenario", "estimator", "hydra") and (paths.CONF / name).is_dir()



#: the ``hydra.*`` settings a command line may change (``.``-ended: every key below it): folders,
#: the launcher's and sweeper's settings, a job's name and folder naming, and the choice of Hydra's
#: launcher, sweeper and logging configs. Anything else (``hydra.callbacks``, ``hydra.searchpath``,
#: ``hydra.job.env_set``, ``hydra.job_logging.*``...) names code or moves where configs come from.
HYDRA_KEYS = ("hydra.run.dir", "hydra.sweep.dir", "hydra.sweep.subdir", "hydra.launcher.", "hydra.sweeper.params",
              "hydra.sweeper.max_batch_size", "hydra.job.chdir", "hydra.job.name", "hydra.job.config.override_dirname.",
              "hydra.verbose", "hydra/launcher", "hydra/sweeper", "hydra/job_logging", "hydra/hydra_logging")


def check_hydra_keys(overrides: list[str]) -> None:
    """Refuse a ``hydra.*`` override outside :data:`HYDRA_KEYS`, in one line, before Hydra reads it."""
    for ov in overrides:
        key = ov.partition("=")[0].lstrip("+~")
        if not key.startswith("hydra"):
            continue
        if key.endswith("._target_"):  # checked by check_override_targets
            continue
        if not any(key == k or (k.endswith(".") and key.startswith(k)) or key == k.rstrip(".") for k in HYDRA_KEYS):
            raise MagexpError(f"{ov.partition('=')[0]} is not allowed on the command line: magexp takes hydra.run.dir, "
                              "hydra.sweep.dir|subdir, hydra.launcher.*, hydra.sweeper.params|max_batch_size, "
                              "hydra.job.name|chdir, hydra.job.config.override_dirname.*, hydra.verbose and "
                              "hydra/launcher|sweeper|job_logging|hydra_logging=... (docs/guide/limits.md)")


def check_override_targets(overrides: list[str]) -> None:
    """Every ``_target_`` an override sets (``estimator._target_=...``, or inside a value such as
    ``estimator.velocity={_target_: ...}``) checked by :func:`check_target` before Hydra sees it."""
    for ov in overrides:
        key, _, value = ov.partition("=")
        where = key.lstrip("+~")
        if where.startswith("hydra.sweeper.params") and "_target_" in ov:
            raise MagexpError(f"{key} is not allowed to set a _target_: set the key itself (estimator._target_=...)")
        if where.endswith("_target_"):
            check_target(where.rpartition(".")[0], value)
        elif "_target_" in value:
            try:  # Hydra's grammar, loaded only for such a value (its import: 0.1 s, measured with -X importtime)
                from hydra.core.override_parser.overrides_parser import OverridesParser

                parsed = OverridesParser.create().parse_override(f"k={value}").value()
            except Exception:
                raise MagexpError(f"{key}={value[:40]!r} is not allowed: a _target_ must be a class name") from None
            check_targets(parsed, where)
