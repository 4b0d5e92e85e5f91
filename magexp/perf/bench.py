"""Speed benchmark (``make bench``; never part of ``make test``): an honest peer table.

Every number is measured in this one run; every comparison is a ratio of times measured side
by side (variants alternate within each round: A B A B ...), reported as the median over rounds
with the interquartile range. One BLAS thread (the bench re-executes itself with
``OPENBLAS_NUM_THREADS=OMP_NUM_THREADS=MKL_NUM_THREADS=1`` unless they are set), so "per core"
means one core.

1. **Cost against its floor** (:mod:`magexp.problems.kernels`), scalar (Ding 2024 eq 17) and
   vector (Yuan 2018 eq 8) costs at 300 readings × 50 particles and 3e4 × 500: the fused
   compiled kernel, the chunked numpy fallback, and two floors of the same shapes: the bare BLAS
   product (``features @ coefficients``, what the quadratic form needs before any square root)
   and a measured single-pass lower bound (one pass over readings × particles doing only one
   square root and one add per particle-reading: the irreducible work of a norm-based cost).
   Throughput in particle-readings per second on one core, per second of this process's CPU
   time and per wall-clock second (the same on an idle machine).
2. **Engine overhead**: time per swarm iteration (``ipso``: the whole fit, setup included, over
   its iterations + 1) over the time of one bare cost call (``problem.cost``) on the same swarm,
   at both sizes, in this process's CPU time.
3. **Engine vs pyswarms on equal terms**: magexp ``pso`` and ``pyswarms.single.GlobalBestPSO``
   with the same coefficients (w = 0.7298, c1 = c2 = 1.49618), the same per-dimension velocity
   limit (0.2 × box width), the same box handling (clip: pyswarms' ``nearest``), the same cost
   function (``problem.cost``), swarm and iterations; ratio of times per iteration.
4. **Peer table** on Ding 2024 simulation 1 (300 readings, A = 2 nT), ``--seeds`` seeds (data
   and estimator streams from :func:`magexp.core.seeding.run_generators`): ``ipso``, ``pso``, ``rdpso``,
   ``pyswarms``, ``cmaes``, ``de`` with the same cost, box and budget (50 × 801 cost
   evaluations; ``rdpso`` keeps its configured absolute velocity limit, Yuan 2018's Table 1 value
   in the units of Yuan's data), and the closed forms ``ellipsoid`` and ``lm``. The optimum of a seed is the
   best of ``lm`` and ``ellipsoid`` on its data; a run succeeds when its best cost comes within
   1 % of it. Per estimator: success rate (95 % Wilson interval), evaluations and wall time to
   reach 1 % (median and IQR over the successful seeds), time per evaluation, final cost over
   the optimum. Every iterative peer is timed through the same recording wrapper of the cost;
   each runs once untimed first (imports, compilation); the order of the peers rotates with the
   seed.
5. **The Cramér-Rao bound** (:mod:`magexp.core.bounds`) at N = 1e5 readings: wall-clock and CPU
   time per call.
6. **numba's first call** in a fresh process: with the on-disk cache warm, and cold
   (compilation into an empty cache).
7. **Memory**: peak resident memory of a command-line ``ipso`` run with 500 particles on 1e6
   readings (3 iterations: the peak does not grow with them), from the run's own ``ru_maxrss``,
   minus that of the same command on 300 readings (the interpreter, its imports and compiled
   kernels), beside the run guard's estimate of the same run (:mod:`magexp.run.budget`) and their
   ratio (estimate / measured; kept within 1 to 2 by ``tests/test_budget.py``).

Writes ``results/bench.csv`` in long format (``measure, estimator, value, unit, lo, hi``) and
prints it.
"""

from __future__ import annotations

import argparse
import logging
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
from numba import njit

from magexp.core.atomic import atomic_path
from magexp.core.bounds import cramer_rao
from magexp.core.ellipsoid import quadratic_features
from magexp.core.seeding import run_generators
from magexp.paths import RESULTS
from magexp.problems import kernels, make_problem
from magexp.run import threads
from magexp.run.budget import estimate_run
from magexp.run.compose import compose_config, resolved
from magexp.run.runner import build

try:  # an optional peer of the bench (pip install '.[bench]'): its section says so when it is absent
    import pyswarms
except ImportError:
    pyswarms = None

