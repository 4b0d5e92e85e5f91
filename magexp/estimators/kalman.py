"""Yan & Zhou 2022's linear Kalman filters: the magnetization parameters, then the geomagnetic field.

One kernel, :func:`kalman_update`, serves both filters. For a state ``x`` (s x c: ``c``
columns that share one gain), an observation ``y = H x + v2`` (``H``: k x s) and a
random-walk process ``x(n+1) = x(n) + v1`` (eq 5), one step is (sec 2.1, steps (1)-(4))

.. math::
    \\mathbf R(n) &= \\mathbf P(n-1) + \\mathbf Q\\\\
    \\mathbf m(n) &= \\mathbf R(n)\\mathbf H^T\\,[\\mathbf H\\mathbf R(n)\\mathbf H^T + \\sigma^2\\mathbf E]^{-1}\\\\
    \\mathbf P(n) &= [\\mathbf E - \\mathbf m(n)\\mathbf H]\\,\\mathbf R(n)\\\\
    \\mathbf x(n) &= [\\mathbf E - \\mathbf m(n)\\mathbf H]\\,\\mathbf x(n-1) + \\mathbf m(n)\\,\\mathbf y(n)

(the inverse in step (2) is lost in print). :class:`KalmanFilter` (``kf``) estimates
``x = [K Bp]^T`` (4 x 3) from rows ``H = C(n) = [Be^T A^T, 1]``, ``y = B^T``, reusing the
readings cyclically. :class:`FieldKalmanFilter` (the analysis step ``field_kalman``) then recomputes ``Be`` (3 x 1)
from ``y = B - Bp = (K A) Be`` with ``K``, ``Bp`` given (the paper's Fig 4, which cites its
ref. [3] for this filter), and :func:`direct_field` inverts eq 4, ``Be = (K A)^-1 (B - Bp)``.

With ``Q = 0`` and rows reused, the parameter filter is recursive least squares: it
converges to the least-squares solution of the readings (the prior ``P(0)`` is forgotten as
``1/passes``); ``Q > 0`` keeps it tracking the latest rows, so it fluctuates around it.

**The step of convergence is a censored time-to-event.** ``steps_to_ls`` is the first step ``s``
from which the state stays within tolerance of the least-squares solution through the horizon ``H``
(``horizon``). A state that has just come within tolerance near ``H`` need not stay there, so
:func:`observed_step` reports ``s`` only when ``s <= H/2`` (the *doubling rule*: with ``Q = 0`` the
distance and its swing within a pass shrink as ``1/n``, so a state within tolerance over ``[s, 2s]``
stays within it after ``2s``). Otherwise the step is censored: NaN, and ``<metric>_censored`` holds
the censoring point ``H/2`` (the step is later than it); 0 when observed.

References: Yan & Zhou 2022, Chinese Journal of Ship Research, sec 2.1 and 3.2;
Kalman 1960; Zhang 2002 (the paper's ref. [14]).
"""

from __future__ import annotations

import numpy as np

from magexp.errors import check, check_nonnegative, check_positive_int
from magexp.estimators.base import check_applies
from magexp.estimators.result import FitResult

#: the components of the field ``Be`` the analysis step :class:`FieldKalmanFilter` estimates (its columns)
FIELD = ("Be1", "Be2", "Be3")


def kalman_update(x, p, h, y, q, sigma2: float):
    """One step (1)-(4) of the module docstring (Yan & Zhou 2022, sec 2.1)."""
    r = p + q
    rh = r @ h.T
    m = np.linalg.solve(h @ rh + sigma2 * np.eye(h.shape[0]), rh.T).T
    e_mh = np.eye(r.shape[0]) - m @ h
    return e_mh @ x + m @ y, e_mh @ r


