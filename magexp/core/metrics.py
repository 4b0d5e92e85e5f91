"""Metrics of a fitted calibration, as one flat dict per run, and the one total-field RMS
(:func:`total_field_rms`) that the problems, the calibration and the figures compute it with."""

from __future__ import annotations

import weakref

import numpy as np

from magexp.core.bounds import cramer_rao
from magexp.core.identifiability import recording_metrics
from magexp.core.outcomes import reach_level

#: the errors :func:`bound_metrics` divides by their Cramér-Rao bound (``<name>_bound``, ``<name>_error_ratio``)
BOUNDED = ("offset", "gram", "matrix")
#: the columns :func:`evaluate` writes for every problem, beside the problem's, the recording's
#: (:data:`magexp.core.identifiability.RECORDING_METRICS`) and the estimator's own (their ``METRICS``);
#: conditional: ``noise_floor`` (a known noise level), ``truth_fun``, ``converged`` and ``nfev_to_floor`` (a
#: truth), ``iterations_to_1.1`` and ``nfev_to_1.1`` (a finite history), the bound's (a Cramér-Rao bound;
#: ``rms_bound`` for an RMS objective, else ``residual_rms_bound``)
METRICS = ("fun", "nit", "nfev", "optimizer_flag", "noise_floor", "truth_fun", "converged", "iterations_to_1.1",
           "nfev_to_1.1", "nfev_to_floor", "rms_bound", "residual_rms_bound", "identifiable", "rms_ratio",
           *(f"{name}_bound" for name in BOUNDED), *(f"{name}_error_ratio" for name in BOUNDED))
#: :func:`truth_cost` of each live problem (a problem's data and truth do not change)
_TRUTH_COST: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def rms(values, axis: int = -1):
    """Root mean square of ``values`` along ``axis``.

    .. math:: \\mathrm{RMS}(e) = \\sqrt{\\tfrac1N \\textstyle\\sum_i e_i^2}
    """
    v = np.asarray(values, float)
    out = np.sqrt(np.mean(v * v, axis=axis))
    return float(out) if np.ndim(out) == 0 else out


def total_field_rms(calibrated, reference):
    """Total-field RMS of calibrated readings against a reference total field (Ding 2024, eq 17 and
    eq 18; the RMS of ``|B| - reference`` of ``magexp calibrate``).

    .. math:: \\mathrm{RMS} = \\sqrt{\\tfrac1N \\textstyle\\sum_i \\big(\\lVert \\mathbf b_i\\rVert - B_{a,i}\\big)^2}

    Vectorised over leading axes: a stack of calibrations (e.g. one per particle) in one call.
    """
    return rms(np.linalg.norm(np.asarray(calibrated, float), axis=-1) - np.asarray(reference, float))


def truth_cost(problem) -> float | None:
    """``problem.cost_direct`` at the true parameters (None without a truth): the objective the
    true calibration reaches on the same readings. It depends on the problem's data only, so it is
    computed once per problem object and shared by every estimator fitted to it (and by the
    problem's own metrics, e.g. the vector objective's noise floor).
    """
    if problem not in _TRUTH_COST:
        truth = problem.truth_theta()
        _TRUTH_COST[problem] = None if truth is None else float(problem.cost_direct(truth))
    return _TRUTH_COST[problem]


def noise_floor(dataset, n_identifiable: int = 9) -> float | None:
    """Expected total-field RMS of a perfect scalar fit under the dataset's noise.

    .. math:: \\sigma \\sqrt{(N - p)/N}

    with ``σ`` the per-axis noise standard deviation (``A/√12`` for Ding's
    uniform noise, whose radial component has the same variance) and ``p = 9``
    identifiable parameters of a scalar fit.
    """
    if dataset.noise_std is None:
        return None
    n = dataset.n
    return float(dataset.noise_std * np.sqrt(max(n - n_identifiable, 0) / n))


