"""Run one configuration: scenario x estimator x seed -> metrics and history."""

from __future__ import annotations

import json
import time
from collections import OrderedDict
from collections.abc import Iterator

import numpy as np
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from magexp.core.datafiles import data_files
from magexp.errors import MagexpError
from magexp.estimators.base import check_applies
from magexp.estimators.result import RunOutput
from magexp.run.targets import check_targets
from magexp.core.metrics import evaluate, problem_bound
from magexp.problems import make_problem, problem_class
from magexp.core.seeding import run_sequences, scenario_stream


#: the columns :func:`run_batch` writes beside :func:`magexp.core.metrics.evaluate`'s
RUN_COLUMNS = ("scenario", "estimator", "objective", "seed", "wall_time")


def build(node, what: str):
    """Instantiate a ``_target_`` node with plain-Python arguments, one-line errors. ``what`` begins with
    what the node is (``estimator 'lm'``): every ``_target_`` in the node is checked first
    (:func:`magexp.run.targets.check_targets`: a plug-in class, never a function), so nothing else is called.

    Parameters
    ----------
    node : DictConfig or dict
        A config node with a ``_target_``.
    what : str
        What it is, for the error line (``estimator 'lm'``).

    Returns
    -------
    object
        The instance (``hydra.utils.instantiate``)."""
    check_targets(node, what.split()[0], plugin=True)
    try:
        return instantiate(node, _convert_="all")
    except MagexpError:
        raise
    except Exception as exc:  # hydra wraps constructor errors
        cause = exc
        while cause.__cause__ is not None:
            cause = cause.__cause__
        if isinstance(cause, MagexpError):
            raise cause from None
        raise MagexpError(f"{what} could not be built: {str(cause).splitlines()[0]}") from None


def run(cfg: DictConfig) -> RunOutput:
    """Simulate (or load) the scenario, fit the estimator, evaluate the result.

    Parameters
    ----------
    cfg : DictConfig
        A composed run config (``scenario``, ``estimator``, ``seed``...).

    Returns
    -------
    RunOutput
        The run's fit, metrics and what the summary needs (:class:`magexp.estimators.result.RunOutput`).
    """
    return next(run_batch([cfg]))


def _plain(node):
    """A config node as plain containers (resolved), anything else as it is: what a cache key hashes."""
    return OmegaConf.to_container(node, resolve=True) if isinstance(node, DictConfig) else node


def _text(node) -> str:
    """A config node as sorted JSON: the text two equal nodes share, to key what is built from them."""
    return json.dumps(_plain(node), sort_keys=True, default=str)


#: scenario and estimator objects built in this process, by config node and the data files it names
#: (objects are stateless between fits: a worker builds each once for all its tasks)
_BUILT: OrderedDict = OrderedDict()


def _build_key(plain: dict, what: str) -> tuple:
    """What a built object depends on: its kind, its node's content and its data files' content."""
    return what.split()[0], _text(plain), tuple(sorted(data_files(plain).values()))


def build_once(node, what: str, keep: int = 256, key: tuple | None = None):
    """:func:`build`, memoised in this process by the node's content and its data files' content
    (``key``: its :func:`_build_key`, when the caller has it).

    Parameters
    ----------
    node, what
        As :func:`build`.
    keep : int
        How many built objects this process keeps.
    key : tuple, optional
        The node's key, when the caller has it.

    Returns
    -------
    object
        The instance, built once per key."""
    key = _build_key(_plain(node), what) if key is None else key
    if key in _BUILT:
        _BUILT.move_to_end(key)
    else:
        _BUILT[key] = build(node, what)
        if len(_BUILT) > keep:
            _BUILT.popitem(last=False)
    return _BUILT[key]


