"""The swarm engine's pieces checked by hand on a few particles, the compiled path against the numpy
path, and the seeded fits against independent minimisers and a fresh process."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from magexp.errors import MagexpError
from magexp.estimators.initialisers import CircleMap, Uniform, circle_map
from magexp.estimators.lm import LevenbergMarquardt
from magexp.estimators.local import LocalMinimiser
from magexp.estimators.rdpso import ThermalCoefficient, random_drift
from magexp.estimators.schedules import Constant, Linear
from magexp.estimators.swarm import SwarmOptimizer, numpy_step
from magexp.estimators.velocity import ALL, InertiaVelocity, VelocityRule, inertia


def test_inertia_kernel_by_hand_three_particles_on_whole_arrays_and_element_by_element():
    x = np.array([[0.0, 1.0], [2.0, -1.0], [1.0, 1.0]])
    v = np.array([[0.5, 0.0], [-1.0, 1.0], [0.0, 0.2]])
    p = np.array([[1.0, 1.0], [2.0, 0.0], [0.0, 0.0]])  # the global best: particle 1, [2, 0]
    r = np.array([[[0.5, 1.0], [0.1, 0.2], [1.0, 0.0]], [[0.25, 0.5], [1.0, 1.0], [0.0, 0.5]]])  # r1, r2
    got = inertia(ALL, ALL, x, v, p, 1, p.mean(axis=0), r, (0.5, 2.0, 1.0))
    # particle 0: 0.5*0.5 + 2*0.5*(1-0) + 1*0.25*(2-0) = 0.25 + 1 + 0.5 = 1.75
    #             0.5*0   + 2*1*(1-1)   + 1*0.5*(0-1)  = -0.5
    # particle 1: 0.5*-1 + 2*0.1*0 + 1*1*(2-2) = -0.5 ; 0.5*1 + 2*0.2*(0+1) + 1*1*(0+1) = 1.9
    # particle 2: 0 + 2*1*(0-1) + 0 = -2 ; 0.5*0.2 + 0 + 1*0.5*(0-1) = -0.4
    np.testing.assert_allclose(got, [[1.75, -0.5], [-0.5, 1.9], [-2.0, -0.4]], rtol=1e-15)
    one_by_one = [[inertia(i, j, x, v, p, 1, None, r, (0.5, 2.0, 1.0)) for j in range(2)] for i in range(3)]
    np.testing.assert_array_equal(got, one_by_one)  # the one kernel, both ways: the same bits


def test_a_rule_gives_its_coefficients_at_every_iteration():
    rule = InertiaVelocity(inertia=Linear(0.9, 0.4), c1=Constant(1.5), c2=Linear(0.5, 2.5))
    np.testing.assert_allclose(rule.schedule(np.array([0, 5, 10]), 10), [[0.9, 1.5, 0.5], [0.65, 1.5, 1.5],
                                                                         [0.4, 1.5, 2.5]], rtol=1e-15)


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


def _step_cases() -> list:
    """Every case of :data:`SWARM_CASES` by every boundary and draw block (the default; a few iterations per draw,
    a remainder): in make test each case with ``clip`` and the default draws, and the first case with all of them."""
    return [pytest.param(*case, boundary, draw_block,
                         marks=[] if case == SWARM_CASES[0] or (boundary, draw_block) == ("clip", None) else [pytest.mark.full])
            for case in SWARM_CASES for boundary in ("clip", "reflect", "random") for draw_block in (None, 7 * 4 * 20 * 12)]


@pytest.mark.parametrize("estimator, scenario, objective, parameterisation, boundary, draw_block", _step_cases())
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


def constriction(i, j, x, v, pbest, g, mean, r, c):
    """Clerc & Kennedy 2002: ``χ (v + φ1 r1 (p - x) + φ2 r2 (g - x))``, ``c = (χ, φ1, φ2)``: a rule
    written here, in a test, as a new rule is written anywhere."""
    return c[0] * (v[i, j] + c[1] * r[0, i, j] * (pbest[i, j] - x[i, j]) + c[2] * r[1, i, j] * (pbest[g, j] - x[i, j]))


class Constriction(VelocityRule):
    kernel = staticmethod(constriction)
    coefficients = ("chi", "phi1", "phi2")

    def __init__(self, chi=0.7298, phi1=2.05, phi2=2.05):
        self.chi, self.phi1, self.phi2 = chi, phi1, phi2


def velocity_rules() -> list[type]:
    """Every :class:`VelocityRule` subclass of magexp's estimators (all imported) and of this file."""
    import importlib
    import pkgutil

    import magexp.estimators

    for module in pkgutil.iter_modules(magexp.estimators.__path__):
        importlib.import_module(f"magexp.estimators.{module.name}")
    found, todo = [], list(VelocityRule.__subclasses__())
    while todo:
        cls = todo.pop()
        found.append(cls)
        todo.extend(cls.__subclasses__())
    return sorted(found, key=lambda c: c.__qualname__)


