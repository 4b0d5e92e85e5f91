"""Tables apart from plots: every aggregation in magexp.artifacts.tables (and the kinds' tables built on
it), none in the plot modules; verdicts judged on the runs as written (what a reader recomputes)."""

import ast
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from magexp.artifacts import plots, reproduce
from magexp.artifacts.plan import ArtifactRuns
from magexp.artifacts.spec import parse
from magexp.artifacts.summary import summarise
from magexp.artifacts.tables import interval, quartiles

#: calls that aggregate a table or an array over its rows: they belong in magexp.artifacts.tables
AGGREGATIONS = {"groupby", "agg", "aggregate", "pivot_table", "median", "nanmedian", "mean", "nanmean", "average",
                "quantile", "nanquantile", "percentile", "nanpercentile", "std", "nanstd", "var", "nanvar",
                "describe", "resample", "rolling", "expanding", "quantiles", "interval", "ci"}


def aggregating_calls(path: Path) -> list[str]:
    """``file:line name`` of every call in ``path`` to a name of :data:`AGGREGATIONS` (``np.median(...)``,
    ``frame.groupby(...)``, ``quantiles(...)``), but those of :mod:`magexp.artifacts.tables` itself."""
    tree = ast.parse(path.read_text())
    tables = {a.asname or a.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
              and node.module in ("magexp.artifacts.tables",) for a in node.names}
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            name = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
            if name in AGGREGATIONS and not (isinstance(node.func, ast.Name) and name in tables):
                found.append(f"{path.name}:{node.lineno} {name}")
    return found


def test_no_plot_module_aggregates():
    modules = sorted(Path(plots.__file__).parent.glob("*.py"))
    assert len(modules) > 10
    found = [hit for path in modules for hit in aggregating_calls(path)]
    assert found == [], f"plots draw what magexp.artifacts.tables hands them; these aggregate: {found}"


def test_the_check_sees_an_aggregation_that_comes_back(tmp_path):
    module = tmp_path / "kind.py"
    module.write_text("from magexp.artifacts.tables import median\n\n\ndef draw(frame, spec):\n"
                      "    return median(frame.value), frame.groupby('case').value.median()\n")
    assert aggregating_calls(module) == ["kind.py:5 median", "kind.py:5 groupby"]


def test_one_interval_helper_gives_the_run_interval_the_quartiles_and_the_bootstrap():
    v = np.r_[np.arange(1.0, 41.0), np.nan]
    assert interval(v) == pytest.approx(np.quantile(np.arange(1.0, 41.0), [0.025, 0.975]))
    assert quartiles(v) == pytest.approx((20.5, 10.75, 30.25))
    assert interval([0.0, 1e-12, 3.0], floor=1e-9)[0] == pytest.approx(0.025 * 2 * 1e-9 + 0.0, abs=1e-9)
    lo, hi = interval(v[:-1], stat="median")
    assert 10 < lo < 20.5 < hi < 31 and interval(v[:-1], stat="median") == (lo, hi)  # a fixed generator
    assert np.isnan(interval([np.nan])).all() and np.isnan(interval([1.0], stat="median")).all()


def test_a_verdict_is_judged_on_the_runs_as_written(tmp_path):
    """30 runs at 1.0000004 against a paper value of 1.0 printed to 7 decimals: the runs CSV writes them
    as 1 (6 digits), and the verdict is the one a reader recomputes from it, the paper's value inside
    (reproduced), not the one of the unrounded runs (differs): summary.csv says nothing its runs CSV
    does not (issue 39), and ``--redraw``, which reads the CSV, writes the same row."""
    spec = parse({"kind": "final", "title": "t", "seeds": 30, "plot": {"x": "scenario.noise"},
                  "summarise": [{"quantity": "q", "metric": "q"}],
                  "reported": [{"quantity": "q", "match": {"estimator": "pso"}, "value": 1.0, "decimals": 7}]},
                 Path("p") / "a.yaml")
    table = pd.DataFrame([{"cell": 0, "seed": s, "estimator": "pso", "scenario.noise": "2", "objective": "scalar",
                           "setting": "s", "q": 1.0000004} for s in range(30)])
    stored = SimpleNamespace(parameter_names=[], x=np.array([]), truth_x=None, lower=None, upper=None, design=None)
    runs = ArtifactRuns(spec=spec, cells=[{"estimator": "pso", "scenario.noise": "2"}], table=table,
                        outputs={(0, s): stored for s in range(30)}, overrides=[["estimator=pso", "scenario.noise=2"]])
    assert summarise(runs).verdict.tolist() == ["differs"]  # the unrounded runs, which no file shows
    rows = reproduce.write_artifact(runs, tmp_path)
    assert set(pd.read_csv(tmp_path / "a_runs.csv").q) == {1.0}
    assert rows.verdict.tolist() == ["reproduced"] and rows.value.tolist() == [1.0]
