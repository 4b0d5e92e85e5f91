"""The result types: what every estimator returns (:class:`FitResult`) and what a run produces (:class:`RunOutput`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class FitResult:
    """Outcome of ``estimator.fit`` (after ``scipy.optimize.OptimizeResult``).

    Attributes
    ----------
    x : numpy.ndarray, shape (p,)
        The best parameter vector, in the problem's parameters (``problem.parameter_names()``).
    fun : float
        The problem's objective at ``x`` by its textbook formula (``problem.cost_direct(x)``).
    nit : int
        Iterations: swarm iterations, filter steps, or least-squares evaluations.
    nfev : int
        Objective evaluations (one particle = one evaluation).
    history : numpy.ndarray
        The best objective after each iteration, ``history[0]`` before the first.
    history_nfev : numpy.ndarray
        The evaluations spent when each ``history`` entry was recorded.
    trace : dict of str to numpy.ndarray
        Optional per-iteration arrays (e.g. a filter's state at every step).
    metrics : dict of str to float
        Optional estimator-specific scalar outcomes, added to the run's metrics.
    success : bool
        Whether the estimator met its own criterion (as in scipy).
    message : str
        Why it stopped (as in scipy).
    """

    x: np.ndarray
    fun: float
    nit: int
    nfev: int
    history: np.ndarray
    history_nfev: np.ndarray
    success: bool = True
    message: str = ""
    trace: dict = field(default_factory=dict)
    metrics: dict = field(default_factory=dict)


@dataclass
class RunOutput:
    """What one run produced: flat metrics, the convergence history and the estimate."""

    metrics: dict
    history: np.ndarray
    history_nfev: np.ndarray
    x: np.ndarray
    parameter_names: list[str] = field(default_factory=list)
    trace: dict = field(default_factory=dict)
    readings: np.ndarray | None = None
    calibrated: np.ndarray | None = None
    reference_norm: np.ndarray | None = None
    truth_x: np.ndarray | None = None  # the true parameter vector (simulations)
    # what the summary reads of the run's problem, so that nothing is simulated again: its search box
    # (``lower``, ``upper``) and, for a linear problem, its least-squares summary (``design``: ``gram``
    # ``C^T C``, ``coef``, ``rss`` per axis, ``n`` readings; :func:`magexp.run.runner.design_summary`)
    lower: np.ndarray | None = None
    upper: np.ndarray | None = None
    design: dict | None = None
    fit_cpu: float = 0.0  # CPU seconds of this process inside ``estimator.fit`` (not a metric: it varies)
