"""The speed of the core in this process (:mod:`magexp.perf.bench` sections 1, 2, 3 and 5): the cost against
its floor, the engine's overhead, the engine beside pyswarms on equal terms, the Cramér-Rao bound."""

from __future__ import annotations

import logging
import time

import numpy as np
from numba import njit

from magexp.core.bounds import cramer_rao
from magexp.core.ellipsoid import quadratic_features
from magexp.perf.measuring import row, side_by_side
from magexp.perf.workloads import (BUDGET_ITERATIONS, BUDGET_PARTICLES, SIZES, ding_problem, swarm_estimator,
                                   swarm_in_box, vector_problem)
from magexp.problems import kernels

try:  # an optional peer of the bench (pip install '.[bench]'): its section says so when it is absent
    import pyswarms
except ImportError:
    pyswarms = None

def _sqrt_pass():
    """The single-pass lower bound: ``acc[p] += sqrt(a_i + b_p)`` over every particle-reading."""
    @njit(cache=True, nogil=True, error_model="numpy")
    def sqrt_pass(a, b):
        acc = np.zeros(b.shape[0])
        for i in range(a.shape[0]):
            ai = a[i]
            for p in range(b.shape[0]):
                acc[p] += np.sqrt(ai + b[p])
        return acc

    return sqrt_pass


def cost_rows(rounds: int) -> list[dict]:
    """Section 1's rows: the costs' throughput beside their floors at both :data:`~magexp.perf.workloads.SIZES`."""
    sqrt_pass = _sqrt_pass()
    rows = []
    for n, n_p in SIZES:
        scalar, _ = ding_problem(n)
        vector = vector_problem(n)
        x = swarm_in_box(scalar, n_p)
        w, o = scalar.unpack(x)
        c, s, u = scalar._normalised
        ref = scalar._reference
        features = quadratic_features(u)
        coef = kernels.scalar_coefficients(w, o, c, s).T.copy()
        vfeat = np.column_stack([vector._readings, np.ones(n), vector.reference]).T.copy()
        vcoef = np.random.default_rng(1).random((3 * n_p, 7))
        a, b = np.abs(u[:, 0]) + 1.0, np.abs(x[:, 0]) + 1.0
        variants = {
            "scalar, fused (compiled)": lambda: scalar.cost(x),
            "scalar, numpy (chunked)": lambda: kernels.scalar_cost_numpy(w, o, c, s, u, ref),
            "vector, fused (compiled)": lambda: vector.cost(x),
            "vector, numpy (chunked)": lambda: kernels.vector_cost_numpy(w, o, vector._readings, vector.reference),
            "floor: BLAS product (N x 10) @ (10 x P)": lambda: features @ coef,
            "floor: BLAS product (3P x 7) @ (7 x N)": lambda: vcoef @ vfeat,
            "floor: single pass, one sqrt per particle-reading": lambda: sqrt_pass(a, b),
        }
        np.testing.assert_allclose(variants["scalar, fused (compiled)"](), variants["scalar, numpy (chunked)"](),
                                   rtol=1e-9)
        size = f"{n} readings x {n_p} particles"
        cpu = side_by_side(variants, rounds, clock=time.process_time)
        for name, t in cpu.items():
            rows.append(row(f"cost throughput per CPU-second, {size}", name, n * n_p / t, "particle-readings/s"))
        times = side_by_side(variants, rounds)
        for name, t in times.items():
            rows.append(row(f"cost throughput per wall-clock second, {size}", name, n * n_p / t,
                            "particle-readings/s"))
        floor = times["floor: single pass, one sqrt per particle-reading"]
        for name in ("scalar, fused (compiled)", "vector, fused (compiled)"):
            rows.append(row(f"cost time / single-pass floor, {size}", name, times[name] / floor, "ratio"))
    return rows


