"""Regenerate the papers' artifacts into ``results/<paper>/`` and rebuild the report.

    python -m magexp.artifacts.reproduce all|ding2024|yuan2018|yan2022|benchmark [--jobs N] [--only STEM] [--force]
        [--seeds N] [--tiny] [--out DIR] [--redraw] [--executor local|dask] [--scheduler ADDRESS]

The canonical ``results/`` folder is written only by a canonical reproduction (each artifact's own
seeds and sizes); ``--seeds`` and ``--tiny`` explore, and need ``--out`` naming another folder.
Every run of every selected artifact is planned first and run in one pass through
:func:`magexp.run.executor.run_many` (identical runs of different artifacts run once), then each
artifact's CSVs and figure are written. ``--redraw`` rebuilds the figures, ``summary.csv`` and
``REPORT.md`` from the CSVs already in ``--out``, without a run.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import sys
import time
from collections.abc import Mapping
from pathlib import Path

import pandas as pd

from magexp.artifacts import artifact_memo
from magexp.artifacts.kinds import kind, tabulate
from magexp.artifacts.plan import ArtifactRuns, cells, collect, paper_specs
from magexp.artifacts.plan_cache import planned
from magexp.artifacts.sample_sizes import plan_with_effects
from magexp.artifacts.plots import VECTOR
from magexp.artifacts.formats import MEASURED, write_csv
from magexp.artifacts.report_memo import built
from magexp.artifacts.paper_spec import papers
from magexp.artifacts.stored import facts_rows, summarise_stored, write_facts
from magexp.artifacts.summary import COLUMNS
from magexp import paths
from magexp.errors import MagexpError, exit_code
from magexp.paths import RESULTS
from magexp.core.limits import LIMITS, check_limits, refuse_over, show
from magexp.run.budget import estimate_run
from magexp.run.executor import Outputs, run_many
from magexp.run.executors import check_executor, make_executor
from magexp.run.flags import OneLineParser
from magexp.run.folders import check_destination, check_output_folder, removed_on_failure
from magexp.run.progress import Progress


def available_papers() -> list[str]:
    """The folders of ``experiments/`` (:func:`magexp.artifacts.paper_spec.papers`)."""
    return papers()


def select(papers: list[str], only: str | None) -> dict[str, list]:
    """``{paper: [spec, ...]}`` of ``papers``; with ``only``, just that artifact, in whichever paper has it.
    """
    chosen = {paper: paper_specs(paper) for paper in papers}
    if only is None:
        return chosen
    found = {paper: [s for s in specs if s.name == only] for paper, specs in chosen.items()}
    found = {paper: specs for paper, specs in found.items() if specs}
    if not found:
        where = papers[0] if len(papers) == 1 else "any paper"
        raise MagexpError(f"--only {only!r} is not an artifact of {where}: see experiments/<paper>/*.yaml")
    return found


def check_canonical(out, *, seeds, tiny: bool) -> Path:
    """The folder ``--out`` names, if this reproduction may write there: exploration (``--seeds``,
    ``--tiny``) never into the canonical ``results/``, and no reproduction into a folder inside it
    (:func:`magexp.run.folders.check_destination`: resolved paths).
    """
    text = str(out)
    if "${" in text or any(ord(c) < 32 for c in text):
        raise MagexpError(f"--out={text!r} is not allowed: interpolations (${{...}}) are not expanded here and a folder "
                          "name holds no control characters; give the folder itself")
    out = Path(text).expanduser() if text.strip() else text  # ~/x: the folder check_destination checks
    flags = [f for f, on in (("--seeds", seeds is not None), ("--tiny", tiny)) if on]
    if flags and str(out).strip() and Path(out).resolve() == RESULTS.resolve():
        raise MagexpError(f"{' '.join(flags)} explores: give --out DIR other than results/ "
                          "(results/ holds only canonical reproductions)")
    check_destination(out, "--out", canonical=not flags)
    return Path(out)


def draw(spec, csv: Path, out: Path, *, force: bool = False) -> bool:
    """The figure of ``spec`` (PNG and PDF twin) into ``out``, drawn from its CSV ``csv`` as written
    (the figure ``--redraw`` gives, to the byte); not drawn again when the figure cache
    (:mod:`magexp.artifacts.plots.memo`) says the files in ``out`` are that drawing already, unless ``force``.
    Returns whether it drew.

    A figure drawn into the canonical ``results/`` is checked for the defects a reader sees
    (:func:`magexp.artifacts.plots.check.defects`: text over text, an empty panel, a legend of raw
    config names, ...); each one is printed as a ``warning:`` line to stderr. The check needs a
    layout pass (about a third of a second a figure), so exploration folders and tests skip it;
    ``tests/test_figure_defects.py`` checks one committed figure of each kind, and
    ``make test-full`` all of them.
    """
    # lazy: matplotlib (memo, style) only here, where a figure is checked or drawn; importing this
    # module (--help, a refused command) never pays for it (493 ms CPU after this module, min of 5)
    from magexp.artifacts.plots import memo
    from magexp.artifacts.plots.check import defects
    from magexp.artifacts.plots.style import save

    png = out / f"{spec.name}.png"
    files = [png, png.with_suffix(VECTOR)]
    key = memo.key(spec, Path(csv).read_bytes())
    if not force and memo.current(key, files):
        return False
    fig = kind(spec.kind).draw(pd.read_csv(csv), spec)
    save(fig, png)  # first: the check's layout pass would move what is saved by a pixel
    if Path(out).resolve().is_relative_to(RESULTS.resolve()):
        for found in defects(fig):
            print(f"warning: figure {spec.name}: {found}", file=sys.stderr)
    memo.record(key, files)
    return True


#: columns that identify a row of an artifact's table (kept beside its wall times in the timing file)
ROW_KEYS = ("case", "family", "label", "scenario", "estimator", "objective", "setting")


def split_timing(frame: pd.DataFrame, path: Path) -> pd.DataFrame:
    """Move the wall-time columns of ``frame`` into the timing file ``path`` (with the row keys):
    the results' CSVs then hold only what a fresh clone computes to the same bytes, and
    ``results/timing/`` and ``results/timing.csv`` what this machine measured.
    """
    timed = [c for c in frame.columns if MEASURED in c]
    if not timed:
        return frame
    path.parent.mkdir(parents=True, exist_ok=True)
    write_csv(frame[[c for c in ROW_KEYS if c in frame] + timed], path)
    return frame.drop(columns=timed)


def write_artifact(runs, out: Path, *, force: bool = False) -> pd.DataFrame:
    """An artifact's CSVs and figure into ``out`` (``force``: draw it even if unchanged); returns its
    summary rows, computed from the CSVs just written (:func:`summarise_stored`, as ``--redraw`` does).
    """
    path = out / f"{runs.spec.name}.csv"
    frame = tabulate(runs)
    if runs.spec.kind != "speed":  # wall times measure this machine today: kept beside timing.csv
        frame = split_timing(frame, out.parent / "timing" / f"{runs.spec.name}.csv")
    write_csv(frame, path)
    write_csv(runs.table.drop(columns=["wall_time"], errors="ignore"), out / f"{runs.spec.name}_runs.csv")
    write_facts(facts_rows(runs), out / f"{runs.spec.name}_cells.csv")
    draw(runs.spec, path, out, force=force)
    return summarise_stored(runs.spec, out, runs)


def write_unchanged(plan, outputs, out: Path, *, seeds=None, tiny: bool = False, force: bool = False) -> pd.DataFrame:
    """:func:`write_artifact` of ``plan``'s runs ``outputs`` into ``out``, unless the artifact's memo
    (:mod:`magexp.artifacts.artifact_memo`) says its files in ``out`` are what these inputs write: then its
    summary rows are those kept. ``force`` writes it all the same."""
    k = artifact_memo.key(plan, outputs, seeds, tiny)
    rows = None if force else artifact_memo.recall(k, plan.spec, out)
    if rows is None:
        rows = write_artifact(collect(plan, outputs), out, force=force)
        artifact_memo.keep(k, plan.spec, out, rows)
    return rows


def write_summary(paper: str, parts: dict[str, pd.DataFrame], out: Path) -> pd.DataFrame:
    """``out/summary.csv`` of ``paper``: the rows of the artifacts in ``parts`` replace their old rows.
    """
    summary = pd.concat(list(parts.values()), ignore_index=True) if parts else pd.DataFrame(columns=COLUMNS)
    path = out / "summary.csv"
    if path.exists() and path.stat().st_size > 0:
        old = pd.read_csv(path, keep_default_na=False, na_values=[""])
        summary = pd.concat([old[~old.artifact.isin(list(parts))], summary], ignore_index=True)
    order = {s.name: i for i, s in enumerate(paper_specs(paper))}
    summary = summary.sort_values("artifact", key=lambda c: c.map(order), kind="stable")
    write_csv(summary, path)
    return summary


def skipped_for_data(spec, log=print) -> bool:
    """Whether ``spec`` reads a recording that is not in :data:`magexp.paths.SHARED_DATA` (the
    recordings of others are never shipped): then it is skipped, with one line.
    """
    missing = [f for f in spec.get("requires_data") or [] if not (paths.SHARED_DATA / f).is_file()]
    if missing:
        log(f"{spec.name}: skipped, {missing[0]} is not in {paths.SHARED_DATA} (set MAGEXP_DATA)")
    return bool(missing)


def slice_outputs(outputs, start: int, n: int):
    """Runs ``start .. start + n`` of :class:`magexp.run.executor.Outputs`, as an ``Outputs`` of their own
    (metrics at hand, outputs read from the same run cache on access).
    """
    keys = outputs.keys[start:start + n]
    return Outputs(keys, {key: outputs.metrics(start + j) for j, key in enumerate(keys)}, outputs.root,
                   held=outputs.held)


def reproduce(selected: dict[str, list], root: Path = RESULTS, *, seeds=None, jobs: int = 0, tiny: bool = False,
              force: bool = False, executor=None, log=print) -> dict:
    """Plan every run of the ``selected`` artifacts, run them in one pass, write each artifact.

    Returns ``{"requested", "distinct", "computed", "cached", "paper summaries": {...}}``.
    """
    plans = [(paper, planned(spec, seeds=seeds, tiny=tiny, fresh=force)) for paper, specs in selected.items()
             for spec in specs if not skipped_for_data(spec, log)]
    configs = [c for _, plan in plans for c in plan.configs]
    counts: dict = {}
    outputs = run_many(configs, jobs=jobs, use_cache=not force, executor=executor, counts=counts,
                       progress=Progress(len(configs), "reproduce"))
    if configs:
        log(f"{counts['requested']} runs requested, {counts['distinct']} distinct: "
            f"{counts['computed']} computed, {counts['cached']} from the cache")
    start, parts = 0, {paper: {} for paper, _ in plans}
    for paper, plan in plans:
        out = root / paper
        out.mkdir(parents=True, exist_ok=True)
        n = len(plan.configs)
        parts[paper][plan.spec.name] = write_unchanged(plan, slice_outputs(outputs, start, n), out, seeds=seeds,
                                                       tiny=tiny, force=force)
        start += n
    counts["paper summaries"] = {paper: write_summary(paper, parts[paper], root / paper) for paper in parts}
    return counts


def reproduce_paper(paper: str, *, root: Path = RESULTS, seeds=None, jobs: int = 0, tiny: bool = False,
                    only: str | None = None, force: bool = False, log=print) -> pd.DataFrame:
    """Every artifact of ``paper`` (or just ``only``); writes ``root/<paper>/`` and returns its summary."""
    counts = reproduce(select([paper], only), root, seeds=seeds, jobs=jobs, tiny=tiny, force=force, log=log)
    return counts["paper summaries"].get(paper, pd.DataFrame(columns=COLUMNS))


def redraw(selected: dict[str, list], root: Path, *, force: bool = False) -> tuple[int, int]:
    """Each selected artifact's figure from its CSV in ``root`` (unchanged ones are kept, unless
    ``force``: :func:`draw`) and its summary rows from its runs CSV (:func:`summarise_stored`, into
    ``root/<paper>/summary.csv``): what a reproduction into ``root`` wrote, to the byte.
    """
    drawn = kept = 0
    for paper, specs in selected.items():
        parts = {}
        for spec in specs:
            if skipped_for_data(spec):
                continue
            path = root / paper / f"{spec.name}.csv"
            stored = [path] + [root / paper / f"{spec.name}_{part}.csv" for part in ("runs", "cells")]
            if not all(p.is_file() for p in stored):
                raise MagexpError(f"--redraw: {path}, its runs CSV or its cells CSV does not exist: "
                                  f"reproduce {spec.name} first")
            if draw(spec, path, root / paper, force=force):
                drawn += 1
            else:
                kept += 1
            parts[spec.name] = summarise_stored(spec, root / paper)
        if parts:
            write_summary(paper, parts, root / paper)
    return drawn, kept


def cpu_seconds() -> float:
    """CPU seconds of this process and of its finished (waited-for) worker processes."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def cpu_line(cpu: float, counts: dict) -> str:
    """Where the CPU went: inside the computed runs' fits; the workers' CPU outside them per computed
    run (``task_cpu - fit_cpu``, measured inside the workers); the parent's (all the rest)."""
    fit, n, task = counts.get("fit_cpu", 0.0), counts["computed"], counts.get("task_cpu", 0.0)
    split = f"; worker: {(task - fit) / n * 1e3:.1f} ms per run outside fits; parent: {cpu - task:.1f} s" if n else ""
    return f"CPU {cpu:.1f} s: {fit:.1f} s inside fits ({fit / cpu:.0%}){split}"


