"""Where tasks execute: this process, worker processes on this machine, or a Dask cluster.

Executors (:func:`make_executor`):

* ``local`` (default): worker processes on this machine (``jobs``; 0 = all cores). With ``jobs=1``
  or a single task the runs execute in this process.
* ``dask``: a Dask ``distributed`` cluster. ``scheduler=None`` starts a ``LocalCluster`` of ``jobs``
  single-threaded workers; ``scheduler="tcp://host:8786"`` connects to a running scheduler, e.g.
  one started on a SLURM/PBS/SGE cluster with ``dask-jobqueue`` (the optional extra ``cluster``,
  ``pip install 'magexp[cluster]'``). A worker that dies midway loses only its running task: the
  scheduler gives it to another worker, and since every run is a pure function of its config the
  results are the same bytes as a local run.

The executor API, for callers other than :func:`magexp.run.executor.run_many` (e.g. sweeps)::

    from magexp.run.executor import run_many
    from magexp.run.executors import make_executor

    with make_executor("dask", jobs=2) as ex:           # or make_executor("local", jobs=0)
        outputs = run_many(configs, executor=ex)        # cached, deduplicated, batched
        future = ex.submit(fn, *args)                   # any picklable function
        for future in ex.as_completed([future]):
            value = future.result()

``submit`` returns a future with ``result()``; ``as_completed`` yields futures as they finish.
"""

from __future__ import annotations

import ctypes
import importlib
import multiprocessing
import os
import pkgutil
import re
import signal
import sys
import threading
import time
from collections.abc import Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures import as_completed as futures_as_completed

from magexp.errors import MagexpError

EXECUTORS = ("local", "dask")


def preload() -> None:
    """Import what a run executes (runner, bounds, every scenario, problem and estimator module)
    in this process, so that forked workers start with it instead of importing it each."""
    for name in ("magexp.run.runner", "magexp.core.bounds"):
        importlib.import_module(name)
    for package in ("magexp.scenarios", "magexp.problems", "magexp.estimators"):
        module = importlib.import_module(package)
        for info in pkgutil.iter_modules(module.__path__, f"{package}."):
            importlib.import_module(info.name)


#: seconds between two looks of a worker at its parent (:func:`watch_parent`)
PARENT_POLL = 0.5
#: ``prctl`` option: the signal the kernel sends this process when its parent dies (linux/prctl.h)
PR_SET_PDEATHSIG = 1


def watch_parent(parent: int, poll: float = PARENT_POLL) -> None:
    """Make this process end when process ``parent`` (the one that started it) dies.

    On Linux the kernel sends SIGKILL the moment the parent exits (``prctl(PR_SET_PDEATHSIG)``);
    everywhere a daemon thread also looks every ``poll`` seconds whether the parent is still
    ``os.getppid()`` (an orphan is re-parented) and ends the process if not. A worker killed so
    loses only its running task: its runs are cached only once complete (:func:`_run_task`).
    The kernel's "parent" is the *thread* that forked the worker: :class:`LocalExecutor` forks its
    workers at the first ``submit``, from the calling thread (the command's main thread)."""
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # no prctl in this libc: the thread below is enough
            pass
    if os.getppid() != parent:  # the parent died before the kernel was told
        os._exit(1)

    def look() -> None:
        while os.getppid() == parent:
            time.sleep(poll)
        os._exit(1)

    threading.Thread(target=look, name="magexp-watch-parent", daemon=True).start()


#: seconds the parent waits for a stopped worker to clean up (its temporary files) before killing it
STOP_GRACE = 10.0


def _stopped(signum, frame) -> None:
    """SIGTERM in a worker: leave through ``SystemExit``, so that every ``finally`` runs (an atomic
    write being made removes its temporary file: :func:`magexp.core.atomic.atomic_path`)."""
    raise SystemExit(128 + signum)


def _in_worker(fn, *args):
    """``fn(*args)`` in a worker process; stopped in the middle (:func:`_stopped`), the worker ends
    once ``fn`` has unwound (the pool would otherwise catch the exit and wait for the next task)."""
    try:
        return fn(*args)
    except SystemExit as stop:
        os._exit(stop.code if isinstance(stop.code, int) else 1)