def kalman_filter(h, y, *, p0, q, sigma2: float, x0, stop=None) -> np.ndarray:
    """The state at every step, ``(T + 1, s, c)`` with ``[0] = x0``, of :func:`kalman_update` over a sequence
    of observations (cut at the step where ``stop(n, x)`` first returns true)."""
    states = np.empty((len(h) + 1,) + np.shape(x0))
    x, p = np.asarray(x0, float), np.asarray(p0, float)
    states[0] = x
    for n in range(len(h)):
        x, p = kalman_update(x, p, h[n], y[n], q, sigma2)
        states[n + 1] = x
        if stop is not None and stop(n + 1, x):
            return states[: n + 2]
    return states


def cyclic(n_rows: int, n_steps: int) -> np.ndarray:
    """Row index of every filter step: the readings reused in order, ``0, 1, ..., N-1, 0, ...``."""
    return np.arange(n_steps) % n_rows


def settled_since(distance: np.ndarray) -> int:
    """The first step from which ``distance`` (True while apart) stays False; -1 if the last step is apart."""
    apart = np.flatnonzero(distance)
    if apart.size == 0:
        return 0
    return -1 if apart[-1] == len(distance) - 1 else int(apart[-1] + 1)


def observed_step(step: float, horizon: int) -> tuple[float, float]:
    """``(step, 0.0)`` when ``step <= horizon / 2``, else ``(nan, horizon / 2)``: a step of convergence censored
    by the doubling rule (module docstring)."""
    bound = horizon / 2
    return (float(step), 0.0) if np.isfinite(step) and step <= bound else (np.nan, float(bound))


def checked_tuning(p0: float, q: float, sigma2: float, n_steps: int, group: str) -> tuple:
    """The shared filter settings, checked."""
    check(check_nonnegative(sigma2, f"{group}.sigma2") > 0,
          f"{group}.sigma2={sigma2!r} is not allowed: the noise variance must be > 0")
    return (check_nonnegative(p0, f"{group}.p0"), check_nonnegative(q, f"{group}.q"), float(sigma2),
            check_positive_int(n_steps, f"{group}.n_steps"))


class _Tuning:
    """Shared hyper-parameters: ``P(0) = p0 D``, ``Q = q D`` with ``D`` the state's scale matrix."""

    needs = ("linear_design",)  # filters of the linear model B = K A Be + Bp (= S u + b)
    iterative = True
    monotone_history = False  # the fit RMS per filter step need not decrease

    def __init__(self, *, name: str, p0: float, q: float, sigma2: float, n_steps: int):
        self.name = name
        self.p0, self.q, self.sigma2, self.n_steps = checked_tuning(p0, q, sigma2, n_steps, "estimator")