def record_timing(root: Path, target: str, seconds: float, counts: dict) -> None:
    """Keep the wall time of the last reproduction of ``target`` in ``root/timing.csv``, with how
    many runs it computed and how many came from the cache (``source``: computed, cached or mixed)."""
    path = root / "timing.csv"
    columns = ["target", "seconds", "cores", "source", "runs", "distinct", "computed", "cached"]
    rows = pd.read_csv(path) if path.exists() else pd.DataFrame(columns=columns)
    rows = rows[rows.target != target].reindex(columns=columns)
    computed, cached = counts["computed"], counts["cached"]
    source = "computed" if cached == 0 else "cached" if computed == 0 else "mixed"
    new = pd.DataFrame([{"target": target, "seconds": round(seconds, 1), "cores": os.cpu_count(), "source": source,
                         "runs": counts["requested"], "distinct": counts["distinct"], "computed": computed,
                         "cached": cached}])
    write_csv(pd.concat([rows, new], ignore_index=True) if len(rows) else new, path)


# ---------------------------------------------------------------------------------------------
# the work a reproduction asks for, against the limits of magexp.run.budget

def check_reproduction(selected: Mapping, seeds: int | None) -> int:
    """Refuse a reproduction of more runs than the runs limit (cells times seeds of each selected
    artifact, counted before any is planned); returns that count."""
    runs = sum(len(cells(spec)) * int(seeds if seeds is not None else spec.seeds)
               for specs in selected.values() for spec in specs)
    refuse_over(runs, "runs", f"--seeds {seeds}" if seeds is not None else "the reproduction", "it makes")
    return runs


