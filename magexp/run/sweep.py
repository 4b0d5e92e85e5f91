"""``-m`` sweeps: every job through magexp's executor and run cache, and one tidy table at the end.

Hydra's sweeper expands a sweep into jobs; magexp's launcher (the default,
``hydra_plugins/magexp_launcher``) hands each batch of them to :func:`launch`, which

1. composes every job with :func:`magexp.run.compose.compose_config` (Hydra's compose), once per cell: the
   jobs that differ only in ``seed`` share one composed config, each job's seed set on it;
2. runs the batch with :func:`magexp.run.executor.run_many`, the layer behind ``make reproduce``:
   each distinct run once, through the same run cache (a killed sweep, started again, redoes
   only the unfinished runs), in tasks of one scenario and a block of seeds, on local processes
   (``hydra.launcher.executor=local``, ``hydra.launcher.jobs=N``) or a Dask cluster
   (``hydra.launcher.executor=dask``, ``hydra.launcher.scheduler=...``);
3. writes each job's folder ``<sweep dir>/<hydra.sweep.subdir>/`` (by default the job number):
   the run's ``metrics.csv``, ``estimate.csv``, ``history.csv`` and ``config.yaml``
   (:func:`magexp.run.outputs.write_outputs`) and ``.hydra/overrides.yaml``.

:class:`SweepTable` (a Hydra callback, see ``conf/config.yaml``) then gathers the job folders into
``<sweep dir>/sweep.csv``: one row per job, the swept keys first as columns (their values as typed
on the command line), then ``job`` and the union of the jobs' metric columns (a metric a job lacks
is left empty). magexp's launcher does not call Hydra's per-job callbacks (``on_job_start``,
``on_job_end``) or set up a job's logging: no Hydra job runs. Hydra's other launchers (``hydra/launcher=basic|joblib|slurm``) still work, one
Hydra job at a time (:func:`magexp.run.command.sweep_job`), with the same run cache.
"""

from __future__ import annotations

import csv
import logging
from collections.abc import Sequence
from pathlib import Path

import yaml
from hydra.core.utils import JobReturn, JobStatus, filter_overrides
from hydra.experimental.callback import Callback
from omegaconf import OmegaConf, open_dict

from magexp.core.atomic import atomic_open, write_text
from magexp.errors import MagexpError
from magexp.run.compose import apply_overrides, compose_config, hydra_compose, resolved
from magexp.run.executor import run_many
from magexp.run.executors import check_executor, make_executor
from magexp.run.folders import check_job_folders
from magexp.run.hydra_cli import check_hydra_node
from magexp.run.outputs import write_outputs
from magexp.run.preflight import expand_sweep, swept_keys
from magexp.run.progress import Progress

TABLE = "sweep.csv"
#: the jobs of the sweep under way, by its overrides: the list magexp checked, which its sweeper launches
_PLANNED: dict[tuple[str, ...], list[list[str]]] = {}


def plan_jobs(overrides: list[str], jobs: list[list[str]]) -> None:
    """Hand the jobs of a checked sweep to the sweeper that launches them (:func:`planned_jobs`)."""
    _PLANNED[tuple(overrides)] = jobs


def planned_jobs(overrides: list[str]) -> list[list[str]]:
    """The jobs of the sweep of ``overrides``: those :func:`plan_jobs` handed over (the sweep expanded once),
    else expanded and counted now (a sweep Hydra started without magexp's command)."""
    jobs = _PLANNED.pop(tuple(overrides), None)
    return jobs if jobs is not None else expand_sweep(overrides)


def _job_overrides(job_dir: Path) -> dict[str, str]:
    """``{key: value}`` of the overrides Hydra recorded for the job in ``job_dir`` (empty if none)."""
    path = job_dir / ".hydra" / "overrides.yaml"
    if not path.exists():
        return {}
    return dict(str(o).split("=", 1) for o in yaml.safe_load(path.read_text()) or [] if "=" in str(o))


def gather(sweep_dir: Path | str, keys: list[str]) -> Path:
    """Write ``sweep_dir/sweep.csv`` from the job folders' ``metrics.csv``; return its path."""
    sweep_dir = Path(sweep_dir)
    jobs = sorted((p.parent for p in sweep_dir.glob("*/metrics.csv")),
                  key=lambda p: (0, int(p.name)) if p.name.isdigit() else (1, p.name))
    rows, columns = [], {k: None for k in keys}
    columns["job"] = None
    for job in jobs:
        with (job / "metrics.csv").open(newline="") as fh:
            metrics = next(csv.DictReader(fh), {})
        chosen = _job_overrides(job)
        row = {**{k: chosen.get(k, "") for k in keys}, "job": job.name,
               **{k: v for k, v in metrics.items() if k not in keys}}
        columns.update(dict.fromkeys(row))
        rows.append(row)
    path = sweep_dir / TABLE
    with atomic_open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(columns), restval="")
        writer.writeheader()
        writer.writerows(rows)
    return path


class SweepTable(Callback):
    """Hydra callback: after a multirun, write ``sweep.csv`` into the sweep folder."""

    def on_multirun_end(self, config, **kwargs) -> None:
        """Write the sweep's table (:func:`gather`) when the sweep ends."""
        overrides = [str(o) for o in config.hydra.overrides.task]
        path = gather(config.hydra.sweep.dir, swept_keys(overrides))
        print(f"sweep table: {path}")


