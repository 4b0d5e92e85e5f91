"""The swarm engine's pieces checked by hand on a few particles."""

import numpy as np
import pytest

from magexp.errors import MagexpError
from magexp.estimators.initialisers import CircleMap, Uniform, circle_map
from magexp.estimators.schedules import Constant, Linear
from magexp.estimators.swarm import SwarmOptimizer
from magexp.estimators.velocity import InertiaVelocity, inertia_velocity


def test_inertia_velocity_by_hand_three_particles():
    x = np.array([[0.0, 1.0], [2.0, -1.0], [1.0, 1.0]])
    v = np.array([[0.5, 0.0], [-1.0, 1.0], [0.0, 0.2]])
    p = np.array([[1.0, 1.0], [2.0, 0.0], [0.0, 0.0]])
    g = np.array([1.0, 0.0])
    r1 = np.array([[0.5, 1.0], [0.1, 0.2], [1.0, 0.0]])
    r2 = np.array([[0.25, 0.5], [1.0, 1.0], [0.0, 0.5]])
    got = inertia_velocity(v, x, p, g, w=0.5, c1=2.0, c2=1.0, r1=r1, r2=r2)
    # particle 0: 0.5*0.5 + 2*0.5*(1-0) + 1*0.25*(1-0) = 0.25 + 1 + 0.25 = 1.5
    #             0.5*0   + 2*1*(1-1)   + 1*0.5*(0-1)  = -0.5
    # particle 1: 0.5*-1 + 2*0.1*0 + 1*1*(1-2) = -1.5 ; 0.5*1 + 2*0.2*(0+1) + 1*1*(0+1) = 1.9
    # particle 2: 0 + 2*1*(0-1) + 0 = -2 ; 0.5*0.2 + 0 + 1*0.5*(0-1) = -0.4
    np.testing.assert_allclose(got, [[1.5, -0.5], [-1.5, 1.9], [-2.0, -0.4]])


def test_inertia_velocity_rule_uses_schedules_at_iteration():
    rule = InertiaVelocity(inertia=Linear(0.9, 0.4), c1=Constant(0.0), c2=Constant(0.0))
    v = np.ones((3, 2))
    out = rule(np.zeros((3, 2)), v, np.zeros((3, 2)), np.zeros(2), 5, 10, rng=np.random.default_rng(0))
    np.testing.assert_allclose(out, 0.65 * v)  # w(5/10) = 0.9 - 0.5*0.5


def test_linear_schedules_match_ding_eqs_12_to_14():
    w, c1, c2 = Linear(0.9, 0.4), Linear(2.5, 0.5), Linear(0.5, 2.5)
    t_max = 800
    for t in (0, 200, 800):
        assert w(t, t_max) == pytest.approx(0.4 + (0.9 - 0.4) * (t_max - t) / t_max)
        assert c1(t, t_max) == pytest.approx(0.5 + (2.5 - 0.5) * (t_max - t) / t_max)
        assert c2(t, t_max) == pytest.approx(0.5 + (2.5 - 0.5) * t / t_max)
    assert Constant(0.7)(3, 10) == 0.7


def test_circle_map_printed_and_usual_by_hand():
    z = np.array([0.0, 0.25, 0.6])
    # printed: mod(2z + 0.2 - 0.7/(2pi) cos(2pi z + pi/2), 1) = mod(2z + 0.2 + 0.7/(2pi) sin(2pi z), 1)
    k = 0.7 / (2 * np.pi)
    expected = np.mod([0.2, 0.5 + 0.2 + k, 1.2 + 0.2 + k * np.sin(1.2 * np.pi)], 1.0)
    np.testing.assert_allclose(circle_map(z, "printed"), expected, atol=1e-15)
    k = 0.5 / (2 * np.pi)
    np.testing.assert_allclose(circle_map(z, "usual"), np.mod([0.2, 0.45 - k, 0.8 - k * np.sin(1.2 * np.pi)], 1.0))
    with pytest.raises(MagexpError, match="form='bad'"):
        circle_map(z, "bad")


def test_circle_map_initialiser_iterates_along_particles():
    init = CircleMap("printed")
    rng = np.random.default_rng(1)
    z0 = np.random.default_rng(1).random(2)
    lo, hi = np.array([-1.0, 0.0]), np.array([1.0, 10.0])
    pos = init(3, lo, hi, rng=rng)
    z1 = circle_map(z0)
    z2 = circle_map(z1)
    z3 = circle_map(z2)
    np.testing.assert_allclose(pos, lo + np.vstack([z1, z2, z3]) * (hi - lo))
    assert np.all((pos >= lo) & (pos <= hi))


def test_uniform_initialiser_in_box():
    pos = Uniform()(100, np.zeros(3), np.array([1.0, 2.0, 3.0]), rng=np.random.default_rng(0))
    assert pos.shape == (100, 3) and np.all(pos >= 0) and np.all(pos <= [1, 2, 3])


class _Quadratic:
    """A bowl with its minimum at 0.3 inside [-1, 1]^d."""

    def __init__(self, d=3):
        self.lower, self.upper = -np.ones(d), np.ones(d)
        self.calls = []

    def cost(self, thetas):
        self.calls.append(thetas.shape)
        return ((thetas - 0.3) ** 2).sum(axis=1)


