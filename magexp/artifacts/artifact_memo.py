"""An artifact written once per content of its inputs: an unchanged artifact's files and summary rows are reused.

Writing an artifact (:func:`magexp.artifacts.reproduce.write_artifact`: its table, runs CSV, cells CSV, timing
file, figure, then its summary rows read back from what it wrote) is deterministic: the same inputs give the
same bytes. So an artifact is keyed by

* its runs: the run keys of its plan (each naming a run's config and the code it executed,
  :mod:`magexp.run.runkeys`) and their rows as read (:func:`magexp.run.executor.run_row`),
* its plan: the artifact (``repr`` of the validated :class:`magexp.artifacts.spec.Artifact`, its file), its cells
  and their overrides, the ``seeds`` and ``tiny`` asked for,
* what writes it: every file of magexp's source, ``conf/`` and ``experiments/``
  (:func:`magexp.artifacts.plan_cache.inputs_digest`), the drawing libraries and matplotlib's settings
  (:func:`magexp.artifacts.plots.memo.drawing_version`),

and its memo (:class:`magexp.artifacts.memo.Memo`, ``<run cache>-artifacts``) keeps under that key the digests of
the files written and the summary rows returned (as columns of plain values with their dtypes, kept only when
they read back equal). An artifact whose files are all still in place with those digests is not written again,
and its summary rows are those kept.
"""

from __future__ import annotations

import hashlib
import json
from functools import lru_cache
from pathlib import Path

import pandas as pd

from magexp.artifacts.memo import Memo, beside_cache
from magexp.artifacts.plan_cache import inputs_digest
from magexp.artifacts.plots import VECTOR
from magexp.artifacts.plots.memo import drawing_version

#: the written artifacts' digests and summary rows
ARTIFACTS = Memo("WrittenArtifact", lambda: beside_cache("artifacts"))


@lru_cache(maxsize=1)
def code_version() -> str:
    """The digest of what writes an artifact or builds the report, but its own inputs (module docstring)."""
    return hashlib.sha256(f"{inputs_digest()} {drawing_version()}".encode()).hexdigest()


def _plain(value):
    """A value of a run's row that JSON cannot hold (a numpy array or scalar) as the list or number it equals."""
    return value.tolist() if hasattr(value, "tolist") else repr(value)


def key(plan, outputs, seeds: int | None, tiny: bool) -> str:
    """The key of the artifact of ``plan`` written from ``outputs`` (its runs, in ``plan.configs`` order) for
    ``seeds`` and ``tiny`` (module docstring)."""
    h = hashlib.sha256(code_version().encode())
    h.update(json.dumps([repr(plan.spec), str(getattr(plan.spec, "path", None)), seeds, tiny, plan.cells,
                         plan.overrides, [list(i) for i in plan.index]], default=_plain).encode())
    h.update(json.dumps(list(outputs.keys)).encode())
    h.update(json.dumps([outputs.metrics(i) for i in range(len(outputs))], default=_plain).encode())
    return h.hexdigest()[:32]


def files(spec, out: Path) -> list[Path]:
    """The files :func:`magexp.artifacts.reproduce.write_artifact` wrote for ``spec`` into ``out`` (its timing file
    where there is one)."""
    name = spec.name
    written = [out / f"{name}{end}" for end in (".csv", "_runs.csv", "_cells.csv", ".png", VECTOR)]
    timing = out.parent / "timing" / f"{name}.csv"
    return written + ([timing] if timing.is_file() else [])


def columns(frame: pd.DataFrame) -> dict | None:
    """``frame`` as plain values (``{"columns", "dtypes", "values"}``), or None where that does not read back
    (:func:`frame_of`) to an equal frame of the same dtypes."""
    value = {"columns": [str(c) for c in frame.columns], "dtypes": [str(t) for t in frame.dtypes],
             "values": [frame[c].tolist() for c in frame.columns]}
    try:
        again = frame_of(json.loads(json.dumps(value)))
    except (TypeError, ValueError):
        return None
    same = (list(again.columns) == list(frame.columns) and list(again.dtypes) == list(frame.dtypes)
            and again.index.equals(frame.index) and again.equals(frame))
    return value if same else None


def frame_of(value: dict) -> pd.DataFrame:
    """The frame :func:`columns` gave ``value``."""
    data = {c: pd.Series(v, dtype=t) for c, t, v in zip(value["columns"], value["dtypes"], value["values"])}
    return pd.DataFrame(data, columns=value["columns"])


def recall(k: str, spec, out: Path) -> pd.DataFrame | None:
    """The summary rows kept under key ``k`` if the files written then are in ``out`` unchanged; else None."""
    kept = ARTIFACTS.recall(k, out)
    if kept is None:
        return None
    try:
        return frame_of(kept["value"])
    except (TypeError, ValueError, KeyError):
        return None


def keep(k: str, spec, out: Path, rows: pd.DataFrame) -> None:
    """Keep, under key ``k``, the digests of the artifact ``spec`` just written into ``out`` and its summary
    ``rows`` (nothing where the rows do not read back equal)."""
    value = columns(rows)
    if value is not None:
        ARTIFACTS.record(k, out, files(spec, out), value)
