"""Replay a fixed list of runs: issue 13.4's before/after comparison on the same workload.

A *workload list* is a CSV, one row per distinct run (``experiments/benchmark/workload_b533850.csv``
lists the 2,952 distinct runs that ``make reproduce`` planned at commit b533850, before issue 13)::

    run, artifact, artifacts, requested, cell, seed, overrides, mapped, status

``overrides`` are the run's Hydra overrides at that commit (``;``-joined), ``mapped`` today's
overrides for the same run, ``status`` is ``ok`` or ``inexpressible: <why>``. The list is written in
two steps: ``tools/old_workload.py list`` (run with the old checkout's interpreter) plans the old runs
and records each cell's old resolved config (``cells.json``); :func:`map_cells` (``python -m
magexp.workload map``) then composes each cell with today's configs and adds an override for every
setting whose default changed since (in this list only ``lm``'s ``estimator.tol``: 1e-15 then), so
that the replay runs the old settings wherever a key still exists. A cell is *inexpressible* when an
old setting has no key today, or today's compose refuses the old overrides.

Settings that exist only today (e.g. ``estimator.boundary``) keep today's defaults, and today's
runs draw their data from per-scenario random streams (issue 9): the replay reproduces the old
workload's *shape* (the same scenarios, estimators, sizes, budgets and seeds), not its numbers.
Today's :func:`~magexp.executor.run_many` finds 2,942 distinct runs among the 2,952 rows: the
old cache keyed a run by its config's JSON text, so ``scenario.noise=100`` (an int) and the
default ``100.0`` of ``yan2022_sim`` were two runs (10 seeds of ``kf``); today's schema types the
value and they are one.

:func:`replay` runs the ``ok`` rows through today's :func:`magexp.executor.run_many`, from an empty
temporary run cache (never the project's ``.cache``) and measures

* ``wall_s``: wall time, composing included (``plan_s``: composing alone);
* ``cpu_s``: CPU seconds of this process and of its worker processes;
* ``fit_cpu_s``: CPU seconds inside the estimators' ``fit`` (measured per run);
* ``fit_wall_s``: wall seconds inside ``fit`` summed over runs (the old code measured only this:
  the like-for-like column for the "before" side, ``tools/old_workload.py replay``);
* ``outside_fit_ms_per_run``: ``(cpu_s - fit_cpu_s) / runs``, the framework's cost per run.

Command line::

    python -m magexp.workload replay experiments/benchmark/workload_b533850.csv --jobs 2
    python -m magexp.workload replay FILE --jobs 1 --limit 20          # a smoke replay
    python -m magexp.workload map RUNS.csv CELLS.json --out FILE       # write a mapped list
    python -m magexp.workload compare --old ../old --jobs 2 --rounds 3 --every 10   # before/after

``compare`` alternates the old code's replay (``tools/old_workload.py replay`` with the old
checkout's interpreter) and today's on the same rows, each a fresh process from an empty cache,
and reports medians and the median ratio before / after: speed as a ratio measured side by side.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from magexp.atomic import atomic_open
from magexp.errors import MagexpError
from magexp.paths import EXPERIMENTS

#: the committed list of the runs of ``make reproduce`` at commit b533850
DEFAULT_LIST = EXPERIMENTS / "benchmark" / "workload_b533850.csv"
COLUMNS = ("run", "artifact", "artifacts", "requested", "cell", "seed", "overrides", "mapped", "status")
#: the nodes of a resolved config that define a run (the rest is the command's: task, data, out...)
RUN_NODES = ("scenario", "estimator", "objective", "analysis")


# ---------------------------------------------------------------------------------------------
# the list

def read_list(path: Path | str) -> list[dict]:
    """The rows of a workload list, checked: every column of :data:`COLUMNS`, integer ``seed``,
    ``requested`` and ``run``, a ``status`` of ``ok`` or ``inexpressible: ...``."""
    path = Path(path)
    if not path.is_file():
        raise MagexpError(f"workload list {str(path)!r} does not exist: give a CSV such as {DEFAULT_LIST.name}")
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        missing = [c for c in COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise MagexpError(f"workload list {path.name}: column {missing[0]!r} is missing "
                              f"(the columns are {', '.join(COLUMNS)})")
        rows = list(reader)
    for line, row in enumerate(rows, start=2):
        for key in ("run", "requested", "seed", "cell"):
            try:
                row[key] = int(row[key])
            except ValueError:
                raise MagexpError(f"workload list {path.name}, line {line}: {key}={row[key]!r} is not an "
                                  "integer") from None
        if row["seed"] < 0:
            raise MagexpError(f"workload list {path.name}, line {line}: seed={row['seed']} must be >= 0")
        if not (row["status"] == "ok" or row["status"].startswith("inexpressible: ")):
            raise MagexpError(f"workload list {path.name}, line {line}: status={row['status']!r} is not "
                              "allowed: ok or 'inexpressible: <why>'")
    return rows


def split(overrides: str) -> list[str]:
    """``a=1;b=2`` -> ``["a=1", "b=2"]`` (the list's ``;``-joined form)."""
    return [o for o in overrides.split(";") if o]


# ---------------------------------------------------------------------------------------------
# mapping old runs onto today's configs

def _leaves(node, prefix: str = "") -> dict:
    """``{dotted key: value}`` of a nested dict (lists are values)."""
    if not isinstance(node, dict):
        return {prefix: node}
    out = {}
    for key, value in node.items():
        out.update(_leaves(value, f"{prefix}.{key}" if prefix else str(key)))
    return out


def _run_part(resolved: dict) -> dict:
    return {k: resolved.get(k) for k in RUN_NODES}


def _constant_schedules(node):
    """Old ``schedules.Constant(value)`` nodes as today's ``schedules.Linear(start=value, end=value)``
    (traditional PSO's coefficients since the ablation: ``start + 0 * t / t_max`` is ``value`` exactly)."""
    if isinstance(node, list):
        return [_constant_schedules(v) for v in node]
    if not isinstance(node, dict):
        return node
    if node.get("_target_") == "magexp.estimators.schedules.Constant" and set(node) == {"_target_", "value"}:
        return {"_target_": "magexp.estimators.schedules.Linear", "start": node["value"], "end": node["value"]}
    return {k: _constant_schedules(v) for k, v in node.items()}


#: settings that did not exist at b533850, with the value that does what the old code did; where
#: today's default differs, the mapping sets it (other new settings keep today's defaults)
OLD_BEHAVIOUR = {
    "estimator.boundary": "clip",              # the swarms clipped to the box
    "scenario.rotation.segments": None,        # Yuan's rotations from rotation.mode
    "estimator.gauge": "free",                 # lm fitted all 12 parameters of a scalar objective
}

#: old estimators that became today's ``analysis=field_kalman`` step after another estimator (Yan 2022 Fig 4)
FIELD_KALMAN = {"kf_be", "kf_be_paper"}


def translate(overrides: list[str], old: dict) -> tuple[list[str], dict]:
    """An old cell in today's vocabulary, before any comparison: the overrides and the old resolved
    config rewritten where a setting changed its form but not its meaning.

    * ``estimator=kf_be`` / ``kf_be_paper`` (a ``FieldKalmanFilter`` wrapping the ``kf`` /
      ``yan2022_paper_mockup`` estimate) -> ``estimator=<the wrapped one>`` and ``+analysis=field_kalman``;
    * ``schedules.Constant`` coefficients -> ``schedules.Linear`` with ``start = end``.
    """
    old = {k: _constant_schedules(v) for k, v in old.items()}
    est = old.get("estimator") or {}
    if est.get("name") in FIELD_KALMAN:
        inner = est["magnetization"]
        old = {**old, "estimator": inner,
               "analysis": {**{k: v for k, v in est.items() if k != "magnetization"}, "name": "field_kalman"}}
        overrides = [f"estimator={inner['name']}" if o == f"estimator={est['name']}" else o for o in overrides]
        overrides.append("+analysis=field_kalman")
    return overrides, old


def override_value(value) -> str:
    """A value in Hydra's override grammar (what :func:`magexp.config.yaml_value` parses back)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(override_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ",".join(f"{k}:{override_value(v)}" for k, v in value.items()) + "}"
    return "'" + str(value).replace("\\", "\\\\").replace("'", "\\'") + "'"


def map_cell(overrides: list[str], old: dict) -> tuple[list[str], str]:
    """Today's overrides for an old cell, and its status (``ok`` or ``inexpressible: <why>``).

    ``old`` is the cell's resolved config at the old commit. Both are first put in today's
    vocabulary (:func:`translate`); today's config for ``overrides`` is then composed; every run setting (:data:`RUN_NODES`) whose value differs from ``old`` and whose key
    exists today gets an override with the old value (a setting that is new since, the value of
    :data:`OLD_BEHAVIOUR`, where it names one); the result is composed again and must then
    agree with ``old`` on every key both have.
    """
    from omegaconf import OmegaConf

    from magexp.config import compose_config

    def resolved(ovr):
        return _leaves(_run_part(OmegaConf.to_container(compose_config(ovr), resolve=True)))

    overrides, old = translate(overrides, old)
    try:
        today = resolved(overrides)
    except MagexpError as exc:
        return overrides, f"inexpressible: {exc}"
    wanted = _leaves(_run_part(old))
    wanted.update({k: v for k, v in OLD_BEHAVIOUR.items() if k in today and k not in wanted})
    gone = sorted(k for k in wanted if k not in today and not k.endswith("_target_"))
    if gone:
        return overrides, f"inexpressible: {gone[0]}={override_value(wanted[gone[0]])} has no key today"
    fixes = [f"{k}={override_value(wanted[k])}" for k in sorted(wanted)
             if wanted[k] != today[k] and not k.endswith("_target_")]
    mapped = list(overrides) + fixes
    try:
        again = resolved(mapped)
    except MagexpError as exc:
        return mapped, f"inexpressible: {exc}"
    still = sorted(k for k in wanted if k in again and again[k] != wanted[k] and not k.endswith("_target_"))
    if still:
        return mapped, f"inexpressible: {still[0]} cannot be set to {override_value(wanted[still[0]])}"
    return mapped, "ok"


def map_cells(runs_csv: Path, cells_json: Path, out: Path) -> dict:
    """Write the mapped workload list ``out`` from the old side's ``runs.csv`` and ``cells.json``
    (``tools/old_workload.py list``); returns ``{status: count of runs}``."""
    cells = {c["cell"]: c for c in json.loads(Path(cells_json).read_text())}
    mapped = {ci: map_cell(list(c["overrides"]), c["config"]) for ci, c in cells.items()}
    with Path(runs_csv).open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    counts: dict = {}
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_open(out, "w", newline="") as fh:
        writer = csv.DictWriter(fh, COLUMNS, lineterminator="\n")
        writer.writeheader()
        for row in rows:
            overrides, status = mapped[int(row["cell"])]
            writer.writerow({**row, "mapped": ";".join(overrides), "status": status})
            counts[status] = counts.get(status, 0) + 1
    return counts


# ---------------------------------------------------------------------------------------------
# the replay

def configs_of(rows: list[dict]) -> list[dict]:
    """Today's resolved config of each ``ok`` row (composed once per distinct ``mapped``)."""
    from omegaconf import OmegaConf

    from magexp.config import compose_config

    base: dict[str, dict] = {}
    out = []
    for row in rows:
        if row["status"] != "ok":
            continue
        if row["mapped"] not in base:
            resolved = OmegaConf.to_container(compose_config(split(row["mapped"])), resolve=True)
            resolved.pop("seed", None)
            base[row["mapped"]] = resolved
        out.append({**base[row["mapped"]], "seed": row["seed"]})
    return out


@contextlib.contextmanager
def empty_cache():
    """A temporary, empty run cache (and composed-config store) for the duration of the block;
    removed afterwards. The project's ``.cache`` is never read or written."""
    from magexp import cache, paths

    root = Path(tempfile.mkdtemp(prefix="magexp-replay-"))
    saved = paths.CACHE, cache.CACHE
    paths.CACHE = cache.CACHE = root / "runs"
    try:
        yield paths.CACHE
    finally:
        paths.CACHE, cache.CACHE = saved
        shutil.rmtree(root, ignore_errors=True)


def pick(rows: list[dict], *, every: int = 1, limit: int | None = None) -> list[dict]:
    """The ``ok`` rows of every ``every``-th cell (``cell % every == 0``: a sample of whole cells,
    every seed of each, so that what a cell's runs share is shared as in the full list), the first
    ``limit`` of them. ``tools/old_workload.py`` selects the same rows."""
    ok = [r for r in rows if r["status"] == "ok" and r["cell"] % every == 0]
    return ok[:limit] if limit is not None else ok


def replay(rows: list[dict], *, jobs: int = 0, executor: str = "local") -> dict:
    """Run the ``ok`` rows from an empty run cache; returns the measurements (see the module
    docstring) and the run counts."""
    from magexp.executor import make_executor, run_many
    from magexp.reproduce import cpu_seconds  # this process's and its finished workers' CPU

    ok = pick(rows)
    counts: dict = {}
    with empty_cache():
        start, cpu = time.perf_counter(), cpu_seconds()
        configs = configs_of(ok)
        planned = time.perf_counter()
        with make_executor(executor, jobs=jobs) as ex:
            outputs = run_many(configs, executor=ex, counts=counts)
        wall, cpu = time.perf_counter() - start, cpu_seconds() - cpu
        fit_wall = sum(float(outputs.metrics(i)["wall_time"]) for i in range(len(outputs)))
    n = max(counts.get("computed", 0), 1)
    return {"side": "after", "runs": len(configs), "distinct": counts.get("distinct", 0),
            "computed": counts.get("computed", 0), "jobs": jobs, "wall_s": wall, "plan_s": planned - start,
            "cpu_s": cpu, "fit_cpu_s": counts.get("fit_cpu", 0.0), "fit_wall_s": fit_wall,
            "outside_fit_ms_per_run": (cpu - counts.get("fit_cpu", 0.0)) / n * 1e3}


def parse_line(text: str) -> dict:
    """The last ``key=value ...`` line of a replay's output as a dict (numbers as floats)."""
    lines = [ln for ln in text.splitlines() if ln.startswith("side=")]
    if not lines:
        raise MagexpError(f"a replay printed no measurement line: {text.strip()[-300:]!r}")
    out = {}
    for item in lines[-1].split():
        key, _, value = item.partition("=")
        try:
            out[key] = float(value)
        except ValueError:
            out[key] = value
    return out


#: the measurements compared by :func:`compare` (before / after)
COMPARED = ("wall_s", "cpu_s", "fit_cpu_s", "outside_fit_ms_per_run")


def compare(old_checkout: Path, file: Path = DEFAULT_LIST, *, jobs: int = 2, rounds: int = 3, every: int = 10,
            log=print) -> dict:
    """Before/after side by side: the same rows replayed by the old code (``old_checkout``: a
    checkout of b533850 with its own ``.venv``, running ``tools/old_workload.py replay``) and by
    today's (``python -m magexp.workload replay``), each in a fresh process from an empty cache,
    alternating (A B, B A, ...) for ``rounds`` rounds. Returns per measurement of :data:`COMPARED`
    the medians before and after and the median over rounds of before / after."""
    tool = Path(__file__).resolve().parent.parent / "tools" / "old_workload.py"
    python = Path(old_checkout) / ".venv" / "bin" / "python"
    if not tool.is_file():
        raise MagexpError(f"compare needs a source checkout: {tool} does not exist")
    if not python.is_file():
        raise MagexpError(f"--old {str(old_checkout)!r}: {python} does not exist (a b533850 checkout with its .venv)")
    args = [str(file), "--jobs", str(jobs), "--every", str(every)]
    sides = {"before": ([str(python), str(tool), "replay", *args], Path(old_checkout)),
             "after": ([sys.executable, "-m", "magexp.workload", "replay", *args], Path.cwd())}
    measured: dict[str, list[dict]] = {"before": [], "after": []}
    for r in range(rounds):
        for side in (("before", "after") if r % 2 == 0 else ("after", "before")):
            command, cwd = sides[side]
            done = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
            if done.returncode != 0:
                raise MagexpError(f"the {side} replay failed: {done.stderr.strip().splitlines()[-1:]}")
            measured[side].append(parse_line(done.stdout))
            log(f"round {r + 1} {done.stdout.strip().splitlines()[-1]}")
    import numpy as np

    out = {"runs": measured["after"][0]["runs"], "rounds": rounds, "jobs": jobs}
    for key in COMPARED:
        before = np.array([m[key] for m in measured["before"]])
        after = np.array([m[key] for m in measured["after"]])
        out[key] = (float(np.median(before)), float(np.median(after)), float(np.median(before / after)))
    return out


def line(measured: dict) -> str:
    """The measurements as one ``key=value`` line (the old side prints the same shape)."""
    return " ".join(f"{k}={v:.2f}" if isinstance(v, float) else f"{k}={v}" for k, v in measured.items())


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m magexp.workload", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    play = sub.add_parser("replay", help="run a workload list from an empty cache and measure it")
    play.add_argument("file", type=Path, nargs="?", default=DEFAULT_LIST)
    play.add_argument("--jobs", type=int, default=0, help="parallel processes (0: all cores)")
    play.add_argument("--executor", default="local", help="local or dask")
    play.add_argument("--every", type=int, default=1, help="the runs of every K-th cell (a sample)")
    play.add_argument("--limit", type=int, default=None, help="only the first N runnable rows")
    both = sub.add_parser("compare", help="before/after side by side: the old checkout's replay and today's, alternating")
    both.add_argument("file", type=Path, nargs="?", default=DEFAULT_LIST)
    both.add_argument("--old", type=Path, required=True, help="a checkout of b533850 with its own .venv")
    both.add_argument("--jobs", type=int, default=2)
    both.add_argument("--rounds", type=int, default=3)
    both.add_argument("--every", type=int, default=10, help="the runs of every K-th cell (default 10)")
    mapper = sub.add_parser("map", help="map the old side's runs.csv and cells.json onto today's configs")
    mapper.add_argument("runs", type=Path)
    mapper.add_argument("cells", type=Path)
    mapper.add_argument("--out", type=Path, default=DEFAULT_LIST)
    return p


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    try:
        if args.command == "map":
            with empty_cache():  # composing stores nothing in the project's .cache
                counts = map_cells(args.runs, args.cells, args.out)
            for status, n in sorted(counts.items()):
                print(f"{n:6d}  {status}")
            return 0
        for flag in ("limit", "every", "rounds"):
            value = getattr(args, flag, None)
            if value is not None and value < 1:
                raise MagexpError(f"--{flag} {value} is not allowed: it must be an integer >= 1")
        from magexp.executor import check_executor

        check_executor(getattr(args, "executor", "local"), args.jobs, None)
        rows = read_list(args.file)
        if args.command == "compare":
            result = compare(args.old, args.file, jobs=args.jobs, rounds=args.rounds, every=args.every)
            print(f"{result['runs']:.0f} runs, {args.jobs} jobs, medians of {args.rounds} alternating rounds:")
            for key in COMPARED:
                before, after, ratio = result[key]
                print(f"  {key:24s} before {before:10.2f}  after {after:10.2f}  before/after {ratio:6.2f}")
            return 0
        skipped = sum(r["status"] != "ok" for r in rows)
        print(line(replay(pick(rows, every=args.every, limit=args.limit), jobs=args.jobs, executor=args.executor))
              + f" inexpressible={skipped}")
    except MagexpError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
