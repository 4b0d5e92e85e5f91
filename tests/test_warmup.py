"""``python -m magexp.perf.warmup`` (run by ``make venv``) stores every compiled kernel a fit uses."""

import os
import subprocess
import sys

import pytest

pytest.importorskip("numba")


@pytest.mark.full  # compiles every kernel from cold (about 7 s): make test-full
def test_warmup_stores_the_kernels_that_later_fits_load_without_compiling(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "MAGEXP_NUMBA": "1"}
    out = subprocess.run([sys.executable, "-m", "magexp.perf.warmup"], env=env, capture_output=True, text=True, check=True)
    assert "compiled and stored" in out.stdout
    stored = {p.name.split(".")[0] for p in tmp_path.rglob("*.nbi")}
    assert {"_compiled"} <= stored and len(list(tmp_path.rglob("*.nbc"))) >= 10
    # a later process running a swarm fit on each objective loads everything and compiles nothing
    probe = ("from magexp.run.compose import compose_config; from magexp.run.runner import run; "
             "[run(compose_config(o)) for o in (['scenario=ding2024_exp1','estimator=ipso','estimator.n_iterations=2'],"
             "['scenario=yuan2018_mode1','objective=vector','estimator=rdpso','estimator.n_iterations=2'])]")
    later = subprocess.run([sys.executable, "-c", probe], env={**env, "NUMBA_DEBUG_CACHE": "1"},
                           capture_output=True, text=True, check=True)
    assert "data saved" not in later.stdout and "data loaded" in later.stdout