def test_engine_one_call_per_iteration_monotone_history_and_bounds():
    prob = _Quadratic()
    opt = SwarmOptimizer(n_particles=7, n_iterations=40)
    res = opt.fit(prob, rng=np.random.default_rng(0))
    assert prob.calls == [(7, 3)] * 41  # the whole swarm in one call, every iteration
    assert len(res.history) == 41 and np.all(np.diff(res.history) <= 0)
    assert res.nfev == 7 * 41 and res.history_nfev[-1] == res.nfev
    assert np.all(res.x >= prob.lower) and np.all(res.x <= prob.upper)
    assert res.fun == pytest.approx(((res.x - 0.3) ** 2).sum())
    assert res.fun < 1e-4


def test_engine_callback_stops_the_run():
    res = SwarmOptimizer(n_particles=5, n_iterations=100).fit(
        _Quadratic(), rng=np.random.default_rng(0), callback=lambda t, x, f: t >= 3)
    assert res.nit == 3 and len(res.history) == 4


@pytest.mark.parametrize("kwargs, word", [
    ({"n_particles": 0}, "n_particles=0"), ({"n_iterations": -5}, "n_iterations=-5"),
    ({"velocity_clamp": -1}, "velocity_clamp=-1"), ({"initial_velocity": "random"}, "initial_velocity='random'"),
])
def test_engine_rejects_bad_settings(kwargs, word):
    with pytest.raises(MagexpError, match=word.replace("(", r"\(")):
        SwarmOptimizer(**kwargs)


# ---- the compiled steps against the numpy path --------------------------------------------------

@pytest.mark.parametrize("draw_block", [None, 7 * 4 * 20 * 12])  # default; a few iterations per draw, a remainder
@pytest.mark.parametrize("boundary", ["clip", "reflect", "random"])
@pytest.mark.parametrize("estimator, scenario", [
    ("ipso", "ding2024_exp1"), ("pso", "ding2024_exp1"), ("rdpso", "yuan2018_mode1"), ("pso9", "ding2024_exp1"),
])
def test_compiled_steps_give_the_numpy_path_bit_for_bit(make_cfg, monkeypatch, estimator, scenario, boundary,
                                                         draw_block):
    """Same seed, same problem: the compiled swarm steps and the numpy path end at the same
    ``x``, ``fun`` and history, bit for bit (the same draws, the same operations in the same order)."""
    from hydra.utils import instantiate

    from magexp.estimators import swarm
    from magexp.problems import make_problem

    if swarm.compiled() is None:
        pytest.skip("numba not installed")
    if draw_block is not None:
        monkeypatch.setattr(swarm, "DRAW_BLOCK", draw_block)
    cfg = make_cfg(f"scenario={scenario}", f"estimator={estimator}", "estimator.n_particles=20",
                   "estimator.n_iterations=60", f"estimator.boundary={boundary}", "scenario.n_readings=100")
    sc = instantiate(cfg.scenario, _convert_="all")
    prob = make_problem(sc.objective if estimator != "pso9" else "scalar", sc.generate(rng=np.random.default_rng(0)),
                        sc.search, **getattr(sc, "problem_options", {}))
    est = instantiate(cfg.estimator, _convert_="all")
    fast = est.fit(prob, rng=np.random.default_rng(7))
    monkeypatch.setattr(swarm, "compiled", lambda: None)
    slow = est.fit(prob, rng=np.random.default_rng(7))
    assert fast.fun == slow.fun
    np.testing.assert_array_equal(fast.x, slow.x)
    np.testing.assert_array_equal(fast.history, slow.history)
    assert fast.metrics == slow.metrics


def test_update_best_keeps_argmin_semantics():
    """Strict improvement only; ties keep the first index; a NaN personal best is returned as argmin does."""
    from magexp.estimators import swarm

    nb = swarm.compiled()
    if nb is None:
        pytest.skip("numba not installed")
    x = np.arange(8.0).reshape(4, 2)
    pbest, pcost = np.zeros((4, 2)), np.array([3.0, 1.0, 2.0, 1.0])
    g = nb.update_best(x, np.array([3.0, 5.0, 1.0, 0.5]), pbest, pcost)
    assert g == 3 and g == int(pcost.argmin())
    np.testing.assert_array_equal(pcost, [3.0, 1.0, 1.0, 0.5])
    np.testing.assert_array_equal(pbest, [[0, 0], [0, 0], [4, 5], [6, 7]])  # particle 0: a tie is no improvement
    pcost[1] = np.nan
    assert nb.update_best(x, pcost.copy(), pbest, pcost) == int(np.argmin(pcost)) == 1


def test_a_rule_changed_by_a_subclass_runs_its_own_numpy_rule():
    """A subclass that overrides ``__call__`` but inherits ``step`` must not run the parent's
    compiled step: the numpy path follows the new rule."""
    from magexp.estimators import swarm

    class Frozen(InertiaVelocity):
        def __call__(self, x, v, pbest, gbest, t, t_max, *, rng):
            return np.zeros_like(x)

    assert swarm._has_step(InertiaVelocity()) and not swarm._has_step(Frozen())
    res = SwarmOptimizer(n_particles=5, n_iterations=10, velocity=Frozen()).fit(_Quadratic(), rng=np.random.default_rng(0))
    assert np.all(res.history == res.history[0])  # nobody moves