@pytest.mark.parametrize("boundary", ["clip", "reflect"])  # the cost compiled into the loop; a step per iteration
@pytest.mark.parametrize("rule", velocity_rules(), ids=lambda c: c.__qualname__)
def test_every_velocity_rule_gives_the_same_bits_compiled_and_in_numpy(make_cfg, monkeypatch, rule, boundary):
    """A new rule is one kernel: with its default settings, each rule (the built-in ones and
    :class:`Constriction`, written in this file) runs its one kernel compiled and in numpy, from one
    seed, to the same ``x``, ``fun`` and history, bit for bit."""
    from magexp.estimators import swarm

    if swarm.compiled() is None:
        pytest.skip("numba not installed or MAGEXP_NUMBA=0: there is only the numpy path")
    est, prob = _swarm_case(make_cfg, "pso", "ding2024_exp1", None, None, "estimator.n_iterations=40",
                            f"estimator.boundary={boundary}")
    est.velocity = rule()
    fast = est.fit(prob, rng=np.random.default_rng(5))
    monkeypatch.setattr(swarm, "compiled", lambda: None)
    slow = est.fit(prob, rng=np.random.default_rng(5))
    assert fast.fun == slow.fun and np.all(np.diff(fast.history) <= 0)
    np.testing.assert_array_equal(fast.x, slow.x)
    np.testing.assert_array_equal(fast.history, slow.history)


