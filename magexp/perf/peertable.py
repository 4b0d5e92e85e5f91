"""The peer table of the bench (:mod:`magexp.perf.bench` section 4): every peer on the same seeds, cost, box
and budget; success within 1 % of the optimum, with its Wilson interval, and the evaluations and time to reach it."""

from __future__ import annotations

import time

import numpy as np

from magexp.core.seeding import run_generators
from magexp.perf.measuring import row
from magexp.perf.throughput import PyswarmsPSO, pyswarms
from magexp.perf.workloads import compose, ding_problem, swarm_estimator
from magexp.run.runner import build


PEERS = ("ipso", "pso", "rdpso", "pyswarms", "cmaes", "de", "ellipsoid", "lm")


WITHIN = 0.01  # success: best cost within 1 % of the optimum


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
        """The problem's cost, the call counted and the best so far stamped with its time."""
        f = self._problem.cost(thetas)
        self._nfev += len(f)
        self._best = min(self._best, float(np.min(f)))
        self.calls.append((self._nfev, self._best, time.perf_counter()))
        return f


def peer_estimators():
    """``{name: estimator}`` of :data:`PEERS` with the bench's budget (pyswarms left out when absent)."""
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
    """
    if not run["trace"]:
        return (run["nfev"], run["wall"]) if run["fun"] <= target else (np.nan, np.nan)
    return next(((e, t) for e, b, t in run["trace"] if b <= target), (np.nan, np.nan))


def wilson(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson score interval of a success rate."""
    if n == 0:
        return np.nan, np.nan
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(centre - half, 0.0), min(centre + half, 1.0)


def peer_rows(seeds: int) -> list[dict]:
    """The peer table's rows over ``seeds`` seeds (module docstring)."""
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

