"""What a fresh process costs (:mod:`magexp.perf.bench` sections 6 and 7): numba's first call, cache warm and
cold, and the peak memory of a command-line run beside the run guard's estimate."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from magexp.perf.measuring import row
from magexp.perf.workloads import compose
from magexp.run.budget import estimate_run
from magexp.run.compose import resolved


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
    """numba import + first calls of both costs in a fresh process, cache warm and cold."""
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
    """Peak memory of a command-line ``ipso`` run beside the run guard's estimate (:func:`memory_check`)."""
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

