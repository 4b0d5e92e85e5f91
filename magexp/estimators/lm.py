"""Levenberg-Marquardt refinement of the problem's residuals (``scipy.optimize.least_squares``).

**The rotation gauge of a scalar objective.** ``|Q W (r - o)| = |W (r - o)|`` for every orthogonal
``Q`` (Ding 2024 eq 17 sees only ``W^T W`` and ``o``), so over ``[vec W, o]`` the residuals have an
exact 3-dimensional valley and a Jacobian with three dependent columns. MINPACK's pivoted QR on that
rank-deficient matrix can end anywhere along the valley: with bit-identical residuals its iterates
have been seen to differ with the memory left by earlier work in the process, up to the 3rd-4th digit
of ``W``. On a total-field problem this estimator therefore fixes the gauge (``gauge: symmetric``,
the default) and fits the 9 parameters ``q`` of :mod:`magexp.estimators.reduced` (a symmetric
matrix part ``M = M^T`` of the problem's parameters, and ``o``), whose Jacobian has full rank
wherever the data determine ``W^T W`` and ``o``. The result is the polar factor ``P = (W^T W)^{1/2}``
of every ``W = Q P`` (:func:`magexp.core.identifiability.canonical`, the form ``magexp calibrate``
reports): the same numbers in every process (``tests/test_determinism.py``).
``gauge: free`` fits all 12 parameters, kept to compare.

**Its path is a diagnostic.** The default tolerances are met at round-off level, so on another
processor the test is met an iteration earlier or later: ``nit``/``nfev`` move by one Jacobian while
the fit agrees to its 6th digit, and ``magexp verify`` compares them as path diagnostics
(:data:`magexp.artifacts.compare.PATH_DIAGNOSTICS`). A fit the data leave undetermined walks its flat
valley to the evaluation budget, and where it stops moves with the round-off.
"""

from __future__ import annotations

import numpy as np

from magexp.core.ellipsoid import normalise
from magexp.core.identifiability import canonical, identifiability
from magexp.errors import check, check_positive_int
from magexp.estimators.base import Stop, applies_to, stopper
from magexp.estimators.ellipsoid import EllipsoidFit
from magexp.core.marquardt import minimise_numpy, stacked_jacobian
from magexp.problems.symmetric import UPPER, expand
from magexp.estimators.result import FitResult

STARTS = ("ellipsoid", "centre", "problem")
GAUGES = ("symmetric", "free")
JACOBIANS = ("2-point", "stacked")
SOLVERS = ("minpack", "numpy")


