"""An interrupted reproduction resumes without rerunning finished runs, and ends as an uninterrupted one."""

import os
import signal
import subprocess
import sys
import time

import pytest

from magexp import cache


def reproduce(out, cache_dir, *extra):
    env = {**os.environ, "MAGEXP_CACHE": str(cache_dir)}
    return subprocess.Popen([sys.executable, "-m", "magexp.reproduce", "ding2024", "--only", "ding2024_table_rms",
                             "--seeds", "2", "--jobs", "1", "--out", str(out), *extra],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def results(cache_dir):
    return {p.name: p.stat().st_mtime_ns for p in cache_dir.rglob("*.pkl")}


@pytest.mark.slow
def test_kill_midway_then_resume(tmp_path):
    cache_dir = tmp_path / "cache"
    proc = reproduce(tmp_path / "a", cache_dir)
    deadline = time.time() + 120
    while len(results(cache_dir)) < 10 and time.time() < deadline and proc.poll() is None:
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    finished = results(cache_dir)
    assert 0 < len(finished) < 64, "the kill must land midway"
    resumed = reproduce(tmp_path / "a", cache_dir)
    assert resumed.wait(timeout=300) == 0, resumed.stderr.read()
    after = results(cache_dir)
    assert len(after) == 64
    assert {k: after[k] for k in finished} == finished  # finished runs were not rerun
    whole = reproduce(tmp_path / "b", tmp_path / "cache2")
    assert whole.wait(timeout=300) == 0
    for name in ("summary.csv", "ding2024/ding2024_table_rms.csv"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_corrupt_result_is_rerun(tmp_path):
    cache.store("abcd", {"x": 1}, root=tmp_path)
    assert cache.load("abcd", root=tmp_path) == {"x": 1}
    path = next(tmp_path.rglob("abcd.pkl"))
    path.write_bytes(path.read_bytes()[:5])  # a partial write
    assert cache.load("abcd", root=tmp_path) is None
    assert not path.exists()


def test_run_key_depends_on_every_config_value():
    a = cache.run_key({"seed": 1, "scenario": {"noise": 2}})
    assert a == cache.run_key({"scenario": {"noise": 2}, "seed": 1})
    assert a != cache.run_key({"seed": 1, "scenario": {"noise": 2.5}})
