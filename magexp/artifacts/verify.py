"""Does a reproduction agree with the published one? ``magexp verify`` (what ``make verify`` runs).

    python -m magexp verify [--against DIR] [--committed DIR] [--paper NAME ...] [--rtol R] [--all] [--jobs N]

On another machine (another CPU, numba kernels compiled for another target, the numpy path
``MAGEXP_NUMBA=0``) a reproduction differs from the committed ``results/`` in the last printed digits
of some numbers and in the pixels of its figures; it should not differ in a verdict. ``verify``
holds a reproduction to that; the rules of the comparison (every verdict identical, every number
within a tolerance, texts up to their numbers, figures through their data, what is left out by
design) are :mod:`magexp.artifacts.compare`'s. ``--paper NAME`` (repeatable) checks only those papers: their
files, their rows of ``summary.csv`` and ``claims.csv`` and their sections of the report; a paper the
reproduction has and the committed results lack is named as added, one it lacks as missing
(:mod:`magexp.artifacts.scope`).

The reproduction is ``--against DIR`` if given; else ``results/`` when it differs from the committed
one (after ``make reproduce``); else a reproduction of every paper into ``--into DIR``, by default
:func:`scratch` (``verify/`` beside the run cache: ``.cache/verify`` in a checkout; never ``results/``: only
the runs the cache lacks are computed), named on the screen before it starts. The committed side is
``--committed DIR`` or ``results/`` of the last commit, read from git (``git archive``), so it is
there after ``make reproduce`` overwrote ``results/``.

``--against`` and ``--committed`` are results folders (:func:`results_folder`: they hold
:data:`RESULTS_FILES`, every file of them passing the file gate :func:`magexp.run.files.check_file`); the folder
a reproduction is computed into is new, empty or a results folder of an earlier one (:func:`reproduction_folder`),
whose files it replaces. Anything else is refused in one line before anything is read or computed.
Exit code 0: it agrees; 1: it does not; 2: bad input (no git, a folder that is not a results folder).
"""

from __future__ import annotations

import argparse
import io
import math
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

import numpy as np

from magexp import paths
from magexp.artifacts.compare import FIGURES, PATH_DIAGNOSTICS, Comparison, Difference, compare
from magexp.artifacts.paper_spec import papers
from magexp.artifacts.tolerances import RTOL
from magexp.errors import MagexpError, exit_code
from magexp.core.limits import check_limits
from magexp.run.files import check_file
from magexp.run.flags import OneLineParser
from magexp.run.folders import check_destination

#: how many disagreements the screen lists (the count says how many there are)
SHOWN = 20
#: the files every results folder holds (what ``magexp reproduce`` writes at its top, and verify counts verdicts in)
RESULTS_FILES = ("summary.csv", "claims.csv")
#: the most files a results folder may hold (the committed one holds a few hundred)
MAX_FILES = 100_000


# ---------------------------------------------------------------------------------------------
# which folders

def git(*args: str) -> str:
    """The output of ``git ARGS`` in the checkout; one line (exit 2) when there is no git or no repository."""
    try:
        done = subprocess.run(["git", "-C", str(paths.ROOT), *args], capture_output=True, check=True)
    except FileNotFoundError:
        raise MagexpError("verify reads the committed results/ from git, and git is not installed: "
                          "give the published results with --committed DIR") from None
    except subprocess.CalledProcessError as exc:
        first = (exc.stderr.decode(errors="replace").strip().splitlines() or [""])[0]
        raise MagexpError(f"verify reads the committed results/ from git, which says: {first} "
                          "(give the published results with --committed DIR)") from None
    return done.stdout.decode(errors="replace") if args[0] != "archive" else done.stdout


def committed_results(dest: Path, files=("results",)) -> str:
    """Extract ``results/`` (or only ``files``, paths from the checkout's root) of the last commit
    into ``dest`` (``dest/results/...``); returns a line naming the commit.
    """
    head = git("rev-parse", "--short=12", "HEAD").strip()
    last = git("log", "-1", "--format=%h %cs", "--", "results").strip()
    with tarfile.open(fileobj=io.BytesIO(git("archive", "--format=tar", "HEAD", "--", *files))) as tar:
        tar.extractall(dest, filter="data")
    return f"the committed results/ of HEAD {head} (results last committed in {last})"


