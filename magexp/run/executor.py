"""Where runs execute: one layer behind ``make reproduce`` and ``-m`` sweeps.

Runs (resolved configs) go through :func:`run_many`, which

1. keys each run (:func:`magexp.run.runkeys.run_key`) and runs each distinct key once, also under
   ``use_cache=False`` (``--force``): identical runs of several artifacts are one run;
2. groups the runs to do into *tasks*: the runs of one scenario (and objective) for a block of
   seeds, every estimator included, so that a task builds its scenario and estimators once and each
   seed's dataset, problem and Cramér-Rao bound once (:func:`magexp.run.runner.run_batch`);
3. hands the tasks to an executor, longest first. A worker that shares the parent's file system
   (local processes, a Dask ``LocalCluster``) stores each run in the run cache as it finishes and
   sends back only its metrics row (:func:`_run_task`); a remote worker sends the outputs, which the
   parent stores as they arrive. The parent keeps only the small metrics dicts, and :class:`Outputs`
   reads a full output back from the cache when a figure needs it.

Where the tasks execute (worker processes, a Dask cluster): :mod:`magexp.run.executors`.
"""

from __future__ import annotations

import json
import math
import time
from collections import OrderedDict, defaultdict
from collections.abc import Sequence

import numpy as np

from magexp.run import cache, runkeys
from magexp.run.budget import check_runs
from magexp.errors import MagexpError
from magexp.run.executors import InlineExecutor, make_executor
from magexp.run.runner import run_batch


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
    ``results`` holds the outputs."""
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
    """A rough relative cost of a run, to hand out the longest tasks first."""
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
    of a seed in one task), about ``len(configs) / (8 workers)`` runs a task; longest first."""
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


#: the fields of a run that its row (:func:`run_row`) reads
ROW_FIELDS = ("metrics", "parameter_names", "x")


def run_row(out) -> dict:
    """A run's row of the runs table: its metrics and its parameter estimates (one column per
    parameter name that is not already a metric)."""
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
        """Run ``i``'s row (:func:`run_row`: metrics and estimates) without reading its output."""
        return self._metrics[self.keys[i]]

    def was_cached(self, i: int) -> bool:
        """Whether run ``i`` was read from the run cache (a valid entry) rather than computed."""
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

    ``executor`` from :func:`magexp.run.executors.make_executor` (default: local processes over ``jobs``, 0 = all
    cores); ``use_cache=False`` reruns every distinct run (and stores it); ``progress(n)`` is called with the
    number of runs just finished; ``counts`` receives ``requested``, ``distinct``, ``computed``, ``cached``,
    ``fit_cpu`` (CPU seconds inside the computed runs' fits) and ``task_cpu`` (CPU seconds of the tasks, measured
    inside the workers around each task), so ``task_cpu - fit_cpu`` is the workers' cost outside the fits."""
    check_runs(configs)  # the runs limit, each run's memory and work, their total: before any runs
    keys = runkeys.run_keys(configs)
    first = {}
    for i, key in enumerate(keys):
        first.setdefault(key, i)
    metrics = cached_rows(first, use_cache)
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


def cached_rows(first: dict[str, int], use_cache: bool) -> dict[str, dict]:
    """The rows (:func:`run_row`) of the distinct runs ``first`` (key -> index) already in the run cache: those
    kept beside their entries (:func:`magexp.run.cache.known_rows`), the others read and then kept."""
    if not use_cache:
        return {}
    known = cache.known_rows(first)
    rows, read = {}, {}
    for key in first:
        if key in known:
            rows[key] = known[key]
            continue
        out = cache.load(key, fields=ROW_FIELDS)
        if out is not None:
            rows[key] = read[key] = run_row(out)
    if read:
        cache.keep_rows(read)
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
