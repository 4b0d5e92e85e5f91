"""Command line: ``python -m magexp scenario=... estimator=... seed=...`` (Hydra; ``-m`` sweeps)."""

from __future__ import annotations

import sys
from pathlib import Path

import hydra
import pandas as pd
from omegaconf import DictConfig

from magexp.errors import MagexpError


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
    width = max(len(k) for k in out.metrics)
    for key, value in out.metrics.items():
        print(f"{key:<{width}}  {value:.6g}" if isinstance(value, float) else f"{key:<{width}}  {value}")
    print(f"{'written to':<{width}}  {out_dir}")
    return out.metrics


@hydra.main(version_base=None, config_path="../conf", config_name="config")
def _hydra_main(cfg: DictConfig):
    from hydra.core.hydra_config import HydraConfig

    try:
        return run_task(cfg, Path(HydraConfig.get().runtime.output_dir))
    except MagexpError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)


def main() -> None:
    """Entry point: check the overrides first (one-line errors), then hand over to Hydra."""
    from magexp.cli_checks import check_overrides

    args = [a for a in sys.argv[1:] if not a.startswith("-")]
    try:
        check_overrides(args)
    except MagexpError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    _hydra_main()


if __name__ == "__main__":
    main()
