"""Claims: conditions on the runs, evaluated from the data; no claim the report states as true is false."""

import numpy as np
import pandas as pd
import pytest

from magexp.claims import Claim, ci, evaluate, interpolate
from magexp.errors import MagexpError
from magexp.paths import RESULTS
from magexp.report import claim_outcomes


def _table(groups: dict) -> pd.DataFrame:
    """A runs table: one cell per estimator with the given per-seed ``fun`` values."""
    rows = []
    for ci_, (est, values) in enumerate(groups.items()):
        rows += [{"cell": ci_, "seed": s, "estimator": est, "setting": "scenario=x", "fun": v,
                  "succeeded": float(v < 10)} for s, v in enumerate(values)]
    return pd.DataFrame(rows)


RNG = np.random.default_rng(1)
TABLE = _table({"a": 1 + 0.01 * RNG.standard_normal(40), "b": 2 + 0.01 * RNG.standard_normal(40),
                "c": 1.001 + 0.01 * RNG.standard_normal(40), "d": np.r_[np.ones(15), np.full(25, 100.0)]})


def test_ordering_holds_and_fails():
    up = Claim(id="o", text="", kind="ordering", cells=[{"estimator": "a"}, {"estimator": "b"}])
    down = Claim(id="o", text="", kind="ordering", cells=[{"estimator": "b"}, {"estimator": "a"}])
    assert evaluate(up, TABLE).holds and not evaluate(down, TABLE).holds


def test_a_winner_needs_separated_intervals():
    clear = Claim(id="w", text="", kind="winner", cells=[{"estimator": "a"}, {"estimator": "b"}])
    close = Claim(id="w", text="", kind="winner", cells=[{"estimator": "a"}, {"estimator": "c"}])
    assert evaluate(clear, TABLE).holds
    assert not evaluate(close, TABLE).holds  # a has the lower median, but the CIs overlap


def test_threshold_and_success_on_every_selected_cell():
    ok = Claim(id="t", text="", kind="threshold", where={"estimator": "a"}, op="<", value=1.1)
    bad = Claim(id="t", text="", kind="threshold", where={}, op="<", value=1.1)  # b fails it
    assert evaluate(ok, TABLE).holds and not evaluate(bad, TABLE).holds
    fails = Claim(id="s", text="", kind="success", where={"estimator": "d"}, op=">=", value=0.5)
    outcome = evaluate(fails, TABLE)
    assert not outcome.holds and "success_rate 0.375" in outcome.evidence


def test_seeds_key_keeps_the_first_seeds():
    c = Claim(id="t", text="", kind="success", where={"estimator": "d", "seeds": 15}, op=">=", value=1.0)
    assert evaluate(c, TABLE).holds  # the first 15 seeds of d succeed, all 40 do not
    assert interpolate("{n:fun@estimator=d,seeds=10}", TABLE) == "10"
    assert interpolate("{max:fun@estimator=d,succeeded=1}", TABLE) == "1"  # a runs column filters rows


def test_no_runs_never_holds():
    c = Claim(id="t", text="", kind="threshold", where={"estimator": "zz"}, op="<", value=1)
    assert not evaluate(c, TABLE).holds


def test_bootstrap_interval_covers_the_statistic_and_is_deterministic():
    v = RNG.standard_normal(200)
    lo, hi = ci(v, "mean")
    assert lo < v.mean() < hi and hi - lo == pytest.approx(2 * 1.96 / np.sqrt(200), rel=0.25)
    assert ci(v, "mean") == (lo, hi)


def test_notes_interpolate_measured_values():
    text = interpolate("a: {median:fun@estimator=d:.3g}, ok {success_rate:fun@estimator=d:.0%}", TABLE)
    assert text == "a: 100, ok 38%"
    with pytest.raises(MagexpError, match="stat 'avg'"):
        interpolate("{avg:fun@estimator=a}", TABLE)


def test_bad_claims_fail_with_one_line():
    with pytest.raises(MagexpError, match="kind='rank' is not allowed"):
        Claim(id="x", text="", kind="rank")
    with pytest.raises(MagexpError, match="needs at least two cells"):
        Claim(id="x", text="", kind="winner", cells=[{}])


def test_no_claim_the_report_states_is_false():
    """Every ``by: magexp`` claim holds on the committed results (skipped where they are absent or
    predate the success column, i.e. were made by an older magexp: regenerate them)."""
    summary = RESULTS / "summary.csv"
    if not summary.exists() or "success_rate" not in summary.read_text().splitlines()[0]:
        pytest.skip("results/ are absent or predate the verdict columns: run make reproduce")
    outcomes = claim_outcomes(RESULTS)
    if not outcomes:
        pytest.skip("no results with claims under results/")
    false = [f"{name}: {o.claim.id}: {o.evidence}" for name, o in outcomes if o.claim.by == "magexp" and not o.holds]
    assert not false, "\n".join(false)


def test_cell_settings_are_each_cells_first_row():
    import pandas as pd

    from magexp.claims import cell_settings

    def by_groupby(table):  # the reference: a groupby over cells, each cell's first row
        out = {}
        for ci, sub in table.groupby("cell", sort=True):
            first = sub.iloc[0]
            pairs = dict(p.split("=", 1) for p in str(first.get("setting", "") or "").split(";") if "=" in p)
            for key in ("estimator", "objective", "scenario", "case"):
                if key in sub and key not in pairs:
                    pairs[key] = first[key]
            out[int(ci)] = pairs
        return out

    table = pd.DataFrame({"cell": [2, 0, 2, 1, 0], "seed": [0, 0, 1, 0, 1],
                          "setting": ["scenario=a;noise=2", "scenario=b;noise=0.5", "x=9", None, "y=1"],
                          "estimator": ["lm", "pso", "ipso", "kf", "ls"], "fun": [1.0, 2.0, 3.0, 4.0, 5.0]})
    assert cell_settings(table) == by_groupby(table)
    assert cell_settings(table) == {0: {"scenario": "b", "noise": "0.5", "estimator": "pso"},
                                    1: {"estimator": "kf"}, 2: {"scenario": "a", "noise": "2", "estimator": "lm"}}
    assert cell_settings(table.drop(columns=["setting"])) == by_groupby(table.drop(columns=["setting"]))
    assert cell_settings(table.iloc[:0]) == {}