SIZES = [(300, 50), (30_000, 500)]  # (readings, particles)
BUDGET_PARTICLES, BUDGET_ITERATIONS = 50, 800  # every iterative peer: 50 x 801 cost evaluations
PEERS = ("ipso", "pso", "rdpso", "pyswarms", "cmaes", "de", "ellipsoid", "lm")
WITHIN = 0.01  # success: best cost within 1 % of the optimum


# -- measuring ---------------------------------------------------------------------------------------
def row(measure: str, estimator: str, values, unit: str) -> dict:
    """One long-format row: the median of ``values`` and their interquartile range.

    Parameters
    ----------
    measure, estimator, values, unit : str, str, sequence of float, str
    """
    values = np.asarray(values, float)
    if values.size == 0 or not np.any(np.isfinite(values)):
        return {"measure": measure, "estimator": estimator, "value": np.nan, "unit": unit, "lo": np.nan, "hi": np.nan}
    lo, med, hi = np.nanpercentile(values, [25, 50, 75])
    return {"measure": measure, "estimator": estimator, "value": med, "unit": unit, "lo": lo, "hi": hi}


def side_by_side(variants: dict, rounds: int, target: float = 0.05, clock=time.perf_counter) -> dict:
    """Seconds per call of every variant, alternating variants within each round.

    Each variant is called in batches of about ``target`` seconds (sized by a first call); the
    result maps each name to its ``rounds`` batch means, by ``clock`` (wall clock by default;
    ``time.process_time``: this process's CPU time, which leaves out waiting for a core on a
    shared machine).

    Parameters
    ----------
    variants, rounds, target, clock : dict of callables, int, float, callable
    """
    number = {}
    for name, fn in variants.items():
        fn()
        start = time.perf_counter()
        fn()
        number[name] = max(1, int(target / max(time.perf_counter() - start, 1e-7)))
    times = {name: [] for name in variants}
    for _ in range(rounds):
        for name, fn in variants.items():
            start = clock()
            for _ in range(number[name]):
                fn()
            times[name].append((clock() - start) / number[name])
    return {name: np.asarray(t) for name, t in times.items()}


BLAS_THREADS = threads.BLAS_THREADS


def compose(overrides: list[str]):
    """The run config of ``overrides`` (the project's one composer).

    Parameters
    ----------
    overrides : list of str
    """
    return compose_config(overrides)


# -- problems ----------------------------------------------------------------------------------------
def ding_problem(n_readings: int, seed: int = 0, *overrides: str):
    """Ding 2024 simulation 1 with ``n_readings`` readings (data of ``seed``) and its scenario.

    Parameters
    ----------
    n_readings, seed, *overrides : int, int, str
    """
    cfg = compose(["scenario=ding2024_exp1", f"scenario.n_readings={n_readings}", *overrides])
    scenario = build(cfg.scenario, "scenario")
    dataset = scenario.generate(rng=run_generators(seed)[0])
    return make_problem(scenario.objective, dataset, scenario.search), scenario


def vector_problem(n_readings: int):
    """A vector problem (Yuan 2018 eq 8) of any size: Ding's readings with their true body-frame field as the
    reference vectors (identity attitudes: only shapes matter; Yuan's trajectories are too short for 3e4 readings).

    Parameters
    ----------
    n_readings : int
    """
    problem, scenario = ding_problem(n_readings)
    ds = problem.dataset
    ds = replace(ds, attitude=np.broadcast_to(np.eye(3), (ds.n, 3, 3)), field_nav=ds.field_body_true)
    return make_problem("vector", ds, scenario.search, parameterisation="inverse")


