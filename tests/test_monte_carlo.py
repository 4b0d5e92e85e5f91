"""A paper's Monte-Carlo value (a statistic over its own trials) is judged against the interval of our
statistic over as many runs (magexp.artifacts.monte_carlo), not the spread of single runs; bad entries fail
at load in one line."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from magexp.artifacts import monte_carlo
from magexp.artifacts.report import MONTE_CARLO_RULE, RULE, rule
from magexp.artifacts.spec import parse
from magexp.artifacts.summary import summarise
from magexp.errors import MagexpError

RNG = np.random.default_rng(7)
#: our 200 runs of a cell: lognormal around a median of 2, a spread as wide as the value itself
OURS = 2.0 * np.exp(0.6 * RNG.standard_normal(200))
MEDIAN = float(np.median(OURS))


def verdict(value: float, **mc) -> dict:
    """The summary row of a paper ``value`` for one cell whose runs are :data:`OURS` (``mc``: statistic,
    trials), by :func:`magexp.artifacts.summary.summarise`."""
    spec = parse({"title": "t", "kind": "final", "seeds": OURS.size, "grid": {"estimator": ["ellipsoid"]},
                  "plot": {"x": "estimator"}, "summarise": [{"quantity": "offset_error", "metric": "offset_error"}],
                  "reported": [{"quantity": "offset_error", "value": value, **mc}]}, Path("p_fig1.yaml"))
    table = pd.DataFrame({"cell": 0, "seed": np.arange(OURS.size), "estimator": "ellipsoid", "objective": "scalar",
                          "setting": "estimator=ellipsoid", "offset_error": OURS, "succeeded": 1.0})
    runs = SimpleNamespace(spec=spec, cells=[{"estimator": "ellipsoid"}], table=table, overrides=[["estimator=ellipsoid"]],
                           outputs={})
    return summarise(runs).iloc[0].to_dict()


def test_a_paper_median_over_its_trials_inside_our_medians_interval_is_reproduced():
    row = verdict(round(MEDIAN, 2), statistic="median", trials=1000)
    assert row["verdict"] == "reproduced", row["reason"]
    assert row["judged_runs"] == "median of 1000 trials (bootstrap), all seeds" and row["judged_n"] == OURS.size
    assert row["judged_lo"] < MEDIAN < row["judged_hi"] and "our median of 1000 trials" in row["reason"]


def test_one_outside_it_differs_though_a_single_run_could_have_it():
    lo, hi = monte_carlo.interval(OURS, "median", 1000)
    value = round(hi * 1.3, 2)
    assert np.quantile(OURS, 0.025) < value < np.quantile(OURS, 0.975)  # inside the spread of single runs
    assert verdict(value, statistic="median", trials=1000)["verdict"] == "differs"


def test_the_same_value_judged_as_one_run_is_uninformative():
    assert verdict(round(MEDIAN, 2))["verdict"] == "uninformative"


def test_the_interval_holds_our_own_uncertainty_and_the_papers():
    """Two-stage bootstrap: wider than the paper's sampling alone (a median of 1000 draws from our runs), and
    wider for fewer of our runs; the same to the bit on every call."""
    lo, hi = monte_carlo.interval(OURS, "median", 1000)
    draws = np.random.default_rng(0).choice(OURS, size=(2000, 1000))
    paper_only = np.subtract(*np.quantile(np.median(draws, axis=1), [0.975, 0.025]))
    assert hi - lo > 1.5 * paper_only
    few = monte_carlo.interval(OURS[:30], "median", 1000)
    assert few[1] - few[0] > hi - lo
    assert monte_carlo.interval(OURS, "median", 1000) == (lo, hi)


def test_one_trial_is_about_the_spread_of_single_runs():
    lo, hi = monte_carlo.interval(OURS, "mean", 1)
    assert lo == pytest.approx(np.quantile(OURS, 0.025), rel=0.2) and hi == pytest.approx(np.quantile(OURS, 0.975), rel=0.2)


BASE = {"title": "t", "kind": "final", "seeds": 30, "grid": {"estimator": ["lm"]}, "plot": {"x": "estimator"}}
ENTRY = {"quantity": "offset_error", "value": 1.8, "statistic": "median", "trials": 1000}


@pytest.mark.parametrize("change, words", [
    ({"trials": 0}, ["trials=0", "at least 1"]),
    ({"statistic": "mode"}, ["statistic='mode'", "median, mean"]),
    ({"trials": None}, ["trials=None", "at least 1"]),
    ({"statistic": None}, ["statistic=None", "median, mean"]),
    ({"tolerance": {"rel": 0.1, "reason": "r"}}, ["statistic='median' with a fixed tolerance"]),
])
def test_a_bad_monte_carlo_entry_fails_at_load_in_one_line(change, words):
    entry = {k: v for k, v in {**ENTRY, **change}.items() if v is not None}
    with pytest.raises(MagexpError) as info:
        parse({**BASE, "reported": [entry]}, Path("toy_fig1.yaml"))
    message = str(info.value)
    assert "\n" not in message and message.startswith("toy_fig1.reported[0] (offset_error): ")
    for w in words:
        assert w in message, (w, message)


def test_the_reports_rule_names_the_case_only_where_a_row_uses_it():
    plain = pd.DataFrame({"judged_runs": ["all seeds", "successful seeds"]})
    assert rule(plain) == RULE  # the committed report: unchanged
    with_mc = pd.DataFrame([verdict(round(MEDIAN, 2), statistic="median", trials=1000)])
    assert rule(with_mc) == RULE + MONTE_CARLO_RULE and "trials" in MONTE_CARLO_RULE
