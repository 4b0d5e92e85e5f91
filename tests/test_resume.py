"""An interrupted reproduction resumes without rerunning finished runs, and ends as an uninterrupted one."""

import os
import signal
import subprocess
import sys

import pytest

from magexp.run import cache, runkeys


KILL_AFTER = 2
# a real process, killed by SIGKILL at a fixed point: right after its KILL_AFTER-th run reached the cache
KILLED = f"""
import os, signal, sys
from magexp.run import cache
from magexp.artifacts.reproduce import main
store, stored = cache.store, []
def store_then_die(*args, **kw):
    kept = store(*args, **kw)
    stored.append(1)
    if len(stored) == {KILL_AFTER}:
        os.kill(os.getpid(), signal.SIGKILL)
    return kept
cache.store = store_then_die
sys.exit(main(sys.argv[1:]))
"""


def results(cache_dir):
    return {p.name: p.stat().st_mtime_ns for p in cache_dir.rglob(f"*{cache.SUFFIX}")}


@pytest.mark.full  # make test's budget: a slow case (make test-full runs it)
@pytest.mark.slow
def test_kill_midway_then_resume(tmp_path, mockup_reproduction, figures_not_rendered):
    """A reproduction killed (SIGKILL, no clean-up) after its 2nd finished run of 6 resumes: the finished
    runs are not rerun, and every file is byte-identical to an uninterrupted reproduction's (its figure
    built, not rendered: the same CSV giving the same figure is test_reproduce.py's)."""
    cache_dir, args = tmp_path / "cache", mockup_reproduction.args
    killed = subprocess.run([sys.executable, "-c", KILLED, *args, "--out", str(tmp_path / "a")],
                            env={**os.environ, "MAGEXP_CACHE": str(cache_dir)}, capture_output=True, text=True,
                            timeout=300)
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    finished = results(cache_dir)
    assert len(finished) == KILL_AFTER, "the kill must land midway"
    assert mockup_reproduction.reproduce_into(tmp_path / "a", cache_dir) == 0
    after = results(cache_dir)
    assert len(after) == len(results(mockup_reproduction.runs)) == 6
    assert {k: after[k] for k in finished} == finished  # finished runs were not rerun
    figures = (".png", ".pdf")
    written = {p.relative_to(tmp_path / "a").as_posix(): p.read_bytes()
               for p in sorted((tmp_path / "a").rglob("*")) if p.is_file() and p.suffix not in figures}
    assert written == {k: v for k, v in mockup_reproduction.files.items() if not k.endswith(figures)}
    assert figures_not_rendered == {"yan2022_table_mockup": 1}  # its figure built again


def test_run_key_depends_on_every_config_value():
    a = runkeys.run_key({"seed": 1, "scenario": {"noise": 2}})
    assert a == runkeys.run_key({"scenario": {"noise": 2}, "seed": 1})
    assert a != runkeys.run_key({"seed": 1, "scenario": {"noise": 2.5}})
