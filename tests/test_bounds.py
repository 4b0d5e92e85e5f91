"""The Cramér-Rao bound against closed forms and a small Monte Carlo."""

import numpy as np
import pytest
from hydra.utils import instantiate

from magexp.bounds import cramer_rao
from magexp.estimators.lm import LevenbergMarquardt
from magexp.problems import make_problem


def test_scalar_bound_identifies_nine_and_matches_the_floor_formula(make_cfg):
    sc = instantiate(make_cfg("scenario.noise=2", "scenario.noise_kind=gaussian").scenario, _convert_="all")
    prob = make_problem("scalar", sc.generate(rng=np.random.default_rng(0)), sc.search)
    crb = cramer_rao(prob)
    assert crb["identifiable"] == 9  # a scalar objective cannot see a rotation of W
    assert crb["rms_floor"] == pytest.approx(2 * np.sqrt(291 / 300), rel=0.02)


def test_least_squares_is_near_efficient_in_monte_carlo(make_cfg):
    sc = instantiate(make_cfg("scenario.noise=5", "scenario.noise_kind=gaussian", "scenario.n_readings=100").scenario,
                     _convert_="all")
    errors, bound = [], None
    for seed in range(40):
        prob = make_problem("scalar", sc.generate(rng=np.random.default_rng(seed)), sc.search)
        bound = bound or cramer_rao(prob)["offset_bound"]
        errors.append(LevenbergMarquardt().fit(prob).x[9:] - prob.dataset.truth.offset)
    mc = np.sqrt(np.mean(np.sum(np.square(errors), axis=1)))
    assert 0.75 * bound < mc < 1.35 * bound


def test_no_bound_without_noise(make_cfg):
    sc = instantiate(make_cfg("scenario.noise=0").scenario, _convert_="all")
    assert cramer_rao(make_problem("scalar", sc.generate(rng=np.random.default_rng(0)), sc.search)) is None


def test_two_rings_leave_the_scalar_offset_unidentified(make_cfg):
    """Turns about only two axes put the readings on two planar rings, which do not fix a
    quadric: the scalar bound of the offset is infinite, the vector one finite."""
    sc = instantiate(make_cfg("scenario=yuan2018_mode2").scenario, _convert_="all")
    ds = sc.generate(rng=np.random.default_rng(0))
    scalar = cramer_rao(make_problem("scalar", ds, sc.search, **sc.problem_options))
    vector = cramer_rao(make_problem("vector", ds, sc.search, **sc.problem_options))
    assert scalar["offset_bound"] == np.inf and scalar["unidentified_invariants"] > 0
    assert 0 < vector["offset_bound"] < 1.0 and vector["unidentified_invariants"] == 0


def test_ship_offset_bound_matches_monte_carlo(make_cfg):
    """Gains (~1) and offsets (~1000 nT) differ in scale by orders of magnitude: the bound must
    still match the least-squares spread (a relative cut-off on the unscaled Fisher matrix
    once dropped the offset directions and gave a bound of 1e-8 nT)."""
    from magexp.estimators.linear import LeastSquares

    sc = instantiate(make_cfg("scenario=yan2022_sim", "scenario.angle_noise_deg=0").scenario, _convert_="all")
    errors, bounds = [], []
    for seed in range(60):
        prob = make_problem("ship", sc.generate(rng=np.random.default_rng(seed)), sc.search)
        if seed < 5:
            bounds.append(cramer_rao(prob)["offset_bound"])
        errors.append(LeastSquares().fit(prob).x[9:] - prob.dataset.truth.offset)
    mc = np.sqrt(np.mean(np.sum(np.square(errors), axis=1)))
    assert 0.7 * np.mean(bounds) < mc < 1.3 * np.mean(bounds)
