"""``magexp new-paper NAME``: a new paper's folder, ``experiments/NAME/``, that reproduces as written.

It writes two files, every value the user must replace marked ``EDIT`` (in the titles and texts, which the
report shows) and every key commented:

* ``paper.yaml``: the title, an intro linking to the guide (``docs/extending.md``), the report ``order``, one
  deviation and one headline with its section, figure and parts;
* ``NAME_fig1.yaml``: one artifact, a grid over the existing scenario ``ding2024_exp1`` (the number of readings
  swept, two closed-form estimators: a few seconds on 2 cores), its ``summarise``, one ``reported`` value that is
  a Monte-Carlo statistic (``statistic: median``, ``trials:``) and a claim of each kind: a comparison
  (``ordering``), a ``threshold`` and a ``trend`` (the trend and the threshold: the headline's parts).

``magexp reproduce NAME`` then checks the spec whole, runs it and writes its section of the report
(docs/extending.md, "Start from the scaffold"). NAME must be a lowercase Python identifier that is no folder of
``experiments/`` yet: otherwise one line, exit code 2, nothing written.
"""

from __future__ import annotations

import argparse
import keyword
import re
from pathlib import Path
from string import Template

from magexp import paths
from magexp.errors import MagexpError

#: a paper's name: a lowercase identifier (it prefixes its artifacts' names and is a make target)
NAME = re.compile(r"[a-z][a-z0-9_]*\Z")

PAPER = Template('''\
# experiments/$name/paper.yaml: the paper's section of the report (docs/extending.md, "Every key of a spec").
# Written by `magexp new-paper $name`: replace every EDIT with the paper's own words.
title: "$name (a new paper: EDIT experiments/$name/paper.yaml)"
# the section's opening paragraph: what the paper does and what magexp runs of it
intro: >
  EDIT: the paper's method and what magexp reproduces of it. Scaffolded by `magexp new-paper`; the guide to
  completing it is [docs/extending.md](../docs/extending.md#start-from-the-scaffold).
order: 900          # the section's place in the report (lower: earlier; the existing papers' are lower)
deviations:         # where magexp departs from the paper's text, and why
  - text: "EDIT: a setting the paper does not state (here: the noise amplitude A = 2 nT)."
    reason: "EDIT: why magexp's choice is the one the paper's words make most plausible."
headline:           # the paper's own claims, each judged by the artifact claims named in parts
  - id: offset_falls_with_n
    text: "EDIT: the paper's claim in its own words (here: the ellipsoid fit's offset error falls as N grows and is small at N = 200)."
    section: "EDIT: where the paper says it (Sec., Fig.)"
    figure: $name/${name}_fig1       # <paper folder>/<artifact> whose figure shows it
    parts: [${name}_fig1.offset_falls, ${name}_fig1.offset_small_at_200]
''')