class LevenbergMarquardt:
    """Least-squares refinement: ``θ* = argmin_θ Σ_i r_i(θ)²`` over the problem's residuals.

    On the scalar problem ``r_i = |W(B_i - o)| - B_a`` (Ding 2024 eq 17's RMS, minimised in the gauge of
    the module docstring); on the vector problem the components of ``C_i H_i - W(B_i - o)`` (Yuan 2018
    eq 8's terms, squared).

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator`.
    start : str
        ``problem`` (default): the problem's own closed-form ``initial_estimate()`` (e.g. the linear
        least-squares fit of the vector problem), else the ellipsoid fit, else the centre of the search
        box; ``ellipsoid``: the ellipsoid fit, else the centre; ``centre``.
    max_nfev : int
        Cap on residual evaluations.
    tol : float
        ``xtol = ftol = gtol`` of ``least_squares``, in (machine epsilon, 1).
    gauge : str
        On a total-field problem, ``symmetric`` (default) fits the 9 parameters of a symmetric matrix
        part and returns the polar factor (module docstring); ``free`` fits all 12 (its ``W`` carries an
        arbitrary rotation). Other problems always fit all 12.
    jacobian : str
        ``2-point`` (default): scipy's forward differences, one residual evaluation per parameter;
        ``stacked``: the same differences from one call of the problem's ``residual_swarm`` on the
        ``p + 1`` points (:func:`magexp.core.marquardt.stacked_jacobian`), where it has one: faster where
        numpy's per-call overhead dominates an evaluation (the gyro-aided problem's prefix scan).
    solver : str
        ``minpack`` (default): ``scipy.optimize.least_squares``; ``numpy``:
        :func:`magexp.core.marquardt.minimise_numpy` (no scipy import; it needs ``jacobian: stacked`` and a
        problem with ``residual_swarm``; the callback is not called).

    References
    ----------
    Levenberg (1944); Marquardt (1963); Moré (1978), The Levenberg-Marquardt algorithm:
    implementation and theory (MINPACK).
    """

    references = "Levenberg 1944; Marquardt 1963; More 1978 (MINPACK)"
    label = ""
    smoke = {"max_nfev": 50}
    #: the columns its fit writes: :func:`offset_check`'s, in a gauge-fixed fit (``gauge: symmetric``, a
    #: total-field problem)
    METRICS = ("offset_standard_error", "offset_determined")
    needs = ("residuals",)
    iterative = True

    def __init__(self, *, name: str = "lm", start: str = "problem", max_nfev: int = 2000, tol: float = 1e-12,
                 gauge: str = "symmetric", jacobian: str = "2-point", solver: str = "minpack"):
        check(start in STARTS, f"estimator.start={start!r} is not allowed: choose one of {', '.join(STARTS)}")
        check(gauge in GAUGES, f"estimator.gauge={gauge!r} is not allowed: choose one of {', '.join(GAUGES)}")
        check(jacobian in JACOBIANS,
              f"estimator.jacobian={jacobian!r} is not allowed: choose one of {', '.join(JACOBIANS)}")
        # solver numpy: no scipy import, measured 0.45-0.5 CPU-s saved per process
        check(solver in SOLVERS, f"estimator.solver={solver!r} is not allowed: choose one of {', '.join(SOLVERS)}")
        self.jacobian = jacobian
        self.solver = solver
        self.name = name
        self.start = start
        self.max_nfev = check_positive_int(max_nfev, "estimator.max_nfev")
        self.tol = float(tol) if isinstance(tol, (int, float)) and not isinstance(tol, bool) else float("nan")
        check(np.isfinite(self.tol) and np.finfo(float).eps < self.tol < 1,
              f"estimator.tol={tol!r} is not allowed: it must be a number in (2.2e-16, 1) (above machine epsilon)")
        self.gauge = gauge

    def initial(self, problem) -> np.ndarray:
        """The start of the fit (``start``, the class docstring).

        Parameters
        ----------
        problem : magexp.problems.base.Problem
            Its ``initial_estimate()`` where it has one, its readings (the ellipsoid fit), its box.

        Returns
        -------
        numpy.ndarray
            ``(p,)`` parameters.
        """
        if self.start == "problem" and hasattr(problem, "initial_estimate"):
            return problem.initial_estimate()
        if self.start in ("ellipsoid", "problem") and applies_to(EllipsoidFit, problem)[0]:
            first = EllipsoidFit().fit(problem)
            if first.success:
                return first.x
        return (problem.lower + problem.upper) / 2

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        """Minimise ``sum(problem.residuals(x)^2)``.

        Parameters
        ----------
        problem, rng, callback
            As in :meth:`magexp.estimators.base.Estimator.fit`. ``problem``: its ``residuals`` (and
            ``residual_swarm`` for ``jacobian: stacked``). ``rng``: unused (the fit draws nothing).
            ``callback``: ``callback(k, best x, best RMS)`` after each residual evaluation ``k`` (a stop
            returns the best point so far).

        Returns
        -------
        FitResult
            ``history`` the best RMS of the residuals after each evaluation.
        """
        if self.gauge == "symmetric" and "total_field" in problem.capabilities:
            return self.fit_symmetric(problem, callback=callback)
        jac = stacked_jacobian(problem) if self.jacobian == "stacked" and hasattr(problem, "residual_swarm") else None
        if self.solver == "numpy" and jac is not None:
            x, status, message, history = minimise_numpy(problem.residuals, self.initial(problem), jac=jac, tol=self.tol,
                                                         max_nfev=self.max_nfev)
            return self.result(problem, x, status, message, history)
        x, status, message, history = minimise_residuals(problem.residuals, self.initial(problem), tol=self.tol,
                                                         max_nfev=self.max_nfev, callback=callback, jac=jac)
        return self.result(problem, x, status, message, history)

    def fit_symmetric(self, problem, *, callback=None) -> FitResult:
        """The gauge-fixed fit of a total-field problem (module docstring): LM over ``q`` from the polar
        factor of the start.

        Parameters
        ----------
        problem : magexp.problems.base.Problem
            A total-field problem of 12 parameters.
        callback : callable, optional
            As :meth:`fit`, ``x`` expanded to 12.

        Returns
        -------
        FitResult
            In the problem's 12 parameters, with the metrics of :func:`offset_check` (a fit whose
            offset the data leave undetermined is not a success).
        """
        x0 = polar(problem, self.initial(problem))
        relay = None if callback is None else (lambda k, q, fun: callback(k, expand(q)[0], fun))
        q, status, message, history = minimise_residuals(lambda q: problem.residuals(expand(q)[0]),
                                                         np.concatenate([x0[UPPER], x0[9:]]), tol=self.tol,
                                                         max_nfev=self.max_nfev, callback=relay)
        result = self.result(problem, polar(problem, expand(q)[0]), status, message, history)
        if np.all(np.isfinite(q)):
            result.metrics = offset_check(problem, q)
            if not result.metrics["offset_determined"]:
                result.success = False
                result.message += "; the data leave the offset undetermined"
        return result

    @staticmethod
    def result(problem, x, status: int, message: str, history) -> FitResult:
        """The :class:`FitResult` of a least-squares fit.

        Parameters
        ----------
        problem : magexp.problems.base.Problem
            The problem fitted: ``fun`` is its ``cost_direct(x)``.
        x : numpy.ndarray
            The solution.
        status, message : int, str
            scipy's status (> 0: success) and message.
        history : numpy.ndarray
            The best value after every evaluation.

        Returns
        -------
        FitResult

        Raises
        ------
        MagexpError
            When ``x`` is not finite (lm diverged).
        """
        check(np.all(np.isfinite(x)), "lm diverged: the residuals became non-finite")
        return FitResult(x=x, fun=problem.cost_direct(x), nit=len(history), nfev=len(history),
                         history=history, history_nfev=np.arange(1, len(history) + 1),
                         success=status > 0, message=message)