#: the ``hydra.launcher.*`` settings of magexp's launcher, as :func:`magexp.run.executors.check_executor`'s options
SETTINGS = {"executor": "--executor", "jobs": "--jobs", "scheduler": "--scheduler"}


def check_settings(settings: dict) -> None:
    """Refuse bad ``hydra.launcher.*`` settings in one line naming the setting (the executor's rules)."""

    try:
        check_executor(settings["executor"], settings["jobs"], settings["scheduler"])
    except MagexpError as exc:
        message = str(exc)
        for key, option in SETTINGS.items():
            message = message.replace(f"{option} ", f"hydra.launcher.{key}=")
        raise MagexpError(message) from None


def check_hydra_settings(settings: list[str]):
    """Check a sweep's ``hydra.*`` overrides before anything is written (one line on the first bad one):
    Hydra composes its own node with them, then magexp's launcher settings are checked if it is the
    launcher chosen."""

    node = hydra_compose(tuple(settings), with_hydra=True).hydra
    check_hydra_node(node)
    launcher = node.launcher
    if str(launcher.get("_target_", "")).startswith("hydra_plugins.magexp_launcher."):
        check_settings({key: launcher.get(key) for key in SETTINGS})
    return node


def job_subdir(config, num: int, overrides: Sequence[str]) -> str:
    """The folder name of job ``num``: ``hydra.sweep.subdir`` resolved for it (by default ``num``)."""

    raw = OmegaConf.to_container(config.hydra.sweep, resolve=False)["subdir"]
    if raw == "${hydra.job.num}":
        return str(num)

    node = OmegaConf.create({"hydra": OmegaConf.to_container(config.hydra, resolve=False)})
    with open_dict(node):
        node.hydra.job.num = node.hydra.job.id = num
        dirname = node.hydra.job.config.override_dirname
        items = sorted(o for o in filter_overrides(overrides) if o.split("=", 1)[0] not in dirname.exclude_keys)
        node.hydra.job.override_dirname = dirname.item_sep.join(o.replace("=", dirname.kv_sep, 1) for o in items)
    return str(node.hydra.sweep.subdir)


def _configs(jobs: list[list[str]]) -> list[dict]:
    """The resolved config of each job; jobs that differ only in ``seed`` (a cell) are composed once,
    and each job's seed set on that config (Hydra's override step)."""

    composed: dict[tuple, object] = {}
    plains = []
    for job in jobs:
        rest = tuple(o for o in job if o.partition("=")[0] != "seed")
        seeds = [o.partition("=")[2] for o in job if o.partition("=")[0] == "seed"]
        if rest not in composed:
            composed[rest] = compose_config(list(rest))
        cfg = composed[rest]
        if seeds:
            apply_overrides(cfg, [f"seed={seeds[-1]}"])
        plains.append(resolved(cfg))
    return plains


def _quiet_dask() -> None:
    """Dask's cluster messages (INFO, set per logger when ``distributed`` is imported) would print through
    Hydra's log handler on every sweep: warnings and errors only."""

    import distributed  # noqa: F401  (configures its loggers first; imported only for a Dask sweep: 1 s)

    for name in list(logging.root.manager.loggerDict):
        if name.split(".")[0] == "distributed":
            logging.getLogger(name).setLevel(logging.WARNING)


def launch(config, job_overrides: Sequence[Sequence[str]], initial_job_idx: int, settings: dict) -> list:
    """Run a batch of sweep jobs through :func:`magexp.run.executor.run_many`; Hydra's job returns.

    ``settings``: ``executor`` (``local`` | ``dask``), ``jobs`` (0: all cores) and ``scheduler``
    (:func:`magexp.run.executors.make_executor`). A job's ``cached`` column says whether its result
    was read from the run cache (a valid entry; a damaged one is recomputed and says False)."""
    check_settings(settings)
    jobs = [list(o) for o in job_overrides]
    plains = _configs(jobs)
    sweep_dir = Path(str(config.hydra.sweep.dir))
    folders = [sweep_dir / job_subdir(config, initial_job_idx + n, job) for n, job in enumerate(jobs)]
    check_job_folders(folders, sweep_dir)  # before the first run
    progress = Progress(len(plains), "sweep")
    if settings["executor"] == "local":
        outputs = run_many(plains, jobs=settings["jobs"], progress=progress)
    else:
        _quiet_dask()
        with make_executor(settings["executor"], jobs=settings["jobs"], scheduler=settings["scheduler"]) as ex:
            outputs = run_many(plains, executor=ex, progress=progress)
    returns = []
    for n, (job, plain, folder) in enumerate(zip(jobs, plains, folders)):
        metrics = write_outputs(outputs[n], plain, folder, cached=outputs.was_cached(n))
        (folder / ".hydra").mkdir(exist_ok=True)
        write_text(folder / ".hydra" / "overrides.yaml", OmegaConf.to_yaml(job))
        returns.append(JobReturn(overrides=job, working_dir=str(folder), task_name=str(config.hydra.job.name),
                                 status=JobStatus.COMPLETED, _return_value=metrics))
    return returns
