"""The Hydra launcher of ``magexp -m`` sweeps: every job through :mod:`magexp.run.executor`.

Hydra's sweeper expands the sweep (``a,b``, ``range()``, globs, ``hydra.sweeper.params``) and
hands each batch of jobs to :meth:`MagexpLauncher.launch`, which runs it with
:func:`magexp.run.sweep.launch`: each cell composed once with Hydra's compose, the batch run by
:func:`magexp.run.executor.run_many` (the run cache and the executors of ``make reproduce``), each
job's folder written. Its settings (``conf/hydra/launcher/magexp.yaml``)::

    hydra.launcher.executor=local|dask   # where the runs execute
    hydra.launcher.jobs=N                # processes or Dask workers (0: all cores)
    hydra.launcher.scheduler=...         # dask: null (a LocalCluster), tcp://host:8786, slurm, pbs, sge

Hydra finds this class by scanning the ``hydra_plugins`` namespace (magexp's package list ships it).
"""

from __future__ import annotations

from collections.abc import Sequence

from hydra.plugins.launcher import Launcher

from magexp.errors import guarded


class MagexpLauncher(Launcher):
    """Runs a batch of sweep jobs through :func:`magexp.run.sweep.launch`."""

    def __init__(self, executor: str = "local", jobs: int = 0, scheduler: str | None = None) -> None:
        super().__init__()
        self.executor, self.jobs, self.scheduler = executor, jobs, scheduler
        self.config = None

    def setup(self, *, hydra_context, task_function, config) -> None:
        self.config = config

    def launch(self, job_overrides: Sequence[Sequence[str]], initial_job_idx: int):
        # imported on launch: Hydra imports every plugin whenever it composes a config
        from magexp.run.sweep import launch

        return guarded(launch, self.config, job_overrides, initial_job_idx,
                       {"executor": self.executor, "jobs": self.jobs, "scheduler": self.scheduler})