ARTIFACT = Template('''\
# experiments/$name/${name}_fig1.yaml: one figure of the paper (docs/extending.md, "Every key of a spec").
# Written by `magexp new-paper $name`; reproduce it with `magexp reproduce $name --out scratch`.
name: ${name}_fig1
paper: $name
title: "EDIT: Fig. 1 of the paper (here: offset error vs number of readings, Ding 2024 simulation 1, A = 2 nT)"
kind: final                  # a plot kind (docs/extending.md, "Plot kinds")
seeds: 30                    # per cell (a cell compared with a paper number needs 30; a trend 5 at each axis value)
base: [scenario=ding2024_exp1, scenario.noise=2]   # overrides of every run: an existing scenario
grid:                        # the cells: the cartesian product of these keys' values
  scenario.n_readings: [20, 60, 200]
  estimator: [ellipsoid, lm]
plot: {x: scenario.n_readings, hue: estimator, xscale: log, metric: offset_error,
       ylabel: "offset error (nT)", labels: {scenario.n_readings: "number of readings N"}}
summarise:                   # rows of summary.csv: a statistic of a metric per cell
  - {quantity: offset_error, metric: offset_error}
reported:                    # the paper's printed numbers, each compared with the cell it matches
  # EDIT: the paper's value. statistic/trials: it is the median over the paper's own 1000 trials
  # (judged against the interval of that statistic, docs/extending.md, "Trend claims and Monte-Carlo values")
  - {quantity: offset_error, match: {scenario.n_readings: 200, estimator: ellipsoid}, value: 1.0,
     statistic: median, trials: 1000}
claims:                      # each judged against the distribution of the runs
  - id: offset_falls
    by: paper
    section: "EDIT: where the paper says it"
    text: "EDIT (a trend): the ellipsoid fit's offset error falls as the number of readings N grows"
    kind: trend
    metric: offset_error
    axis: scenario.n_readings    # a numeric key of the grid: the slope is over every cell along it
    where: {estimator: ellipsoid}
    log: true                    # the slope of log metric against log axis: an exponent
    sign: negative               # or between: [lo, hi] (e.g. [-0.6, -0.4] for "falls as 1/sqrt(N)")
    # EDIT: the slope you expect and the spread of a seed's log error around the line, which plan the seeds
    # (tested in the paper's Holm family: docs/extending.md, "Trend claims and Monte-Carlo values")
    effect: {slope: -0.5, spread: 0.5}
  - id: offset_small_at_200
    by: paper
    section: "EDIT: where the paper says it"
    text: "EDIT (a threshold): with 200 readings the ellipsoid fit's median offset error is at most 5 nT"
    kind: threshold
    metric: offset_error
    where: {estimator: ellipsoid, scenario.n_readings: 200}
    op: "<="
    value: 5
  - id: more_readings_better
    text: "EDIT (a comparison): Levenberg-Marquardt's offset error is smaller with 200 readings than with 20"
    kind: ordering               # each cell better (here: lower median) than the next, by a one-sided test
    metric: offset_error
    # EDIT: the smallest effect worth detecting (here: a median twice as low) and the metric's log spread over
    # seeds, which plan the cells' seeds (docs/results.md, "Sample sizes")
    effect: {ratio: 2, spread: 0.5}
    cells: [{estimator: lm, scenario.n_readings: 200}, {estimator: lm, scenario.n_readings: 20}]
caption: >
  EDIT: median over {seeds} seeds (bars: IQR) of the offset error; numbers in a caption are interpolated from
  the runs, never typed.
''')


def check_name(name: str, root: Path) -> None:
    """Raise :class:`~magexp.errors.MagexpError` unless ``name`` is a lowercase identifier and no folder of ``root``."""
    if not NAME.match(name) or keyword.iskeyword(name):
        raise MagexpError(f"new-paper: NAME={name!r} is not allowed: a lowercase identifier "
                          "(a letter, then letters, digits or _), e.g. smith2025")
    if (root / name).exists():
        taken = ", ".join(sorted(p.name for p in root.iterdir() if p.is_dir()))
        raise MagexpError(f"new-paper: experiments/{name} exists and is never overwritten: choose a name other "
                          f"than {taken}")


def new_paper(name: str, root: Path | None = None) -> list[Path]:
    """Write the folder of a new paper, ``root/name/``: its ``paper.yaml`` and one artifact.

    Parameters
    ----------
    name : str
        The paper's name: a lowercase identifier that is no folder of ``root`` yet.
    root : pathlib.Path, optional
        The folder of the papers (default ``experiments/``).

    Returns
    -------
    list of pathlib.Path
        The files written.

    Raises
    ------
    magexp.errors.MagexpError
        When ``name`` is not allowed or ``root/name`` exists (nothing is written).
    """
    root = root or paths.EXPERIMENTS
    check_name(name, root)
    folder = root / name
    files = {folder / "paper.yaml": PAPER, folder / f"{name}_fig1.yaml": ARTIFACT}
    folder.mkdir(parents=True)
    for path, template in files.items():
        path.write_text(template.substitute(name=name))
    return list(files)


def command(args: list[str]) -> None:
    """``magexp new-paper NAME``: write ``experiments/NAME/`` and say what to do next.

    Parameters
    ----------
    args : list of str
        The command line after ``new-paper``.
    """
    parser = argparse.ArgumentParser(prog="magexp new-paper", description="Write experiments/NAME/: a new paper (paper.yaml and one artifact) that reproduces as written; every value to replace is marked EDIT (docs/extending.md, \"Start from the scaffold\").")
    parser.add_argument("name", help="the paper's name: a lowercase identifier, not yet a folder of experiments/")
    name = parser.parse_args(args).name
    for path in new_paper(name):
        print(f"wrote {path.relative_to(Path.cwd()) if path.is_relative_to(Path.cwd()) else path}")  # where it is
    print(f"next: replace every EDIT, then `magexp reproduce {name} --out scratch` "
          "(docs/extending.md, \"Start from the scaffold\")")
