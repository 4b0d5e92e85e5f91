"""Guards of every entry point: where a command may write, and which values it refuses before it starts.

* :func:`check_destination`: an output folder a command may write into. Never an empty path
  (it would mean the working folder), never a filesystem root, and never inside ``results/``
  (:data:`magexp.paths.RESULTS`, compared as resolved paths, so ``results/x``, ``./results``
  and a symbolic link into it are all inside) unless the command is a canonical reproduction
  writing ``results/`` itself;
* :func:`check_subdir`, :func:`check_job_folders`: each sweep job's folder is its own, inside the sweep's folder;
* :func:`removed_on_failure`: what a command created is removed again when it fails
  (a refused or interrupted command leaves nothing behind);
* :func:`check_override_values`: command-line values are values (no ``${...}`` interpolation,
  which would read other keys, the environment or files), and a value Hydra's lexer cannot read
  (``data.unit=µT``) is quoted for it;
* :func:`check_run_values`: the values of a run config that no constructor checks
  (every number finite and of magnitude <= :data:`magexp.errors.LARGEST`, the geomagnetic field's
  ranges, ``write_history`` a boolean);
* :func:`readings_array`: an API caller's readings as an ``(N, 3)`` float array, refusing
  complex and masked input and anything that is not numbers;
* :class:`OneLineParser`: ``argparse`` whose errors are one line and exit 2 (not its usage);
* :func:`check_hydra_keys`, :func:`check_override_targets`: no code from an override. A command line
  changes only the ``hydra.*`` settings of :data:`HYDRA_KEYS`; a ``_target_`` it sets is checked by
  :func:`magexp.run.targets.check_target` (which the runner also applies to every node it builds)
  before Hydra reads it.

Every refusal is a :class:`~magexp.errors.MagexpError` of one line that names the value and what
is allowed.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import itertools
import os
import re
import shutil
import sys
import tempfile
from pathlib import Path, PurePosixPath

import numpy as np

from magexp import paths
from magexp.errors import LARGEST, MagexpError, check_positive_int
from magexp.run.keys import check_number
from magexp.run.targets import check_target, check_targets

#: The geomagnetic field's ranges (degrees): inclination from the horizontal, declination from north.
INCLINATION = (-90.0, 90.0)
DECLINATION = (-180.0, 360.0)
#: Dask scheduler addresses that name a cluster system instead of a host (:data:`magexp.run.executor.JOBQUEUES`).
CLUSTER_SYSTEMS = ("slurm", "pbs", "sge")
_ADDRESS = re.compile(r"(?:(?:tcp|tls|ucx|ws|wss)://)?(\[[0-9a-fA-F:]+\]|[A-Za-z0-9_.\-]+):([0-9]{1,5})/?")


# ---------------------------------------------------------------------------------------------
# where a command may write

def _results() -> Path:
    return paths.RESULTS.resolve()


def check_destination(folder, what: str, *, canonical: bool = False) -> Path:
    """The resolved output folder ``folder``, or one line saying why a command may not write there.

    Parameters
    ----------
    folder : str or Path
        The folder as the user gave it.
    what : str
        The option or key that named it (``--out``, ``hydra.run.dir``...), for the message.
    canonical : bool
        The command is a canonical reproduction: it may write ``results/`` itself (but no folder
        inside it: the canonical layout is ``results/<paper>/``, made by the command).

    Returns
    -------
    Path
        The resolved folder.
    """
    text = "" if folder is None else str(folder)
    if not text.strip():
        raise MagexpError(f"{what}={text!r} is not allowed: name a folder (an empty path would write into the "
                          "working folder)")
    path = Path(text).expanduser().resolve()
    if path == Path(path.anchor):
        raise MagexpError(f"{what}={text!r} is not allowed: it is the root folder {path.anchor!r}; name a folder "
                          "of its own")
    results = _results()
    if path == results and canonical:
        return path
    if path == results or results in path.parents:
        raise MagexpError(f"{what}={text!r} is not allowed: it is inside results/ ({results}), which only a "
                          "canonical reproduction writes; name a folder outside it")
    return path


@functools.lru_cache(maxsize=16)
def check_cache_folder(root: str) -> None:
    """A run cache (``$MAGEXP_CACHE``) or a cache beside it (the figures'), never inside ``results/``
    (:func:`check_destination`), checked before any command starts and before every cache write.

    Parameters
    ----------
    root : str
        The cache folder.
    """
    check_destination(root, "MAGEXP_CACHE (the run cache folder)")


def check_subdir(subdir: str, what: str = "hydra.sweep.subdir") -> None:
    """A sweep job's folder name: relative, not empty, and with no ``..``, so that every job's
    folder is a folder of its own inside the sweep's folder.

    Parameters
    ----------
    subdir : str
        The folder name.
    what : str
        The key naming it in messages.
    """
    text = str(subdir)
    parts = PurePosixPath(text.replace("\\", "/")).parts
    if not text.strip() or text.startswith(("/", "~")) or ".." in parts or all(p == "." for p in parts):
        raise MagexpError(f"{what}={text!r} is not allowed: it must be a relative folder name without '..' "
                          "(each job's folder inside the sweep's folder), e.g. ${{hydra.job.num}}")


def check_job_folders(folders: list[Path], sweep_dir: Path) -> None:
    """Each job's folder (``hydra.sweep.subdir`` resolved for it, whose overrides may hold a ``/``)
    strictly inside the sweep's folder, and no two jobs sharing one (the second would overwrite
    the first's files).

    Parameters
    ----------
    folders : list of pathlib.Path
        Each job's folder.
    sweep_dir : pathlib.Path
        The sweep's folder.
    """
    outer = Path(sweep_dir).resolve()
    seen: dict = {}
    for n, folder in enumerate(folders):
        inner = Path(folder).resolve()
        if outer not in inner.parents:
            raise MagexpError(f"hydra.sweep.subdir={str(folder.relative_to(sweep_dir))!r} is not allowed: job {n}'s "
                              f"folder must be inside the sweep's folder {str(outer)!r}")
        if inner in seen:
            raise MagexpError(f"hydra.sweep.subdir={str(folder.relative_to(sweep_dir))!r} is not allowed: jobs "
                              f"{seen[inner]} and {n} would share a folder; include ${{hydra.job.num}}")
        seen[inner] = n


@contextlib.contextmanager
def removed_on_failure(folder: Path, created: Path | None = None):
    """Undo what the block creates in ``folder`` if it fails (an exception, a non-zero exit, Ctrl-C).

    A folder that did not exist (or ``created``, the highest folder the caller made for it) is
    removed with every parent made for it; in a folder that existed, only the entries the block
    added are removed (what the user had is kept).

    Parameters
    ----------
    folder : pathlib.Path
        The folder the block writes into.
    created : pathlib.Path or None
        The highest folder the caller created for it.
    """
    folder = Path(folder).absolute()
    top = created if created is not None else first_missing(folder)
    before = set() if top is not None or not folder.is_dir() else {p.name for p in folder.iterdir()}
    try:
        yield
    except SystemExit as exc:
        if exc.code not in (0, None):
            _undo(folder, top, before)
        raise
    except BaseException:
        _undo(folder, top, before)
        raise


def _undo(folder: Path, top: Path | None, before: set) -> None:
    """Remove ``top`` (a folder made for the failed command), else the entries of ``folder`` not in ``before``."""
    if top is not None:
        shutil.rmtree(top, ignore_errors=True)
    elif folder.is_dir():
        for entry in folder.iterdir():
            if entry.name not in before:
                if entry.is_dir() and not entry.is_symlink():
                    shutil.rmtree(entry, ignore_errors=True)
                else:
                    entry.unlink(missing_ok=True)


# ---------------------------------------------------------------------------------------------
# command-line values

def check_override_values(overrides: list[str]) -> list[str]:
    """The ``KEY=VALUE`` overrides, checked and ready for Hydra's parser.

    A key is set, never added (``+key=``) or deleted (``~key``): the objects a config builds take
    the keys it has; only a config group the primary config leaves out is added, with one of its
    choices (``+analysis=field_kalman``). A value holding ``${`` is refused (an interpolation reads other keys, the environment or
    files: a command-line value must be the value itself); ``hydra.*`` settings keep theirs
    (``hydra.sweep.subdir=${hydra.job.num}``). A plain value with characters outside ASCII
    (``data.unit=µT``), which Hydra's lexer cannot read, is quoted for it.

    Parameters
    ----------
    overrides : list of str
        The command-line overrides.

    Returns
    -------
    list of str
        The checked overrides.
    """
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


#: what ``--cfg`` may show (Hydra's choices)
CFG_CHOICES = ("job", "hydra", "all")


def check_flags(flags: dict) -> None:
    """The options of ``magexp`` that Hydra would read, checked before Hydra sees them (whose own
    errors are its usage text, or exit 1): ``--cfg job|hydra|all``, ``--config-name`` naming a
    primary config of ``conf/``; ``--experimental-rerun`` (which unpickles a file) and ``--config-dir`` /
    ``--config-path`` (configs from elsewhere, with their own ``_target_``) are refused.

    Parameters
    ----------
    flags : dict
        Each ``--name`` flag to its value.
    """

    for flag in ("--cfg", "-c"):
        if flag in flags and flags[flag] not in CFG_CHOICES:
            raise MagexpError(f"{flag} {flags[flag]!r} is not allowed: choose one of {', '.join(CFG_CHOICES)}")
    names = ["config"]  # calibrate.yaml is magexp calibrate's own (magexp calibrate KEY=VALUE ...)
    for flag in ("--config-name", "-cn"):
        if flag in flags and flags[flag] not in names:
            raise MagexpError(f"{flag} {flags[flag]!r} is not allowed: choose one of {', '.join(names)}")
    if "--experimental-rerun" in flags:
        raise MagexpError(f"--experimental-rerun {flags['--experimental-rerun']!r} is not allowed: it unpickles a "
                          "file, which can run any code; rerun with the overrides of the run's config.yaml")
    for flag in ("--config-dir", "-cd", "--config-path", "-cp"):
        if flag in flags:
            raise MagexpError(f"{flag} {flags[flag]!r} is not allowed: configs come from magexp's conf/ only (a "
                              "folder of configs would name its own code); add a config there (docs/extending.md)")


def _numbers(node, where: str):
    """``(dotted key, number)`` of every number in a plain config container."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _numbers(v, f"{where}.{k}" if where else str(k))
    elif isinstance(node, (list, tuple)):
        for i, v in enumerate(node):
            yield from _numbers(v, f"{where}[{i}]")
    elif isinstance(node, (int, float)) and not isinstance(node, bool):
        yield where, node


def check_run_values(plain: dict) -> None:
    """Values of a resolved run config that no constructor checks, refused in one line.

    * every number of ``scenario`` and ``estimator`` finite, of magnitude <= :data:`LARGEST`
      (``hard_iron=[1e308,0,0]`` would overflow the simulation into a singular matrix), zero or of
      magnitude >= :data:`magexp.run.keys.SMALLEST` (:func:`magexp.run.keys.check_number`);
    * ``scenario.field``: a vector not zero; ``total`` > 0, ``inclination`` in :data:`INCLINATION`,
      ``declination`` in :data:`DECLINATION` (degrees);
    * ``write_history``: true or false.

    Parameters
    ----------
    plain : dict
        The resolved run config.
    """
    for group in ("scenario", "estimator"):
        for key, value in _numbers(plain.get(group) or {}, group):
            check_number(value, key)
    _check_field((plain.get("scenario") or {}).get("field"))
    history = plain.get("write_history", True)
    if not isinstance(history, bool):
        raise MagexpError(f"write_history={history!r} is not allowed: choose true or false")


def _check_field(field) -> None:
    """``scenario.field``: a vector not zero, or ``total`` > 0 and the angles in their ranges."""
    if isinstance(field, list) and not any(v != 0 for v in field if isinstance(v, (int, float))):
        raise MagexpError(f"scenario.field={field!r} is not allowed: the field vector must not be zero (nT)")
    if isinstance(field, dict):
        total = field.get("total")
        if isinstance(total, (int, float)) and not total > 0:
            raise MagexpError(f"scenario.field.total={total!r} is not allowed: the field's total intensity must be "
                              "a number > 0 (nT)")
        for name, (lo, hi) in (("inclination", INCLINATION), ("declination", DECLINATION)):
            value = field.get(name)
            if isinstance(value, (int, float)) and not lo <= value <= hi:
                raise MagexpError(f"scenario.field.{name}={value!r} is not allowed: it must be in [{lo:g}, {hi:g}] "
                                  "degrees")


def check_scheduler_address(scheduler) -> None:
    """A Dask scheduler: None (a local cluster), a cluster system (slurm, pbs, sge) or an address
    with a port (``tcp://host:8786``, ``host:8786``).

    Parameters
    ----------
    scheduler : str or None
        The scheduler setting.
    """
    if scheduler is None or scheduler in CLUSTER_SYSTEMS:
        return
    match = _ADDRESS.fullmatch(str(scheduler))
    if not match or not 0 < int(match.group(2)) < 65536:
        raise MagexpError(f"--scheduler {scheduler!r} is not allowed: give tcp://HOST:PORT (e.g. tcp://node1:8786), "
                          f"or one of {', '.join(CLUSTER_SYSTEMS)}")


def check_folds(folds) -> int:
    """The held-out check's folds: an integer >= 0 (0 or 1: no held-out check).

    Parameters
    ----------
    folds : object
        The folds setting.

    Returns
    -------
    int
        The folds.
    """
    if isinstance(folds, str):
        raise MagexpError(f"folds={folds!r} is not allowed: it must be an integer >= 0 (0: no held-out check)")
    return check_positive_int(folds, "folds", minimum=0)


# ---------------------------------------------------------------------------------------------
# readings given to the Python API

def readings_array(readings):
    """``readings`` as a float array, or one line: complex numbers and masked arrays are refused
    (their imaginary part and their mask would be dropped silently), as is anything that is not
    numbers.

    Parameters
    ----------
    readings : array_like
        The readings.

    Returns
    -------
    numpy.ndarray
        The readings as floats.
    """
    if np.ma.isMaskedArray(readings):
        raise MagexpError("masked readings are not allowed: a masked array's hidden values would be used; give "
                          "only the valid readings (readings[~readings.mask.any(axis=1)].data)")
    if readings is None or isinstance(readings, (bytes, dict, set)):
        raise MagexpError(f"readings of type {type(readings).__name__} are not allowed: give an (N, 3) array, "
                          "a DataFrame or a recording's path")
    try:
        raw = np.asarray(readings)
    except (TypeError, ValueError) as exc:
        raise MagexpError(f"readings are not allowed: they are not an array of numbers ({str(exc)[:80]})") from None
    if np.iscomplexobj(raw):
        raise MagexpError("complex readings are not allowed: a magnetometer reading is real; give the real (N, 3) "
                          "array")
    if raw.dtype.kind not in "biuf":
        try:
            raw = raw.astype(float)
        except (TypeError, ValueError):
            raise MagexpError(f"readings of type {raw.dtype} are not allowed: every value must be a number") from None
        if np.iscomplexobj(raw):
            raise MagexpError("complex readings are not allowed: a magnetometer reading is real")
    values = raw.astype(float)
    if values.size and not np.all(np.abs(values[np.isfinite(values)]) <= LARGEST):
        raise MagexpError(f"readings larger than {LARGEST:g} in magnitude are not allowed")
    return values


# ---------------------------------------------------------------------------------------------

class OneLineParser(argparse.ArgumentParser):
    """``argparse`` whose every error is one line on stderr and exit 2 (``--help`` still prints the usage)."""

    def error(self, message: str):
        """Print ``message``'s first line (not the usage text) and exit with code 2.

        Parameters
        ----------
        message : str
            What argparse refused.
        """
        print(f"error: {message.splitlines()[0]} (see {self.prog} --help)", file=sys.stderr)
        sys.exit(2)


def check_output_folder(folder: Path | str, what: str = "output folder", *, canonical: bool = False) -> Path:
    """Fail unless ``folder`` is (or can be created as) a writable directory a command may write
    (:func:`magexp.run.guard.check_destination`: not empty, not a root, not inside ``results/`` unless
    ``canonical``); create nothing.

    Parameters
    ----------
    folder : pathlib.Path or str
        The folder.
    what : str
        What it is, named in messages.
    canonical : bool
        Allow a folder inside ``results/``.

    Returns
    -------
    pathlib.Path
        The folder as a path.
    """
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
    removing it after a failure leaves no trace of the folders made for it.

    Parameters
    ----------
    folder : pathlib.Path
        The folder.

    Returns
    -------
    pathlib.Path or None
        The highest missing folder.
    """
    if folder.exists():
        return None
    top = folder
    while not top.parent.exists():
        top = top.parent
    return top


def create_unique(folder: Path | str) -> tuple[Path, Path]:
    """Create ``folder`` exclusively; if it exists, ``folder-2``, ``folder-3``...: two runs started
    in the same second never share a folder. Returns ``(folder, top)``, ``top`` the highest
    folder this call created (remove it to leave no trace).

    Parameters
    ----------
    folder : pathlib.Path or str
        The folder wanted.

    Returns
    -------
    tuple of pathlib.Path
        ``(folder, top)``.
    """
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


# ---------------------------------------------------------------------------------------------
# code named by an override or a config: ``_target_`` and Hydra's own settings

#: the ``hydra.*`` settings a command line may change (``.``-ended: every key below it): folders,
#: the launcher's and sweeper's settings, a job's name and folder naming, and the choice of Hydra's
#: launcher, sweeper and logging configs. Anything else (``hydra.callbacks``, ``hydra.searchpath``,
#: ``hydra.job.env_set``, ``hydra.job_logging.*``...) names code or moves where configs come from.
HYDRA_KEYS = ("hydra.run.dir", "hydra.sweep.dir", "hydra.sweep.subdir", "hydra.launcher.", "hydra.sweeper.params",
              "hydra.sweeper.max_batch_size", "hydra.job.chdir", "hydra.job.name", "hydra.job.config.override_dirname.",
              "hydra.verbose", "hydra/launcher", "hydra/sweeper", "hydra/job_logging", "hydra/hydra_logging")


def check_hydra_keys(overrides: list[str]) -> None:
    """Refuse a ``hydra.*`` override outside :data:`HYDRA_KEYS`, in one line, before Hydra reads it.

    Parameters
    ----------
    overrides : list of str
        The ``hydra.*`` overrides.
    """
    for ov in overrides:
        key = ov.partition("=")[0].lstrip("+~")
        if not key.startswith("hydra"):
            continue
        if key.endswith("._target_"):  # checked by check_override_targets
            continue
        if not any(key == k or (k.endswith(".") and key.startswith(k)) or key == k.rstrip(".") for k in HYDRA_KEYS):
            raise MagexpError(f"{ov.partition('=')[0]} is not allowed on the command line: it would name code or "
                              "where configs come from; magexp takes hydra.run.dir, hydra.sweep.dir|subdir, "
                              "hydra.launcher.*, hydra.sweeper.params and hydra/launcher=...")


def check_override_targets(overrides: list[str]) -> None:
    """Every ``_target_`` an override sets (``estimator._target_=...``, or inside a value such as
    ``estimator.velocity={_target_: ...}``) checked by :func:`check_target` before Hydra sees it.

    Parameters
    ----------
    overrides : list of str
        The command-line overrides.
    """
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

