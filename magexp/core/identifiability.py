"""How well a fitted calibration is determined by its own data: canonical form, standard errors,
conditioning, what the data cannot determine, direction coverage, and the spread of magnitudes.

The model core uses it (:mod:`magexp.core.metrics`, the problems' and estimators' own metrics) and so
does ``magexp calibrate`` (:mod:`magexp.calibration.fit`, whose degenerate-data checks live in
:mod:`magexp.calibration.checks`). It imports only numpy and the core.

* **Canonical form** (:func:`canonical`). A total-field (scalar) objective sees only
  ``|W (r - o)|``, so ``Q W`` fits as well as ``W`` for every orthogonal ``Q``: the fit
  determines ``WᵀW`` and ``o`` (9 numbers), not the 3 numbers of a rotation. Whatever the
  estimator returned, scalar calibrations are reported as the symmetric positive-definite polar
  factor ``P`` of ``W = Q P`` (``P = (WᵀW)^{1/2}``), the unique member of the family without a
  rotation. A vector objective sees the rotation and keeps its ``W``.
* **Standard errors and conditioning** (:func:`identifiability`). With the residuals ``e(θ)`` of
  the fit at its estimate (a problem's own residuals, :meth:`magexp.problems.base.CalibrationProblem.residual_stack`:
  e.g. scalar ``|W(r_i - o)| - B_i`` over ``θ = [P_11, P_12, P_13, P_22, P_23, P_33, o]``; vector the 3N
  components over ``[vec W, o]``), the Jacobian ``J`` (central
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
* **Regions of directions** (:func:`direction_regions`): each direction assigned to the nearest of
  the six half-axes ``±v_k`` of the principal axes ``v_k`` of the direction scatter: the regions a
  held-out check leaves out one at a time (:func:`magexp.calibration.fit.heldout`).
"""

from __future__ import annotations

import numpy as np

from magexp.core.bounds import central_differences

#: Equal-area cells of the sphere for the coverage measure.
CELLS = 32
#: A scaled singular value below this fraction of the largest: a combination the data cannot determine.
UNDETERMINED = 1e-8

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


def direction_regions(centred: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(labels, axes)``: the region ``0..5`` of each direction ``u`` of ``centred`` (readings less a
    centre), ``2 k + (u·v_k > 0)`` for the principal axis ``v_k`` (eigenvectors of ``(1/N) Σ u uᵀ``,
    ``k = 0`` the smallest) on which ``u`` has its largest component, and ``axes`` ``(6, 3)``, the
    half-axis ``±v_k`` of each region. Independent of the sensor's axes: a turn about any one axis
    fills the four regions around it, not the two along it.
    """
    u = centred / np.maximum(np.linalg.norm(centred, axis=1, keepdims=True), 1e-300)
    vectors = np.linalg.eigh(u.T @ u / len(u))[1]
    proj = u @ vectors
    k = np.argmax(np.abs(proj), axis=1)
    axes = np.repeat(vectors.T, 2, axis=0) * np.tile([-1.0, 1.0], 3)[:, None]
    return 2 * k + (proj[np.arange(len(u)), k] > 0), axes


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
    step = 1e-6 * np.maximum(np.abs(theta), 1e-3 * max(float(np.abs(theta).max()), 1e-12))
    return central_differences(lambda t: fun(t[None])[0], theta, step)


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


def spread(magnitudes) -> float:
    """Relative spread ``std / mean`` of total-field magnitudes (NaN for none)."""
    mags = np.asarray(magnitudes, float)
    return float(mags.std() / mags.mean()) if mags.size else float("nan")


#: the columns :func:`recording_metrics` writes (a recording's run; the ``heldout_*`` ones with a held-out block)
RECORDING_METRICS = ("spread_before", "spread_after", "coverage_cells", "heldout_spread", "heldout_spread_lo",
                     "heldout_spread_hi")


def recording_metrics(problem, theta) -> dict:
    """Spread of a recording before and after the fit, on the fit's readings and on the held-out block
    (``dataset.extra["heldout"]``, :class:`magexp.scenarios.recording.RecordingScenario`), and the direction
    coverage of the calibrated readings (a fit sending every reading to one direction has a tiny spread and is
    wrong); empty for a simulated dataset.
    """
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
    as :func:`magexp.artifacts.tables.interval`). NaN for fewer readings than blocks.
    """
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
