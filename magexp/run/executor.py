"""Where runs execute: one layer behind ``make reproduce`` and ``-m`` sweeps.

Runs (resolved configs) go through :func:`run_many`, which

1. keys each run (:func:`magexp.run.cache.run_key`) and runs each distinct key once, also under
   ``use_cache=False`` (``--force``): identical runs of several artifacts are one run;
2. groups the runs to do into *tasks*: the runs of one scenario (and objective) for a block of
   seeds, every estimator included, so that a task builds its scenario and estimators once and each
   seed's dataset, problem and Cramér-Rao bound once (:func:`magexp.run.runner.run_batch`);
3. hands the tasks to an executor, longest first. A worker that shares the parent's file system
   (local processes, a Dask ``LocalCluster``) stores each run in the run cache as it finishes and
   sends back only its metrics row (:func:`_run_task`); a remote worker sends the outputs, which the
   parent stores as they arrive. The parent keeps only the small metrics dicts, and :class:`Outputs`
   reads a full output back from the cache when a figure needs it.

Executors (:func:`make_executor`):

* ``local`` (default): worker processes on this machine (``jobs``; 0 = all cores). With ``jobs=1``
  or a single task the runs execute in this process.
* ``dask``: a Dask ``distributed`` cluster. ``scheduler=None`` starts a ``LocalCluster`` of ``jobs``
  single-threaded workers; ``scheduler="tcp://host:8786"`` connects to a running scheduler, e.g.
  one started on a SLURM/PBS/SGE cluster with ``dask-jobqueue`` (the optional extra ``cluster``,
  ``pip install 'magexp[cluster]'``). A worker that dies midway loses only its running task: the
  scheduler gives it to another worker, and since every run is a pure function of its config the
  results are the same bytes as a local run.

The executor API, for callers other than :func:`run_many` (e.g. sweeps)::

    from magexp.run.executor import make_executor, run_many

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
import json
import math
import multiprocessing
import os
import pkgutil
import re
import signal
import sys
import threading
import time
from collections import OrderedDict, defaultdict
from collections.abc import Iterable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures import as_completed as futures_as_completed

import numpy as np

from magexp.run import cache
from magexp.run.budget import check_runs
from magexp.errors import MagexpError
from magexp.run.runner import run_batch

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
    workers at the first ``submit``, from the calling thread (the command's main thread).

    Parameters
    ----------
    parent, poll : int, float
        The parent's process id; seconds between looks.
    """
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
        return self.fn(*self.args)