#: fits recorded with the code of 90c6f51, before the one-kernel redesign (a numpy function, a class,
#: two numba functions and a branch per rule; its compiled and numpy paths gave these same bits):
#: (estimator, scenario, objective, parameterisation, boundary) -> (fun, x) after 150 iterations of
#: 20 particles from seed 7 on 100 readings (:func:`_swarm_case`)
RECORDED_AT_90C6F51 = {
    ("ipso", "ding2024_exp1", None, None, "clip"): (0.5784438085636234, [
        0.894012340700453, -0.3825008975793716, 0.35235046555405175, 0.05705786965105265, 0.9841440903004678,
        0.13342669846678462, -0.12408140476647447, -0.37925325678938976, 0.8986782824907765, 292.34358734363377,
        -296.69386183108315, 348.16266277977337]),
    ("pso", "ding2024_exp1", None, None, "clip"): (768.8376549762696, [
        0.8561629760875334, -0.5, 0.5, 0.10422479426757002, 0.9561447600092983, 0.15033472688283897,
        -0.27843305327906237, -0.2975107663778082, 0.8256238121908808, 581.9636894346671, 1000.0, 691.6135389726967]),
    ("rdpso", "ding2024_exp1", None, None, "clip"): (143.5324681869904, [
        0.8585354092030276, -0.07064830804794968, 0.4233066409459224, -0.13053699181606404, 1.1148659401488281,
        -0.3829210867551033, -0.25506054324669103, 0.13732490939799127, 0.7882333795425651, 73.16730718235485,
        -279.17338043954976, 453.14983970985577]),
    ("rdpso", "yuan2018_mode1", None, None, "clip"): (26735.16773150455, [
        -2.998859356704507, -2.4457568070693694, 1.1362895651945788, -2.998529532121825, -0.003919350084093919,
        0.18918184274496494, 1.4602339029944975, 1.137181566608423, 1.1027817527686434, 55.476868032392154,
        53.712172403313154, 32.141821063013786]),
    ("pso9", "ding2024_exp1", "scalar", None, "clip"): (1.4866398044012714, [
        0.8914134369228834, -0.11113657135098796, 0.10457970591028493, -0.11113657135098796, 1.1046146492841742,
        -0.16147383568852913, 0.10457970591028493, -0.16147383568852913, 0.9552554068949556, 293.9196700782687,
        -297.5356094726991, 346.70699913000647]),
    ("ipso", "yuan2018_mode1", None, "inverse", "clip"): (754.0465771837345, [
        1.110846655584808, -0.09299069113993519, -0.26511661423476024, 0.1837090858304895, 0.5217681014949279,
        0.09322329635634051, -0.10586127454150226, -0.06851733990397209, 0.7200310812919196, -38.6792501471057,
        4.606911708508246, 54.32785080615957]),
    ("pso", "ding2024_exp1", None, None, "reflect"): (1.7492833558678613, [
        0.8785514453357891, -0.29900307659999337, 0.4497821221065632, -0.022848979200746522, 1.0574471472081697,
        -0.013807784564601633, -0.21332183711235092, -0.22581871033468148, 0.8643474043901472, 293.2161660343029,
        -298.50226332200236, 346.775955097766]),
    ("rdpso", "ding2024_exp1", None, None, "random"): (136.10229546531255, [
        0.9044157330069704, -0.2985251845086355, 0.2864931278532604, 0.01808869918220068, 1.0597903033514156,
        -0.05991750429076609, -0.04783943686201392, -0.209651359909244, 0.9286161688148962, 83.10356009543226,
        -337.67338043954976, 486.56898553817194]),
}


@pytest.mark.parametrize("path", ["this process's", "numpy"])
@pytest.mark.parametrize("case", list(RECORDED_AT_90C6F51), ids=lambda case: "/".join(map(str, case)))
def test_the_fits_recorded_before_the_one_kernel_redesign(make_cfg, monkeypatch, case, path):
    """Every velocity rule of conf/estimator (``pso``, ``ipso``, ``pso9``: the inertia rule with
    constant and linear schedules; ``rdpso``), both objectives, the cost compiled into the loop or
    not, the three boundaries: the fits end where the code before the redesign ended, on the
    compiled path (``MAGEXP_NUMBA``'s) and on the numpy path. On the host they were recorded on,
    and after the redesign, every bit of ``x`` and of the history was the same, on both paths (144
    fits compared); the tolerance leaves room for another host's ``log`` and BLAS (the docstring of
    :func:`test_a_seed_gives_the_same_bits_in_a_fresh_process`)."""
    from magexp.estimators import initialisers, swarm
    from magexp.problems import kernels

    if path == "numpy":
        for module, name in ((kernels, "compiled"), (swarm, "compiled"), (initialisers, "_compiled_sequence")):
            monkeypatch.setattr(module, name, lambda: None)
    estimator, scenario, objective, parameterisation, boundary = case
    est, prob = _swarm_case(make_cfg, estimator, scenario, objective, parameterisation, "estimator.n_iterations=150",
                            f"estimator.boundary={boundary}")
    res = est.fit(prob, rng=np.random.default_rng(7))
    fun, x = RECORDED_AT_90C6F51[case]
    assert res.fun == pytest.approx(fun, rel=1e-9, abs=0)
    np.testing.assert_allclose(res.x, x, rtol=1e-9, atol=0)


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
    engine = nb.engine(est.velocity.kernel, est.velocity.needs_mean)
    run = engine.run

    def spy(x, v, pbest, pcost, history, t, n, *rest):
        calls.append((t, n))
        return run(x, v, pbest, pcost, history, t, n, *rest)

    monkeypatch.setattr(engine, "run", spy)
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


