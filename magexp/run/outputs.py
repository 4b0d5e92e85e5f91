"""A run's outputs: its folder (``metrics.csv``, ``estimate.csv``, ``history.csv``, ``config.yaml``)
and the table printed at the end of a command.

A single run (``magexp scenario=... seed=...``) and every job of a ``-m`` sweep go through the
same path: :func:`execute` runs the config through :func:`magexp.run.executor.run_many` (the run
cache, its per-key lock, the work limits), and :func:`write_outputs` writes the folder.
"""

from __future__ import annotations

import csv
from pathlib import Path

from omegaconf import OmegaConf

from magexp.core.atomic import atomic_open, write_text
from magexp.run.compose import resolved
from magexp.run.executor import run_many
from magexp.run.provenance import provenance


def print_table(rows: dict) -> None:
    """``key  value`` lines, keys aligned; floats with 6 significant digits."""
    width = max(len(k) for k in rows)
    for key, value in rows.items():
        print(f"{key:<{width}}  {value:.6g}" if isinstance(value, float) else f"{key:<{width}}  {value}")


def write_csv(path: Path, header: list[str], rows) -> None:
    """``path`` written atomically: ``header``, then ``rows``."""
    with atomic_open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows(rows)


def write_outputs(out, plain: dict, out_dir: Path, *, cached: bool) -> dict:
    """Write a run's folder: ``metrics.csv``, ``estimate.csv``, ``history.csv``, ``config.yaml``.

    ``metrics.csv`` is one row: the run's metrics, ``cached`` (whether the result came from the
    cache) and the provenance (:func:`magexp.run.provenance.provenance`); ``config.yaml`` is the
    resolved config ``plain`` the run read. Returns the metrics with ``cached``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    metrics = {**out.metrics, "cached": cached, **provenance(plain)}
    write_csv(out_dir / "metrics.csv", list(metrics), [list(metrics.values())])
    write_csv(out_dir / "estimate.csv", ["parameter", "x"], zip(out.parameter_names, out.x.tolist()))
    if plain.get("write_history", True):
        write_csv(out_dir / "history.csv", ["iteration", "nfev", "fun"],
                  zip(range(len(out.history)), out.history_nfev.tolist(), out.history.tolist()))
    write_text(out_dir / "config.yaml", OmegaConf.to_yaml(plain))
    return {**out.metrics, "cached": cached}


def execute(cfg, out_dir: Path, *, use_cache: bool = True) -> dict:
    """Run ``cfg`` in this process through the run cache (:func:`magexp.run.executor.run_many`) and
    write its outputs into ``out_dir`` (:func:`write_outputs`); returns its metrics."""
    plain = resolved(cfg)
    counts: dict = {}
    outputs = run_many([plain], jobs=1, use_cache=use_cache, counts=counts)
    return write_outputs(outputs[0], plain, out_dir, cached=counts["cached"] == 1)
