"""Regenerate a paper's artifacts into ``results/<paper>/`` and rebuild the report.

    python -m magexp.reproduce all|ding2024|yuan2018|yan2022 [--jobs N] [--seeds N] [--only STEM] [--tiny] [--out DIR]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import pandas as pd

from magexp.artifacts import paper_specs, run_artifact
from magexp.errors import MagexpError
from magexp.paths import RESULTS
from magexp.plots import kind_module
from magexp.report import write_csv
from magexp.summary import COLUMNS, summarise

def available_papers() -> list[str]:
    """The folders of ``experiments/`` (:func:`magexp.spec.papers`)."""
    from magexp.spec import papers

    return papers()


def reproduce_artifact(spec, out: Path, *, seeds=None, jobs: int = 0, tiny: bool = False,
                       force: bool = False) -> pd.DataFrame:
    """Run one artifact, write its CSVs and figure into ``out``; return its summary rows."""
    from magexp.plots.style import save

    runs = run_artifact(spec, seeds=seeds, jobs=jobs, tiny=tiny, use_cache=not force)
    kind = kind_module(spec.kind)
    frame = kind.tabulate(runs)
    write_csv(frame, out / f"{spec.name}.csv")
    write_csv(runs.table.drop(columns=["wall_time"], errors="ignore"), out / f"{spec.name}_runs.csv")
    save(kind.draw(frame, spec), out / f"{spec.name}.png")
    return summarise(runs)


def reproduce_paper(paper: str, *, root: Path = RESULTS, seeds=None, jobs: int = 0, tiny: bool = False,
                    only: str | None = None, force: bool = False, log=print) -> pd.DataFrame:
    """Every artifact of ``paper``; writes ``root/<paper>/summary.csv`` (its part of the summary)."""
    out = root / paper
    parts = []
    specs = [s for s in paper_specs(paper) if only is None or s.name == only]
    if only is not None and not specs:
        raise MagexpError(f"--only {only!r} is not an artifact of {paper}")
    out.mkdir(parents=True, exist_ok=True)
    for spec in specs:
        from magexp.paths import SHARED_DATA

        missing = [f for f in spec.get("requires_data") or [] if not (SHARED_DATA / f).is_file()]
        if missing:  # recordings of others, not shipped: skip in one line
            log(f"{spec.name}: skipped, {missing[0]} is not in {SHARED_DATA} (set MAGEXP_DATA)")
            continue
        start = time.perf_counter()
        parts.append(reproduce_artifact(spec, out, seeds=seeds, jobs=jobs, tiny=tiny, force=force))
        log(f"{spec.name}: {time.perf_counter() - start:.1f} s")
    summary = pd.concat(parts, ignore_index=True) if parts else pd.DataFrame(columns=COLUMNS)
    if only is not None and (out / "summary.csv").exists():
        old = pd.read_csv(out / "summary.csv", keep_default_na=False, na_values=[""])
        summary = pd.concat([old[old.artifact != only], summary], ignore_index=True)
        order = {s.name: i for i, s in enumerate(paper_specs(paper))}
        summary = summary.sort_values("artifact", key=lambda c: c.map(order), kind="stable")
    write_csv(summary, out / "summary.csv")
    return summary


def record_timing(root: Path, target: str, seconds: float) -> None:
    """Keep the wall time of the last full reproduction of ``target`` in ``root/timing.csv``."""
    path = root / "timing.csv"
    rows = pd.read_csv(path) if path.exists() else pd.DataFrame(columns=["target", "seconds", "cores"])
    rows = rows[rows.target != target]
    import os

    new = pd.DataFrame([{"target": target, "seconds": round(seconds, 1), "cores": os.cpu_count()}])
    pd.concat([rows, new], ignore_index=True).to_csv(path, index=False)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m magexp.reproduce", description=__doc__.splitlines()[0])
    parser.add_argument("paper", help="all, or one of: " + ", ".join(available_papers()))
    parser.add_argument("--jobs", type=int, default=0, help="parallel processes (0: all cores)")
    parser.add_argument("--seeds", type=int, default=None, help="seeds per cell (default: each artifact's own)")
    parser.add_argument("--only", default=None, help="one artifact stem")
    parser.add_argument("--tiny", action="store_true", help="tiny sizes (smoke test)")
    parser.add_argument("--out", type=Path, default=RESULTS, help="results folder (default: results/)")
    parser.add_argument("--force", action="store_true", help="rerun every run even if a cached result exists")
    args = parser.parse_args(argv)
    try:
        papers = available_papers() if args.paper == "all" else [args.paper]
        for paper in papers:
            if paper not in available_papers():
                raise MagexpError(f"paper={paper!r} is not allowed: choose all or one of {', '.join(available_papers())}")
        if args.jobs < 0:
            raise MagexpError(f"--jobs {args.jobs} is not allowed: it must be >= 0 (0: all cores)")
        from magexp.cli_checks import check_output_folder

        check_output_folder(args.out, "--out")
        start = time.perf_counter()
        for paper in papers:
            reproduce_paper(paper, root=args.out, seeds=args.seeds, jobs=args.jobs, tiny=args.tiny, only=args.only,
                            force=args.force)
        from magexp.report import build

        build(args.out)
        seconds = time.perf_counter() - start
        if args.only is None and args.seeds is None and not args.tiny:
            record_timing(args.out, args.paper, seconds)
        print(f"done in {seconds:.1f} s; report: {args.out / 'REPORT.md'}")
    except MagexpError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("error: interrupted (Ctrl-C); finished runs are cached, rerun the same command to resume",
              file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
