"""The "before" side of issue 13.4's comparison: magexp as of commit b533850 (before issue 13).

Run with the old checkout's own interpreter (its ``magexp`` is the one imported)::

    git worktree add --detach /work/wt/old b533850       # or: git clone . old && git -C old checkout b533850
    cd /work/wt/old && python3 -m venv .venv && .venv/bin/pip install -c ../workload/requirements.lock -e '.[test]'
    .venv/bin/python ../workload/tools/old_workload.py list --out /tmp/workload_old
    .venv/bin/python ../workload/tools/old_workload.py replay ../workload/experiments/benchmark/workload_b533850.csv --jobs 2

``list`` plans every run that the old ``make reproduce`` (``python -m magexp.reproduce all``) planned,
exactly as its ``run_artifact`` did (compose each cell, apply the optional ``?key=value`` overrides,
one config per seed), and writes

* ``runs.csv``: one row per *distinct* run (the old run cache keyed a run by its resolved config, so
  identical runs of several artifacts ran once): ``run`` (index), ``artifact`` (the first artifact
  that asked for it), ``artifacts`` (all of them, ``|``-joined), ``requested`` (how many times it was
  asked for), ``cell`` (index into ``cells.json``), ``seed``, ``overrides`` (the cell's effective
  Hydra overrides, ``;``-joined, as the old ``setting`` column wrote them but with the estimator);
* ``cells.json``: per cell, its overrides and the old resolved config without the seed (what the
  mapping to today's configs compares against: :mod:`magexp.workload`).

``replay FILE`` runs the ``status == ok`` rows of a mapped list (:mod:`magexp.workload`) through the
old ``run_many`` (joblib, as the old reproduce did) from an empty temporary run cache, runs only (no
figures), and prints one line of ``key=value`` measurements. This file is not part of the package:
it imports the *old* magexp and only runs against that checkout.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

OLD_COMMIT = "b533850"


def _check_old() -> None:
    """Refuse to run against anything but the old code (today's magexp has plan_artifact)."""
    import magexp.artifacts as artifacts

    if hasattr(artifacts, "plan_artifact"):
        sys.exit(f"error: this is today's magexp ({artifacts.__file__}); run with the interpreter of a "
                 f"checkout of {OLD_COMMIT}")


def plan() -> tuple[list[dict], list[dict]]:
    """(cells, runs) of the old ``make reproduce``, runs deduplicated by resolved config."""
    from omegaconf import OmegaConf

    from magexp.artifacts import applicable, apply_optional, cells, compose_config, overrides_of, paper_specs
    from magexp.reproduce import available_papers

    cell_rows, runs, by_config = [], [], {}
    for paper in available_papers():
        for spec in paper_specs(paper):
            for cell in cells(spec):
                cfg = compose_config(overrides_of(spec, cell))
                # the ?key=value overrides that apply, judged before they are applied (judged after, as
                # the old setting column was, a ?key=null one disappears: its key then selects None)
                overrides = overrides_of(spec, cell, cfg)
                cfg = apply_optional(spec, cfg)
                if spec.skip_inapplicable and not applicable(cfg):
                    continue
                base = OmegaConf.to_container(cfg, resolve=True)
                base.pop("seed", None)
                again = OmegaConf.to_container(compose_config(overrides), resolve=True)
                again.pop("seed", None)
                if again != base:  # the overrides alone must give the run (the replay composes them)
                    sys.exit(f"error: {spec.name}: the overrides {overrides} do not compose to the planned config")
                ci = len(cell_rows)
                cell_rows.append({"cell": ci, "artifact": spec.name, "overrides": overrides, "config": base})
                for seed in range(int(spec.seeds)):
                    cfg.seed = seed
                    resolved = json.dumps(OmegaConf.to_container(cfg, resolve=True), sort_keys=True, default=str)
                    if resolved in by_config:
                        run = runs[by_config[resolved]]
                        run["requested"] += 1
                        if spec.name not in run["artifacts"]:
                            run["artifacts"].append(spec.name)
                        continue
                    by_config[resolved] = len(runs)
                    runs.append({"run": len(runs), "artifact": spec.name, "artifacts": [spec.name], "requested": 1,
                                 "cell": ci, "seed": seed, "overrides": ";".join(overrides)})
    return cell_rows, runs


def write_list(out: Path) -> None:
    cell_rows, runs = plan()
    out.mkdir(parents=True, exist_ok=True)
    (out / "cells.json").write_text(json.dumps(cell_rows, sort_keys=True, default=str, indent=0) + "\n")
    with (out / "runs.csv").open("w", newline="") as fh:
        writer = csv.DictWriter(fh, ["run", "artifact", "artifacts", "requested", "cell", "seed", "overrides"])
        writer.writeheader()
        for run in runs:
            writer.writerow({**run, "artifacts": "|".join(run["artifacts"])})
    requested = sum(r["requested"] for r in runs)
    print(f"{requested} runs requested, {len(runs)} distinct, {len(cell_rows)} cells: {out}")


def _cpu() -> float:
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def timed_execute(resolved: dict):
    """The old ``artifacts._execute`` (``runner.run`` on a resolved config), with the CPU seconds of
    this process inside ``estimator.fit`` put into ``metrics["fit_cpu"]`` (as today's runner
    measures it). Defined in ``__main__``, so joblib's workers receive it by value."""
    import time

    from omegaconf import OmegaConf

    import magexp.runner as runner

    spent, original = [], runner.build

    def build(node, what):
        built = original(node, what)
        if what.startswith("estimator"):
            fit = built.fit

            def timed(*args, **kwargs):
                cpu = time.process_time()
                try:
                    return fit(*args, **kwargs)
                finally:
                    spent.append(time.process_time() - cpu)

            built.fit = timed
        return built

    runner.build = build
    try:
        out = runner.run(OmegaConf.create(resolved))
    finally:
        runner.build = original
    out.metrics["fit_cpu"] = sum(spent)
    return out


def replay(path: Path, jobs: int, every: int, limit: int | None) -> None:
    """The ok rows of ``path`` (those of every ``every``-th cell, the first ``limit``: the rows
    today's ``magexp.workload.pick`` selects) through the old run_many from an empty cache; prints
    the measurements."""
    with path.open(newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["status"] == "ok" and int(r["cell"]) % every == 0]
    rows = rows[:limit] if limit else rows
    start, cpu = time.perf_counter(), _cpu()
    from omegaconf import OmegaConf

    import magexp.artifacts as artifacts
    from magexp.artifacts import compose_config, run_many

    artifacts._execute = timed_execute  # run_many calls (and ships to its workers) artifacts._execute

    configs, composed = [], {}
    for row in rows:
        if row["overrides"] not in composed:
            composed[row["overrides"]] = compose_config(row["overrides"].split(";"))
        cfg = composed[row["overrides"]]
        cfg.seed = int(row["seed"])
        configs.append(OmegaConf.to_container(cfg, resolve=True))
    planned = time.perf_counter()
    outputs = run_many(configs, jobs=jobs, use_cache=True)
    if jobs != 1:  # join joblib's workers: their CPU then counts as this process's children's
        from joblib.externals.loky import get_reusable_executor

        get_reusable_executor().shutdown(wait=True)
    wall, cpu = time.perf_counter() - start, _cpu() - cpu
    fit_wall = sum(float(o.metrics["wall_time"]) for o in outputs)
    fit_cpu = sum(float(o.metrics["fit_cpu"]) for o in outputs)
    print(f"side=before commit={OLD_COMMIT} runs={len(configs)} jobs={jobs} wall_s={wall:.2f} "
          f"plan_s={planned - start:.2f} cpu_s={cpu:.2f} fit_cpu_s={fit_cpu:.2f} fit_wall_s={fit_wall:.2f} "
          f"outside_fit_ms_per_run={(cpu - fit_cpu) / max(len(configs), 1) * 1e3:.2f}")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    lister = sub.add_parser("list", help="list the distinct runs of the old make reproduce")
    lister.add_argument("--out", type=Path, required=True)
    player = sub.add_parser("replay", help="run a mapped list through the old run_many (empty cache)")
    player.add_argument("file", type=Path)
    player.add_argument("--jobs", type=int, default=0)
    player.add_argument("--every", type=int, default=1, help="the ok rows of every K-th cell (a sample)")
    player.add_argument("--limit", type=int, default=None, help="only the first N ok rows")
    args = p.parse_args(argv)
    if args.command == "replay":  # before magexp.paths is imported: it reads MAGEXP_CACHE once
        os.environ["MAGEXP_CACHE"] = tempfile.mkdtemp(prefix="magexp-old-replay-")
    _check_old()
    if args.command == "list":
        write_list(args.out)
        return 0
    try:
        replay(args.file, args.jobs, args.every, args.limit)
    finally:
        shutil.rmtree(os.environ["MAGEXP_CACHE"], ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
