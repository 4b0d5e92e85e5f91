"""An artifact as a reproduction stores it, and its summary read back from what is stored.

Beside an artifact's table (``<name>.csv``) a reproduction writes its runs (``<name>_runs.csv``: one
row per run, :func:`magexp.artifacts.formats.write_csv`, 6 significant digits, round-off floored) and
the facts the summary needs of each cell's first run (``<name>_cells.csv``: :func:`facts_rows`, at
full precision). The summary rows of the artifact are computed from these two files only
(:func:`summarise_stored`), by a reproduction just after writing them and by ``--redraw`` from the
committed ones: one path, so that ``--redraw`` rewrites ``summary.csv`` to the byte and every number
of it recomputes from the runs CSV it names.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd

from magexp.artifacts.formats import read_runs
from magexp.artifacts.plan import ArtifactRuns, plan_artifact
from magexp.artifacts.summary import summarise
from magexp.artifacts.tables import first_output
from magexp.core.atomic import atomic_path


class StoredOutputs(Mapping):
    """``(cell, seed) -> `` the parts of a run's output the summary reads, from the files a reproduction
    wrote (``--redraw``: no run): ``x`` from the runs CSV's parameter columns, and ``parameter_names``,
    ``truth_x``, ``lower``, ``upper``, ``design`` of the cell's first run from its cells CSV
    (``facts``: ``{cell: facts}``, :func:`read_facts`).
    """

    def __init__(self, table: pd.DataFrame, facts: dict):
        self._table = table.set_index(["cell", "seed"], drop=False)
        self._facts = facts

    def __getitem__(self, key):
        facts = self._facts[int(key[0])]
        row = self._table.loc[key]
        x = np.array([float(row[n]) if n in row.index else np.nan for n in facts["parameter_names"]])
        return SimpleNamespace(x=x, **facts)

    def __iter__(self):
        return iter(zip(self._table.cell.astype(int), self._table.seed.astype(int)))

    def __len__(self) -> int:
        return len(self._table)


#: the stored facts of a run that the summary reads (:class:`magexp.estimators.result.RunOutput`): per
#: parameter, and the linear design's arrays (flattened, row-major)
PARAMETER_FACTS, DESIGN_FACTS = ("truth_x", "lower", "upper"), ("gram", "coef", "rss", "n")


def facts_rows(runs) -> pd.DataFrame:
    """The cells CSV of an artifact: per cell, the facts its first run stored (:data:`PARAMETER_FACTS`
    by parameter; :data:`DESIGN_FACTS` where the artifact judges on a least-squares design: ``interval:
    ls``, ``mode: ftest``), one value a row: ``cell, seed, fact, parameter, index, value``.
    """
    design = any(item.interval == "ls" or item.mode == "ftest" for item in runs.spec.summarise)
    rows = []
    for ci in range(len(runs.cells)):
        seed = min(s for c, s in runs.outputs if c == ci)
        out = first_output(runs, ci)
        for fact in PARAMETER_FACTS:
            values = getattr(out, fact, None)
            rows += [] if values is None else [(ci, seed, fact, n, k, float(v))
                                               for k, (n, v) in enumerate(zip(out.parameter_names, values))]
        for fact, values in (out.design or {}).items() if design else ():
            rows += [(ci, seed, fact, "", k, float(v)) for k, v in enumerate(np.ravel(values))]
    return pd.DataFrame(rows, columns=["cell", "seed", "fact", "parameter", "index", "value"])


def write_facts(frame: pd.DataFrame, path: Path) -> None:
    """The cells CSV at full precision (``%.17g``: read back to the bit, so that ``--redraw`` judges on
    what the reproduction judged on).
    """
    with atomic_path(path) as tmp:
        frame.to_csv(tmp, index=False, float_format="%.17g")


def read_facts(path: Path) -> dict[int, dict]:
    """``{cell: {parameter_names, truth_x, lower, upper, design}}`` of a cells CSV (:func:`facts_rows`)."""
    frame = pd.read_csv(path, keep_default_na=False, na_values=[""])  # pandas 3 reads %.17g back to the bit
    out = {}
    for ci, sub in frame.groupby("cell", sort=True):
        arrays = {f: g.sort_values("index") for f, g in sub.groupby("fact")}
        names = [str(n) for n in arrays["lower"].parameter] if "lower" in arrays else []
        got = {f: arrays[f].value.to_numpy(float) if f in arrays else None for f in (*PARAMETER_FACTS, *DESIGN_FACTS)}
        design = None
        if got["gram"] is not None:
            p = int(round(np.sqrt(got["gram"].size)))
            design = {"gram": got["gram"].reshape(p, p), "coef": got["coef"].reshape(p, -1), "rss": got["rss"],
                      "n": int(got["n"][0])}
        out[int(ci)] = {"parameter_names": names, "truth_x": got["truth_x"], "lower": got["lower"],
                        "upper": got["upper"], "design": design}
    return out


def summarise_stored(spec, folder: Path, plan=None) -> pd.DataFrame:
    """The summary rows of ``spec`` from its runs CSV and its cells CSV in ``folder``: the runs as
    written (6 digits, round-off floored), nothing run or simulated. A reproduction returns these
    rows and ``--redraw`` rebuilds them: one path, so that every number of ``summary.csv``
    recomputes from the runs CSV it names.
    """
    plan = plan if plan is not None else plan_artifact(spec)
    table = read_runs(folder / f"{spec.name}_runs.csv")
    facts = read_facts(folder / f"{spec.name}_cells.csv")
    return summarise(ArtifactRuns(spec=spec, cells=plan.cells, table=table, outputs=StoredOutputs(table, facts),
                                  overrides=plan.overrides))
