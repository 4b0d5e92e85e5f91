"""The search box of a recording comes from the data and holds the optimum, axis flips included;
success and intervals without a truth (magexp.scenarios.search, magexp.artifacts.plan.BEST, magexp.core.identifiability)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from magexp.errors import MagexpError
from magexp.paths import SHARED_DATA
from magexp.scenarios.search import SearchBox, search_box

FULL_SPHERE = (SHARED_DATA / "hmc5883l_full-sphere_mag.csv").is_file()


def _inside(box: SearchBox, x12: np.ndarray) -> bool:
    lo, hi = box.bounds()
    return bool(np.all((lo <= x12) & (x12 <= hi)))


def _flipped_readings(rng, s):
    """Readings ``B = S h + b`` of a magnetometer whose x and y axes point opposite to the reference's."""
    h = rng.normal(size=(400, 3))
    h = 0.5 * h / np.linalg.norm(h, axis=1, keepdims=True)
    b = np.array([0.01, -0.1, 0.02])
    return h @ s.T + b, b


def test_signed_box_holds_flipped_axes_and_the_aligned_box_does_not():
    rng = np.random.default_rng(1)
    s = np.diag([-1.07, -1.11, 0.94]) + 0.03 * rng.normal(size=(3, 3))
    readings, b = _flipped_readings(rng, s)
    truth = np.concatenate([s.ravel(), b])
    twin = np.concatenate([-s.ravel(), b])  # (-S, -h): the same F_g
    signed = search_box(readings, 0.5, forward=True, shape="signed")
    assert _inside(signed, truth) and _inside(signed, twin)
    assert not _inside(search_box(readings, 0.5, forward=True), truth)  # the old rule excludes the optimum
    assert signed.offset == (readings.min(), readings.max())  # the offset as in aligned: the readings' range
    narrow = search_box(readings, 0.5, forward=True, shape="signed", offset_width=0.19)
    assert narrow.offset[1] - narrow.offset[0] < np.ptp(readings)  # offset_width: centred on the sphere, narrower


@pytest.mark.parametrize("kwargs", [{"shape": "tilted"}, {"shape": "signed", "matrix_bound": 0.5},
                                    {"shape": "signed", "offset_width": 0.0}, {"shape": "signed", "matrix_bound": np.nan}])
def test_bad_box_settings_are_one_line_errors(kwargs):
    with pytest.raises(MagexpError, match="is not allowed"):
        search_box(np.random.default_rng(0).normal(size=(50, 3)), 1.0, **kwargs)


@pytest.mark.skipif(not FULL_SPHERE, reason="recordings absent")
def test_real_table7_box_holds_the_lm_optimum_and_its_twin():
    from hydra.utils import instantiate

    from magexp.run.compose import compose_config
    from magexp.estimators.lm import LevenbergMarquardt
    from magexp.problems import make_problem

    scenario = instantiate(compose_config(["scenario=real_hmc5883l_full_sphere"]).scenario, _convert_="all")
    problem = make_problem("gyro", scenario.generate(), scenario.search, **scenario.problem_options)
    x = LevenbergMarquardt().fit(problem).x
    assert x[0] < 0 and x[4] < 0  # the magnetometer's x and y axes point opposite to the gyroscope's
    twin = x.copy()
    twin[:9], twin[12], twin[13] = -x[:9], x[12] + np.pi, -x[13]  # (-S, b, -h)
    assert problem.cost_direct(twin) == pytest.approx(problem.cost_direct(x), rel=1e-9)  # the pair is one optimum
    assert _inside(scenario.search, x[:12]) and _inside(scenario.search, twin[:12])  # S and b
    assert np.all(np.abs(x[14:]) <= problem.upper[14:])  # the gyro bias (the field direction spans the sphere)
    assert not _inside(search_box(problem.dataset.readings, problem.total, forward=True), x[:12])