# ---- what the seeded fits must satisfy on any machine -------------------------------------------

#: estimator/scenario/objective/parameterisation: every velocity rule, both objectives, both parameterisations,
#: the cost compiled into the loop and not (``pso9``, a forward parameterisation)
SEEDED_CASES = ["ipso/ding2024_exp1/scalar/default", "pso/ding2024_exp1/scalar/default",
                "rdpso/ding2024_exp1/scalar/default", "pso9/ding2024_exp1/scalar/default",
                "rdpso/yuan2018_mode1/vector/default", "pso/yuan2018_mode1/vector/default",
                "ipso/yuan2018_mode1/vector/inverse", "rdpso/yuan2018_mode1/vector/inverse",
                "pso9/yuan2018_mode1/scalar/default"]


def seeded_fits(make_cfg, seeds=(1, 2, 3), n_iterations=150) -> dict:
    """``{case: [FitResult of each seed]}`` of :data:`SEEDED_CASES` (20 particles, 100 readings)."""
    out = {}
    for case in SEEDED_CASES:
        estimator, scenario, objective, parameterisation = case.split("/")
        est, prob = _swarm_case(make_cfg, estimator, scenario, objective,
                                None if parameterisation == "default" else parameterisation,
                                f"estimator.n_iterations={n_iterations}")
        out[case] = [est.fit(prob, rng=np.random.default_rng(seed)) for seed in seeds]
    return out


def fit_bytes(results) -> bytes:
    """The bytes of ``x``, ``fun`` and the history of every fit in ``results``."""
    return b"".join(np.asarray(r.x, float).tobytes() + np.float64(r.fun).tobytes()
                    + np.asarray(r.history, float).tobytes() for r in results)


#: :func:`seeded_fits` in a fresh interpreter started in the tests folder (``-c`` puts it on the path),
#: each case's :func:`fit_bytes` printed in hex
SEEDED_IN_A_FRESH_PROCESS = """
from magexp.run.compose import compose_config
from test_swarm_kernels import fit_bytes, seeded_fits
for case, results in seeded_fits(lambda *o: compose_config(list(o))).items():
    print(case, fit_bytes(results).hex())
"""


@pytest.mark.full  # a fresh interpreter fitting every seeded case; make test: the same bits within this process
def test_a_seed_gives_the_same_bits_in_a_fresh_process(make_cfg):
    """Same seed, same host, same path (this environment's ``MAGEXP_NUMBA``, ``NUMBA_CPU_NAME``...):
    ``x``, ``fun`` and the history of every seeded case are the same bytes in a fresh interpreter as
    in this process (which ran other tests before). What is pinned is the reproducibility, not a
    machine's bits: numpy's and OpenBLAS's kernels are chosen per CPU (an AVX-512 host and the same
    host with numpy's AVX-512 loops off differ in the last bits of RDPSO's ``log``; OpenBLAS's Haswell
    and Zen/SkylakeX kernels in the data of Yuan's vector problem), so the bits of another machine
    may differ."""
    here = {case: fit_bytes(results).hex() for case, results in seeded_fits(make_cfg).items()}
    out = subprocess.run([sys.executable, "-c", SEEDED_IN_A_FRESH_PROCESS], cwd=Path(__file__).parent,
                         capture_output=True, text=True, check=True).stdout
    fresh = dict(line.split() for line in out.splitlines())
    assert fresh.keys() == here.keys()
    for case in here:
        assert fresh[case] == here[case], case