class KalmanFilter(_Tuning):
    """Yan & Zhou's filter for ``x = [K Bp]^T`` (``kf``).

    The recursion of Yan 2022 sec 2.1, steps (1)-(4) (module docstring), on the rows
    ``C(n) = [Be^T A^T, 1]`` and observations ``y(n) = B^T`` of the model ``B = K A Be + Bp`` (eqs 1-2),
    from ``x(0) = 0``.

    Parameters
    ----------
    name : str
        As in :class:`~magexp.estimators.base.Estimator`.
    p0 : float
        ``P(0) = p0 diag(1, 1, 1, offset_scale^2)`` (the paper: a diagonal matrix).
    q : float
        ``Q = q diag(1, 1, 1, offset_scale^2)``, process noise per step.
    sigma2 : float
        Observation noise variance ``σ²`` (nT²), one value for the three components.
    offset_scale : float
        Size (nT) of ``Bp`` relative to the entries of ``K`` (~1), > 0.
    n_steps : int
        Filter steps; the readings are reused cyclically.
    agree_k, agree_bp : float
        Tolerances on ``K`` and ``Bp`` of the ``steps_to_ls`` diagnostic (module docstring): the first
        pass end from which the state stays within them of the least-squares solution through
        ``horizon``; ``steps_to_ls_every_step`` the same at every step after the first pass.
    horizon : int
        Steps over which the step of convergence is observed; the filter runs on to
        ``max(n_steps, horizon)``, its estimate and trace stay those of step ``n_steps``. 0 (default):
        ``n_steps``.

    References
    ----------
    Yan & Zhou (2022), Chinese Journal of Ship Research, sec 2.1; Kalman (1960).
    """

    references = "Yan & Zhou 2022, sec 2.1"
    label = "KF"
    smoke = {"n_steps": 12}
    #: the columns its fit writes (:meth:`fit`'s ``metrics``)
    METRICS = ("steps_to_ls", "steps_to_ls_censored", "steps_to_ls_every_step", "steps_to_ls_every_step_censored")

    def __init__(self, *, name: str = "kf", p0: float = 1.0, q: float = 0.0, sigma2: float = 3333.0,
                 offset_scale: float = 3000.0, n_steps: int = 600, agree_k: float = 1e-4, agree_bp: float = 1.0,
                 horizon: int = 0):
        super().__init__(name=name, p0=p0, q=q, sigma2=sigma2, n_steps=n_steps)
        check(check_nonnegative(offset_scale, "estimator.offset_scale") > 0,
              f"estimator.offset_scale={offset_scale!r} is not allowed: it must be a number > 0 (P(0) and Q scale "
              "the offset Bp by offset_scale^2: 0 would keep Bp at its start, never estimated)")
        self.scale = np.diag([1.0, 1.0, 1.0, float(offset_scale) ** 2])
        self.agree_k = check_nonnegative(agree_k, "estimator.agree_k")
        self.agree_bp = check_nonnegative(agree_bp, "estimator.agree_bp")
        self.horizon = max(int(check_nonnegative(horizon, "estimator.horizon")), self.n_steps)

    def fit(self, problem, *, rng: np.random.Generator | None = None, callback=None) -> FitResult:
        """Filter the rows of ``problem.design()``, reused cyclically.

        Parameters
        ----------
        problem, rng, callback
            As in :meth:`magexp.estimators.base.Estimator.fit`. ``problem``: its linear design ``C x = Y``
            and least-squares solution. ``rng``: unused (the filter draws nothing). ``callback``:
            ``callback(step, x, None)`` after every step.

        Returns
        -------
        FitResult
            ``history`` the fit RMS and ``trace["x"]`` the state as ``theta`` (``n_steps + 1``, 12) at every
            step; ``metrics`` ``steps_to_ls``, ``steps_to_ls_every_step``.
        """
        c, y = problem.design()
        rows = cyclic(len(c), self.horizon)
        stop = None if callback is None else (  # the callback sees the filter's n_steps, not the watch beyond them
            lambda n, x: n <= self.n_steps and callback(n, problem.from_linear(x), None))
        states = kalman_filter(c[rows, None, :], y[rows, None, :], p0=self.p0 * self.scale, q=self.q * self.scale,
                               sigma2=self.sigma2, x0=np.zeros((4, 3)), stop=stop)
        watched = problem.from_linear(states)
        last = len(states) - 1  # the horizon, or the step a callback stopped at
        steps = min(last, self.n_steps)
        thetas = watched[: steps + 1]
        history = problem.cost(thetas)
        ls = problem.least_squares()
        ends = np.arange(len(c), last + 1, len(c))  # every full pass weighs each reading equally
        every = np.arange(len(c), last + 1)  # every step from the end of the first pass
        metrics = {}
        for name, at in (("steps_to_ls", ends), ("steps_to_ls_every_step", every)):
            metrics[name], metrics[f"{name}_censored"] = observed_step(self._settled(watched, ls, at), last)
        return FitResult(x=thetas[-1], fun=problem.cost_direct(thetas[-1]), nit=steps, nfev=steps,
                         history=history, history_nfev=np.arange(steps + 1), trace={"x": thetas},
                         metrics=metrics, message=f"{steps} steps over {len(c)} readings (watched to {last})")

    def _settled(self, thetas: np.ndarray, ls: np.ndarray, steps: np.ndarray) -> float:
        """The first of ``steps`` from which the state at every later one of ``steps`` stays within
        ``agree_k`` (K) and ``agree_bp`` (Bp) of the least-squares solution ``ls``; NaN if never."""
        apart = (np.abs(thetas[steps, :9] - ls[:9]).max(axis=1) > self.agree_k) | (
            np.abs(thetas[steps, 9:] - ls[9:]).max(axis=1) > self.agree_bp)
        first = settled_since(apart)
        return float(steps[first]) if 0 <= first < len(steps) else np.nan