def changed_results() -> bool:
    """Whether the working tree's ``results/`` differs from the committed one (git)."""
    return bool(git("status", "--porcelain", "--untracked-files=all", "--", "results").strip())


def scratch() -> Path:
    """The folder of :func:`reproduce_scratch`: beside the run cache (``.cache/verify``), never ``results/``."""
    return paths.CACHE.parent / "verify"


def reproduce_scratch(jobs: int, out: Path, only=None) -> Path:
    """Reproduce every paper (or those of ``only``, one after the other) into ``out`` (:func:`scratch` unless ``--into``;
    runs from the run cache where it has them). The
    figures of the last such reproduction are kept, so that an unchanged figure is not drawn again
    (:mod:`magexp.artifacts.plots.memo`); every other file is written afresh, and a figure whose CSV
    was not written again is removed. (The reproduction takes the committed ``results/peers/`` with it:
    :func:`magexp.artifacts.reproduce.with_peer_bench`.)
    """
    if out.is_dir():
        for path in [p for p in out.rglob("*") if p.is_file() and p.suffix not in FIGURES]:
            path.unlink()
    for target in only or ["all"]:  # a process of its own, as make reproduce runs it (its progress on this terminal)
        code = subprocess.run([sys.executable, "-m", "magexp", "reproduce", target, "--out", str(out), "--jobs",
                               str(jobs)], cwd=paths.ROOT).returncode
        if code:
            raise MagexpError(f"the reproduction of {target} into {out} failed (exit {code})")
    for figure in [p for p in out.rglob("*") if p.suffix in FIGURES and not p.with_suffix(".csv").is_file()]:
        figure.unlink()
    return out


# ---------------------------------------------------------------------------------------------
# the screen

def render(result: Comparison, ours: str, committed: str, *, every: bool = False) -> str:
    """One screen: what was compared with what, the counts, and the verdict of the comparison; up to
    :data:`SHOWN` disagreements each on a line, more grouped by file and column (``every``: each on a line).
    """
    n = sum(result.verdicts.values())
    lines = [f"verify: {ours}", f"  against {committed}",
             f"compared {result.csv_files} CSV files ({result.rows:,} rows, {result.values:,} values), "
             f"{result.text_files} report and LaTeX files ({result.lines:,} lines), {result.figures} figures "
             "(present on both sides; drawn from the CSVs, pixels not compared)",
             "excluded by design: " + ("; ".join(result.excluded) or "nothing"),
             f"verdicts: {n:,} compared (" + ", ".join(f"{v:,} {k}" for k, v in result.verdicts.items())
             + f"): {len(result.changed)} changed" if n else f"verdicts: {len(result.changed)} changed"]
    rule = f"relative {result.rtol:g} or one unit of the printed digit, whichever is larger"
    if result.below:
        big = result.largest
        lines.append(f"within the tolerance ({rule}): {sum(result.below.values()):,} values in {len(result.below)} "
                     f"files differ; the largest: {big.line()} (relative {big.relative:.2g})")
    else:
        lines.append(f"every number identical to the byte (tolerance: {rule})")
    named = ", ".join(PATH_DIAGNOSTICS)
    if result.paths:
        big = result.path_largest
        lines.append(f"path diagnostics ({named}: compared through the verdicts that read them): "
                     f"{sum(result.paths.values()):,} values in {len(result.paths)} files differ; the largest: "
                     f"{big.line()} (relative {big.relative:.2g})")
    else:
        lines.append(f"path diagnostics ({named}: compared through the verdicts that read them): none differ")
    lines += _paper_lines(result)
    wrong = result.changed + result.disagreements
    if result.agrees:
        lines.append("AGREES: every verdict, claim and headline identical, every number within the tolerance "
                     "(path diagnostics through the verdicts), every word identical")
        return "\n".join(lines)
    lines.append(f"DISAGREES: {len(result.changed)} verdicts changed, {len(result.disagreements)} other disagreements"
                 + (f", papers missing: {len(result.scope.missing)}" if result.scope.missing else ""))
    if len(wrong) <= SHOWN or every:
        return "\n".join(lines + [f"  {_shown(d)}" for d in wrong])
    groups: dict[tuple, list] = {}
    for d in wrong:
        groups.setdefault((d.file, d.column), []).append(d)
    lines.append(f"  in {len(groups)} columns and files (each with its largest difference; --all lists every one):")
    lines += [f"  {len(ds)} x {_shown(max(ds, key=_size))}" for ds in list(groups.values())[:SHOWN]]
    if len(groups) > SHOWN:
        lines.append(f"  ... and {len(groups) - SHOWN} more columns and files")
    return "\n".join(lines)