def swarm_in_box(problem, n_particles: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return problem.lower + rng.random((n_particles, problem.n_params)) * (problem.upper - problem.lower)


# -- 1. cost against its floor -------------------------------------------------------------------------
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


# -- 2. engine overhead; 3. engine vs pyswarms -----------------------------------------------------------
def swarm_estimator(name: str, n_particles: int = BUDGET_PARTICLES, n_iterations: int = BUDGET_ITERATIONS):
    cfg = compose([f"estimator={name}", f"estimator.n_particles={n_particles}",
                   f"estimator.n_iterations={n_iterations}"])
    return build(cfg.estimator, "estimator")


def engine_rows(rounds: int) -> list[dict]:
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


# -- 4. peer table ----------------------------------------------------------------------------------
class Recorded:
    """The problem seen by an iterative peer: ``cost`` calls are counted and timed (the same
    wrapper for every peer); everything else is the problem's own."""

    def __init__(self, problem):
        self._problem = problem
        self.calls: list[tuple[int, float, float]] = []  # (evaluations so far, best so far, time)
        self._nfev, self._best, self.start = 0, np.inf, time.perf_counter()

    def __getattr__(self, name):
        return getattr(self._problem, name)

    def cost(self, thetas):
        f = self._problem.cost(thetas)
        self._nfev += len(f)
        self._best = min(self._best, float(np.min(f)))
        self.calls.append((self._nfev, self._best, time.perf_counter()))
        return f


def peer_estimators():
    out = {}
    for name in PEERS:
        if name in ("ipso", "pso", "rdpso"):
            out[name] = swarm_estimator(name)
        elif name == "pyswarms":
            if pyswarms is not None:
                out[name] = PyswarmsPSO()
        else:
            out[name] = build(compose([f"estimator={name}"]).estimator, "estimator")
    return out


def run_peer(estimator, problem, rng) -> dict:
    """One run: final cost (direct formula), evaluations, wall time, and the trace of
    ``(evaluations so far, best so far, seconds since the start)`` after every cost call.

    Parameters
    ----------
    estimator, problem, rng : estimator, CalibrationProblem, numpy.random.Generator
    """
    rec = Recorded(problem)
    rec.start = time.perf_counter()
    if isinstance(estimator, PyswarmsPSO):
        _, x = estimator.fit(rec, rng=rng)
        nfev = rec.calls[-1][0]
    else:
        result = estimator.fit(rec, rng=rng)
        x, nfev = result.x, int(result.nfev)
    wall = time.perf_counter() - rec.start
    trace = [(e, b, stamp - rec.start) for e, b, stamp in rec.calls]
    return {"fun": problem.cost_direct(x), "nfev": nfev, "wall": wall, "trace": trace}


def reach(run: dict, target: float) -> tuple[float, float]:
    """Evaluations and seconds until the best cost first came within ``target`` (nan if never).

    A closed form (no cost calls) reaches it with all its evaluations and its whole wall time.

    Parameters
    ----------
    run, target : dict (of :func:`run_peer`), float
    """
    if not run["trace"]:
        return (run["nfev"], run["wall"]) if run["fun"] <= target else (np.nan, np.nan)
    return next(((e, t) for e, b, t in run["trace"] if b <= target), (np.nan, np.nan))


def wilson(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson score interval of a success rate.

    Parameters
    ----------
    successes, n, z : int, int, float
    """
    if n == 0:
        return np.nan, np.nan
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(centre - half, 0.0), min(centre + half, 1.0)


def peer_rows(seeds: int) -> list[dict]:
    estimators = peer_estimators()
    names = list(estimators)
    runs = {name: [] for name in names}
    warm, _ = ding_problem(300, seeds)  # one untimed run each first: imports, compilation, caches
    for name in names:
        run_peer(estimators[name], warm, run_generators(seeds)[1])
    for seed in range(seeds):
        problem, _ = ding_problem(300, seed)
        shift = seed % len(names)
        for name in names[shift:] + names[:shift]:  # alternate who goes first
            runs[name].append(run_peer(estimators[name], problem, run_generators(seed)[1]))
        optimum = min(runs["lm"][-1]["fun"], runs["ellipsoid"][-1]["fun"])
        for name in names:
            runs[name][-1]["optimum"] = optimum
    rows = []
    for name in names:
        reached = np.array([reach(r, (1 + WITHIN) * r["optimum"]) for r in runs[name]])
        ok = np.isfinite(reached[:, 0])
        lo, hi = wilson(int(ok.sum()), len(ok))
        rows += [
            {"measure": f"success within 1 % of the optimum ({len(ok)} seeds)", "estimator": name,
             "value": float(ok.mean()), "unit": "fraction", "lo": lo, "hi": hi},
            row("evaluations to 1 % of the optimum", name, reached[ok, 0], "evaluations"),
            row("wall time to 1 % of the optimum", name, reached[ok, 1], "s"),
            row("time per evaluation", name, [r["wall"] / r["nfev"] for r in runs[name]], "s"),
            row("evaluations spent", name, [r["nfev"] for r in runs[name]], "evaluations"),
            row("final cost / optimum", name, [r["fun"] / r["optimum"] for r in runs[name]], "ratio"),
        ]
    return rows


# -- 5. the bound; 6. numba's first call; 7. memory ----------------------------------------------------
def bound_rows(rounds: int, n_readings: int = 100_000) -> list[dict]:
    """Seconds per bound, wall clock and CPU (the process's own CPU time: what the call costs an
    idle core; on a shared machine the wall clock also counts waiting for one).

    Parameters
    ----------
    rounds, n_readings : int
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


FIRST_CALL = """
import time
import numpy as np
from magexp.problems import kernels
start = time.perf_counter()
nb = kernels.compiled()
r = np.ones((10, 3)); w = np.ones((4, 3, 3)); o = np.ones((4, 3))
nb.scalar_cost(w, o, np.zeros(3), 1.0, r, np.ones(10)); nb.vector_cost(w, o, r, r)
print(time.perf_counter() - start)
"""


def first_call_rows(repeat: int = 3) -> list[dict]:
    """numba import + first calls of both costs in a fresh process, cache warm and cold.

    Parameters
    ----------
    repeat : int
    """
    rows = []
    for label, cache in (("warm cache", None), ("cold, compiling", "fresh")):
        values = []
        for _ in range(repeat):
            with tempfile.TemporaryDirectory() as tmp:
                env = dict(os.environ, **({"NUMBA_CACHE_DIR": tmp} if cache else {}))
                out = subprocess.run([sys.executable, "-c", FIRST_CALL], capture_output=True, text=True, env=env,
                                     check=True)
                values.append(float(out.stdout.split()[-1]))
        rows.append(row(f"numba import and first call of both costs, {label}", "fused cost", values, "s"))
    return rows


#: the command-line run of the memory section (its sizes are the section's arguments)
MEMORY_RUN = ("scenario=ding2024_exp1", "estimator=ipso")
#: readings of the baseline run: the same command, whose data are negligible (300 readings: 0.2 MB)
BASELINE_READINGS = 300


#: a small launcher: runs its arguments and prints their exit code and peak resident memory (kB on
#: Linux). Linux counts the resident memory of the process a child is forked from into the child's
#: ``ru_maxrss`` (at its exec), so a command spawned straight from this (large) process would
#: report at least this process's size; spawned from the launcher (a few MB), its peak is its own.
LAUNCH = ("import os, subprocess, sys\n"
          "child = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL)\n"
          "_, status, usage = os.wait4(child.pid, 0)\n"
          "print(os.waitstatus_to_exitcode(status), usage.ru_maxrss)")


def run_peak(overrides) -> tuple[int, float]:
    """Peak resident memory (bytes) and wall time of ``python -m magexp *overrides`` in a fresh process.

    The peak is that process's own ``ru_maxrss`` (``os.wait4`` in :data:`LAUNCH`: no other process
    counts); its output folder and its run cache are temporary, so it computes (never reads a
    cached result) and leaves nothing behind. A failed run raises, with the end of its error output.

    Parameters
    ----------
    overrides : sequence of str
    """
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, MAGEXP_CACHE=str(Path(tmp) / "cache"))
        start = time.perf_counter()
        done = subprocess.run([sys.executable, "-c", LAUNCH, sys.executable, "-m", "magexp", *overrides,
                               f"hydra.run.dir={tmp}/run"], capture_output=True, text=True, env=env)
        wall = time.perf_counter() - start
    code, maxrss = (int(v) for v in done.stdout.split()) if done.returncode == 0 else (done.returncode, 0)
    if code != 0:
        raise RuntimeError(f"python -m magexp {' '.join(overrides)} exited {code}: {done.stderr.strip()[-500:]}")
    return maxrss * (1 if sys.platform == "darwin" else 1024), wall  # Linux: kB, macOS: bytes


def memory_check(n_readings: int, n_particles: int, n_iterations: int) -> dict:
    """The run guard's memory estimate of an ``ipso`` run beside the peak it measures.

    ``estimate``: :func:`magexp.run.budget.estimate_run` of the composed config, what
    ``magexp`` checks against its limit. ``peak``: :func:`run_peak` of the same command;
    ``baseline``: that of the same command on :data:`BASELINE_READINGS` readings (the same
    interpreter, imports, compiled kernels and steps, on negligible data); ``measured = peak -
    baseline``, the part the estimate models (it leaves out the interpreter and its libraries);
    ``ratio = estimate / measured``.

    Parameters
    ----------
    n_readings, n_particles, n_iterations : int
    """
    sizes = [f"estimator.n_particles={n_particles}", f"estimator.n_iterations={n_iterations}"]
    overrides = [*MEMORY_RUN, f"scenario.n_readings={n_readings}", *sizes]
    estimate = estimate_run(resolved(compose(overrides))).memory
    baseline, _ = run_peak([*MEMORY_RUN, f"scenario.n_readings={BASELINE_READINGS}", *sizes])
    peak, wall = run_peak(overrides)
    measured = peak - baseline
    return {"estimate": estimate, "peak": peak, "baseline": baseline, "measured": measured,
            "ratio": estimate / measured if measured > 0 else np.nan, "wall": wall}


def memory_rows(n_readings: int = 1_000_000, n_particles: int = 500, n_iterations: int = 3) -> list[dict]:
    """Peak memory of a command-line ``ipso`` run beside the run guard's estimate (:func:`memory_check`).

    Parameters
    ----------
    n_readings, n_particles, n_iterations : int
    """
    m = memory_check(n_readings, n_particles, n_iterations)
    size = f"{n_readings} readings x {n_particles} particles, {n_iterations} iterations"
    mib = 2.0 ** 20
    return [row(f"peak resident memory, command-line run, {size}", "ipso", [m["peak"] / mib], "MiB"),
            row(f"peak resident memory, the same run on {BASELINE_READINGS} readings (baseline)", "ipso",
                [m["baseline"] / mib], "MiB"),
            row(f"peak memory above the baseline, {size}", "ipso", [m["measured"] / mib], "MiB"),
            row(f"run guard's memory estimate, {size}", "ipso", [m["estimate"] / mib], "MiB"),
            row(f"run guard's memory estimate / peak above the baseline, {size}", "ipso", [m["ratio"]], "ratio"),
            row(f"wall time, command-line run, {size}", "ipso", [m["wall"]], "s")]


SECTIONS = ("cost", "engine", "pyswarms", "peers", "bound", "first-call", "memory")


def measure(sections=SECTIONS, rounds: int = 7, seeds: int = 20) -> list[dict]:
    """The long-format rows of the bench's ``sections`` (module docstring), in one list.

    Parameters
    ----------
    sections, rounds, seeds : sequence of str (of :data:`SECTIONS`), int, int
    """
    rows = []
    if "memory" in sections:
        rows += memory_rows()
    if "first-call" in sections:
        rows += first_call_rows()
    if "cost" in sections:
        rows += cost_rows(rounds)
    if "engine" in sections:
        rows += engine_rows(rounds)
    if "pyswarms" in sections:
        rows += pyswarms_rows(rounds)
    if "bound" in sections:
        rows += bound_rows(rounds)
    if "peers" in sections:
        rows += peer_rows(seeds)
    return rows


def main(argv=None) -> int:
    if any(os.environ.get(var) != "1" for var in BLAS_THREADS):  # one BLAS thread, set before numpy loads it
        env = dict(os.environ, **dict.fromkeys(BLAS_THREADS, "1"))
        argv = sys.argv[1:] if argv is None else list(argv)
        return subprocess.run([sys.executable, "-m", "magexp.perf.bench", *argv], env=env).returncode
    parser = argparse.ArgumentParser(prog="python -m magexp.perf.bench", description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7, help="alternating rounds per timing (default 7)")
    parser.add_argument("--seeds", type=int, default=20, help="seeds of the peer table (default 20)")
    parser.add_argument("--only", nargs="+", choices=SECTIONS, default=None, help="run only these sections")
    parser.add_argument("--out", type=Path, default=RESULTS / "bench.csv")
    args = parser.parse_args(argv)
    sections = args.only or SECTIONS
    frame = pd.DataFrame(measure(sections, args.rounds, args.seeds),
                         columns=["measure", "estimator", "value", "unit", "lo", "hi"])
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(args.out) as tmp:
        frame.to_csv(tmp, index=False)
    with pd.option_context("display.max_rows", None, "display.width", 200, "display.max_colwidth", 70):
        print(frame.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
