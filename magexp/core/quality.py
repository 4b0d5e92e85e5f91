"""How good a calibration is on its own data: canonical form, standard errors, conditioning,
what the data cannot determine, direction coverage, and the degenerate cases.

Every function takes the raw readings ``r_i`` (N, 3) and a fitted ``B = W (r - o)``.

* **Canonical form** (:func:`canonical`). A total-field (scalar) objective sees only
  ``|W (r - o)|``, so ``Q W`` fits as well as ``W`` for every orthogonal ``Q``: the fit
  determines ``WᵀW`` and ``o`` (9 numbers), not the 3 numbers of a rotation. Whatever the
  estimator returned, scalar calibrations are reported as the symmetric positive-definite polar
  factor ``P`` of ``W = Q P`` (``P = (WᵀW)^{1/2}``), the unique member of the family without a
  rotation. A vector objective sees the rotation and keeps its ``W``.
* **Standard errors and conditioning** (:func:`identifiability`). With the residuals ``e(θ)`` of
  the fit at its estimate (scalar: ``|W(r_i - o)| - B_i`` over ``θ = [P_11, P_12, P_13, P_22,
  P_23, P_33, o]``; vector: the 3N components over ``[vec W, o]``), the Jacobian ``J`` (central
  differences), ``σ² = ‖e‖² / (m - p)`` and the Gauss-Newton covariance
  ``Cov θ = σ² (JᵀJ)^{-1}`` (inverted with columns scaled to unit norm; a direction whose scaled
  singular value is below ``1e-8`` of the largest is reported as undetermined, not inverted).
  The condition number is that of the column-scaled ``J``; the parameter combinations it cannot
  determine are the right singular vectors of the smallest singular values, named by their
  largest entries.
* **Direction coverage** (:func:`coverage`): of the calibrated directions ``u_i = B_i / |B_i|``,
  the fraction of :data:`CELLS` equal-area cells of the sphere that hold a reading (nearest of
  a Fibonacci lattice), and ``λ_min`` of the direction scatter ``(1/N) Σ u uᵀ`` (``1/3`` for
  a full sphere, 0 for a plane or one attitude).
"""

from __future__ import annotations

import numpy as np

from magexp.errors import MagexpError

#: Equal-area cells of the sphere for the coverage measure.
CELLS = 32
#: A scaled singular value below this fraction of the largest: a combination the data cannot determine.
UNDETERMINED = 1e-8
#: Degenerate-data thresholds (see :func:`check_readings` and :func:`check_fit`).
MIN_DISTINCT = 12
PLANE_RATIO = 0.02   # sqrt(λ_min / λ_max) of the raw readings' covariance below it: one plane
MIN_CELLS = 8        # fewer occupied cells (a quarter of the sphere): too few distinct directions
PARTIAL = 0.75       # fewer occupied cells after a failed fit: say the coverage is partial
ONE_ATTITUDE_DEG = 20.0
STILL = 0.05         # RMS distance of the raw readings from their centroid below this fraction of their magnitude: one attitude  # every calibrated direction within this angle of their mean: one attitude

def canonical(w: np.ndarray) -> np.ndarray:
    """The symmetric positive-definite polar factor ``P = V Σ Vᵀ`` of ``W = U Σ Vᵀ`` (``W = (U Vᵀ) P``)."""
    _, s, vt = np.linalg.svd(w)
    return (vt.T * s) @ vt


def fibonacci_sphere(n: int) -> np.ndarray:
    """``n`` nearly evenly spread unit vectors (golden-angle spiral); nearest-point cells are nearly equal-area."""
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = np.pi * (1 + 5**0.5) * k
    rho = np.sqrt(1 - z * z)
    return np.column_stack([rho * np.cos(phi), rho * np.sin(phi), z])


def coverage(calibrated: np.ndarray) -> dict:
    """Direction coverage of calibrated readings (module docstring)."""
    u = calibrated / np.maximum(np.linalg.norm(calibrated, axis=1, keepdims=True), 1e-300)
    cells = np.unique(np.argmax(u @ fibonacci_sphere(CELLS).T, axis=1))
    scatter = np.linalg.eigvalsh(u.T @ u / len(u))
    mean = u.mean(axis=0)
    spread_deg = float(np.rad2deg(np.arccos(np.clip(u @ (mean / max(np.linalg.norm(mean), 1e-300)), -1, 1))).max())
    return {"coverage_cells": float(len(cells) / CELLS), "coverage_lambda_min": float(scatter[0]),
            "direction_max_angle_deg": spread_deg}