class InlineExecutor:
    """Runs each submitted call in this process, when its result is asked for (``jobs=1``)."""

    workers = 1
    shares_files = True  # workers see the parent's run cache (they store runs there themselves)

    def submit(self, fn, *args):
        """``fn(*args)``, called when its result is asked for.

        Parameters
        ----------
        fn, *args : callable and its arguments
        """
        return _Deferred(fn, args)

    def as_completed(self, futures: Iterable) -> Iterator:
        """``futures``, in order.

        Parameters
        ----------
        futures : iterable of submitted calls
        """
        return iter(list(futures))

    def close(self) -> None:
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
        if self._pool is None:
            method = "fork" if "fork" in multiprocessing.get_all_start_methods() else None
            if method == "fork":
                preload()
            self._pool = ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context(method),
                                             initializer=_init_worker, initargs=(os.getpid(),))
        return self._pool

    def submit(self, fn, *args):
        return self.pool.submit(_in_worker, fn, *args)

    def as_completed(self, futures: Iterable) -> Iterator:
        return futures_as_completed(list(futures))

    def close(self) -> None:
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
        return self.client.submit(fn, *args, pure=False)

    def as_completed(self, futures: Iterable) -> Iterator:
        from distributed import as_completed  # lazy: as in __init__ (distributed: 0.30 s CPU)

        return iter(as_completed(list(futures)))

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def check_executor(kind: str, jobs: int, scheduler: str | None) -> None:
    """Refuse bad executor settings in one line (before anything is computed).

    Parameters
    ----------
    kind, jobs, scheduler : str, int, str or None
    """
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
    with a port (``tcp://host:8786``, ``host:8786``).

    Parameters
    ----------
    scheduler : str or None
        The scheduler setting.
    """
    if scheduler is None or scheduler in JOBQUEUES:
        return
    match = _ADDRESS.fullmatch(str(scheduler))
    if not match or not 0 < int(match.group(2)) < 65536:
        raise MagexpError(f"--scheduler {scheduler!r} is not allowed: give tcp://HOST:PORT (e.g. tcp://node1:8786), "
                          f"or one of {', '.join(JOBQUEUES)}")


def jobqueue_cluster(system: str):
    """A ``dask-jobqueue`` cluster for ``system`` (slurm, pbs, sge): one single-threaded worker a job.

    Parameters
    ----------
    system : str
    """
    try:  # lazy: an optional extra that imports distributed (as in DaskExecutor), only for --scheduler slurm|pbs|sge
        import dask_jobqueue
    except ImportError:
        raise MagexpError(f"--scheduler {system} needs dask-jobqueue: pip install 'magexp[cluster]'") from None
    return getattr(dask_jobqueue, JOBQUEUES[system])(processes=1, cores=1)


def make_executor(kind: str = "local", *, jobs: int = 0, scheduler: str | None = None):
    """The executor ``kind`` (:data:`EXECUTORS`); ``jobs``: processes (0: all cores).

    Parameters
    ----------
    kind, jobs, scheduler : str, int, str or None
        ``scheduler``: :class:`DaskExecutor`'s.
    """
    check_executor(kind, jobs, scheduler)
    if kind == "dask":
        return DaskExecutor(jobs, scheduler)
    return InlineExecutor() if jobs == 1 else LocalExecutor(jobs)


def _run_task(configs: list[dict], keys: list[str], root=None, reuse: bool = True,
              wait: bool = False) -> tuple[list, float, list]:
    """A task, in a worker: its runs through :func:`magexp.run.runner.run_batch`; returns
    ``(results, task_cpu, notes)``, ``task_cpu`` the CPU seconds this process spent on the task and
    ``notes`` the run cache's problems (:func:`magexp.run.cache.take_notes`) for the parent to say.

    With ``root`` (the run cache, on a file system this worker shares with the parent) the task
    first claims each of its runs (:func:`magexp.run.cache.claim`; with ``wait``, waiting for the runs
    another process holds, in key order); it computes the runs it claimed and stores them when its
    last fit is done, each atomically (a task killed midway is rerun whole, as a remote one is). A
    run that appeared in the cache meanwhile (another reproduction on the same cache computed it)
    is read instead, unless not ``reuse`` (``--force``) and not ``wait``. ``results`` holds, per
    run, ``(row, fit_cpu)`` (:func:`run_row`; ``fit_cpu`` None for a run read, not computed), the
    output itself where the cache could not keep it, or None for a run another process is computing
    (without ``wait``): nothing large goes back to the parent otherwise. Without ``root``,
    ``results`` holds the outputs.
    """
    start = time.process_time()
    if root is None:
        return list(run_batch(configs)), time.process_time() - start, []
    results: list = [None] * len(keys)
    mine, claims = [], []
    for i in sorted(range(len(keys)), key=keys.__getitem__) if wait else range(len(keys)):
        claim = cache.claim(keys[i], root, wait=wait)
        if claim is None:  # another process is computing it
            continue
        out = cache.load(keys[i], root) if (reuse or wait) and cache.exists(keys[i], root) else None
        if out is not None:  # another process computed it
            claim.release()
            results[i] = run_row(out), None
        else:
            mine.append(i)
            claims.append(claim)
    for i, out in zip(mine, run_batch([configs[i] for i in mine])):
        results[i] = out
    for i, claim in zip(mine, claims):  # in one loop after the fits: measured cheaper than between them
        out = results[i]
        results[i] = (run_row(out), out.fit_cpu) if cache.store(keys[i], out, root) else out
        claim.release()
    return results, time.process_time() - start, cache.take_notes()


def _group_key(cfg: dict) -> str:
    """Runs with the same key share their data: same scenario node, same objective."""
    return json.dumps([cfg.get("scenario"), cfg.get("objective")], sort_keys=True, default=str)


def cost_hint(cfg: dict) -> float:
    """A rough relative cost of a run, to hand out the longest tasks first.

    Parameters
    ----------
    cfg : dict
    """
    est, scen = cfg.get("estimator") or {}, cfg.get("scenario") or {}

    def number(node, *keys, default=1.0):
        for key in keys:
            value = node.get(key)
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                return float(value)
        return default

    return number(est, "n_particles") * number(est, "n_iterations", "n_steps", "max_nfev") * number(scen, "n_readings",
                                                                                                    default=300.0)


def plan_tasks(configs: Sequence[dict], workers: int) -> list[list[int]]:
    """Indices of ``configs`` in tasks: per scenario group, blocks of whole seeds (every estimator
    of a seed in one task), about ``len(configs) / (8 workers)`` runs a task; longest first.

    Parameters
    ----------
    configs, workers : sequence of dict, int
        The resolved configs; the executor's workers.
    """
    groups: dict[str, dict[int, list[int]]] = defaultdict(lambda: defaultdict(list))
    for i, cfg in enumerate(configs):
        groups[_group_key(cfg)][cfg.get("seed")].append(i)
    size = max(1, min(64, math.ceil(len(configs) / (8 * max(workers, 1)))))
    tasks = []
    for by_seed in groups.values():
        task: list[int] = []
        for seed in sorted(by_seed, key=str):
            if task and len(task) + len(by_seed[seed]) > size:
                tasks.append(task)
                task = []
            task.extend(by_seed[seed])
        if task:
            tasks.append(task)
    return sorted(tasks, key=lambda t: -sum(cost_hint(configs[i]) for i in t))


def run_row(out) -> dict:
    """A run's row of the runs table: its metrics and its parameter estimates (one column per
    parameter name that is not already a metric).

    Parameters
    ----------
    out : RunOutput
        The run's output.
    """
    estimate = {n: float(v) for n, v in zip(out.parameter_names, np.ravel(out.x)) if n not in out.metrics}
    return {**out.metrics, **estimate}


class Outputs(Sequence):
    """The outputs of :func:`run_many`, read back from the run cache on access (a few are kept)."""

    def __init__(self, keys: list[str], metrics: dict[str, dict], root=None, keep: int = 256, held=None,
                 read: frozenset = frozenset()):
        self.keys, self._metrics, self.root, self.keep, self.read = keys, metrics, root, keep, read
        self.held = {} if held is None else held  # outputs the run cache could not keep, by key
        self._recent: OrderedDict = OrderedDict()

    def __len__(self) -> int:
        return len(self.keys)

    def metrics(self, i: int) -> dict:
        """Run ``i``'s row (:func:`run_row`: metrics and estimates) without reading its output.

        Parameters
        ----------
        i : int
        """
        return self._metrics[self.keys[i]]

    def was_cached(self, i: int) -> bool:
        """Whether run ``i`` was read from the run cache (a valid entry) rather than computed.

        Parameters
        ----------
        i : int
        """
        return self.keys[i] in self.read

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        key = self.keys[i]
        if key in self.held:
            return self.held[key]
        if key in self._recent:
            self._recent.move_to_end(key)
            return self._recent[key]
        out = cache.load(key, self.root)
        if out is None:
            raise MagexpError(f"the run cache lost run {key} while it was read back (is another process clearing it?)")
        self._recent[key] = out
        if len(self._recent) > self.keep:
            self._recent.popitem(last=False)
        return out


def run_many(configs: Sequence[dict], *, jobs: int = 0, use_cache: bool = True, progress=None, executor=None,
             counts: dict | None = None) -> Outputs:
    """Run resolved configs, each distinct one once, cached; returns their :class:`Outputs`.

    Parameters
    ----------
    configs : sequence of dict
        The resolved configs.
    jobs, executor : int, executor or None
        From :func:`make_executor` (default: local processes over ``jobs``, 0 = all cores).
    use_cache : bool
        False reruns every distinct run (and stores it).
    progress : callable or None
        ``progress(n)`` is called with the number of runs just finished.
    counts : dict or None
        Receives ``requested``, ``distinct``, ``computed``, ``cached``, ``fit_cpu`` (CPU seconds inside
        the computed runs' fits) and ``task_cpu`` (CPU seconds of the tasks, measured inside the workers
        around each task), so ``task_cpu - fit_cpu`` is the workers' cost outside the fits.
    """
    check_runs(configs)  # the runs limit, each run's memory and work, their total: before any runs
    keys = cache.run_keys(configs)
    first = {}
    for i, key in enumerate(keys):
        first.setdefault(key, i)
    metrics = _cached_rows(first, use_cache)
    read = frozenset(metrics)  # valid entries only: a damaged one is recomputed, not read
    todo = [i for key, i in first.items() if key not in metrics]
    if counts is not None:
        counts.update(requested=len(configs), distinct=len(first), computed=len(todo), cached=len(first) - len(todo))
    multiplicity = defaultdict(int)
    for key in keys:
        multiplicity[key] += 1
    if progress:
        progress(len(configs) - sum(multiplicity[keys[i]] for i in todo))
    done = _Done(metrics, multiplicity, progress)
    if todo:
        own = executor is None
        ex = executor if executor is not None else make_executor("local", jobs=jobs)
        try:
            ex = _run_todo(configs, keys, todo, ex, own, use_cache, done)
        except BaseException:
            if own:
                ex.__exit__(KeyboardInterrupt, None, None)
            raise
        if own:
            ex.close()
    cache.say_notes()
    if counts is not None:
        counts.update(fit_cpu=done.fit_cpu, task_cpu=done.task_cpu, computed=counts["computed"] - done.shared,
                      cached=counts["cached"] + done.shared)
    return Outputs(keys, metrics, held=done.held, read=read)


def _cached_rows(first: dict[str, int], use_cache: bool) -> dict[str, dict]:
    """The rows (:func:`run_row`) of the distinct runs ``first`` (key -> index) already in the run cache."""
    rows = {}
    for key in first:
        out = cache.load(key) if use_cache else None
        if out is not None:
            rows[key] = run_row(out)
    return rows


class _Done:
    """What :func:`run_many` gathers as results arrive: rows by key, outputs the cache could not keep
    (``held``), CPU seconds inside fits and tasks, runs another process computed (``shared``)."""

    def __init__(self, metrics: dict, multiplicity: dict, progress):
        self.metrics, self.multiplicity, self.progress = metrics, multiplicity, progress
        self.held: dict = {}
        self.fit_cpu = self.task_cpu = 0.0
        self.shared = 0

    def add(self, key: str, result) -> None:
        """One run's result from a task: ``(row, fit_cpu)`` (``fit_cpu`` None: read, not computed), or
        the output itself (a remote worker's), stored here or held."""
        if not isinstance(result, tuple):  # the output itself: store it here, or hold it
            if not cache.store(key, result):
                self.held[key] = result
            result = run_row(result), result.fit_cpu
        self.metrics[key], fit = result
        if fit is None:  # another process computed it
            self.shared += 1
        else:
            self.fit_cpu += fit
        if self.progress:
            self.progress(self.multiplicity[key])


def _run_todo(configs, keys, todo: list[int], ex, own: bool, use_cache: bool, done: _Done):
    """Run the configs ``todo`` in tasks on ``ex`` (inline when one task and the executor is ours),
    then wait for the runs another process was computing; returns the executor used."""
    tasks = [[todo[j] for j in t] for t in plan_tasks([configs[i] for i in todo], ex.workers)]
    if len(tasks) == 1 and own:
        ex.close()
        ex = InlineExecutor()
    root = cache.CACHE if getattr(ex, "shares_files", False) else None
    waiting: list[list[int]] = []  # runs another process was computing, per task
    for wait in (False, True):  # then wait for them (their results are read, not computed)
        futures = {ex.submit(_run_task, [configs[i] for i in task], [keys[i] for i in task], root,
                             use_cache, wait): task for task in (waiting if wait else tasks)}
        waiting = _collect(ex, futures, keys, done)
    return ex


def _collect(ex, futures: dict, keys: list[str], done: _Done) -> list[list[int]]:
    """Gather the tasks' results as they finish into ``done``; returns, per task, the runs another
    process was computing (to wait for)."""
    waiting = []
    for future in ex.as_completed(futures):
        results, cpu, notes = future.result()
        done.task_cpu += cpu
        cache.add_notes(notes)
        task = futures.pop(future)
        waiting.append([i for i, result in zip(task, results) if result is None])
        for i, result in zip(task, results):
            if result is not None:
                done.add(keys[i], result)
    return [task for task in waiting if task]
