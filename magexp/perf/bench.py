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
prints it. Where each part lives: sections 1, 2, 3 and 5 in :mod:`~magexp.perf.throughput`, 4 in
:mod:`~magexp.perf.peertable`, 6 and 7 in :mod:`~magexp.perf.footprint`; the timing side by side in
:mod:`~magexp.perf.measuring`, the problems and estimators measured in :mod:`~magexp.perf.workloads`.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import pandas as pd

from magexp.core.atomic import atomic_path
from magexp.paths import RESULTS
from magexp.perf.footprint import first_call_rows, memory_rows
from magexp.perf.peertable import peer_rows
from magexp.perf.throughput import bound_rows, cost_rows, engine_rows, pyswarms_rows
from magexp.run import threads

BLAS_THREADS = threads.BLAS_THREADS


SECTIONS = ("cost", "engine", "pyswarms", "peers", "bound", "first-call", "memory")


def measure(sections=SECTIONS, rounds: int = 7, seeds: int = 20) -> list[dict]:
    """The long-format rows of the bench's ``sections`` (module docstring), in one list."""
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
    """Run the bench's sections (``--help``) in a process with one BLAS thread; write and print the rows."""
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
