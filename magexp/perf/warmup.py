"""Compile and store magexp's numba kernels once, when the environment is made (``make venv``).

The kernels are compiled with ``cache=True``: the machine code is stored beside their modules and
loaded by every later process. Without this step the first processes of a fresh clone (each
worker of ``make reproduce``, each process of ``make test``) compile the same kernels side by
side. Here one process compiles them by running a few tiny fits that take every compiled path:
the fused scalar and vector costs inside each velocity rule's compiled swarm loop (``ipso``,
``rdpso``), the per-iteration path of a boundary that draws (``random``), and the compiled
residuals of a large recording. Nothing is written outside the package's own ``__pycache__`` folders and the run
cache is not used.

numba keys the stored code by its target (CPU name and features, with the source): a process with
another target (``NUMBA_CPU_NAME=generic``, or the folder copied to another machine) compiles and
stores its own beside it and never loads code built for other instructions (a test checks the key).

Usage: ``python -m magexp.perf.warmup`` (a no-op printing one line when numba is unavailable).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from magexp.problems import kernels
from magexp.run.compose import compose_config
from magexp.run.runner import run

#: tiny configurations that between them reach every compiled kernel
FITS = (
    ["scenario=ding2024_exp1", "estimator=ipso", "estimator.n_iterations=3", "estimator.n_particles=4"],
    ["scenario=ding2024_exp1", "estimator=ipso", "estimator.init.form=usual", "estimator.n_iterations=3",
     "estimator.n_particles=4"],
    ["scenario=ding2024_exp1", "estimator=pso", "estimator.boundary=random", "estimator.n_iterations=3",
     "estimator.n_particles=4"],
    # each velocity rule has its own compiled loop (magexp.estimators._compiled.engine): RDPSO's with the cost in it
    ["scenario=ding2024_exp1", "estimator=rdpso", "estimator.n_iterations=3", "estimator.n_particles=4"],
    ["scenario=yuan2018_mode1", "objective=vector", "estimator=rdpso", "estimator.n_iterations=3",
     "estimator.n_particles=4"],
    ["scenario=yuan2018_mode1", "objective=scalar", "estimator=rdpso", "estimator.n_iterations=3",
     "estimator.n_particles=4"],
)


def main() -> int:
    """Compile and store every numba kernel: run :data:`FITS` and the scalar residuals (``make venv`` calls it)."""
    if kernels.compiled() is None:
        print("warm-up: numba is not in use (MAGEXP_NUMBA=0 or not installed); nothing to compile")
        return 0
    start = time.perf_counter()
    for overrides in FITS:
        run(compose_config(overrides))
    n = kernels.COMPILE_MIN_READINGS
    rng = np.random.default_rng(0)
    kernels.scalar_residuals(np.eye(3), np.zeros(3), rng.normal(size=(n, 3)), np.ones(n))
    print(f"warm-up: numba kernels compiled and stored in {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
