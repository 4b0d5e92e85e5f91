"""The columns a planned run will write, from the declarations beside the code that writes them.

A run's row of the runs table (:func:`magexp.run.executor.run_row`, :func:`magexp.artifacts.plan.collect`) is
written by:

* the runner (:data:`magexp.run.runner.RUN_COLUMNS`) and :func:`magexp.core.metrics.evaluate`
  (:data:`magexp.core.metrics.METRICS`);
* the problem of the run's objective (its class's ``METRICS``; its parameter estimates, ``PARAMETERS`` of the
  run's parameterisation, and the columns named after each parameter, ``PARAMETER_METRICS`` prefixes);
* the scenario's class (``METRICS``: a recording's spread, :data:`magexp.core.identifiability.RECORDING_METRICS`),
  the estimator's class and an analysis step's class (each its ``METRICS``, what its ``FitResult.metrics`` holds);
* the runs table itself (:data:`magexp.artifacts.plan.TABLE_COLUMNS`, ``best_<metric>``).

Each name is declared once, beside its writer, and built from the same tuples the writer uses;
``tests/test_run_columns.py`` runs every estimator on every objective at smoke sizes and checks that a run writes
only declared columns and that each declared column is written by some run. The spec check
(:mod:`magexp.artifacts.spec_check`) parses every claim's metric against :func:`planned_columns`, so a metric
that only a new estimator writes is known before any run.
"""

from __future__ import annotations

import functools
import inspect

from hydra.utils import get_class

from magexp.artifacts.formats import MEASURED
from magexp.artifacts.plan import BEST, TABLE_COLUMNS, objective_of
from magexp.core.metrics import METRICS
from magexp.problems import problem_class
from magexp.run.runner import RUN_COLUMNS


@functools.lru_cache(maxsize=256)
def _class(target: str):
    """The class a ``_target_`` names (imported, not built), once per name."""
    return get_class(target)


def _declared(node) -> tuple:
    """The ``METRICS`` of the class a config node's ``_target_`` names (none without a node)."""
    target = node.get("_target_") if isinstance(node, dict) else None
    return tuple(getattr(_class(target), "METRICS", ())) if target else ()


def _parameters(problem, scenario: dict) -> tuple:
    """The problem's parameter names in a run of ``scenario``: in the parameterisation its scenario class
    chooses (``problem_options``), else the problem constructor's default, else the problem's one."""
    names = getattr(problem, "PARAMETERS", {})
    options = getattr(_class(scenario["_target_"]), "problem_options", None) if scenario.get("_target_") else None
    chosen = options.get("parameterisation") if isinstance(options, dict) else None
    if chosen is None:
        default = inspect.signature(problem).parameters.get("parameterisation")
        chosen = default.default if default is not None else next(iter(names), None)
    return tuple(names.get(chosen, ()))


def run_columns(cfg: dict) -> frozenset:
    """Every column a run of the resolved config ``cfg`` may write into its runs table row (module docstring);
    nothing is built or run.

    Parameters
    ----------
    cfg : dict
        A resolved run config (``scenario``, ``estimator``, ``seed``, an optional ``objective`` and ``analysis``).

    Returns
    -------
    frozenset of str
        The column names (some only when their data are: a truth, a bound, a held-out block, beside each
        declaration).
    """
    scenario = cfg.get("scenario") or {}
    problem = problem_class(objective_of(cfg))
    parameters = _parameters(problem, scenario)
    named = {f"{prefix}{name}" for prefix in getattr(problem, "PARAMETER_METRICS", ()) for name in parameters}
    return frozenset({*RUN_COLUMNS, *METRICS, *getattr(problem, "METRICS", ()), *parameters, *named,
                      *_declared(scenario), *_declared(cfg.get("estimator")), *_declared(cfg.get("analysis"))})


def cell_configs(plan) -> dict:
    """``{cell: config}``: the resolved config of each planned cell's first seed (its seeds differ by their seed)."""
    first: dict = {}
    for k, (ci, _) in enumerate(plan.index):
        first.setdefault(ci, plan.configs[k])
    return first


def planned_columns(plan) -> frozenset:
    """Every column the runs table of ``plan`` (:class:`magexp.artifacts.plan.ArtifactPlan`) may have as it is
    stored: the union of its planned runs' :func:`run_columns`, the columns the runs table adds and the cells'
    settings, less the measured wall times (kept beside the results, :data:`magexp.artifacts.formats.MEASURED`).

    Parameters
    ----------
    plan : ArtifactPlan
        What :func:`magexp.artifacts.plan.plan_artifact` planned: its cells, their configs and its spec's ``success``.

    Returns
    -------
    frozenset of str
        The names a claim's metric may use beside pandas' words.
    """
    found = set(TABLE_COLUMNS) | {k for cell in plan.cells for k in cell}
    for cfg in cell_configs(plan).values():
        found |= run_columns(cfg)
    success = plan.spec.success
    if success is not None and success.reference == BEST:
        found.add(f"best_{success.metric}")
    return frozenset(c for c in found if MEASURED not in c)