def evaluate(problem, result, crb=None) -> dict:
    """Every metric of one fitted run; a diverged fit is measured (inf/NaN), not warned about.

    ``crb``: the problem's :func:`problem_bound`, when the caller shares it between the estimators
    of one dataset (it depends on the data and the truth only); None computes it here.
    """
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return _evaluate(problem, result, problem_bound(problem) if crb is None else crb)


def _evaluate(problem, result, crb) -> dict:
    """Every metric of one fitted run (direct formulas, not the swarm's fast cost)."""
    out = {
        "fun": float(problem.cost_direct(result.x)),
        "nit": int(result.nit),
        "nfev": int(result.nfev),
        "optimizer_flag": bool(result.success),  # the optimiser's own flag, not a success (core.outcomes)
    }
    floor = noise_floor(problem.dataset)
    if floor is not None:
        out["noise_floor"] = floor
    truth_fun = truth_cost(problem)
    reached = None  # as good as the true calibration on the same readings (core.outcomes.reach_level)
    if truth_fun is not None:
        out["truth_fun"] = truth_fun
        reached = reach_level(truth_fun)
        out["converged"] = bool(out["fun"] <= reached)
    out.update(problem.metrics(result.x))
    out.update(recording_metrics(problem, result.x))  # recorded data: spread before, after, held out
    out.update(result.metrics)
    out.update(time_to_reach(result, factor=1.1))
    if reached is not None:
        out["nfev_to_floor"] = evaluations_to(result, reached)
    out.update(bound_metrics(problem, {**out, "x": result.x}, crb))
    return out


def evaluations_to(result, level: float) -> float:
    """Objective evaluations spent when the best value first came within ``level`` (NaN if never):
    with ``level = 1.01 x`` the true calibration's objective, the cost of reaching the floor.
    Only meaningful for a history of the problem's own objective (a monotone one).
    """
    hist = np.asarray(result.history, float)
    reached = np.flatnonzero(hist <= level)
    return float(np.asarray(result.history_nfev)[reached[0]]) if reached.size else float("nan")


def time_to_reach(result, factor: float = 1.1) -> dict:
    """Iterations and objective evaluations until the best value first came within
    ``factor`` times its final value: ``iterations_to_1.1`` and ``nfev_to_1.1`` (empty without a finite history).
    """
    hist = np.asarray(result.history, float)
    if hist.size == 0 or not np.isfinite(hist[-1]):
        return {}
    k = int(np.argmax(hist <= factor * hist[-1] + 1e-300))
    return {"iterations_to_1.1": k, "nfev_to_1.1": int(np.asarray(result.history_nfev)[k])}


def problem_bound(problem) -> dict | bool:
    """The Cramér-Rao bound of ``problem`` at its truth (:func:`magexp.core.bounds.cramer_rao`), or False
    when it has none. It depends on the dataset and the truth only, not on the estimator.
    """
    if not hasattr(problem, "invariants") or not hasattr(problem, "options"):
        return False
    return cramer_rao(problem) or False


def bound_metrics(problem, measured: dict, crb: dict | bool | None = None) -> dict:
    """The Cramér-Rao bound of the run's problem (``crb``: :func:`problem_bound`, computed here if
    None) and each error as a ratio to it.
    """
    if crb is None:
        crb = problem_bound(problem)
    if not crb:
        return {}
    # the floor is an RMS per residual component: it bounds `fun` only when the objective is such an RMS
    # (the vector objective F is a sum of norms), so it is named after what it can be drawn against
    name = "rms_bound" if getattr(problem, "objective_is_rms", True) else "residual_rms_bound"
    out = {name: crb["rms_floor"], "identifiable": crb["identifiable"]}
    if crb["rms_floor"] > 0:  # residual RMS per component against the expected floor
        out["rms_ratio"] = rms(problem.residuals(measured["x"])) / crb["rms_floor"]
    for name in BOUNDED:
        bound = crb.get(f"{name}_bound")
        if bound is not None:
            out[f"{name}_bound"] = bound  # inf: the data cannot identify it
            if f"{name}_error" in measured and 0 < bound < np.inf:
                out[f"{name}_error_ratio"] = measured[f"{name}_error"] / bound
    return out