def _paper_lines(result: Comparison) -> list[str]:
    """The screen's lines on the papers: which were compared (when not all), which added, which missing."""
    scope, lines = result.scope, []
    if scope.scoped:
        lines.append(f"papers compared (--paper): {', '.join(sorted(scope.compared)) or 'none on both sides'}")
    if scope.added:
        lines.append(f"papers ADDED (in the reproduction, not in the committed results; not compared): "
                     f"{', '.join(scope.added)}")
    if scope.missing:
        lines.append(f"papers MISSING (committed, not in the reproduction): {', '.join(scope.missing)}"
                     + ("" if scope.scoped else "; --paper NAME checks only the papers reproduced"))
    return lines


def _size(d: Difference) -> float:
    """How far apart a difference is, for sorting (``inf`` when not relative)."""
    return d.relative if np.isfinite(d.relative) else math.inf


def _shown(d: Difference) -> str:
    """A difference's line with its relative size when it has one."""
    return d.line() + (f" (relative {d.relative:.2g})" if np.isfinite(d.relative) else "")


def parser() -> argparse.ArgumentParser:
    """The argument parser of ``magexp verify``."""
    p = OneLineParser(prog="magexp verify", description=__doc__.splitlines()[0])
    p.add_argument("--against", "--out", dest="against", default=None,
                   help="the reproduction to check, a results folder (default: results/ if it differs from the "
                        "committed one, else a fresh reproduction into --into)")
    p.add_argument("--committed", default=None,
                   help="the published results, a results folder (default: results/ of git's HEAD)")
    p.add_argument("--into", default=None,
                   help="where a fresh reproduction is computed: a new or empty folder, or an earlier one's "
                        "(default: verify/ beside the run cache, .cache/verify in a checkout)")
    p.add_argument("--paper", action="append", dest="papers", default=None, metavar="NAME",
                   help="check only this paper (repeatable): its files, rows and report sections")
    p.add_argument("--rtol", type=float, default=RTOL, help=f"relative tolerance of a number (default {RTOL:g})")
    p.add_argument("--all", action="store_true", dest="every", help="list every disagreement, one a line")
    p.add_argument("--jobs", type=int, default=0, help="processes of a fresh reproduction (0: all cores)")
    return p


def results_folder(text: str, what: str) -> Path:
    """The results folder ``text`` given as ``what`` (``--against``, ``--committed``): a folder holding
    :data:`RESULTS_FILES`, at most :data:`MAX_FILES` files, each passing the file gate
    (:func:`magexp.run.files.check_file`: no device or FIFO, within the size and line limits); else one line
    (a :class:`~magexp.errors.MagexpError`).
    """
    path = Path(text).expanduser()
    if not path.is_dir():  # a device, FIFO or socket too: refused unopened
        raise MagexpError(f"{what} {text!r} is not allowed: it is not a folder (give a results folder: "
                          f"one holding {' and '.join(RESULTS_FILES)}, as magexp reproduce writes)")
    missing = [name for name in RESULTS_FILES if not (path / name).is_file()]
    if missing:
        raise MagexpError(f"{what} {text!r} is not allowed: it is not a results folder (it has no "
                          f"{' and no '.join(missing)}); give results/ or a folder magexp reproduce --out wrote")
    for n, file in enumerate(path.rglob("*")):
        if n >= MAX_FILES:
            raise MagexpError(f"{what} {text!r} is not allowed: it holds more than {MAX_FILES} files, "
                              "and a results folder a few hundred")
        check_file(file, what, kind="figure" if file.suffix in FIGURES else "text", folder=True)
    return path


