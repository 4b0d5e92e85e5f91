"""The swarm engine's pieces checked by hand on a few particles."""

import numpy as np
import pytest

from magexp.errors import MagexpError
from magexp.estimators.initialisers import CircleMap, Uniform, circle_map
from magexp.estimators.rdpso import ThermalCoefficient
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

def _swarm_case(make_cfg, estimator, scenario, objective=None, parameterisation=None, *overrides):
    """``(estimator, problem)``: ``estimator`` with 20 particles on 100 readings of ``scenario``
    (data of seed 0), on the scenario's objective (or ``objective``) and parameterisation (or
    ``parameterisation``)."""
    from hydra.utils import instantiate

    from magexp.problems import make_problem

    cfg = make_cfg(f"scenario={scenario}", f"estimator={estimator}", "estimator.n_particles=20",
                   "scenario.n_readings=100", *overrides)
    sc = instantiate(cfg.scenario, _convert_="all")
    options = dict(getattr(sc, "problem_options", {}))
    if parameterisation is not None:
        options["parameterisation"] = parameterisation
    prob = make_problem(objective or sc.objective, sc.generate(rng=np.random.default_rng(0)), sc.search, **options)
    return instantiate(cfg.estimator, _convert_="all"), prob


# ipso, pso and rdpso on the scalar problem and ipso on the inverse vector one run with the cost compiled
# into the loop (boundary clip); rdpso on Yuan's forward problem and pso9 run one compiled step per iteration
SWARM_CASES = [("ipso", "ding2024_exp1", None, None), ("pso", "ding2024_exp1", None, None),
               ("rdpso", "ding2024_exp1", None, None), ("rdpso", "yuan2018_mode1", None, None),
               ("pso9", "ding2024_exp1", "scalar", None), ("ipso", "yuan2018_mode1", None, "inverse")]


@pytest.mark.parametrize("draw_block", [None, 7 * 4 * 20 * 12])  # default; a few iterations per draw, a remainder
@pytest.mark.parametrize("boundary", ["clip", "reflect", "random"])
@pytest.mark.parametrize("estimator, scenario, objective, parameterisation", SWARM_CASES)
def test_compiled_steps_give_the_numpy_path_bit_for_bit(make_cfg, monkeypatch, estimator, scenario, objective,
                                                         parameterisation, boundary, draw_block):
    """Same seed, same problem: the compiled swarm steps (and the compiled run with the cost inside)
    and the numpy path end at the same ``x``, ``fun`` and history, bit for bit (the same draws, the
    same operations in the same order)."""
    from magexp.estimators import swarm

    if swarm.compiled() is None:
        pytest.skip("numba not installed")
    if draw_block is not None:
        monkeypatch.setattr(swarm, "DRAW_BLOCK", draw_block)
    est, prob = _swarm_case(make_cfg, estimator, scenario, objective, parameterisation, "estimator.n_iterations=60",
                            f"estimator.boundary={boundary}")
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


