"""``-m`` sweeps: every job through the run cache, and one tidy table at the end.

A sweep's folder holds one sub-folder per job (Hydra's ``<sweep dir>/<job number>/`` with its
``metrics.csv`` and ``.hydra/overrides.yaml``); :class:`SweepTable` (a Hydra callback, see
``conf/config.yaml``) gathers them into ``<sweep dir>/sweep.csv``: one row per job, the swept
keys first as columns (their values as typed on the command line), then ``job`` and the union
of the jobs' metric columns (a metric a job lacks is left empty).
"""

from __future__ import annotations

import csv
from pathlib import Path

from hydra.experimental.callback import Callback

TABLE = "sweep.csv"


def _job_overrides(job_dir: Path) -> dict[str, str]:
    from omegaconf import OmegaConf

    path = job_dir / ".hydra" / "overrides.yaml"
    if not path.exists():
        return {}
    return dict(str(o).split("=", 1) for o in OmegaConf.load(path) if "=" in str(o))


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
    tmp = path.with_suffix(".tmp")
    with tmp.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(columns), restval="")
        writer.writeheader()
        writer.writerows(rows)
    tmp.replace(path)
    return path


class SweepTable(Callback):
    """Hydra callback: after a multirun, write ``sweep.csv`` into the sweep folder."""

    def on_multirun_end(self, config, **kwargs) -> None:
        from magexp.cli_checks import swept_keys

        overrides = [str(o) for o in config.hydra.overrides.task]
        path = gather(config.hydra.sweep.dir, swept_keys(overrides))
        print(f"sweep table: {path}")
