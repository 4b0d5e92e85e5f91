"""Trend claims: a slope over every cell of a grid axis with its bootstrap interval, judged against a range or
a sign (magexp.artifacts.trends), on synthetic runs whose true slope is known; drawn on the figure; a bad
trend spec fails at load in one line."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from magexp.artifacts import claims, kinds, trends
from magexp.artifacts.claims import Claim, evaluate
from magexp.artifacts.comparisons import HOLDS, UNDECIDED
from magexp.artifacts.spec import parse
from magexp.errors import MagexpError

AXIS = "scenario.n_readings"
NS = (20, 50, 200, 500, 2000)


def runs(exponent: float = -0.5, seeds: int = 30, sigma: float = 0.3, seed: int = 3, ns=NS) -> pd.DataFrame:
    """A runs table along ``AXIS``: ``offset_error = 5 N^exponent`` times a lognormal factor per seed (a
    second estimator beside it that the claims' ``where`` leaves out)."""
    rng = np.random.default_rng(seed)
    rows = []
    for est_i, est in enumerate(("ellipsoid", "lm")):
        for j, n in enumerate(ns):
            rows += [{"cell": est_i * len(ns) + j, "seed": s, "estimator": est, "objective": "scalar",
                      "setting": f"scenario=x;{AXIS}={n}",
                      "offset_error": (5 if est == "ellipsoid" else 50) * n ** (exponent if est == "ellipsoid" else 0.0)
                      * np.exp(sigma * rng.standard_normal())} for s in range(seeds)]
    return pd.DataFrame(rows)


def claim(**keys) -> Claim:
    """An exponent claim on the ellipsoid's offset error (log-log), "falls as 1/sqrt(N)" by default."""
    return Claim(**{"id": "falls", "text": "", "kind": "trend", "metric": "offset_error", "axis": AXIS,
                    "where": {"estimator": "ellipsoid"}, "log": True, "between": [-0.6, -0.4], **keys})


def test_a_known_exponent_inside_the_range_holds_and_outside_does_not():
    inside, outside = evaluate(claim(), runs(-0.5)), evaluate(claim(), runs(-1.0))
    assert inside.result == HOLDS and inside.holds
    assert outside.result == claims.FAILS == trends.FAILS and not outside.holds
    assert abs(inside.observed + 0.5) < 0.05 and abs(outside.observed + 1.0) < 0.05
    assert "required between -0.6 and -0.4" in inside.short and "95 % CI" in inside.short


def test_two_seeds_cannot_decide_and_say_why():
    o = evaluate(claim(), runs(-0.5, seeds=2))
    assert o.result == UNDECIDED and not o.holds
    assert "2 seeds" in o.short and "below 5" in o.short


def test_an_interval_wider_than_the_range_cannot_decide_and_says_what_could_be_seen():
    o = evaluate(claim(), runs(-0.5, seeds=6, sigma=1.5))
    assert o.result == UNDECIDED
    assert "wider than the range" in o.short and "80 % power" in o.short


def test_a_sign_claim():
    negative = claim(between=[], sign="negative")
    assert evaluate(negative, runs(-0.5)).result == HOLDS
    assert evaluate(negative, runs(+0.5)).result == claims.FAILS
    flat = evaluate(negative, runs(0.0, sigma=0.5))
    assert flat.result == UNDECIDED and "holds 0" in flat.short


def test_a_linear_trend_is_the_slope_of_the_metric_itself():
    table = runs(-0.5, sigma=0.0)
    table["offset_error"] = 3.0 + 0.01 * table[AXIS] if AXIS in table else 3.0 + 0.01 * table.setting.str.extract(
        rf"{AXIS}=(\d+)")[0].astype(float)
    o = evaluate(claim(log=False, between=[0.009, 0.011]), table)
    assert o.result == HOLDS and o.observed == pytest.approx(0.01)


def test_the_interval_is_bit_identical_from_run_to_run():
    table = runs(-0.5)
    a, b = trends.fit(claim(), table), trends.fit(claim(), table.sample(frac=1, random_state=1))
    assert a.ci == b.ci and np.array_equal(a.boot, b.boot)


def test_the_interval_covers_a_known_slope_at_about_its_level():
    """Coverage sanity: over 60 data sets with a true exponent of -0.5, the 95 % interval holds it about 95 %
    of the time (a percentile bootstrap of medians at 30 seeds; below 85 % would mean a broken interval)."""
    covered = [lo <= -0.5 <= hi for lo, hi in (trends.fit(claim(), runs(-0.5, seed=100 + k)).ci for k in range(60))]
    assert 0.85 <= np.mean(covered) <= 1.0


def test_the_figure_draws_the_fitted_line_and_its_band():
    spec = parse({"title": "t", "kind": "final", "seeds": 30, "grid": {AXIS: list(NS), "estimator": ["ellipsoid", "lm"]},
                  "plot": {"x": AXIS, "metric": "offset_error"},
                  "claims": [{"id": "falls", "text": "t", "kind": "trend", "metric": "offset_error", "axis": AXIS,
                              "where": {"estimator": "ellipsoid"}, "log": True, "between": [-0.6, -0.4]}]},
                 Path("toy_fig1.yaml"))
    rows = pd.DataFrame(trends.figure_rows(spec, runs(-0.5), AXIS, ["offset_error"]))
    assert len(rows) == trends.BAND_POINTS and set(rows.trend) == {"falls"} and (rows.estimator == "ellipsoid").all()
    assert rows[AXIS].min() == pytest.approx(20) and rows[AXIS].max() == pytest.approx(2000)
    assert (rows.fit_lo <= rows.fit).all() and (rows.fit <= rows.fit_hi).all()
    slope = np.polyfit(np.log(rows[AXIS]), np.log(rows.fit), 1)[0]  # a straight line in log-log
    assert slope == pytest.approx(trends.fit(spec.claims[0], runs(-0.5)).slope)
    assert trends.figure_rows(spec, runs(-0.5), "estimator", ["offset_error"]) == []  # another x: not drawn


BASE = {"title": "t", "kind": "final", "seeds": 30, "grid": {AXIS: [20, 200], "estimator": ["lm"]},
        "plot": {"x": AXIS}}
TREND = {"id": "falls", "text": "t", "kind": "trend", "metric": "offset_error", "axis": AXIS, "log": True,
         "between": [-0.6, -0.4]}


@pytest.mark.parametrize("change, words", [
    ({"axis": "scenario.noise"}, ["axis='scenario.noise'", "choose a key of the grid", AXIS]),
    ({"between": [-0.4, -0.6]}, ["between=[-0.4, -0.6]", "lo < hi"]),
    ({"between": [], "sign": "down"}, ["sign='down'", "negative, positive"]),
    ({"sign": "negative"}, ["exactly one of between", "sign"]),
    ({"axis": "estimator"}, ["axis='estimator'", "not all numbers"]),
    ({"kind": "threshold", "value": 1.0}, ["axis='scenario.n_readings'", "only a trend claim"]),
    ({"stat": "n"}, ["stat='n'", "median"]),
])
def test_a_bad_trend_fails_at_load_in_one_line(change, words):
    with pytest.raises(MagexpError) as info:
        parse({**BASE, "claims": [{**TREND, **change}]}, Path("toy_fig1.yaml"))
    message = str(info.value)
    assert "\n" not in message and message.startswith("toy_fig1.claims[0] (falls): ")
    for w in words:
        assert w in message, (w, message)


def test_a_log_trend_needs_a_positive_axis():
    with pytest.raises(MagexpError, match="all positive with log: true"):
        parse({**BASE, "grid": {AXIS: [0, 20]}, "claims": [TREND]}, Path("toy_fig1.yaml"))


def test_the_final_kind_draws_the_trend_and_a_figure_without_one_is_unchanged():
    spec = parse({"title": "t", "kind": "final", "seeds": 30, "grid": {AXIS: list(NS), "estimator": ["ellipsoid", "lm"]},
                  "plot": {"x": AXIS, "metric": "offset_error", "xscale": "log"},
                  "claims": [{**TREND, "where": {"estimator": "ellipsoid"}}]}, Path("toy_fig1.yaml"))
    table = runs(-0.5)
    table[AXIS] = table.setting.str.extract(rf"{AXIS}=(\d+)")[0].astype(float)
    cells = (table.groupby(["estimator", AXIS]).offset_error.quantile([0.25, 0.5, 0.75]).unstack()
             .set_axis(["q25", "median", "q75"], axis=1).reset_index()
             .assign(objective="scalar", metric="offset_error", n_seeds=30))
    frame = pd.concat([cells, pd.DataFrame(trends.figure_rows(spec, table, AXIS, ["offset_error"]))], ignore_index=True)
    drawn = kinds.kind("final").draw(frame, spec).axes[0]
    labels = [line.get_label() for line in drawn.get_lines()]
    assert "trend claim falls: least-squares fit" in labels and len(drawn.collections) >= 1
    plain = kinds.kind("final").draw(cells, spec).axes[0]
    assert not any("trend" in line.get_label() for line in plain.get_lines())
