"""What an estimator is (the :class:`Estimator` protocol) and whether it applies to a problem.

An estimator declares what it needs from a problem as ``needs``, a tuple of capability names of
:data:`magexp.problems.base.CAPABILITIES` (``cost``, ``residuals``, ``linear_design``,
``total_field``); a problem declares what it offers as ``capabilities``. :func:`applies_to`
compares the two and is the one answer used by ``task=run`` (:mod:`magexp.run.runner`), the
artifacts (:func:`magexp.artifacts.plan.applicable`), ``calibrate`` and the contract test. It works on
classes as well as instances, so an artifact can skip a cell before simulating anything.
"""

from __future__ import annotations

from typing import Callable, Optional, Protocol, runtime_checkable

import numpy as np

from magexp.errors import MagexpError
from magexp.estimators.result import FitResult
from magexp.problems.base import CAPABILITIES, describe

#: ``callback(t, x, fun) -> bool``: a true value stops the run.
Callback = Callable[[int, np.ndarray, Optional[float]], bool]


@runtime_checkable
class Estimator(Protocol):
    """An estimator: one class and one config (``conf/estimator/<name>.yaml``).

    Its constructor takes the hyper-parameters as typed keyword arguments (``n_particles: int = 50``):
    they are the config's keys, and their annotations and defaults are its typed schema
    (:func:`magexp.run.compose.schema_of`), which the config names in its defaults list
    (``- /schema/estimator/<ClassName>@_here_``). Everything else about it is a class attribute.

    Attributes
    ----------
    name : str
        Its config name (the constructor's ``name``: every estimator class takes one, as
        ``name: str``, and the result tables name the run by it).
    needs : tuple of str
        Capabilities the problem must offer (:data:`magexp.problems.base.CAPABILITIES`).
    iterative : bool
        Whether ``fit`` iterates (and so honours ``callback``).
    label : str
        Its name in the report's row labels (``"KF"``); empty: the config name. A config may set its
        own ``label:`` where its class takes one (the swarm engine: ``pso``, ``ipso``, ``rdpso``).
    smoke : dict of str to int
        The sizes a smoke run (``reproduce --tiny``, the smoke tests) caps each key to
        (``{"n_iterations": 6, "n_particles": 6}``); empty: nothing to cap.
    references : str
        The paper(s) the method comes from.
    monotone_history : bool, optional
        False where the history need not decrease (a filter's objective per step); default True.
    METRICS : tuple of str, optional
        The columns its ``FitResult.metrics`` holds (``("on_boundary",)``), so the spec check knows them before
        any run (:mod:`magexp.artifacts.run_columns`); ``tests/test_run_columns.py`` fails on a column written
        undeclared or declared and never written. Default: none.

    Raises
    ------
    MagexpError
        From every estimator's constructor, for a hyper-parameter outside what its class docstring
        allows (one line naming the value and what is allowed); a problem lacking what the estimator
        needs is refused in one line too (:func:`check_applies`).
    """

    name: str
    needs: tuple
    iterative: bool
    label: str
    smoke: dict
    references: str

    def fit(self, problem, *, rng: np.random.Generator, callback: Callback | None = None) -> FitResult:
        """Fit ``problem``.

        Parameters
        ----------
        problem : magexp.problems.base.Problem
            What to fit: it offers every capability of ``needs``.
        rng : numpy.random.Generator
            The run's estimator stream (:mod:`magexp.core.seeding`): every random draw comes from it.
        callback : callable, optional
            :data:`Callback` ``callback(t, x, fun)`` after every iteration of an iterative estimator (``t`` =
            1, 2, ...; ``x`` its current best or state; ``fun`` its objective, or None where it evaluates
            none); a true return stops it.

        Returns
        -------
        FitResult
            ``x`` the estimate, ``fun`` the problem's objective at ``x`` (``problem.cost_direct(x)``), the
            history of the best objective.
        """


def applies_to(estimator, problem) -> tuple[bool, str]:
    """Whether ``estimator`` applies to ``problem``: what it ``needs`` against what the problem offers, and its
    ``only_objective`` if it is bound to one (e.g. a paper's printed solution of one model)."""
    name = name_of(estimator)
    objective = getattr(problem, "objective", "?")
    needs = tuple(getattr(estimator, "needs", ("cost",)))
    unknown = [c for c in needs if c not in CAPABILITIES]
    if unknown:
        raise MagexpError(f"estimator {name!r} needs {unknown[0]!r}: not a capability, choose from "
                          f"{', '.join(CAPABILITIES)}")
    offered = frozenset(getattr(problem, "capabilities", ()))
    missing = [c for c in needs if c not in offered]
    if missing:
        return False, (f"estimator {name!r} needs {describe(missing)}, which the {objective!r} problem does not "
                       f"offer (it offers {describe(offered) or 'nothing'})")
    only = getattr(estimator, "only_objective", None)
    if isinstance(only, str) and only != objective:
        return False, f"estimator {name!r} is the solution of the {only!r} model: it does not apply to {objective!r}"
    return True, ""


def name_of(estimator) -> str:
    """The config name of ``estimator``: its ``name``, else its class's name."""
    name = getattr(estimator, "name", None)
    return name if isinstance(name, str) else getattr(estimator, "__name__", type(estimator).__name__)


def check_applies(estimator, problem, where: str = "", alternatives=None) -> None:
    """Raise a one-line :class:`MagexpError` unless :func:`applies_to` says yes."""
    ok, reason = applies_to(estimator, problem)
    if ok:
        return
    at = f" ({where})" if where else ""
    if alternatives is not None:
        fits = [name for name, cls in alternatives().items() if applies_to(cls, problem)[0]]
        reason = f"choose one of {', '.join(fits)} ({reason})"
    raise MagexpError(f"estimator={name_of(estimator)!r} is not allowed for objective "
                      f"{getattr(problem, 'objective', '?')!r}{at}: {reason}")


class Stop(Exception):
    """Raised inside an objective to stop a library optimiser when the callback asks to."""


def stopper(callback: Callback | None, best: dict):
    """A recorder for library optimisers (``least_squares``, ``minimize``...)."""
    best.setdefault("history", [])
    best.setdefault("fun", np.inf)

    def record(x: np.ndarray, fun: float) -> None:
        if fun < best["fun"]:
            best["fun"], best["x"] = float(fun), np.array(x, float)
        best["history"].append(best["fun"])
        if callback is not None and callback(len(best["history"]), best["x"], best["fun"]):
            raise Stop

    return record
