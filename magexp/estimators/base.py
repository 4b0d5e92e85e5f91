"""What an estimator is (the :class:`Estimator` protocol) and whether it applies to a problem.

An estimator declares what it needs from a problem as ``needs``, a tuple of capability names of
:data:`magexp.problems.base.CAPABILITIES` (``cost``, ``residuals``, ``linear_design``,
``total_field``); a problem declares what it offers as ``capabilities``. :func:`applies_to`
compares the two and is the one answer used by ``task=run`` (:mod:`magexp.run.runner`), the
artifacts (:func:`magexp.artifacts.plan.applicable`), ``calibrate`` and the contract test. It works on
classes as well as instances, so an artifact can skip a cell before simulating anything.

An iterative estimator (``iterative = True``) calls ``callback(t, x, fun)`` after every
iteration (``t`` = 1, 2, ...; ``x`` its current best or state; ``fun`` its objective, or
``None`` where the estimator does not evaluate one) and stops when it returns a true value.
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
    """An estimator: keyword-only hyper-parameters, a ``name``, what it ``needs``, and ``fit``.

    Attributes
    ----------
    name : its config name.
    needs : capabilities the problem must offer (:data:`magexp.problems.base.CAPABILITIES`).
    iterative : whether ``fit`` iterates (and so honours ``callback``).
    """

    name: str
    needs: tuple
    iterative: bool

    def fit(self, problem, *, rng: np.random.Generator, callback: Callback | None = None) -> FitResult: ...


def applies_to(estimator, problem) -> tuple[bool, str]:
    """Whether ``estimator`` (class or instance) applies to ``problem`` (class or instance).

    Returns ``(True, "")`` or ``(False, reason)``, the reason one line naming what the estimator
    needs and what the problem offers. An estimator may also be bound to one objective
    (``only_objective``, e.g. a paper's printed solution of one model).
    """
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
    """The config name of ``estimator`` (class or instance): its ``name``, else its class's name."""
    name = getattr(estimator, "name", None)
    return name if isinstance(name, str) else getattr(estimator, "__name__", type(estimator).__name__)


def check_applies(estimator, problem, where: str = "", alternatives=None) -> None:
    """Raise a one-line :class:`MagexpError` unless :func:`applies_to` says yes: it names the
    estimator, the problem's objective, ``where`` (e.g. the scenario) and the reason, and, given
    ``alternatives`` (a callable returning ``{name: estimator class}``, called only on failure),
    the estimators that do apply (``magexp calibrate``: every ``conf/estimator/*.yaml``)."""
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
    """A recorder for library optimisers (``least_squares``, ``differential_evolution``...):
    ``record(x, fun)`` keeps the best ``x`` seen in ``best`` (``best["x"]``, ``best["fun"]``),
    its history in ``best["history"]``, and raises :class:`Stop` when ``callback`` asks to."""
    best.setdefault("history", [])
    best.setdefault("fun", np.inf)

    def record(x: np.ndarray, fun: float) -> None:
        if fun < best["fun"]:
            best["fun"], best["x"] = float(fun), np.array(x, float)
        best["history"].append(best["fun"])
        if callback is not None and callback(len(best["history"]), best["x"], best["fun"]):
            raise Stop

    return record