def canonical_needs(chosen: list[str] | None = None) -> dict:
    """The estimates of the canonical reproduction's runs of the ``chosen`` papers (None: every paper):
    ``runs``, the largest run's ``memory`` and ``run_work`` (each with its artifact), the ``work`` of all
    (keys of :data:`magexp.core.limits.LIMITS`)."""
    out = {"runs": 0, "work": 0, "run_memory": (0, ""), "run_work": (0, "")}
    for paper in chosen or papers():
        for spec in paper_specs(paper):
            plan = plan_with_effects(spec)
            for cfg in plan.configs:
                est = estimate_run(cfg)
                out["runs"] += 1
                out["work"] += est.work
                out["run_memory"] = max(out["run_memory"], (est.memory, spec.name))
                out["run_work"] = max(out["run_work"], (est.work, spec.name))
    return out


def print_limits(chosen: list[str] | None = None) -> None:
    """``magexp reproduce [PAPER] --limits``: the limits in force beside what ``make reproduce`` needs of each
    (of the ``chosen`` papers' reproduction).
    """
    need = canonical_needs(chosen)
    for name, lim in LIMITS.items():
        value = need.get(name, None)
        if isinstance(value, tuple):
            shown = f"{show(value[0], lim.unit)} ({value[1]})"
        elif value is not None:
            shown = show(value, lim.unit)
        else:
            shown = "none (no recording)"
        print(f"{name}: {show(lim.value(), lim.unit)} in force ({lim.env}); make reproduce needs {shown}")


