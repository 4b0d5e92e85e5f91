"""The whole spec checked before any run (issue 44 item 2, :mod:`magexp.artifacts.spec_check`): every committed
artifact passes it; a metric names dotted config keys as written, evaluated and checked alike; a claim that cannot
be evaluated is a bug, never a verdict. Each spec mistake through the command line: ``tests/test_bad_input.py``
(its ``spec_mistake`` rows)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from magexp import paths
from magexp.artifacts.claims import Claim, NotEvaluable, evaluate
from magexp.artifacts.paper_spec import papers
from magexp.artifacts.plan import paper_specs, plan_artifact
from magexp.artifacts.reproduce import skipped_for_data
from magexp.artifacts.run_columns import planned_columns
from magexp.artifacts.selection import column, expression
from magexp.artifacts.spec import parse
from magexp.artifacts.spec_check import check_claims, check_plan, planned_table
from magexp.errors import MagexpError
from magexp.estimators.lm import LevenbergMarquardt


#: make test checks the smallest paper; make test-full every one
@pytest.mark.parametrize("paper", [pytest.param(p, marks=[] if p == "yan2022" else [pytest.mark.full]) for p in papers()])
def test_every_committed_artifact_passes_the_check(paper):
    """Each artifact of ``experiments/`` planned (one seed a cell: the cells are what is checked) passes the
    check, on a planned table that has each planned cell once and the columns its claims name, and every column of
    its committed runs table (an artifact whose recordings are absent is skipped, as a reproduction skips it)."""
    for spec in [s for s in paper_specs(paper) if not skipped_for_data(s, log=lambda line: None)]:
        plan = plan_artifact(spec, seeds=1)
        check_plan(plan)
        table = planned_table(plan)
        assert len(table) == len(plan.cells) and table.columns.is_unique
        assert {c.metric for c in spec.claims if c.metric in table} <= set(table.columns)
        runs = paths.RESULTS / paper / f"{spec.name}_runs.csv"  # the committed runs: no column the census lacks
        if runs.exists():
            assert set(pd.read_csv(runs, nrows=0).columns) <= set(table.columns), spec.name


def test_a_dotted_config_key_is_written_as_it_is():
    """``scenario.n_readings`` and ``iterations_to_1.1`` are columns, not attribute access: quoted where they
    stand whole, left as written inside backticks or as part of a longer name."""
    columns = ["offset_error", "scenario.n_readings", "scenario.n", "iterations_to_1.1"]
    assert expression("offset_error * scenario.n_readings ** 0.6", columns) == "offset_error * `scenario.n_readings` ** 0.6"
    assert expression("`scenario.n` + scenario.n", columns) == "`scenario.n` + `scenario.n`"
    assert expression("log(iterations_to_1.1) - 1.5e-3", columns) == "log(`iterations_to_1.1`) - 1.5e-3"
    table = pd.DataFrame({c: [2.0, 4.0] for c in columns})
    np.testing.assert_allclose(column(table, "offset_error * scenario.n_readings ** 0.5"), [2 * 2 ** 0.5, 8.0])
    with pytest.raises(MagexpError, match="scenario.n_reading"):
        column(table, "offset_error * scenario.n_reading")


def _runs() -> pd.DataFrame:
    """A runs table of two cells (noise 1 and 2) of three seeds."""
    return pd.DataFrame({"cell": [0, 0, 0, 1, 1, 1], "seed": [0, 1, 2] * 2, "scenario.noise": [1.0] * 3 + [2.0] * 3,
                         "setting": ["scenario=s;scenario.noise=1"] * 3 + ["scenario=s;scenario.noise=2"] * 3,
                         "estimator": ["lm"] * 6, "fun": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]})


def test_a_claim_that_cannot_be_evaluated_is_a_bug_not_a_verdict():
    """A metric the runs lack or a selection of no cell raises :class:`NotEvaluable` when judged (never "does
    not hold"), and the check refuses it first, naming the entry and what exists."""
    runs = _runs()
    good = Claim(id="low", text="t", kind="threshold", metric="fun * scenario.noise", op="<=", value=20)
    assert evaluate(good, runs).holds
    bad = [Claim(id="typo", text="t", kind="threshold", metric="fum", op="<=", value=1),
           Claim(id="none", text="t", kind="threshold", where={"scenario.noise": 3}, op="<=", value=1),
           Claim(id="pair", text="t", kind="ordering", cells=[{"scenario.noise": 1}, {"scenario.noise": 5}])]
    words = ["'fum' is no column", "selects no planned cell", "selects no planned cell"]
    for claim, said in zip(bad, words):
        with pytest.raises(NotEvaluable, match="a bug"):
            evaluate(claim, runs)
        spec = type("Spec", (), {"name": "art", "claims": [claim]})()
        with pytest.raises(MagexpError, match=f"art.claims\\[{claim.id}\\].*{said}.*"):
            check_claims(spec, runs)


def _toy(metric: str):
    """An artifact of ``lm`` at two noise levels with one threshold claim on ``metric``."""
    claim = {"id": "steps", "text": "t", "kind": "threshold", "metric": metric, "where": {"estimator": "lm"},
             "op": "<=", "value": 100}
    return parse({"title": "t", "kind": "final", "seeds": 2, "base": ["scenario=ding2024_exp1"],
                  "grid": {"scenario.noise": [1, 10], "estimator": ["lm"]}, "plot": {"x": "scenario.noise"},
                  "claims": [claim]}, Path("toy_fig1.yaml"))


def test_a_metric_an_estimator_declares_is_known_before_any_run(monkeypatch):
    """The census comes from the writers' declarations, not from committed runs: a metric the estimator class
    declares (``METRICS``) passes the check with no run anywhere; undeclared, or misspelt, it is refused in one
    line naming the artifact, the claim and the nearest columns."""
    def plan(metric):
        return plan_artifact(_toy(metric), seeds=1)

    with pytest.raises(MagexpError, match="toy_fig1.claims\\[steps\\].metric='lm_steps'.*no column"):
        check_plan(plan("lm_steps"))
    monkeypatch.setattr(LevenbergMarquardt, "METRICS", (*LevenbergMarquardt.METRICS, "lm_steps"))
    check_plan(plan("lm_steps"))
    check_plan(plan("log(lm_steps) - offset_standard_error"))
    with pytest.raises(MagexpError) as refused:
        check_plan(plan("lm_stesp"))
    said = str(refused.value)
    assert "\n" not in said and "toy_fig1.claims[steps].metric='lm_stesp'" in said and "nearest: lm_steps" in said


def test_the_census_is_the_declarations_of_the_planned_writers():
    """An artifact's columns are its cells' writers' declarations: a Ding artifact (scalar problem, inverse
    parameterisation) has ``Minv11`` and a swarm's ``on_boundary`` but no Kalman filter's ``steps_to_ls``; a Yan
    one with the analysis step has ``K11``, ``steps_to_ls`` and ``Be1``; the wall time is not stored."""
    ding = planned_columns(plan_artifact(paper_specs("ding2024")[0], seeds=1))
    assert {"Minv11", "I3", "offset_error", "fun", "on_boundary", "succeeded"} <= ding
    assert not {"S11", "K11", "steps_to_ls", "Be1", "wall_time"} & ding
    yan = planned_columns(plan_artifact(next(s for s in paper_specs("yan2022") if s.name == "yan2022_fig4"), seeds=1))
    assert {"K11", "Bp3", "steps_to_ls", "Be1", "be_rms"} <= yan and not {"Minv11", "on_boundary"} & yan