@pytest.mark.full  # whole fits both ways; make test: the steps bit for bit (test_compiled_steps_give_the_numpy_path_bit_for_bit)
def test_the_compiled_and_numpy_paths_give_the_same_fits(make_cfg, monkeypatch):
    """The whole compiled path (steps, the cost compiled into the loop, the Circle map) and the whole
    numpy path (``MAGEXP_NUMBA=0``: numpy steps and the numpy fallback costs) from the same seeds:
    ``x`` to ``rtol=1e-12`` and ``fun`` and the history to ``rtol=1e-10``.

    Why these tolerances: both paths do the same IEEE operations in the same order, element by
    element (no fastmath, no BLAS), and gave the same bits on every host measured (AVX-512 and a
    generic-CPU numba build). A machine whose compiled code rounded one operation differently would
    move a cost by about one rounding of the field-sized terms it is formed from: relative to an
    RMS of a few nT out of 50 000 nT fields, up to ~3e-12 (1.5e-12 measured with a BLAS-based numpy
    cost; 1e-10 leaves a margin of 60). The positions are decided by comparisons of costs only, so
    they stay the same unless two compared costs lie within such a rounding of each other: with the
    BLAS-based costs, 180 fits (these 9 cases, 20 seeds) kept every bit of ``x``."""
    from magexp.estimators import initialisers, swarm
    from magexp.problems import kernels

    if swarm.compiled() is None:
        pytest.skip("numba not installed or MAGEXP_NUMBA=0: there is only the numpy path")
    compiled = seeded_fits(make_cfg)
    for module, name in ((kernels, "compiled"), (swarm, "compiled"), (initialisers, "_compiled_sequence")):
        monkeypatch.setattr(module, name, lambda: None)
    numpy_path = seeded_fits(make_cfg)
    for case in SEEDED_CASES:
        for fast, slow in zip(compiled[case], numpy_path[case]):
            np.testing.assert_allclose(fast.x, slow.x, rtol=1e-12, atol=0, err_msg=case)
            np.testing.assert_allclose(fast.history, slow.history, rtol=1e-10, atol=0, err_msg=case)
            assert fast.fun == pytest.approx(slow.fun, rel=1e-10, abs=0), case


def test_the_swarm_reaches_the_least_squares_optimum_of_the_total_field(make_cfg):
    """On Ding's simulation 1 (100 readings), ``pso9`` (20 particles, 600 iterations) ends, from each
    of three seeds, at the minimum ``lm`` (MINPACK, an independent computation) finds for the same
    RMS: ``fun`` within ``1e-9`` relative and the identified invariants (``W^T W``, ``o``) within
    ``1e-6``. Measured: 1.6e-12 and 1.6e-9 (``lm`` stops at its own tolerance, so the swarm may be
    a few 1e-12 below it); a swarm stuck elsewhere is 10 to 1000 times above."""
    est, prob = _swarm_case(make_cfg, "pso9", "ding2024_exp1", None, None, "estimator.n_iterations=600")
    best = LevenbergMarquardt().fit(prob)
    optimum = float(prob.cost(best.x[None])[0])
    for seed in (1, 2, 3):
        res = est.fit(prob, rng=np.random.default_rng(seed))
        assert res.fun == pytest.approx(optimum, rel=1e-9), seed
        np.testing.assert_allclose(prob.invariants(res.x), prob.invariants(best.x), rtol=1e-6, atol=1e-9)


def test_the_swarm_reaches_bfgs_minimum_of_the_sum_of_norms(make_cfg):
    """On Yuan's vector problem (eq 8, the sum of residual norms, inverse parameterisation), ``pso``
    (20 particles, 600 iterations) ends, from each of three seeds, at the minimum BFGS finds from the
    least-squares start (:class:`~magexp.estimators.local.LocalMinimiser`, scipy): ``fun`` within
    ``1e-8`` relative, ``x`` within ``1e-6`` of the box's width. Measured: 2.8e-11 (BFGS stops at
    its precision loss, slightly above the swarm) and 1e-7 relative."""
    est, prob = _swarm_case(make_cfg, "pso", "yuan2018_mode1", "vector", "inverse", "estimator.n_iterations=600")
    best = LocalMinimiser().fit(prob)
    for seed in (1, 2, 3):
        res = est.fit(prob, rng=np.random.default_rng(seed))
        assert res.fun == pytest.approx(best.fun, rel=1e-8), seed
        assert np.all(np.abs(res.x - best.x) <= 1e-6 * (prob.upper - prob.lower)), seed