def parser() -> argparse.ArgumentParser:
    """The command line of ``magexp reproduce`` (its options and their help)."""
    p = OneLineParser(prog="magexp reproduce", description=__doc__.splitlines()[0])
    p.add_argument("paper", nargs="?", help="all, or one of: " + ", ".join(available_papers()))
    p.add_argument("--jobs", type=int, default=0, help="parallel processes (0: all cores)")
    p.add_argument("--seeds", type=int, default=None, help="seeds per cell (exploration: needs --out)")
    p.add_argument("--only", default=None, help="one artifact stem (found in whichever paper has it)")
    p.add_argument("--tiny", action="store_true", help="tiny sizes, a smoke test (exploration: needs --out)")
    p.add_argument("--out", default=str(RESULTS), help="results folder (default: results/)")
    p.add_argument("--force", action="store_true",
                   help="recompute every distinct run even if cached, and write every artifact, figure and report")
    p.add_argument("--redraw", action="store_true", help="rebuild figures, summary and report from the CSVs; no run")
    p.add_argument("--executor", default="local", help="local (processes on this machine) or dask")
    p.add_argument("--scheduler", default=None, help="a Dask scheduler address (default: a local cluster)")
    p.add_argument("--limits", action="store_true",
                   help="print the work limits in force beside what the canonical reproduction needs; no run")
    return p


def command(argv: list[str]) -> int:
    """``magexp reproduce PAPER [OPTIONS]``: errors are raised (the one error path,
    :func:`magexp.errors.guarded`, turns them into one line and an exit code)."""
    check_limits()
    return _main(parser().parse_args(argv))