def engine_rows(rounds: int) -> list[dict]:
    """Section 2's rows: ``ipso``'s time per iteration over one bare cost call."""
    rows = []
    for (n, n_p), iterations in zip(SIZES, (200, 4)):
        problem, _ = ding_problem(n)
        x = swarm_in_box(problem, n_p)
        ipso = swarm_estimator("ipso", n_p, iterations)
        # CPU time of this process: on a shared machine, waiting for a core would blur the ratio
        times = side_by_side({"cost": lambda: problem.cost(x),
                              "iteration": lambda: ipso.fit(problem, rng=np.random.default_rng(0))}, rounds,
                             clock=time.process_time)
        per_iteration = times["iteration"] / (iterations + 1)
        rows.append(row(f"engine time per iteration / bare cost call, {n} readings x {n_p} particles", "ipso",
                        per_iteration / times["cost"], "ratio"))
    return rows


class PyswarmsPSO:
    """``pyswarms.single.GlobalBestPSO`` on magexp's terms: ``pso``'s coefficients, velocity
    limit and budget, clipping to the box, ``problem.cost``; seeded from the run's ``rng``
    (pyswarms draws from numpy's global generator)."""

    name = "pyswarms"

    def __init__(self, n_particles: int = BUDGET_PARTICLES, n_iterations: int = BUDGET_ITERATIONS):
        pso = swarm_estimator("pso", n_particles, n_iterations)
        self.n_particles, self.n_iterations, self.clamp = n_particles, n_iterations, pso.velocity_clamp
        rule = pso.velocity
        self.options = {"w": rule.inertia(1, 1), "c1": rule.c1(1, 1), "c2": rule.c2(1, 1)}

    def fit(self, problem, *, rng: np.random.Generator):
        """``(best cost, best position)`` of pyswarms on ``problem``."""
        logging.getLogger("pyswarms").setLevel(logging.ERROR)
        np.random.seed(int(rng.integers(2**31 - 1)))
        vmax = self.clamp * (problem.upper - problem.lower)
        opt = pyswarms.single.GlobalBestPSO(n_particles=self.n_particles, dimensions=problem.n_params, options=self.options,
                                      bounds=(problem.lower, problem.upper), bh_strategy="nearest",
                                      velocity_clamp=(-vmax, vmax))
        # pyswarms evaluates the swarm at the start of each iteration: n_iterations + 1 of them
        # spend the same budget as magexp's initial evaluation plus n_iterations
        best, x = opt.optimize(problem.cost, iters=self.n_iterations + 1, verbose=False)
        return best, np.asarray(x)


def pyswarms_rows(rounds: int) -> list[dict]:
    """Section 3's rows: pyswarms' time per iteration beside ``pso``'s (one row saying so when absent)."""
    if pyswarms is None:
        return [row("engine vs pyswarms", "pyswarms", [], "not installed (pip install '.[bench]')")]
    rows = []
    iterations = 200
    problem, _ = ding_problem(300)
    pso = swarm_estimator("pso", BUDGET_PARTICLES, iterations)
    peer = PyswarmsPSO(BUDGET_PARTICLES, iterations)
    times = side_by_side({"magexp pso": lambda: pso.fit(problem, rng=np.random.default_rng(0)),
                          "pyswarms": lambda: peer.fit(problem, rng=np.random.default_rng(0))}, rounds)
    for name, t in times.items():
        rows.append(row("time per iteration, 300 readings x 50 particles, equal terms", name,
                        t / (iterations + 1), "s"))
    rows.append(row("pyswarms time / magexp pso time, equal terms", "pso", times["pyswarms"] / times["magexp pso"],
                    "ratio"))
    return rows


def bound_rows(rounds: int, n_readings: int = 100_000) -> list[dict]:
    """Seconds per bound, wall clock and CPU (the process's own CPU time: what the call costs an
    idle core; on a shared machine the wall clock also counts waiting for one).
    """
    problem, _ = ding_problem(n_readings)
    cramer_rao(problem)
    wall, cpu = [], []
    for _ in range(rounds):
        w0, c0 = time.perf_counter(), time.process_time()
        cramer_rao(problem)
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    return [row(f"Cramér-Rao bound, {n_readings} readings, wall clock", "bound", wall, "s"),
            row(f"Cramér-Rao bound, {n_readings} readings, CPU time", "bound", cpu, "s")]