def _jacobian(fun, theta: np.ndarray) -> np.ndarray:
    """Central differences (:func:`magexp.core.bounds.central_differences`) of ``fun`` (which takes a
    stack ``(n, p)``) at ``theta``, with steps relative to each parameter's size."""
    from magexp.core.bounds import central_differences

    step = 1e-6 * np.maximum(np.abs(theta), 1e-3 * max(float(np.abs(theta).max()), 1e-12))
    return central_differences(lambda t: fun(t[None])[0], theta, step)


def scalar_residuals(readings: np.ndarray, reference: np.ndarray):
    """``θ = [P (6 upper entries), o] -> |P (r_i - o)| - B_i`` for a stack of ``θ`` (n, 9)."""
    from magexp.estimators.reduced import expand

    def fun(thetas):
        thetas = np.atleast_2d(thetas)
        p = expand(thetas)[:, :9].reshape(-1, 3, 3)  # symmetric P from its upper entries
        c = np.einsum("nij,nkj->nki", p, readings[None] - thetas[:, None, 6:])
        return np.linalg.norm(c, axis=2) - reference

    return fun


def sphere_residuals(readings: np.ndarray, reference: np.ndarray):
    """``θ = [s, o] -> s |r_i - o| - B_i`` for a stack of ``θ`` (n, 4)."""

    def fun(thetas):
        thetas = np.atleast_2d(thetas)
        return thetas[:, :1] * np.linalg.norm(readings[None] - thetas[:, None, 1:], axis=2) - reference

    return fun


def vector_residuals(readings: np.ndarray, reference_vectors: np.ndarray):
    """``θ = [vec W, o] -> (C_i H_i - W (r_i - o))`` stacked (3N), for a stack of ``θ`` (n, 12)."""

    def fun(thetas):
        thetas = np.atleast_2d(thetas)
        w = thetas[:, :9].reshape(-1, 3, 3)
        c = np.einsum("nij,nkj->nki", w, readings[None] - thetas[:, None, 9:])
        return (reference_vectors[None] - c).reshape(len(thetas), -1)

    return fun


def identifiability(fun, theta: np.ndarray, names: list[str]) -> dict:
    """Standard errors, condition number and undetermined combinations (module docstring)."""
    e = fun(theta[None])[0]
    jac = _jacobian(fun, theta)
    m, p = jac.shape
    sigma2 = float(e @ e) / max(m - p, 1)
    d = np.maximum(np.linalg.norm(jac, axis=0), 1e-300)
    _, sv, vt = np.linalg.svd(jac / d, full_matrices=False)
    ok = sv > UNDETERMINED * sv[0]
    inv = (vt[ok].T / sv[ok] ** 2) @ vt[ok]
    cov = sigma2 * inv / np.outer(d, d)
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    if not ok.all():  # an undetermined direction: every parameter it touches has no finite error
        touched = np.any(np.abs(vt[~ok]) > 0.1, axis=0)
        se[touched] = np.inf
    weak = []
    for k in np.argsort(sv)[:3]:
        v = vt[k] / np.abs(vt[k]).max()
        terms = [f"{v[j]:+.2f}*{names[j]}" for j in np.argsort(-np.abs(v))[:3] if abs(v[j]) > 0.2]
        weak.append({"combination": " ".join(terms), "relative_singular_value": float(sv[k] / sv[0])})
    return {"standard_errors": dict(zip(names, se.tolist())), "residual_std": float(np.sqrt(sigma2)),
            "condition_number": float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf"),
            "undetermined": [w["combination"] for w, s in zip(weak, np.sort(sv)[:3]) if s <= UNDETERMINED * sv[0]],
            "weakest_combinations": weak}


# -- degenerate data ---------------------------------------------------------------------------------
RECORD = "record again while turning the sensor slowly through as many orientations as you can (a full sphere)"


def check_readings(readings: np.ndarray, name: str) -> None:
    """Fail in one line if the raw readings cannot determine a calibration: too few distinct
    readings, readings that barely move (one attitude; an offset over ~20 times the field would
    look the same), or readings in one plane."""
    distinct = len(np.unique(readings, axis=0))
    if distinct < MIN_DISTINCT:
        raise MagexpError(f"{name}: only {distinct} distinct readings, a calibration needs at least {MIN_DISTINCT}: "
                          f"{RECORD}")
    centred = readings - readings.mean(axis=0)
    moved = float(np.sqrt((centred**2).sum(axis=1).mean()) / max(np.linalg.norm(readings, axis=1).mean(), 1e-300))
    if moved < STILL:
        raise MagexpError(f"{name}: the readings barely move (RMS distance from their centroid {100 * moved:.2g} % of "
                          f"their magnitude): one attitude cannot determine a calibration: {RECORD}")
    ev = np.linalg.eigvalsh(centred.T @ centred / len(readings))
    if ev[0] <= (PLANE_RATIO**2) * ev[-1]:
        raise MagexpError(f"{name}: the readings lie in one plane (thickness {np.sqrt(max(ev[0], 0) / ev[-1]):.2g} of "
                          "their width: turns about one axis only), which cannot determine the offset along its "
                          "normal nor the scale across it: also turn the sensor about a second axis")