def test_canonical_sign_returns_the_member_with_positive_determinant():
    names = [f"S{i}{j}" for i in range(1, 4) for j in range(1, 4)] + ["b1", "b2", "b3", "field_azimuth",
                                                                       "field_elevation", "gx", "gy", "gz"]
    from magexp.artifacts.kinds.recording import canonical_sign

    x = np.concatenate([np.diag([-1.0, 1.0, 1.0]).ravel(), [0.1, 0.2, 0.3], [2.5, 0.4], [1.0, 2.0, 3.0]])
    y = canonical_sign(names, x)

    def direction(a, e):
        return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])

    assert np.linalg.det(y[:9].reshape(3, 3)) > 0 and np.allclose(y[:9], -x[:9])
    assert np.allclose(direction(*y[12:14]), -direction(*x[12:14])) and np.allclose(y[9:12], x[9:12])
    assert np.allclose(canonical_sign(names, y), y)  # already canonical: unchanged


def test_success_against_the_best_run_of_the_same_recording():
    from magexp.artifacts.plan import best_of, succeeded
    from magexp.artifacts.spec import Success

    table = pd.DataFrame({"scenario": ["a", "a", "a", "b", "b"], "objective": ["gyro"] * 5,
                          "fg": [2.6, 2.7, 68.6, 10.0, 10.5]})
    ok = succeeded(table, Success(metric="fg", reference="best", factor=1.1))
    assert ok.tolist() == [1.0, 1.0, 0.0, 1.0, 1.0]
    assert best_of(table, "fg").tolist() == [2.6, 2.6, 2.6, 10.0, 10.0]


def test_block_bootstrap_interval_holds_the_spread_and_widens_with_noise():
    from magexp.core.identifiability import block_bootstrap_spread, spread

    rng = np.random.default_rng(0)
    calm, noisy = 1 + 0.01 * rng.normal(size=600), 1 + 0.05 * rng.normal(size=600)
    lo, hi = block_bootstrap_spread(calm)
    assert lo < spread(calm) < hi and block_bootstrap_spread(calm) == (lo, hi)  # fixed generator
    nlo, nhi = block_bootstrap_spread(noisy)
    assert hi < nlo  # separated: a winner can be named
    assert all(np.isnan(block_bootstrap_spread(calm[:5])))


def _recording_frame():
    from magexp.artifacts.kinds.recording import RUN_QUANTITIES
    from magexp.artifacts.plots.real import ESTIMATE_PANELS

    rows = []
    for k, est in enumerate(["lm", "rdpso"]):
        head = {"label": est, "estimator": est, "scenario": "real_x", "n_seeds": 2, "n_success": 2 - k,
                "success_rate": 1 - k / 2}
        for seed in range(2):
            for q in RUN_QUANTITIES:
                rows.append({**head, "row": "run", "quantity": q, "seed": seed, "value": 1.0 + k * seed * 20,
                             "se": np.nan, "succeeded": float(not (k and seed))})
        for _, names in ESTIMATE_PANELS:
            for j, name in enumerate(names):
                rows.append({**head, "row": "estimate", "quantity": name, "seed": np.nan, "value": 0.1 * j - k,
                             "se": [0.01, np.inf][j % 2], "succeeded": np.nan})
    return pd.DataFrame(rows)


def test_recording_figure_draws_every_panel_without_a_truth():
    from magexp.artifacts.kinds import kind
    from magexp.artifacts.spec import parse

    spec = parse({"title": "t", "kind": "recording", "plot": {"metric": "fg"},
                  "success": {"metric": "fg", "reference": "best"}}, Path("real_x.yaml"))
    fig = kind("recording").draw(_recording_frame(), spec)
    shown = [ax for ax in fig.axes if ax.get_visible()]
    assert len(shown) == 6 and all(ax.lines or ax.collections for ax in shown)
    texts = " ".join(ax.get_title() + ax.get_ylabel() for ax in shown)
    assert "truth" not in texts and "F_g" in texts
    ticks = [t.get_text() for t in shown[0].get_xticklabels()]
    assert ticks == ["lm\n2/2 ok", "rdpso\n1/2 ok"]  # the success count under each estimator