def direct_field(k: np.ndarray, bp: np.ndarray, attitude: np.ndarray, readings: np.ndarray) -> np.ndarray:
    """Eq 4 for every reading: ``Be_i = (K A_i)^-1 (B_i - Bp)``."""
    return np.linalg.solve(k @ attitude, (readings - bp)[..., None])[..., 0]


def field_errors(estimates: np.ndarray, field: np.ndarray) -> tuple[float, float]:
    """The RMS error (nT) of field estimates and their largest component error relative to ``|Be|``."""
    err = np.asarray(estimates) - field
    return float(np.sqrt(np.mean(err**2))), float(np.max(np.abs(err)) / np.linalg.norm(field))


class FieldKalmanFilter:
    """The analysis step ``field_kalman`` (not an estimator), ``step(problem, result) -> result``: ``Be`` recomputed
    from the fitted ``K``, ``Bp`` of ``result.x`` (Yan & Zhou Fig 4), state ``Be``, ``H(n) = K A(n)``,
    ``y(n) = B(n) - Bp``, ``Be(0) = 0``, ``P(0) = p0 E``, ``Q = q E``, readings reused cyclically.
    Errors are measured after the fraction ``settle`` of the steps (the paper's "stable solution after
    convergence"): ``trace["be"]``, metrics ``be_rms``, ``be_max_rel`` and ``be_direct_*`` (eq 4), ``Be1..3``.
    """

    references = "Yan & Zhou 2022, sec 3.2, Fig 4"
    #: the columns the step writes: the errors, each component of ``Be`` and its ``truth_`` value
    METRICS = ("be_rms", "be_max_rel", "be_direct_rms", "be_direct_max_rel", *FIELD, *(f"truth_{n}" for n in FIELD))
    needs = ("linear_design",)

    def __init__(self, *, name: str = "field_kalman", p0: float = 1e10, q: float = 0.0, sigma2: float = 3333.0,
                 n_steps: int = 600, settle: float = 0.5):
        self.name = name
        self.p0, self.q, self.sigma2, self.n_steps = checked_tuning(p0, q, sigma2, n_steps, "analysis")
        self.settle = min(check_nonnegative(settle, "analysis.settle"), 1.0)

    def __call__(self, problem, result: FitResult) -> FitResult:
        """Recompute ``Be`` from ``result``'s ``K``, ``Bp`` (the class docstring)."""
        check_applies(self, problem)
        w, bp = (a[0] for a in problem.unpack(result.x))  # B = K u + Bp  <=>  u = K^-1 (B - Bp)
        k = np.linalg.inv(w)
        ds = problem.dataset
        field = ds.field_nav[0]
        rows = cyclic(ds.n, self.n_steps)
        h = k @ ds.attitude[rows]
        states = kalman_filter(h, (ds.readings[rows] - bp)[..., None], p0=self.p0 * np.eye(3), q=self.q * np.eye(3),
                               sigma2=self.sigma2, x0=np.zeros((3, 1)))[..., 0]
        start = min(int(self.settle * self.n_steps) + 1, self.n_steps)
        rms, rel = field_errors(states[start:], field)
        d_rms, d_rel = field_errors(direct_field(k, bp, ds.attitude, ds.readings), field)
        names = list(FIELD)
        result.metrics.update({"be_rms": rms, "be_max_rel": rel, "be_direct_rms": d_rms, "be_direct_max_rel": d_rel,
                               **dict(zip(names, map(float, states[-1]))),
                               **{f"truth_{n}": float(v) for n, v in zip(names, field)}})
        result.trace.update({"be": states, "be_names": names,
                             "be_error": np.sqrt(np.mean((states - field) ** 2, axis=1))})
        return result