def _three_particles():
    """``x, v, pbest, pcost, cost, limits`` of the steps by hand: particle 2 improves on its best
    (cost 0.5 < 2) and becomes the global best, ``p_g = [1, 1]``; ``v_max = 2``, the box
    ``[-10, 10] x [-10, 1.05]``."""
    x = np.array([[0.0, 1.0], [2.0, -1.0], [1.0, 1.0]])
    v = np.array([[0.5, 0.0], [-1.0, 1.0], [0.0, 0.2]])
    pbest = np.array([[1.0, 1.0], [2.0, 0.0], [0.0, 0.0]])
    limits = np.array([[2.0, 2.0], [-10.0, -10.0], [10.0, 1.05]])
    return x, v, pbest, np.array([3.0, 1.0, 2.0]), np.array([5.0, 4.0, 0.5]), limits


R1 = np.array([[0.5, 1.0], [0.1, 0.2], [1.0, 0.0]])
R2 = np.array([[0.25, 0.5], [1.0, 1.0], [0.0, 0.5]])


def _step(path, kernel, x, v, pbest, pcost, cost, r, c, limits):
    """One step of ``path`` (``compiled`` or ``numpy``, then the box clip of the ``clip`` boundary)."""
    if path == "numpy":
        g = numpy_step(kernel, True, x, v, pbest, pcost, cost, True, r, np.array(c), limits, False)
        np.copyto(x, np.clip(x, limits[1], limits[2]))
        return g
    from magexp.estimators import swarm

    nb = swarm.compiled()
    if nb is None:
        pytest.skip("numba not installed or MAGEXP_NUMBA=0")
    return nb.engine(kernel, True).step(x, v, pbest, pcost, cost, True, r, np.array(c), limits, True)


@pytest.mark.parametrize("path", ["compiled", "numpy"])
def test_an_inertia_step_by_hand(path):
    """The best updates and :func:`inertia` with ``w = 0.5, c1 = 2, c2 = 1`` (Ding 2024 eq 10), clamp,
    move, clip."""
    x, v, pbest, pcost, cost, limits = _three_particles()
    g = _step(path, inertia, x, v, pbest, pcost, cost, np.stack([R1, R2]), (0.5, 2.0, 1.0), limits)
    assert g == 2
    np.testing.assert_array_equal(pcost, [3.0, 1.0, 0.5])
    np.testing.assert_array_equal(pbest, [[1, 1], [2, 0], [1, 1]])
    # particle 0: 0.5*0.5 + 2*0.5*(1-0) + 0.25*(1-0) = 1.5 ; 0 + 2*1*(1-1) + 0.5*(1-1) = 0
    # particle 1: 0.5*-1 + 2*0.1*(2-2) + 1*(1-2) = -1.5 ; 0.5*1 + 2*0.2*(0+1) + 1*(1+1) = 2.9, clamped to 2
    # particle 2 (its best and the global best are where it is): 0 ; 0.5*0.2 = 0.1, so y = 1.1, clipped to 1.05
    np.testing.assert_allclose(v, [[1.5, 0.0], [-1.5, 2.0], [0.0, 0.1]], rtol=1e-15)
    np.testing.assert_allclose(x, [[1.5, 1.0], [0.5, 1.0], [1.0, 1.05]], rtol=1e-15)


