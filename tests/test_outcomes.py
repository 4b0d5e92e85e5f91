"""The one definition of a run's outcome (magexp.core.outcomes) and the one total-field RMS
(magexp.core.metrics.total_field_rms): each checked on hand-made cases, and where its readers use it."""

import numpy as np
import pandas as pd
import pytest

from magexp.artifacts.plan import offset_at_face, succeeded
from magexp.artifacts.spec import Success
from magexp.core import outcomes
from magexp.core.metrics import evaluate, rms, total_field_rms
from magexp.estimators.result import FitResult
from magexp.problems import make_problem
from magexp.run.compose import compose_config
from magexp.run.runner import build


def test_a_coordinate_within_the_face_tolerance_is_on_the_face_and_one_beyond_it_is_not():
    low, high = -1000.0, 1000.0  # width 2000: the tolerance is 2e-6
    x = np.array([low + 0.5 * outcomes.FACE_TOL * 2000, high - 1e-6, low + 3 * outcomes.FACE_TOL * 2000, 0.0])
    assert outcomes.on_face(x, low, high).tolist() == [True, True, False, False]
    assert outcomes.on_face([np.inf, 5.0], [-np.inf, 0.0], [np.inf, 10.0]).tolist() == [True, False]  # infinite face


def test_the_runs_table_counts_offsets_on_a_face_with_the_same_tolerance():
    """``offset_at_face`` (the runs CSV) and the swarm's ``on_boundary`` share :func:`outcomes.on_face`."""
    table = pd.DataFrame({"I1": [-50 + 1e-8, 0.0], "I2": [10.0, 50.0], "I3": [0.0, 0.0]})  # 1e-10 of the width 100
    configs = [{"scenario": {"search": {"offset": [-50, 50]}}}] * 2
    assert offset_at_face(table, configs).tolist() == [1.0, 1.0]
    table.loc[0, "I1"] = -50 + 1e-6  # 1e-8 of the width, 10 x the tolerance: inside the box
    assert offset_at_face(table, configs).tolist() == [0.0, 1.0]


def test_a_majority_of_exactly_one_half_has_not_failed():
    assert not outcomes.failed_majority(0.5) and outcomes.succeeded_majority(0.5)
    assert outcomes.failed_majority(0.49) and not outcomes.succeeded_majority(0.49)
    assert not outcomes.failed_majority(np.nan) and not outcomes.succeeded_majority(np.nan)  # nothing judged
    assert outcomes.failed_majority(pd.Series([0.0, 0.5, 1.0, np.nan])).tolist() == [True, False, False, False]


def test_a_run_the_optimiser_calls_a_success_far_above_the_optimum_has_not_succeeded():
    """``results/real/real_table7_runs.csv``: RDPSO's flag says True at F_g 39.4, where the best fit of
    the same recording reaches 2.59. ``succeeded`` judges the objective, never the flag."""
    table = pd.DataFrame({"scenario": ["real_hmc5883l_full_sphere"] * 2, "objective": ["gyro"] * 2,
                          "estimator": ["rdpso", "lm"], "optimizer_flag": [True, True], "fg": [39.3993, 2.5855]})
    ok = succeeded(table, Success(metric="fg", reference="best"))
    assert ok.tolist() == [0.0, 1.0]
    assert outcomes.succeeded(39.3993, 2.5855).item() == 0.0


def test_success_is_the_factor_of_the_reference_plus_the_round_off_floor():
    ref = np.array([2.0, 2.0, 0.0, 0.0, np.nan, 1.0])
    metric = np.array([2.2, 2.2 + 2e-9, 0.9e-9, 2e-9, 1.0, np.nan])
    assert np.array_equal(outcomes.succeeded(metric, ref), [1.0, 0.0, 1.0, 0.0, np.nan, 0.0], equal_nan=True)
    assert outcomes.success_threshold(2.0) == pytest.approx(2.2 + 1e-9, abs=1e-15)
    assert outcomes.reach_level(2.0) == pytest.approx(2.02 + 1e-9, abs=1e-15)


def test_a_recording_run_succeeds_when_the_optimiser_stops_and_the_spread_narrows():
    got = outcomes.recording_succeeded([True, True, False], [0.05, 0.05, 0.05], [0.01, 0.06, 0.01])
    assert got.tolist() == [True, False, False]


def test_total_field_rms_is_vectorised_and_matches_the_formula():
    rng = np.random.default_rng(3)
    calibrated = rng.normal(size=(4, 50, 3)) * 100
    reference = rng.uniform(90, 110, size=50)
    one_by_one = [np.sqrt(sum((np.sqrt(b @ b) - r) ** 2 for b, r in zip(c, reference)) / 50) for c in calibrated]
    np.testing.assert_allclose(total_field_rms(calibrated, reference), one_by_one, rtol=1e-12)
    assert isinstance(total_field_rms(calibrated[0], reference), float)
    assert rms([3.0, 4.0]) == pytest.approx(np.sqrt(12.5))


@pytest.fixture(scope="module")
def yuan_mode1():
    """Yuan's mode 1 (vector and scalar objectives on the same readings) and a fit near the truth."""
    sc = build(compose_config(["scenario=yuan2018_mode1"]).scenario, "scenario")
    ds = sc.generate(rng=np.random.default_rng(0))
    return sc, ds


def _metrics(problem, x, success):
    fit = FitResult(x=x, fun=float(problem.cost_direct(x)), nit=1, nfev=1, history=np.array([1.0]),
                    history_nfev=np.array([1]), success=success)
    return evaluate(problem, fit, crb=False)


def test_a_scalar_run_stores_its_total_field_rms_once_and_a_vector_run_beside_its_objective(yuan_mode1):
    """``fun`` of a scalar problem is the total-field RMS: the runs carry it once (no ``field_rms``);
    a vector fit's ``field_rms`` is another number than its objective, and is kept. The optimiser's
    flag is stored as ``optimizer_flag``, never as a second success column."""
    sc, ds = yuan_mode1
    scalar = make_problem("scalar", ds, sc.search, **sc.problem_options)
    vector = make_problem("vector", ds, sc.search, **sc.problem_options)
    x = scalar.truth_theta() + 1e-3
    m = _metrics(scalar, x, success=True)
    assert "field_rms" not in m and "success" not in m and m["optimizer_flag"] is True
    assert m["fun"] == pytest.approx(total_field_rms(scalar.calibrate(x), ds.reference_norm), rel=1e-12)
    v = _metrics(vector, vector.truth_theta() + 1e-3, success=False)
    assert v["field_rms"] == pytest.approx(total_field_rms(vector.calibrate(vector.truth_theta() + 1e-3),
                                                           ds.reference_norm), rel=1e-12)
    assert v["field_rms"] != pytest.approx(v["fun"], rel=1e-3) and v["optimizer_flag"] is False