def main(argv=None) -> int:
    """``magexp reproduce ...`` (also ``python -m magexp.artifacts.reproduce``, what ``make reproduce``
    runs): 0 on success; one line on stderr and exit 2 on bad input, 130 on Ctrl-C."""
    return exit_code(command, sys.argv[1:] if argv is None else list(argv))


#: the options ``--limits`` ignores (it prints, and runs nothing), with their defaults
NOT_WITH_LIMITS = {"only": None, "seeds": None, "tiny": False, "out": str(RESULTS), "force": False, "redraw": False,
                   "executor": "local", "scheduler": None, "jobs": 0}


def _main(args) -> int:
    """Run the parsed command: check where it writes, then redraw, list the limits or reproduce."""
    if args.paper is None and not args.limits:
        raise MagexpError("a paper is needed: magexp reproduce all, or one of " + ", ".join(available_papers()))
    papers = available_papers() if args.paper in ("all", None) else [args.paper]
    for paper in papers:
        if paper not in available_papers():
            raise MagexpError(f"paper={paper!r} is not allowed: choose all or one of {', '.join(available_papers())}")
    if args.limits:
        given = [f"--{k}" for k, default in NOT_WITH_LIMITS.items() if getattr(args, k) != default]
        if given:
            raise MagexpError(f"--limits is not allowed with {given[0]}: it prints the limits beside what a paper's "
                              "reproduction needs and runs nothing (magexp reproduce [PAPER] --limits)")
        print_limits(None if args.paper in ("all", None) else papers)
        return 0
    check_executor(args.executor, args.jobs, args.scheduler)
    if args.seeds is not None and args.seeds < 1:
        raise MagexpError(f"--seeds {args.seeds} is not allowed: it must be an integer >= 1")
    args.out = check_canonical(args.out, seeds=args.seeds, tiny=args.tiny)
    # a file, or under one: one line, nothing created (results/ itself: check_canonical decided)
    check_output_folder(args.out, "--out", canonical=True)
    selected = select(papers, args.only)
    if not args.redraw:
        check_reproduction(selected, args.seeds)  # cells x seeds within the runs limit, before planning
    with removed_on_failure(args.out):  # a failed or interrupted reproduction leaves nothing behind
        return _write(args, selected)


def with_peer_bench(out: Path) -> None:
    """Copy the committed peer bench (``results/peers/``: written by ``make peers-bench`` only, never by
    a reproduction) into ``out``, where the report reads it, so that a reproduction into another folder
    reports what ``make reproduce`` does; not into ``results/`` itself, nor over a bench ``out`` holds
    (its ``peers.md``)."""
    peers = RESULTS / "peers"
    if out.resolve() != RESULTS.resolve() and peers.is_dir() and not (out / "peers" / "peers.md").exists():
        shutil.copytree(peers, out / "peers", dirs_exist_ok=True)


def _write(args, selected) -> int:
    """Run and write (or redraw) the ``selected`` artifacts into ``args.out`` (checked by :func:`_main`)."""
    args.out.mkdir(parents=True, exist_ok=True)
    with_peer_bench(args.out)
    start = time.perf_counter()
    if args.redraw:
        drawn, kept = redraw(selected, args.out, force=args.force)
        built(args.out, force=args.force)
        print(f"redrew {drawn} figures ({kept} unchanged, kept), summary and report in "
              f"{time.perf_counter() - start:.1f} s: {args.out / 'REPORT.md'}")
        return 0
    cpu = cpu_seconds()
    with make_executor(args.executor, jobs=args.jobs, scheduler=args.scheduler) as executor:
        counts = reproduce(selected, args.out, seeds=args.seeds, jobs=args.jobs, tiny=args.tiny, force=args.force,
                           executor=executor)
    built(args.out, force=args.force)
    seconds = time.perf_counter() - start
    if args.executor == "local":  # remote workers' CPU is not seen here
        print(cpu_line(cpu_seconds() - cpu, counts))
    if args.only is None and args.seeds is None and not args.tiny:
        record_timing(args.out, args.paper, seconds, counts)
    print(f"done in {seconds:.1f} s; report: {args.out / 'REPORT.md'}")
    if args.out.resolve() == RESULTS.resolve():  # the website's pages are generated from results/ (magexp.site)
        print("the results website (claims explorer, a page per paper): make docs, then open site/index.html")
    return 0


if __name__ == "__main__":  # numpy is loaded by now: python -m magexp reproduce sets one BLAS thread first
    sys.exit(main())
