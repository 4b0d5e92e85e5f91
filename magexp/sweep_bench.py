"""Per-job cost of a ``-m`` sweep, launcher against launcher, measured side by side.

``python -m magexp.sweep_bench`` runs the same sweep (by default the 40-job closed-form sweep
``-m scenario=ding2024_exp1 estimator=ellipsoid seed='range(40)'``) as whole commands, one
variant after the other in every round (so that the machine's load falls on each alike), every
command with an empty run cache (each run computed) and a warm composed-config cache, and prints
per variant the median over rounds of the wall time and of the CPU time (the command and every
process it started) per job, with their ratios to the first variant. Variants:

* ``hydra-basic``: Hydra's basic launcher, one Hydra job after the other (the path before sweeps
  went through :mod:`magexp.executor`);
* ``hydra-joblib-2``: Hydra's joblib launcher on 2 processes (the former default);
* ``magexp-1`` / ``magexp-2``: magexp's launcher (:func:`magexp.sweep.launch`) in the command's own
  process / on 2 worker processes.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SWEEP = ["scenario=ding2024_exp1", "estimator=ellipsoid", "seed=range(40)"]
VARIANTS = {"hydra-basic": ["hydra/launcher=basic"],
            "hydra-joblib-2": ["hydra/launcher=joblib", "hydra.launcher.n_jobs=2"],
            "magexp-1": ["hydra.launcher.jobs=1"],
            "magexp-2": ["hydra.launcher.jobs=2"]}


def timed(command: list[str], env: dict) -> tuple[float, float]:
    """Wall and CPU seconds (user + system, of the command and its descendants that were waited for)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def measure(commands: dict[str, list[str]], rounds: int, fresh_env) -> dict[str, list[tuple[float, float]]]:
    """``{name: [(wall, cpu) per round]}``, the commands alternating within each round;
    ``fresh_env(name, round)`` gives each command's environment."""
    times: dict[str, list] = {name: [] for name in commands}
    for k in range(rounds):
        for name, command in commands.items():
            times[name].append(timed(command, fresh_env(name, k)))
    return times


def table(times: dict[str, list[tuple[float, float]]], n_jobs: int) -> list[str]:
    """One line per variant: median wall and CPU per job (ms) and their ratios to the first variant."""
    med = {name: (statistics.median(t[0] for t in ts) / n_jobs, statistics.median(t[1] for t in ts) / n_jobs)
           for name, ts in times.items()}
    wall0, cpu0 = next(iter(med.values()))
    lines = [f"{'variant':<16}{'wall/job ms':>12}{'cpu/job ms':>12}{'wall ratio':>12}{'cpu ratio':>11}"]
    for name, (wall, cpu) in med.items():
        lines.append(f"{name:<16}{wall * 1e3:>12.1f}{cpu * 1e3:>12.1f}{wall / wall0:>12.3f}{cpu / cpu0:>11.3f}")
    return lines


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m magexp.sweep_bench", description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5, help="rounds of alternating variants (default 5)")
    parser.add_argument("--only", nargs="+", choices=list(VARIANTS), help="variants to run (default: all)")
    parser.add_argument("sweep", nargs="*", default=SWEEP, help="the sweep's overrides (default: %(default)s)")
    args = parser.parse_args(argv)
    from magexp.cli_checks import expand_sweep

    n_jobs = len(expand_sweep(args.sweep))
    chosen = {name: VARIANTS[name] for name in (args.only or VARIANTS)}
    with tempfile.TemporaryDirectory(prefix="magexp-sweep-bench-") as tmp:
        root = Path(tmp)
        base = [sys.executable, "-m", "magexp", "-m", *args.sweep]
        commands = {name: [*base, *extra, f"hydra.sweep.dir={root / 'sweeps' / name}"] for name, extra in chosen.items()}
        warm = root / "warm" / "runs"  # compose every config once: later commands find them composed
        subprocess.run([*base, "seed=0", f"hydra.sweep.dir={root / 'warm' / 'sweep'}"], check=True,
                       env={**os.environ, "MAGEXP_CACHE": str(warm)}, stdout=subprocess.DEVNULL)

        def fresh_env(name: str, k: int) -> dict:
            runs = root / f"{name}-{k}" / "runs"
            shutil.copytree(warm.parent / "runs-configs", runs.parent / "runs-configs")
            shutil.rmtree(root / "sweeps" / name, ignore_errors=True)
            return {**os.environ, "MAGEXP_CACHE": str(runs)}

        times = measure(commands, args.rounds, fresh_env)
    print(f"{n_jobs} jobs: {' '.join(args.sweep)}; medians of {args.rounds} alternating rounds, empty run cache")
    print("\n".join(table(times, n_jobs)))


if __name__ == "__main__":
    main()
