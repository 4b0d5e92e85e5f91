"""An interrupted reproduction resumes without rerunning finished runs, and ends as an uninterrupted one."""

import os
import signal
import subprocess
import sys

import pytest

from magexp.run import cache


ARGS = ["ding2024", "--only", "ding2024_table_rms", "--seeds", "2", "--tiny", "--jobs", "1"]  # 64 runs
KILL_AFTER = 10
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


def reproduce_in_process(out, cache_dir, monkeypatch):
    from magexp import paths
    from magexp.artifacts.reproduce import main

    monkeypatch.setattr(cache, "CACHE", cache_dir)
    monkeypatch.setattr(paths, "CACHE", cache_dir)
    return main([*ARGS, "--out", str(out)])


@pytest.mark.slow
def test_kill_midway_then_resume(tmp_path, monkeypatch):
    """A reproduction killed (SIGKILL, no clean-up) after its 10th finished run resumes: the finished
    runs are not rerun, and the outputs are byte-identical to an uninterrupted reproduction's."""
    cache_dir = tmp_path / "cache"
    killed = subprocess.run([sys.executable, "-c", KILLED, *ARGS, "--out", str(tmp_path / "a")],
                            env={**os.environ, "MAGEXP_CACHE": str(cache_dir)}, capture_output=True, text=True,
                            timeout=300)
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    finished = results(cache_dir)
    assert len(finished) == KILL_AFTER, "the kill must land midway"
    assert reproduce_in_process(tmp_path / "a", cache_dir, monkeypatch) == 0
    after = results(cache_dir)
    assert len(after) == 64
    assert {k: after[k] for k in finished} == finished  # finished runs were not rerun
    assert reproduce_in_process(tmp_path / "b", tmp_path / "cache2", monkeypatch) == 0
    for name in ("summary.csv", "ding2024/ding2024_table_rms.csv", "ding2024/ding2024_table_rms_runs.csv"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


def test_run_key_depends_on_every_config_value():
    a = cache.run_key({"seed": 1, "scenario": {"noise": 2}})
    assert a == cache.run_key({"scenario": {"noise": 2}, "seed": 1})
    assert a != cache.run_key({"seed": 1, "scenario": {"noise": 2.5}})