class _Shared:
    """What the runs of one batch share, each built once: scenario and estimator objects
    (:func:`build_once`, the key of a config node worked out once per node in the batch), and per
    (scenario, objective, seed) the dataset, the problem, its Cramér-Rao bound and the seed
    sequences (the data depend on the seed only, so every estimator of a seed sees the same
    readings, and each estimator gets a fresh generator of the same estimator stream)."""

    def __init__(self, keep: int = 64):
        self.problems, self.keep = OrderedDict(), keep
        self._nodes: dict = {}  # id(node) -> (node, key): the node is held, so its id is not reused
        self._keys: dict = {}  # (kind, node text) -> key, for nodes equal but not the same object

    def key(self, node, what: str) -> tuple:
        """:func:`_build_key` of ``node``, worked out once per node object and once per content."""
        entry = self._nodes.get(id(node))
        if entry is None or entry[0] is not node:
            plain = _plain(node)
            text = (what.split()[0], _text(plain))
            if text not in self._keys:
                self._keys[text] = _build_key(plain, what)
            entry = self._nodes[id(node)] = (node, self._keys[text])
        return entry[1]

    def build(self, node, what: str):
        """The object ``node`` builds, built once per batch (:func:`build_once`)."""
        return build_once(node, what, key=self.key(node, what))

    def problem(self, cfg, scenario, seed: int):
        """``(objective, dataset, problem, bound, estimator sequence)`` of the run's scenario and seed;
        ``bound`` is a list that holds the problem's :func:`problem_bound` once it is computed."""
        objective = cfg.get("objective") or scenario.objective
        key = (self.key(cfg["scenario"], "scenario")[1], objective, seed)
        if key not in self.problems:
            data_seq, est_seq = run_sequences(seed, stream=scenario_stream(cfg["scenario"]))
            dataset = scenario.generate(rng=np.random.default_rng(data_seq))
            problem = make_problem(objective, dataset, scenario.search, **getattr(scenario, "problem_options", {}))
            self.problems[key] = (objective, dataset, problem, [], est_seq)
            if len(self.problems) > self.keep:  # bounded memory on long batches
                self.problems.popitem(last=False)
        return self.problems[key]


def run_batch(configs) -> Iterator[RunOutput]:
    """Run resolved configs (dicts or DictConfigs) one after the other, yielding each output.

    Equal to ``run`` on each config, but what the runs share is built once (:class:`_Shared`):
    a batch of one scenario's seeds over several estimators builds the scenario once, each seed's
    dataset and problem once, and computes each seed's Cramér-Rao bound once.

    Parameters
    ----------
    configs : iterable of dict or DictConfig
        Resolved run configs.

    Yields
    ------
    RunOutput
        Each config's output, in order.
    """
    shared = _Shared()
    for cfg in configs:
        seed = cfg["seed"]
        scenario = shared.build(cfg["scenario"], f"scenario {cfg['scenario'].get('name')!r}")
        estimator = shared.build(cfg["estimator"], f"estimator {cfg['estimator'].get('name')!r}")
        objective = cfg.get("objective") or scenario.objective
        check_applies(estimator, problem_class(objective), f"scenario {scenario.name!r}")  # before any data
        objective, dataset, problem, bound, est_seq = shared.problem(cfg, scenario, seed)
        est_rng = np.random.default_rng(est_seq)
        start, cpu = time.perf_counter(), time.process_time()
        result = estimator.fit(problem, rng=est_rng)
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        if cfg.get("analysis"):  # an analysis step on the fitted result (conf/analysis/*.yaml)
            result = shared.build(cfg["analysis"], f"analysis {cfg['analysis'].get('name')!r}")(problem, result)
        if not bound:
            bound.append(problem_bound(problem))
        metrics = {"scenario": scenario.name, "estimator": estimator.name, "objective": objective,
                   "seed": int(seed), **evaluate(problem, result, bound[0]), "wall_time": wall}
        yield RunOutput(metrics=metrics, history=np.asarray(result.history),
                        history_nfev=np.asarray(result.history_nfev), x=np.asarray(result.x),
                        parameter_names=problem.parameter_names(), trace=result.trace, readings=dataset.readings,
                        calibrated=problem.calibrate(result.x), reference_norm=np.asarray(dataset.reference_norm),
                        truth_x=problem.truth_theta(), lower=np.asarray(problem.lower, float),
                        upper=np.asarray(problem.upper, float), design=design_summary(problem), fit_cpu=cpu)


def design_summary(problem) -> dict | None:
    """What the least-squares t-interval and F-test of a linear problem ``Y = C x`` need, without its
    readings (None for a problem without a linear design): ``gram`` ``C^T C``, ``coef`` the
    least-squares ``x`` (``numpy.linalg.lstsq``), ``rss`` the residual sum of squares of each column
    of ``Y`` and ``n`` the readings (:func:`magexp.artifacts.summary.least_squares_interval`).

    Parameters
    ----------
    problem : Problem
        The run's problem.

    Returns
    -------
    dict or None
        ``{"gram", "coef", "rss", "n"}``."""
    if "linear_design" not in problem.capabilities:
        return None
    c, y = (np.asarray(a, float) for a in problem.design())
    coef = np.linalg.lstsq(c, y, rcond=None)[0]
    return {"gram": c.T @ c, "coef": coef, "rss": np.sum((y - c @ coef) ** 2, axis=0), "n": len(c)}