def _init_worker(parent: int) -> None:
    """A worker's start: it ends with its parent (:func:`watch_parent`), leaves Ctrl-C to the
    parent, which stops it (no traceback from every worker), and cleans up when stopped (:func:`_stopped`)."""
    watch_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _stopped)


class _Deferred:
    """A call made when its result is asked for (so results stream one at a time)."""

    def __init__(self, fn, args):
        self.fn, self.args = fn, args

    def result(self):
        """The call's value, computed now."""
        return self.fn(*self.args)


class InlineExecutor:
    """Runs each submitted call in this process, when its result is asked for (``jobs=1``)."""

    workers = 1
    shares_files = True  # workers see the parent's run cache (they store runs there themselves)

    def submit(self, fn, *args):
        """``fn(*args)``, called when its result is asked for."""
        return _Deferred(fn, args)

    def as_completed(self, futures: Iterable) -> Iterator:
        """``futures``, in order."""
        return iter(list(futures))

    def close(self) -> None:
        """Nothing to release: the calls ran in this process."""
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class LocalExecutor(InlineExecutor):
    """Worker processes on this machine (forked, so they start in milliseconds)."""

    def __init__(self, jobs: int = 0):
        self.workers = jobs if jobs > 0 else (os.cpu_count() or 1)
        self._pool = None

    @property
    def pool(self):
        """The process pool, forked at its first use (after :func:`preload`)."""
        if self._pool is None:
            method = "fork" if "fork" in multiprocessing.get_all_start_methods() else None
            if method == "fork":
                preload()
            self._pool = ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context(method),
                                             initializer=_init_worker, initargs=(os.getpid(),))
        return self._pool

    def submit(self, fn, *args):
        """``fn(*args)`` in a worker process (:func:`_in_worker`)."""
        return self.pool.submit(_in_worker, fn, *args)

    def as_completed(self, futures: Iterable) -> Iterator:
        """``futures`` as they finish."""
        return futures_as_completed(list(futures))

    def close(self) -> None:
        """Wait for the workers' tasks and end the pool."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def __exit__(self, kind, *exc) -> None:
        if kind is not None and self._pool is not None:  # interrupted or failed: stop the workers now
            processes = list(getattr(self._pool, "_processes", {}).values())
            for process in processes:
                process.terminate()
            deadline = time.monotonic() + STOP_GRACE
            for process in processes:  # each one's cleanup done before the command says it stopped
                process.join(max(0.0, deadline - time.monotonic()))
                if process.is_alive():
                    process.kill()
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None
        self.close()


#: the cluster systems ``--scheduler`` may name instead of an address, each with its ``dask-jobqueue`` class
JOBQUEUES = {"slurm": "SLURMCluster", "pbs": "PBSCluster", "sge": "SGECluster"}
#: a Dask scheduler's address: an optional protocol, a host (a name, an IPv4 or a bracketed IPv6 address) and a port
_ADDRESS = re.compile(r"(?:(?:tcp|tls|ucx|ws|wss)://)?(\[[0-9a-fA-F:]+\]|[A-Za-z0-9_.\-]+):([0-9]{1,5})/?")


class DaskExecutor(InlineExecutor):
    """A Dask ``distributed`` client.

    ``scheduler``: None starts a ``LocalCluster`` of ``jobs`` single-threaded worker processes;
    ``slurm``, ``pbs`` or ``sge`` submits ``jobs`` batch jobs of one worker each through
    ``dask-jobqueue`` (queue, account, memory and walltime come from its own configuration,
    ``~/.config/dask/jobqueue.yaml``); anything else is the address of a running scheduler
    (``tcp://host:8786``).
    """

    def __init__(self, jobs: int = 0, scheduler: str | None = None):
        try:  # lazy: distributed, 0.30 s CPU to import (min of 3, after numpy), only for --executor dask
            from distributed import Client, LocalCluster
        except ImportError:  # pragma: no cover - distributed is a dependency
            raise MagexpError("--executor dask needs the 'distributed' package: pip install 'magexp[dask]'") from None
        self.cluster = None
        n = jobs if jobs > 0 else (os.cpu_count() or 1)
        self.shares_files = scheduler is None  # remote workers may not see this machine's files
        if scheduler is None:
            self.cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
        elif scheduler in JOBQUEUES:
            self.cluster = jobqueue_cluster(scheduler)
            self.cluster.scale(jobs=n)
        try:
            self.client = Client(self.cluster if self.cluster is not None else scheduler, timeout="30s")
        except OSError as exc:
            raise MagexpError(f"--scheduler {scheduler!r}: no Dask scheduler answers there ({exc})") from None
        if self.cluster is not None and scheduler in JOBQUEUES:
            self.client.wait_for_workers(1)
        self.workers = max(len(self.client.scheduler_info().get("workers", {})), n if self.cluster else 1)

    def submit(self, fn, *args):
        """``fn(*args)`` on the cluster (never taken for a result of the same call: ``pure=False``)."""
        return self.client.submit(fn, *args, pure=False)

    def as_completed(self, futures: Iterable) -> Iterator:
        """``futures`` as they finish (Dask's ``as_completed``)."""
        from distributed import as_completed  # lazy: as in __init__ (distributed: 0.30 s CPU)

        return iter(as_completed(list(futures)))

    def close(self) -> None:
        """Close the client and the cluster this executor started."""
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def check_executor(kind: str, jobs: int, scheduler: str | None) -> None:
    """Refuse bad executor settings in one line (before anything is computed)."""
    if kind not in EXECUTORS:
        raise MagexpError(f"--executor {kind!r} is not allowed: choose one of {', '.join(EXECUTORS)}")
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 0:
        raise MagexpError(f"--jobs {jobs!r} is not allowed: it must be an integer >= 0 (0: all cores)")
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    if jobs > cores and (kind == "local" or scheduler is None):  # processes on this machine
        raise MagexpError(f"--jobs {jobs} is not allowed: this machine gives {cores} cores; give at most {cores} "
                          "(0: all cores)")
    if scheduler is not None and kind != "dask":
        raise MagexpError(f"--scheduler {scheduler!r} needs --executor dask")
    check_scheduler_address(scheduler)


def check_scheduler_address(scheduler) -> None:
    """A Dask scheduler: None (a local cluster), a cluster system (slurm, pbs, sge) or an address
    with a port (``tcp://host:8786``, ``host:8786``)."""
    if scheduler is None or scheduler in JOBQUEUES:
        return
    match = _ADDRESS.fullmatch(str(scheduler))
    if not match or not 0 < int(match.group(2)) < 65536:
        raise MagexpError(f"--scheduler {scheduler!r} is not allowed: give tcp://HOST:PORT (e.g. tcp://node1:8786), "
                          f"or one of {', '.join(JOBQUEUES)}")


def jobqueue_cluster(system: str):
    """A ``dask-jobqueue`` cluster for ``system`` (slurm, pbs, sge): one single-threaded worker a job."""
    try:  # lazy: an optional extra that imports distributed (as in DaskExecutor), only for --scheduler slurm|pbs|sge
        import dask_jobqueue
    except ImportError:
        raise MagexpError(f"--scheduler {system} needs dask-jobqueue: pip install 'magexp[cluster]'") from None
    return getattr(dask_jobqueue, JOBQUEUES[system])(processes=1, cores=1)


def make_executor(kind: str = "local", *, jobs: int = 0, scheduler: str | None = None):
    """The executor ``kind`` (:data:`EXECUTORS`); ``jobs``: processes (0: all cores); ``scheduler``:
    :class:`DaskExecutor`'s."""
    check_executor(kind, jobs, scheduler)
    if kind == "dask":
        return DaskExecutor(jobs, scheduler)
    return InlineExecutor() if jobs == 1 else LocalExecutor(jobs)