@pytest.mark.parametrize("path", ["compiled", "numpy"])
def test_a_drift_step_by_hand(path):
    """:func:`random_drift` with ``α = 0.5, c1 = c2 = 1`` (Yuan 2018 eq 16), ``M`` the mean of the
    personal bests after the update, ``[4/3, 2/3]``, and ``φ = ±ln(1/u)`` signed by ``s > 0.5``."""
    x, v, pbest, pcost, cost, limits = _three_particles()
    s = np.array([[0.9, 0.1], [0.6, 0.6], [0.2, 0.7]])
    log_u = np.array([[1.0, 2.0], [0.5, 1.0], [2.0, 0.25]])  # phi = [[1, -2], [0.5, 1], [-2, 0.25]]
    g = _step(path, random_drift, x, v, pbest, pcost, cost, np.stack([R1, R2, s, log_u]), (0.5, 1.0, 1.0), limits)
    assert g == 2
    # particle 0: |M-x| = [4/3, 1/3]: 0.5*4/3*1 + 0.5*1*(1-0) + 0.25*(1-0) = 17/12 ; 0.5*1/3*-2 + 0 + 0 = -1/3
    # particle 1: |M-x| = [2/3, 5/3]: 0.5*2/3*0.5 + 0 + 1*(1-2) = -5/6 ; 0.5*5/3 + 0.2*(0+1) + 1*(1+1) = 91/30 -> 2
    # particle 2: |M-x| = [1/3, 1/3]: 0.5*1/3*-2 = -1/3 ; 0.5*1/3*0.25 = 1/24
    np.testing.assert_allclose(v, [[17 / 12, -1 / 3], [-5 / 6, 2.0], [-1 / 3, 1 / 24]], rtol=1e-15)
    np.testing.assert_allclose(x, [[17 / 12, 2 / 3], [7 / 6, 1.0], [2 / 3, 25 / 24]], rtol=1e-15)


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
    """numba keys a cached function by its own bytecode (and a closure by a pickle of what it closes
    over, different in every process): the engine's steps carry instead the sources they call into,
    the rule's kernel by its name too (so two rules of one module differ), and the Circle-map
    sequence its map's, so editing those recompiles and a fresh process loads."""
    import hashlib

    from magexp.estimators import swarm

    nb = swarm.compiled()
    if nb is None:
        pytest.skip("numba not installed")
    from magexp.estimators import circle
    from magexp.problems import _compiled as costs
    from magexp.problems import kernels

    def digest(*sources):
        return hashlib.sha256(b"".join(sources)).hexdigest()

    codegen = nb.circle_sequence.targetctx.codegen()
    keys = {kernel: nb.engine(kernel).run._cache._index_key((), codegen)[-1][1] for kernel in (inertia, random_drift)}
    assert keys[inertia] == digest(nb.source_of(inertia, nb), b"\0", nb.source_of(costs, kernels)) != keys[random_drift]
    assert nb.engine(inertia).step._cache._index_key((), codegen)[-1][1] == digest(nb.source_of(inertia, nb), b"\0")
    assert nb.engine(inertia, True).step._cache._index_key((), codegen)[-1][1] == digest(nb.source_of(inertia, nb),
                                                                                           b"\1")
    assert nb.circle_sequence._cache._index_key((), codegen)[-1][1] == digest(nb.source_of(circle))


def test_a_kernel_stored_for_one_cpu_is_never_loaded_for_another():
    """Every cached kernel's on-disk key holds numba's target (triple, CPU name and features; the
    engine's run and the Circle-map sequence keep it beside their extra source digest): a process
    with ``NUMBA_CPU_NAME=generic``, or a cache copied to another machine, compiles and stores its
    own machine code beside the host's instead of loading code built for other instructions."""
    from magexp.estimators import swarm

    nb = swarm.compiled()
    if nb is None:
        pytest.skip("numba not installed or MAGEXP_NUMBA=0")
    from numba.core.dispatcher import Dispatcher  # here: numba may be missing (skipped above)

    from magexp.problems import _compiled as costs

    engines = [vars(nb.engine(kernel)) for kernel in (inertia, random_drift)]
    kernels_ = [d for m in (vars(nb), vars(costs), *engines) for d in m.values() if isinstance(d, Dispatcher)]
    assert nb.engine(inertia).run in kernels_ and costs.scalar_cost in kernels_
    for dispatcher in kernels_:
        codegen = dispatcher.targetctx.codegen()
        target = codegen.magic_tuple()
        assert target[1] and dispatcher._cache._index_key((), codegen)[1] == target, dispatcher.py_func.__name__