@pytest.mark.parametrize("draw_block", [None, 7 * 4 * 20 * 12])
@pytest.mark.parametrize("n_iterations", [1, 2, 29, 60])
def test_the_compiled_run_covers_every_iteration_once(make_cfg, monkeypatch, draw_block, n_iterations):
    """With a compiled cost and ``clip``, the iterations (and the initial move) run in
    :func:`_compiled.run`, one call per block of draws and one for the last iteration, each
    iteration exactly once; a callback takes the per-iteration steps (and gives the same numbers)."""
    from magexp.estimators import swarm

    nb = swarm.compiled()
    if nb is None:
        pytest.skip("numba not installed")
    if draw_block is not None:
        monkeypatch.setattr(swarm, "DRAW_BLOCK", draw_block)
    est, prob = _swarm_case(make_cfg, "rdpso", "ding2024_exp1", None, None, f"estimator.n_iterations={n_iterations}")
    calls = []
    run = nb.run

    def spy(x, v, pbest, pcost, history, t, n, *rest):
        calls.append((t, n))
        return run(x, v, pbest, pcost, history, t, n, *rest)

    monkeypatch.setattr(nb, "run", spy)
    fused = est.fit(prob, rng=np.random.default_rng(3))
    per_block = swarm.DRAW_BLOCK // (4 * 20 * 12)
    assert [t for t, _ in calls] == list(np.cumsum([0] + [n for _, n in calls[:-1]]))  # consecutive, from 0
    assert sum(n for _, n in calls) == n_iterations + 1 and fused.nit == n_iterations  # the initial move too
    assert len(calls) == -(-n_iterations // per_block) + 1  # one per block of draws, then the last iteration
    before = len(calls)
    stepped = est.fit(prob, rng=np.random.default_rng(3), callback=lambda t, x, f: False)
    assert len(calls) == before  # a callback: one step per iteration
    np.testing.assert_array_equal(stepped.history, fused.history)
    np.testing.assert_array_equal(stepped.x, fused.x)


# hashes of x, fun and history of seeds 1, 2, 3 (20 particles, 150 iterations, 100 readings), computed with
# the engine before its cost was compiled into the loop: restructuring the engine must not move a bit. numba
# compiles for the host CPU, and the width of its vector instructions changes the order of some sums, so the
# bits are pinned per instruction set (AVX-512 and AVX2 x86-64 hosts; elsewhere the pins are not known).
PINNED_BY_ISA = {
    "avx512": {
        'ipso/ding2024_exp1/scalar/default': 'b07582a70b624d90',
        'pso/ding2024_exp1/scalar/default': 'd4feb38c52e81ffb',
        'rdpso/ding2024_exp1/scalar/default': 'd22f78e9ca51e0c8',
        'pso9/ding2024_exp1/scalar/default': '80748a99c9e98df8',
        'rdpso/yuan2018_mode1/vector/default': 'c2f70640b968e707',
        'pso/yuan2018_mode1/vector/default': '3c9c201f02bed47a',
        'ipso/yuan2018_mode1/vector/inverse': 'ae43622201645a9e',
        'rdpso/yuan2018_mode1/vector/inverse': 'ebfb9bc01191cb3c',
        'pso9/yuan2018_mode1/scalar/default': '84c60eefe683dd2f',
    },
    "avx2": {
        'ipso/ding2024_exp1/scalar/default': 'b07582a70b624d90',
        'pso/ding2024_exp1/scalar/default': 'd4feb38c52e81ffb',
        'rdpso/ding2024_exp1/scalar/default': '6adfe1ec47a886ef',
        'pso9/ding2024_exp1/scalar/default': '80748a99c9e98df8',
        'rdpso/yuan2018_mode1/vector/default': '803c45c57835e9f0',
        'pso/yuan2018_mode1/vector/default': 'e0598fa04c5dd6d8',
        'ipso/yuan2018_mode1/vector/inverse': 'ae43622201645a9e',
        'rdpso/yuan2018_mode1/vector/inverse': 'f565a7362e710fe7',
        'pso9/yuan2018_mode1/scalar/default': 'ab203d23d5829508',
    },
}
PINNED = PINNED_BY_ISA["avx512"]


def host_isa() -> str | None:
    """``avx512`` or ``avx2`` for an x86-64 host with those instructions (numpy's CPU feature table), else None."""
    from numpy._core._multiarray_umath import __cpu_features__ as features

    if features.get("AVX512F"):
        return "avx512"
    if features.get("AVX2") and features.get("FMA3"):
        return "avx2"
    return None


@pytest.mark.parametrize("case", sorted(PINNED))
def test_swarm_fits_keep_their_pinned_bits(make_cfg, case):
    import hashlib

    from magexp.estimators import swarm

    if swarm.compiled() is None:
        pytest.skip("numba not installed (the pins are the compiled path's bits)")
    isa = host_isa()
    if isa is None:
        pytest.skip("no pinned bits for this host's instruction set (pinned: AVX-512 and AVX2 x86-64)")
    estimator, scenario, objective, parameterisation = case.split("/")
    est, prob = _swarm_case(make_cfg, estimator, scenario, objective,
                            None if parameterisation == "default" else parameterisation, "estimator.n_iterations=150")
    h = hashlib.sha256()
    for seed in (1, 2, 3):
        r = est.fit(prob, rng=np.random.default_rng(seed))
        h.update(np.asarray(r.x, float).tobytes() + np.float64(r.fun).tobytes() + np.asarray(r.history).tobytes())
    assert h.hexdigest()[:16] == PINNED_BY_ISA[isa][case], f"{isa} host"


@pytest.mark.parametrize("form", ["printed", "usual"])
@pytest.mark.parametrize("burn_in", [0, 5])
def test_compiled_circle_map_gives_numpys_bits(form, burn_in):
    """The compiled Circle-map sequence is numpy's, bit for bit, on random seeds of any size."""
    from magexp.estimators import initialisers

    if initialisers._compiled_sequence() is None:
        pytest.skip("numba not installed, or its cos/sin/mod differ from numpy's here (numpy runs)")
    z0 = np.random.default_rng(burn_in).random(37)
    init = CircleMap(form, burn_in)
    np.testing.assert_array_equal(init.sequence(z0, 300), initialisers._numpy_sequence(z0, 300, burn_in, form))


@pytest.mark.parametrize("schedule", [Linear(0.9, 0.4), Linear(0.5, 2.5), Constant(1.49618), ThermalCoefficient()])
def test_schedule_values_are_the_one_by_one_floats(schedule):
    from magexp.estimators.schedules import values

    t = np.arange(1, 1001)
    got = values(schedule, t, 1000)
    assert got.shape == t.shape and got.dtype == float
    np.testing.assert_array_equal(got, [schedule(int(k), 1000) for k in t])


def test_the_compiled_runs_cache_key_holds_the_sources_they_call():
    """numba keys a cached function by its own bytecode: the engine's run (which inlines the costs)
    and the Circle-map sequence also carry the sources they call into, so editing those recompiles."""
    import hashlib
    from pathlib import Path

    from magexp.estimators import swarm

    nb = swarm.compiled()
    if nb is None:
        pytest.skip("numba not installed")
    from magexp.estimators import circle
    from magexp.problems import _compiled as costs
    from magexp.problems import kernels

    def digest(*modules):
        return hashlib.sha256(b"".join(Path(m.__file__).read_bytes() for m in modules)).hexdigest()

    codegen = nb.run.targetctx.codegen()
    assert nb.run._cache._index_key((), codegen)[-1] == digest(costs, kernels)
    assert nb.circle_sequence._cache._index_key((), codegen)[-1] == digest(circle)  # the Circle map's home
