"""Trend claims: a slope over every cell of a grid axis with its bootstrap interval, judged against a range or
a sign (magexp.artifacts.trends), on synthetic runs whose true slope is known; drawn on the figure; a bad
trend spec fails at load in one line."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from magexp.artifacts import claims, kinds, power, significance, trends
from magexp.artifacts.claims import Claim, evaluate
from magexp.artifacts.comparisons import HOLDS, UNDECIDED, adjust
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


def judged(c: Claim, table: pd.DataFrame):
    """The outcome of ``c`` on ``table`` judged as a paper judges it: in its Holm family (alone here)."""
    return adjust([evaluate(c, table)])[0]


def test_a_known_exponent_inside_the_range_holds_and_outside_does_not():
    inside, outside = judged(claim(), runs(-0.5)), judged(claim(), runs(-1.0))
    assert inside.result == HOLDS and inside.holds
    assert outside.result == claims.FAILS == trends.FAILS and not outside.holds
    assert abs(inside.observed + 0.5) < 0.05 and abs(outside.observed + 1.0) < 0.05
    assert "required between -0.6 and -0.4" in inside.short and "95 % CI" in inside.short
    assert "its converse: p = " in outside.short and "its converse" not in inside.short


def test_two_seeds_cannot_decide_and_say_why():
    o = evaluate(claim(), runs(-0.5, seeds=2))
    assert o.result == UNDECIDED and not o.holds
    assert "2 seeds" in o.short and "below 5" in o.short


def test_an_interval_wider_than_the_range_cannot_decide_and_says_what_could_be_seen():
    o = judged(claim(), runs(-0.5, seeds=6, sigma=1.5))
    assert o.result == UNDECIDED
    assert "narrower than twice" in o.short and "80% power" in o.short


def test_a_sign_claim():
    negative = claim(between=[], sign="negative")
    assert judged(negative, runs(-0.5)).result == HOLDS
    assert judged(negative, runs(+0.5)).result == claims.FAILS
    flat = judged(negative, runs(0.0, sigma=0.5))
    assert flat.result == UNDECIDED and "beyond 0" in flat.short and "80% power" in flat.short


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


def test_the_bootstrap_p_is_the_share_of_slopes_on_the_wrong_side():
    inside, outside = np.full(1999, -0.5), np.r_[np.full(1899, -1.0), np.full(100, -0.5)]
    p, pc = trends.p_values([-0.6, -0.4], "", inside)
    assert p == pytest.approx(1 / 2000) and pc == 1.0
    p, pc = trends.p_values([-0.6, -0.4], "", outside)
    assert p == pytest.approx(1900 / 2000) and pc == pytest.approx(2 * 101 / 2000)  # two sides tested
    assert trends.p_values([], "negative", outside)[0] == pytest.approx(1 / 2000)
    assert trends.p_values([], "positive", outside)[0] == 1.0


def test_a_trend_is_tested_in_its_holm_family():
    """Three trends of one family: each p is Holm-adjusted over the three and decided on its adjusted p."""
    outcomes = [evaluate(claim(id=f"t{k}", between=[], sign="negative"), runs(-0.05, seeds=12, sigma=0.4, seed=k))
                for k in range(3)]
    raw = [o.p for o in outcomes]
    adjust(outcomes, ["primary"] * 3)
    for o, p in zip(outcomes, significance.holm(raw)):
        assert o.family_size == 3 and o.p_adjusted == p and o.test == "bootstrap"
        assert o.result == trends.decide(o.p_adjusted, np.nan, o.p_min) or o.result == claims.FAILS
        assert "after Holm over 3 primary tests" in o.short
    alone = adjust([evaluate(claim(id="t0", between=[], sign="negative"), runs(-0.05, seeds=12, sigma=0.4, seed=0))])[0]
    assert alone.p_adjusted == raw[0] and alone.p_adjusted <= outcomes[0].p_adjusted


def test_a_trend_counts_in_its_family_and_plans_its_seeds_by_power():
    spec = parse({**BASE, "grid": {AXIS: [50, 200, 800, 3200], "estimator": ["ellipsoid", "lm"]}, "max_seeds": 120,
                  "claims": [{**TREND, "where": {"estimator": "ellipsoid"}, "effect": {"slope": -0.5, "spread": 0.5}},
                             {"id": "order", "text": "t", "kind": "ordering", "metric": "offset_error",
                              "cells": [{"estimator": "ellipsoid"}, {"estimator": "lm"}]}]}, Path("toy_fig1.yaml"))
    family = {"toy_fig1.falls": "primary", "toy_fig1.order": "primary"}
    assert power.claim_levels([spec], family)["toy_fig1.falls"] == ("primary", 2, 0.025)
    plan = power.claim_plans([spec], family)["toy_fig1.falls"]
    assert plan.test == "bootstrap" and not plan.capped and plan.power >= 0.8
    xs = trends.axis_values(spec.claims[0], spec.grid)
    below = power.trend_power(plan.seeds - 1, xs, "median", (-0.6, -0.4), "", -0.5, 0.5, 0.025)
    assert below < 0.8 <= power.trend_power(plan.seeds, xs, "median", (-0.6, -0.4), "", -0.5, 0.5, 0.025)
    effect = (("slope", -0.5), ("spread", 0.5))
    wider = power.trend_seeds(xs, "median", (-0.7, -0.3), "", effect, 0.025, 30, 120)[0]
    stricter = power.trend_seeds(xs, "median", (-0.6, -0.4), "", effect, 0.0025, 30, 120)[0]
    assert wider < plan.seeds < stricter


@pytest.mark.parametrize("effect, words", [
    ({"slope": -0.7, "spread": 0.5}, ["its slope -0.7 must lie between -0.6 and -0.4"]),
    ({"slope": -0.5}, ["give exactly {slope: number, spread: number}"]),
    ({"slope": -0.5, "spread": 0}, ["spread > 0"]),
])
def test_a_bad_trend_effect_fails_at_load_in_one_line(effect, words):
    with pytest.raises(MagexpError) as info:
        parse({**BASE, "claims": [{**TREND, "effect": effect}]}, Path("toy_fig1.yaml"))
    assert "\n" not in str(info.value) and all(w in str(info.value) for w in words), str(info.value)


@pytest.mark.full
def test_the_simulated_power_is_the_power_of_the_test_the_claim_is_judged_with():
    """The plan's simulation against the judged test itself: 150 runs tables drawn from the planned model,
    each tested by trends.tested; the rejection rates agree within the simulations' binomial spread."""
    ns, n = (50, 200, 800, 3200), 40
    hits = [trends.tested(claim(), runs(-0.5, seeds=n, sigma=0.5, seed=500 + k, ns=ns)).p < 0.05
            for k in range(150)]
    planned = power.trend_power(n, tuple(np.log(ns)), "median", (-0.6, -0.4), "", -0.5, 0.5, 0.05)
    assert abs(np.mean(hits) - planned) < 0.1
