"""Verdicts that can fail: the interval of a single run, the printing precision, success, the floor."""

import numpy as np
import pandas as pd
import pytest

from magexp.artifacts import succeeded
from magexp.report import tidy
from magexp.spec import Success, Tolerance
from magexp.summary import interval, judge


def test_interval_is_the_central_95_percent_of_runs():
    v = np.arange(1, 1001, dtype=float)
    lo, hi = interval(v)
    assert lo == pytest.approx(np.quantile(v, 0.025)) and hi == pytest.approx(np.quantile(v, 0.975))
    assert interval([np.nan, 2.0, 2.0]) == (2.0, 2.0)


def test_judge_inside_outside_and_printing_precision():
    assert judge(1.0, 0.9, 1.1, 0.0, 1.0) == "reproduced"
    assert judge(1.2, 0.9, 1.1, 0.0, 1.0) == "differs"
    assert judge(1.1004, 0.9, 1.1, 0.0005, 1.0) == "reproduced"  # printed to 3 decimals
    assert judge(1.1006, 0.9, 1.1, 0.0005, 1.0) == "differs"
    assert judge(None, 0.9, 1.1, 0.0, 1.0) == "n/a"


def test_a_failed_majority_is_never_reproduced():
    assert judge(1.0, 0.0, 2.0, 0.0, 0.49) == "differs"
    assert judge(1.0, 0.0, 2.0, 0.0, 0.5) == "reproduced"
    assert judge(1.0, 0.0, 2.0, 0.0, np.nan) == "reproduced"  # not judged (no truth): the interval decides


def test_round_off_floor_and_fixed_tolerances():
    assert judge(7e-12, 1e-9, 1e-9, 0.0, 1.0, floor=1e-9) == "reproduced"
    assert judge(7e-6, 1e-9, 1e-9, 0.0, 1.0, floor=1e-9) == "differs"
    assert judge(1.0, 5.0, 6.0, 0.0, 1.0, tolerance=Tolerance(rel=0.15), value=1.1) == "reproduced"
    assert judge(1.0, 0.0, 6.0, 0.0, 1.0, tolerance=Tolerance(rel=0.05), value=1.1) == "differs"


def test_success_is_within_a_factor_of_the_truths_optimum():
    table = pd.DataFrame({"fun": [1.0, 1.05, 1.2, np.nan, 1.0], "truth_fun": [1.0, 1.0, 1.0, 1.0, np.nan]})
    ok = succeeded(table, Success(factor=1.1, floor=0.0))
    assert ok.iloc[:4].tolist() == [1.0, 1.0, 0.0, 0.0] and np.isnan(ok.iloc[4])


def test_tidy_keeps_six_digits_and_floors_round_off():
    frame = pd.DataFrame({"a": [7.05e-12, -3e-13, 0.0, 123.456789, np.nan], "b": ["x"] * 5})
    out = tidy(frame)
    assert out.a.iloc[0] == 1e-9 and out.a.iloc[1] == -1e-9 and out.a.iloc[2] == 0.0
    assert out.a.iloc[3] == 123.457 and np.isnan(out.a.iloc[4])
    # round-off moving the 10th digit does not change what is written
    assert tidy(pd.DataFrame({"a": [0.5611518122387318]})).a.iloc[0] == tidy(pd.DataFrame({"a": [0.561151812238502]})).a.iloc[0]


def test_each_scenario_setting_draws_its_own_stream(make_cfg):
    from magexp.runner import run

    a = run(make_cfg("scenario=ding2024_exp1", "estimator=ellipsoid", "scenario.noise=2", "seed=0"))
    b = run(make_cfg("scenario=ding2024_exp1", "estimator=ellipsoid", "scenario.noise=5", "seed=0"))
    c = run(make_cfg("scenario=ding2024_exp2", "estimator=ellipsoid", "scenario.noise=2", "seed=0"))
    d = run(make_cfg("scenario=ding2024_exp1", "estimator=lm", "scenario.noise=2", "seed=0"))
    ratio = (a.metrics["offset_error"], b.metrics["offset_error"])
    assert not np.allclose(ratio[1] / ratio[0], 2.5)  # not the same draw scaled
    assert not np.array_equal(a.readings, c.readings)
    np.testing.assert_array_equal(a.readings, d.readings)  # every estimator of a scenario sees the same data
