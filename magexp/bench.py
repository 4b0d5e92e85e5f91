"""Speed benchmark (``make bench``; never part of ``make test``).

Measures, on a population-50, 300-reading Ding 2024 problem (simulation 1, A = 2 nT):

* the scalar cost's throughput in particle-readings per second (fast quadratic form, and the
  batched-einsum formula for comparison);
* the same for the vector cost (Yuan 2018 eq 8, ``yuan2018_table2`` with 300 readings: one
  product of residual components vs batched einsum) and the ship cost (Yan & Zhou 2022,
  ``yan2022_sim`` with 300 readings: QR form, independent of the readings, vs batched einsum);
* the swarm engine's time per iteration, as a ratio to one bare cost evaluation;
* the same budget with ``pyswarms.single.GlobalBestPSO`` on the cost a user would write for it
  (batched einsum over readings), with IPSO's coefficients fixed at their mid values (pyswarms has
  no schedules), and both final RMS values;
* the time of the last ``make reproduce`` (from ``results/timing.csv``).

Writes ``results/bench.csv`` and prints a table.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from magexp.paths import RESULTS

N_PARTICLES, N_READINGS, N_ITER = 50, 300, 800


def _best_time(fn, repeat: int, number: int) -> float:
    """Best-of-``repeat`` mean time of ``number`` calls (s per call)."""
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - start) / number)
    return best


def _problem(scenario_name: str, *overrides: str):
    """The problem of ``scenario_name`` (its own objective) with ``N_READINGS`` readings, and the config."""
    from magexp.artifacts import compose_config
    from magexp.problems import make_problem
    from magexp.runner import build
    from magexp.seeding import run_generators

    cfg = compose_config([f"scenario={scenario_name}", *overrides, f"scenario.n_readings={N_READINGS}"])
    scenario = build(cfg.scenario, "scenario")
    dataset = scenario.generate(rng=run_generators(0)[0])
    options = getattr(scenario, "problem_options", {})
    return make_problem(scenario.objective, dataset, scenario.search, **options), cfg


def einsum_cost(readings, reference):
    """The cost a user would write: calibrate every reading for every particle, batched."""

    def cost(x):
        w = x[:, :9].reshape(-1, 3, 3)
        b = np.einsum("nij,nkj->nki", w, readings[None, :, :] - x[:, None, 9:])
        return np.sqrt(np.mean((np.linalg.norm(b, axis=2) - reference) ** 2, axis=1))

    return cost


def einsum_swarm_costs(problem) -> dict:
    """The previous batched formulations: calibrate (vector) or predict (ship) every reading for
    every particle with one ``einsum``, then reduce."""

    def vector(x):
        err = problem.reference[None] - problem.calibrated_swarm(x)
        return np.sqrt(np.einsum("nki,nki->nk", err, err)).sum(axis=1)

    def ship(x):
        err = problem.predict(x) - problem.dataset.readings
        return np.sqrt(np.mean(err * err, axis=(1, 2)))

    return {"vector": vector, "ship": ship}


def fast_cost_rows(repeat: int) -> list[dict]:
    """Throughput of the vector and ship swarm costs against their previous batched einsum."""
    rows = []
    for objective, scenario_name, name in [("vector", "yuan2018_table2", "residual-component product"),
                                           ("ship", "yan2022_sim", "QR form")]:
        problem, _ = _problem(scenario_name)
        thetas = problem.lower + np.random.default_rng(0).random((N_PARTICLES, 12)) * (problem.upper - problem.lower)
        previous = einsum_swarm_costs(problem)[objective]
        np.testing.assert_allclose(problem.cost(thetas), previous(thetas), rtol=1e-9)
        t_fast = _best_time(lambda: problem.cost(thetas), repeat, 2000)
        t_einsum = _best_time(lambda: previous(thetas), repeat, 300)
        pr = N_PARTICLES * N_READINGS
        rows += [
            {"measure": f"{objective} cost, {name}", "value": pr / t_fast, "unit": "particle-readings/s"},
            {"measure": f"{objective} cost, batched einsum", "value": pr / t_einsum, "unit": "particle-readings/s"},
        ]
    return rows


def measure(repeat: int = 5) -> list[dict]:
    from magexp.estimators.swarm import SwarmOptimizer
    from magexp.runner import build

    problem, cfg = _problem("ding2024_exp1", "scenario.noise=2")
    rng = np.random.default_rng(0)
    thetas = problem.lower + rng.random((N_PARTICLES, 12)) * (problem.upper - problem.lower)
    user_cost = einsum_cost(problem.dataset.readings, problem.dataset.reference_norm)
    np.testing.assert_allclose(problem.cost(thetas), user_cost(thetas), rtol=1e-9)
    t_fast = _best_time(lambda: problem.cost(thetas), repeat, 2000)
    t_einsum = _best_time(lambda: user_cost(thetas), repeat, 300)
    pr = N_PARTICLES * N_READINGS
    rows = [
        {"measure": "scalar cost, quadratic form", "value": pr / t_fast, "unit": "particle-readings/s"},
        {"measure": "scalar cost, batched einsum", "value": pr / t_einsum, "unit": "particle-readings/s"},
        *fast_cost_rows(repeat),
    ]
    ipso: SwarmOptimizer = build(cfg.estimator, "estimator")  # default estimator: ipso
    ipso.n_particles, ipso.n_iterations = N_PARTICLES, N_ITER
    times, results = [], []
    for seed in range(repeat):
        start = time.perf_counter()
        results.append(ipso.fit(problem, rng=np.random.default_rng(seed)))
        times.append((time.perf_counter() - start) / (N_ITER + 1))
    t_iter = min(times)
    ipso_rms = float(np.median([problem.cost_direct(r.x) for r in results]))
    rows += [
        {"measure": "ipso engine, time per iteration", "value": t_iter * 1e3, "unit": "ms"},
        {"measure": "ipso engine overhead (iteration / bare cost)", "value": t_iter / t_fast, "unit": "ratio"},
        {"measure": "ipso final RMS (median of seeds)", "value": ipso_rms, "unit": "nT"},
    ]
    try:
        import pyswarms as ps
    except ImportError:
        rows.append({"measure": "pyswarms", "value": np.nan, "unit": "not installed (make bench installs it)"})
        return rows
    import logging

    logging.getLogger("pyswarms").setLevel(logging.ERROR)
    options = {"c1": 1.5, "c2": 1.5, "w": 0.65}
    bounds = (problem.lower, problem.upper)
    ps_times, ps_rms = [], []
    for seed in range(repeat):
        np.random.seed(seed)  # pyswarms draws from numpy's global generator
        opt = ps.single.GlobalBestPSO(n_particles=N_PARTICLES, dimensions=12, options=options, bounds=bounds,
                                      velocity_clamp=(-0.2 * (problem.upper - problem.lower).max(),
                                                      0.2 * (problem.upper - problem.lower).max()))
        start = time.perf_counter()
        best_cost, best_x = opt.optimize(user_cost, iters=N_ITER, verbose=False)
        ps_times.append((time.perf_counter() - start) / N_ITER)
        ps_rms.append(problem.cost_direct(np.asarray(best_x)))
    t_ps = min(ps_times)
    rows += [
        {"measure": "pyswarms GlobalBestPSO, time per iteration", "value": t_ps * 1e3, "unit": "ms"},
        {"measure": "pyswarms final RMS (median of seeds)", "value": float(np.median(ps_rms)), "unit": "nT"},
        {"measure": "ipso speed-up per iteration vs pyswarms", "value": t_ps / t_iter, "unit": "ratio"},
    ]
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m magexp.bench", description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--out", type=Path, default=RESULTS / "bench.csv")
    args = parser.parse_args(argv)
    rows = measure(args.repeat)
    timing = RESULTS / "timing.csv"
    if timing.exists():
        t = pd.read_csv(timing)
        for _, r in t.iterrows():
            rows.append({"measure": f"make reproduce ({r['target']}), wall time", "value": r["seconds"], "unit": "s"})
    frame = pd.DataFrame(rows)
    frame.to_csv(args.out, index=False)
    width = max(len(m) for m in frame.measure)
    for _, r in frame.iterrows():
        print(f"{r.measure:<{width}}  {r.value:>12.4g}  {r.unit}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
