"""Workers end with their parent (:func:`magexp.run.executors.watch_parent`): a reproduction whose parent
is killed (``kill -9``) leaves no worker running."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import psutil
import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith(("linux", "darwin")), reason="POSIX processes")


def alive(processes) -> list[int]:
    out = []
    for p in processes:
        try:
            if p.is_running() and p.status() != psutil.STATUS_ZOMBIE:
                out.append(p.pid)
        except psutil.NoSuchProcess:
            pass
    return out


def wait_gone(processes, seconds: float) -> list[int]:
    end = time.monotonic() + seconds
    while alive(processes) and time.monotonic() < end:
        time.sleep(0.05)
    return alive(processes)


@pytest.mark.full  # a whole reproduction killed (make test-full); the mechanism: test_the_portable_fallback_alone_ends_an_orphan
def test_killing_a_reproductions_parent_ends_its_workers(tmp_path):
    env = {**os.environ, "MAGEXP_CACHE": str(tmp_path / "cache")}  # nothing cached: the workers compute
    parent = subprocess.Popen([sys.executable, "-m", "magexp.artifacts.reproduce", "ding2024", "--only", "ding2024_fig3",
                               "--jobs", "2", "--out", str(tmp_path / "out")],
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        me = psutil.Process(parent.pid)
        end = time.monotonic() + 60
        while len(me.children()) < 2 and parent.poll() is None and time.monotonic() < end:
            time.sleep(0.02)
        workers = me.children()
        assert len(workers) == 2, parent.stderr.read().decode() if parent.poll() is not None else "no workers"
        time.sleep(0.3)  # the workers are inside their first tasks
        assert len(alive(workers)) == 2
    except BaseException:
        parent.kill()
        raise
    parent.kill()  # SIGKILL: the parent cannot stop them itself
    parent.wait()
    left = wait_gone(workers, 5.0)
    for pid in left:  # never leave them behind, even when the test fails
        os.kill(pid, signal.SIGKILL)
    assert left == [], "workers outlived their killed parent"


def test_the_portable_fallback_alone_ends_an_orphan(tmp_path):
    """Without ``prctl`` (another system): the thread that looks at ``os.getppid()`` ends the worker."""
    script = textwrap.dedent("""
        import os, sys, time
        from magexp.run import executors
        pid = os.fork()
        if pid == 0:
            sys.platform = "darwin"  # no prctl: the polling thread only
            executors.watch_parent(os.getppid(), poll=0.05)
            print(os.getpid(), flush=True)
            os.close(1), os.close(2)  # the test reads the output to its end: not this process's end
            time.sleep(60)
            os._exit(0)
        time.sleep(0.5)  # the child is running and watching
        os._exit(0)      # the parent dies without stopping it
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=30)
    assert out.stdout.strip(), out.stderr
    try:
        child = psutil.Process(int(out.stdout.split()[0]))
    except psutil.NoSuchProcess:  # already gone
        return
    left = wait_gone([child], 3.0)
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    assert left == []