def offset_check(problem, q: np.ndarray) -> dict:
    """Whether the data determine the offset of the gauge-fixed fit ``q``: ``offset_standard_error``
    (``sqrt(tr Cov(o))`` of the Gauss-Newton covariance, :func:`magexp.core.identifiability.identifiability`)
    and ``offset_determined`` (it is below the readings' RMS distance from their centroid: readings on two
    planar rings cannot place the centre).
    """
    def fun(qs):  # identifiability evaluates a stack of 2 x 9 perturbed vectors
        return problem.residual_stack(qs, of=lambda q: expand(q)[0])

    names = ["M11", "M12", "M13", "M22", "M23", "M33", "o1", "o2", "o3"]
    with np.errstate(all="ignore"):  # a fit stuck at a singular W is measured (inf), not warned about
        se = identifiability(fun, q, names)["standard_errors"]
        error = float(np.nan_to_num(np.sqrt(sum(se[n] ** 2 for n in names[6:])), nan=np.inf, posinf=np.inf))
    return {"offset_standard_error": error, "offset_determined": bool(error < normalise(problem.dataset.readings)[1])}


def polar(problem, x: np.ndarray) -> np.ndarray:
    """``x`` with its ``W`` replaced by the polar factor ``(W^T W)^{1/2}`` (the same total field, no rotation); an
    SPD matrix part is kept bit for bit (it is that factor already), and so is a singular one (no factor)."""
    x = np.asarray(x, float)
    mat = x[:9].reshape(3, 3)
    if np.array_equal(mat, mat.T) and np.all(np.linalg.eigvalsh(mat) > 0):
        return x
    w, o = problem.unpack(x)
    try:
        return problem.pack(canonical(w[0]), o[0])
    except np.linalg.LinAlgError:  # the forward form cannot hold a singular W
        return x


def minimise_residuals(residuals, x0, *, tol: float = 1e-15, max_nfev: int = 2000, callback=None, measure=None,
                       jac=None):
    """``(x, status, message, history)`` of Levenberg-Marquardt (MINPACK, ``scipy.optimize.least_squares``) on
    ``residuals``, every least-squares refinement's: ``history`` the best ``measure`` (default the RMS) after each
    evaluation; a stop by ``callback`` returns the best ``x`` evaluated with status ``-2``.
    """
    # lazy: scipy.optimize, measured 0.40 s CPU to import (min of 5, after numpy); every command imports this module
    # to register its typed schema (magexp.run.compose.register_schemas), and only a least-squares run needs it
    from scipy.optimize import least_squares

    best: dict = {}
    record = stopper(callback, best)

    def fun(theta):
        r = residuals(theta)
        if not np.all(np.isfinite(r)):
            record(theta, np.inf)
        else:
            record(theta, float(np.sqrt(np.mean(r * r))) if measure is None else measure(theta))
        return r

    try:  # a trial step far out may overflow: its residuals count as inf, judged by the result, not warned
        with np.errstate(over="ignore", invalid="ignore"):
            sol = least_squares(fun, np.asarray(x0, float), method="lm", x_scale="jac", jac=jac or "2-point",
                                xtol=tol, ftol=tol, gtol=tol, max_nfev=max_nfev)
        x, status, message = sol.x, int(sol.status), str(sol.message)
    except Stop:
        x, status, message = best["x"], -2, "stopped by the callback"
    return x, status, message, np.asarray(best["history"])