def reproduction_folder(text: str | None) -> Path:
    """The folder a reproduction is computed into: ``--into`` (``text``) or :func:`scratch`; it must be new,
    empty or a results folder of an earlier reproduction (:func:`reproduce_scratch` replaces its files), and a
    folder a command may write (:func:`magexp.run.folders.check_destination`: not inside ``results/``); a
    folder holding anything else is refused (:class:`~magexp.errors.MagexpError`).
    """
    what = "--into" if text is not None else "the reproduction's default folder (--into)"
    folder = Path(text).expanduser() if text is not None else scratch()
    check_destination(folder, what)
    if folder.exists() and not (folder.is_dir() and not any(folder.iterdir())):
        try:
            results_folder(str(folder), what)
        except MagexpError:
            raise MagexpError(f"{what} {str(folder)!r} is not allowed: it holds files that are no reproduction's, "
                              "which verify would replace; give a new or empty folder with --into DIR") from None
    return folder


def _check_papers(names: list[str] | None, *, fresh: bool) -> None:
    """``--paper`` names: each once and, for a fresh reproduction, a paper of ``experiments/`` (one line if not;
    with ``--against``, :func:`magexp.artifacts.scope.paper_scope` checks them against the folders)."""
    for i, name in enumerate(names or []):
        if name in names[:i]:
            raise MagexpError(f"--paper {name!r} is not allowed twice")
        if fresh and name not in papers():
            raise MagexpError(f"--paper {name!r} is not allowed: it is no paper of experiments/ (there are: "
                              f"{', '.join(papers())})")


def command(argv: list[str]) -> int:
    """``magexp verify [OPTIONS]``: 0 when the reproduction agrees, 1 when not (errors are raised:
    the one error path, :func:`magexp.errors.guarded`, turns them into one line and exit 2).
    """
    check_limits()
    args = parser().parse_args(argv)
    if not 0 <= args.rtol < 1:
        raise MagexpError(f"--rtol {args.rtol!r} is not allowed: it must be a number >= 0 and < 1")
    if args.jobs < 0:
        raise MagexpError(f"--jobs {args.jobs} is not allowed: it must be an integer >= 0")
    _check_papers(args.papers, fresh=args.against is None)
    ours = results_folder(args.against, "--against") if args.against is not None else None
    committed = results_folder(args.committed, "--committed") if args.committed is not None else None
    if ours is not None and args.into is not None:
        raise MagexpError(f"--into {args.into!r} is not allowed with --against: verify reproduces into a folder only "
                          "when it is given no reproduction to check")
    working = ours is None and args.into is None and changed_results()
    into = reproduction_folder(args.into) if ours is None and not working else None
    with tempfile.TemporaryDirectory(prefix="magexp-verify-") as tmp:
        if committed is not None:
            named = f"{args.committed} (--committed)"
        else:
            named = committed_results(Path(tmp))
            committed = Path(tmp) / "results"
        if working:
            ours, label = paths.RESULTS, "results/ (the working tree: it differs from the committed one)"
        elif ours is None:
            print(f"results/ is the committed one: reproducing every paper into {into} first", flush=True)
            ours = reproduce_scratch(args.jobs, into, args.papers)
            label = f"{ours} (reproduced now: results/ is the committed one)"
        else:
            label = str(ours)
        result = compare(ours, committed, rtol=args.rtol, papers=args.papers)
        print(render(result, label, named, every=args.every))
    if not result.agrees:
        raise SystemExit(1)
    return 0


def main(argv=None) -> int:
    """``python -m magexp.artifacts.verify ...``: the exit code of :func:`command` (2 on bad input)."""
    return exit_code(command, sys.argv[1:] if argv is None else list(argv))


if __name__ == "__main__":
    sys.exit(main())
