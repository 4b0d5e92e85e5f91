"""Command line (Hydra; ``-m`` sweeps).

* ``python -m magexp scenario=... estimator=... seed=...``: one simulated run (``task=run``, default);
* ``python -m magexp calibrate data.path=mine.csv [data.unit=uT] estimator=lm [out=folder]``:
  calibrate a recording (:mod:`magexp.calibration`, its own config ``conf/calibrate.yaml``).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import hydra
import pandas as pd
from omegaconf import DictConfig

from magexp.errors import MagexpError


TASKS = ("run", "calibrate")


def print_table(rows: dict) -> None:
    """``key  value`` lines, keys aligned; floats with 6 significant digits."""
    width = max(len(k) for k in rows)
    for key, value in rows.items():
        print(f"{key:<{width}}  {value:.6g}" if isinstance(value, float) else f"{key:<{width}}  {value}")


def calibrate_task(cfg: DictConfig, out_dir: Path) -> dict:
    """``task=calibrate`` moved to its own command."""
    raise MagexpError("task=calibrate is not allowed: calibrate a recording with "
                      "`magexp calibrate data.path=<file> [data.unit=uT] [estimator=lm]`")


def run_task(cfg: DictConfig, out_dir: Path) -> dict:
    """Run one configuration, print its final metrics, write tidy rows into ``out_dir``."""
    from magexp.runner import run

    out = run(cfg)
    out_dir.mkdir(parents=True, exist_ok=True)
    pd.DataFrame([out.metrics]).to_csv(out_dir / "metrics.csv", index=False)
    pd.DataFrame({"x": out.x}, index=out.parameter_names).rename_axis("parameter").to_csv(out_dir / "estimate.csv")
    if cfg.get("write_history", True):
        pd.DataFrame({"iteration": range(len(out.history)), "nfev": out.history_nfev, "fun": out.history}).to_csv(
            out_dir / "history.csv", index=False)
    print_table({**out.metrics, "written to": out_dir})
    return out.metrics


@hydra.main(version_base=None, config_path="../conf", config_name="config")
def _hydra_main(cfg: DictConfig):
    from hydra.core.hydra_config import HydraConfig

    try:
        task = cfg.get("task", "run")
        if task not in TASKS:
            raise MagexpError(f"task={task!r} is not allowed: choose one of {', '.join(TASKS)}")
        return (calibrate_task if task == "calibrate" else run_task)(cfg, Path(HydraConfig.get().runtime.output_dir))
    except MagexpError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    except OSError as exc:  # a file or folder the user named
        print(f"error: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        sys.exit(2)
    except Exception as exc:  # a bug: still one line; MAGEXP_DEBUG=1 shows the traceback
        if os.environ.get("MAGEXP_DEBUG"):
            raise
        first = str(exc).splitlines()[0] if str(exc) else ""
        print(f"error: unexpected {type(exc).__name__}: {first} (rerun with MAGEXP_DEBUG=1 for details)",
              file=sys.stderr)
        sys.exit(3)


def main() -> None:
    """Entry point: check the overrides first (one-line errors), then hand over to Hydra."""
    from magexp.cli_checks import check_overrides

    if sys.argv[1:2] == ["calibrate"]:  # its own command and primary config (conf/calibrate.yaml)
        from magexp.calibration import main as calibrate_main

        sys.exit(calibrate_main(sys.argv[2:]))
    args = [a for a in sys.argv[1:] if not a.startswith("-")]
    try:
        check_overrides(args)
    except MagexpError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    _hydra_main()


if __name__ == "__main__":
    main()
