"""The Hydra sweeper of ``magexp -m`` sweeps: the jobs magexp checked, launched in batches, each job composed once.

magexp expands a sweep (``a,b``, ``range()``, ``choice()``, globs, ``hydra.sweeper.params``) into its jobs
and checks every one of them before Hydra starts (:func:`magexp.run.preflight.expand_sweep`,
:func:`magexp.run.preflight.validate_runs`: one line on the first bad value, nothing written). This
sweeper, on Hydra's public :class:`~hydra.plugins.sweeper.Sweeper` interface, launches that same job
list (:func:`magexp.run.sweep.planned_jobs`: the sweep is expanded once), ``hydra.sweeper.max_batch_size``
jobs at a time, after saving the sweep's config as ``<sweep dir>/multirun.yaml`` as Hydra's basic
sweeper does. It does not compose each job a second time before launching it, as Hydra's basic sweeper
does (a sweep of 40 jobs: 4.0 times less CPU, ``docs/measurements.md``): magexp's launcher composes each
cell once (:func:`magexp.run.compose.compose_config`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from hydra.core.plugins import Plugins
from hydra.plugins.sweeper import Sweeper
from omegaconf import OmegaConf


class MagexpSweeper(Sweeper):
    """Launches the jobs magexp checked, in batches of ``max_batch_size`` (None: all at once)."""

    def __init__(self, max_batch_size: int | None = None, params: dict[str, str] | None = None) -> None:
        super().__init__()
        self.max_batch_size, self.params = max_batch_size, dict(params or {})
        self.hydra_context = self.config = self.launcher = None

    def setup(self, *, hydra_context, task_function, config) -> None:
        """Keep the sweep's config and instantiate its launcher (Hydra's plugin registry)."""
        self.hydra_context, self.config = hydra_context, config
        self.launcher = Plugins.instance().instantiate_launcher(hydra_context=hydra_context,
                                                                 task_function=task_function, config=config)

    def sweep(self, arguments: list[str]) -> Any:
        """Launch every job of ``params`` then ``arguments``; the launcher's job returns, one list per batch."""
        from magexp.run.sweep import planned_jobs  # imported on sweep: Hydra imports every plugin when composing

        jobs = planned_jobs([*(f"{key}={value}" for key, value in self.params.items()), *arguments])
        sweep_dir = Path(str(self.config.hydra.sweep.dir))
        sweep_dir.mkdir(parents=True, exist_ok=True)
        OmegaConf.save(self.config, sweep_dir / "multirun.yaml")
        size = self.max_batch_size or max(len(jobs), 1)
        returns = []
        for start in range(0, len(jobs), size):
            results = self.launcher.launch(jobs[start:start + size], initial_job_idx=start)
            for result in results:
                _ = result.return_value  # raises a failed job's error, as Hydra's basic sweeper does
            returns.append(results)
        return returns