def check_fit(name: str, estimator: str, success: bool, message: str, cover: dict, raw_cover: dict) -> None:
    """Fail in one line if the estimator failed or the calibrated directions show one attitude
    or too few distinct directions. ``raw_cover``: the coverage of the raw readings about the
    centre of their fitted sphere (what a failed fit's message quotes)."""
    if not success:
        why = message.splitlines()[0] if message else "no message"
        if raw_cover["coverage_cells"] < PARTIAL:
            raise MagexpError(f"{name}: estimator={estimator!r} reports failure ({why}), nothing written: the readings "
                              f"cover {100 * raw_cover['coverage_cells']:.0f} % of the sphere, too little for W: record the "
                              "missing orientations, or fit model=sphere (offset and one scale)")
        raise MagexpError(f"{name}: estimator={estimator!r} reports failure ({why}), nothing written: "
                          "try another estimator (ellipsoid, lm), or record more orientations")
    if cover["direction_max_angle_deg"] < ONE_ATTITUDE_DEG:
        raise MagexpError(f"{name}: every calibrated direction lies within {cover['direction_max_angle_deg']:.1f} deg "
                          f"of one (a single attitude): {RECORD}")
    cells = round(cover["coverage_cells"] * CELLS)
    if cells < MIN_CELLS:
        raise MagexpError(f"{name}: the readings point into only {cells} of {CELLS} sphere cells (too few distinct "
                          f"directions): {RECORD}")


def spread(magnitudes) -> float:
    """Relative spread ``std / mean`` of total-field magnitudes (NaN for none)."""
    mags = np.asarray(magnitudes, float)
    return float(mags.std() / mags.mean()) if mags.size else float("nan")


def recording_metrics(problem, theta) -> dict:
    """Spread of a recording before and after the fitted calibration, on the fit's readings and on
    the held-out block, and the direction coverage of the calibrated readings (a fit that sends every
    reading to nearly one direction has a tiny spread and is wrong); the held-out block (``dataset.extra["heldout"]``, :class:`magexp.scenarios.recording.RecordingScenario`)."""
    extra = problem.dataset.extra
    if "all_readings" not in extra:
        return {}

    def spread_of(vectors):
        return spread(np.linalg.norm(vectors, axis=1))

    calibrated = problem.calibrate(theta)
    out = {"spread_before": spread_of(extra["all_readings"]), "spread_after": spread_of(calibrated),
           "coverage_cells": coverage(calibrated)["coverage_cells"]}  # ~0: the fit collapsed the directions
    if len(extra.get("heldout", ())):
        mags = np.linalg.norm(problem.calibrate(theta, extra["heldout"]), axis=1)
        out["heldout_spread"] = spread(mags)
        out["heldout_spread_lo"], out["heldout_spread_hi"] = block_bootstrap_spread(mags)
    return out


#: contiguous blocks and resamples of :func:`block_bootstrap_spread`
SPREAD_BLOCKS, SPREAD_RESAMPLES = 20, 1000


def block_bootstrap_spread(magnitudes, level: float = 0.95) -> tuple[float, float]:
    """Percentile interval of :func:`spread` under a block bootstrap: the magnitudes, in time order,
    are cut into :data:`SPREAD_BLOCKS` contiguous blocks (consecutive readings are correlated, so
    single readings are not resampled) and the blocks drawn with replacement :data:`SPREAD_RESAMPLES`
    times, from a fixed generator (the interval describes the data, it is the same on every run;
    as :func:`magexp.artifacts.claims.ci`). NaN for fewer readings than blocks."""
    mags = np.asarray(magnitudes, float)
    if mags.size < SPREAD_BLOCKS:
        return float("nan"), float("nan")
    blocks = np.array_split(mags, SPREAD_BLOCKS)
    sums = np.array([[b.size, b.sum(), (b * b).sum()] for b in blocks])
    draw = np.random.default_rng(0).integers(0, SPREAD_BLOCKS, size=(SPREAD_RESAMPLES, SPREAD_BLOCKS))
    n, s1, s2 = sums[draw].sum(axis=1).T  # each resample's count, sum and sum of squares
    mean = s1 / n
    boot = np.sqrt(np.maximum(s2 / n - mean**2, 0.0)) / mean
    a = (1 - level) / 2
    return float(np.quantile(boot, a)), float(np.quantile(boot, 1 - a))
