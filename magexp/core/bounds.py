"""Cramér-Rao lower bound of a calibration problem, and the expected RMS floor.

For residuals ``r(θ)`` whose block ``i`` depends on reading ``x_i`` only, reading noise
``ε_i`` (per-axis variance ``σ²``) enters as ``δr_i = G_i ε_i`` with ``G_i = ∂r_i/∂x_i``, so
the residual noise covariance is block-diagonal, ``Σ_i = σ² G_i G_iᵀ``. With ``J = ∂r/∂θ`` at
the truth, the Fisher information (Gaussian noise of the same covariance) is

.. math:: F = J^\\top Σ^{-1} J,

and any unbiased estimate of an identifiable function ``h(θ)`` has
``Cov(h) ⪰ H F^{+} H^\\top`` (``H = ∂h/∂θ``; the pseudo-inverse because a scalar objective
leaves a 3-dimensional rotation of ``W`` unidentifiable, and ``h`` is invariant to it).
The expected in-sample RMS of the least-squares fit (the best any estimator can do on its own
objective) is

.. math:: \\mathrm{RMS}^2_{floor} = \\tfrac1N\\,\\mathrm{tr}\\big((I - P)\\,Σ\\,(I - P)^\\top\\big),
          \\quad P = J J^{+},

which for the scalar problem with isotropic noise reduces to ``σ² (N - 9)/N``.
Uniform noise (Ding 2024) is not Gaussian; the bound above is the Gaussian one with the same
covariance (the usual reference; the noise floor then matches the exact expectation).

Derivatives ``J`` and ``G_i`` are analytic where the problem offers them
(``problem.jacobians(theta) -> (J, G)`` or None), central differences with steps scaled to each
parameter and reading otherwise (and always for ``H``, which has ``p`` columns of ``p`` rows).
"""

from __future__ import annotations

import json
from collections import OrderedDict
from dataclasses import replace

import numpy as np

#: :func:`invariant_jacobian` by problem class, options, ``θ`` and steps (a few hundred kept)
_INVARIANT_JACOBIANS: OrderedDict = OrderedDict()


def central_differences(fun, theta: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """Jacobian of ``fun`` (one vector in, ``(n,)`` out) at ``theta`` by central differences of the
    given ``steps``, one row per parameter, returned transposed (``(n, p)``, column-major).
    """
    rows = None
    for k in range(theta.size):
        e = np.zeros_like(theta)
        e[k] = steps[k]
        plus, minus = fun(theta + e), fun(theta - e)
        if rows is None:
            rows = np.empty((theta.size, plus.size))
        np.subtract(plus, minus, out=rows[k])  # in place: no N-sized temporaries
        rows[k] /= 2 * steps[k]
    return rows.T


def _weighted_gram(jac: np.ndarray, blocks: np.ndarray) -> np.ndarray:
    """``J^T diag(B_1, ..., B_N) J`` for ``m × m`` blocks ``(N, m, m)`` and ``J`` ``(N m, p)``.

    For ``m = 1`` the blocks are non-negative numbers (variances or their pseudo-inverses) and
    this is ``X^T X`` with ``X = diag(\\sqrt{B}) J``: one symmetric rank-k update (half the work
    of a general product).
    """
    n, m = blocks.shape[:2]
    if m == 1:
        xt = jac.T * np.sqrt(blocks[:, 0, 0])
        return xt @ xt.T
    return jac.T @ np.einsum("nab,nbp->nap", blocks, jac.reshape(n, m, -1)).reshape(n * m, -1)


def _pinv_blocks(blocks: np.ndarray) -> np.ndarray:
    """Pseudo-inverse of every symmetric block ``(N, m, m)`` (a singular block carries no
    information along its null space)."""
    if blocks.shape[1] == 1:
        return np.where(blocks > 0, 1 / np.maximum(blocks, 1e-300), 0.0)
    evals, evecs = np.linalg.eigh(blocks)
    return np.einsum("nik,nk,njk->nij", evecs, np.where(evals > 0, 1 / np.maximum(evals, 1e-300), 0), evecs)


def jacobians(problem, theta: np.ndarray, steps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(J, G)``: ``J = ∂r/∂θ`` ``(N m, p)`` and ``G_i = ∂r_i/∂x_i`` ``(N, m, 3)``, the problem's
    analytic ones (``problem.jacobians``) when it has them, else central differences
    (:func:`central_differences`, :func:`finite_difference_noise_blocks`).
    """
    both = problem.jacobians(theta) if hasattr(problem, "jacobians") else None
    if both is not None:
        return both
    return central_differences(problem.residuals, theta, steps), finite_difference_noise_blocks(problem, theta)


def invariant_jacobian(problem, theta: np.ndarray, steps: np.ndarray, keep: int = 256) -> np.ndarray:
    """``H = ∂h/∂θ`` of ``problem.invariants`` at ``theta`` (central differences, :func:`central_differences`),
    read-only.

    ``h`` is a function of ``θ`` alone, fixed by the problem's class and constructor options (its
    parameterisation), not by its readings; so ``H`` is kept per (class, options, ``θ``, steps)
    in this process: every seed of a scenario shares its truth, and computes ``H`` once.
    """
    key = (type(problem), json.dumps(problem.options, sort_keys=True, default=str), theta.tobytes(), steps.tobytes())
    if key in _INVARIANT_JACOBIANS:
        _INVARIANT_JACOBIANS.move_to_end(key)
    else:
        h = central_differences(problem.invariants, theta, steps)
        h.flags.writeable = False
        _INVARIANT_JACOBIANS[key] = h
        if len(_INVARIANT_JACOBIANS) > keep:
            _INVARIANT_JACOBIANS.popitem(last=False)
    return _INVARIANT_JACOBIANS[key]


def finite_difference_noise_blocks(problem, theta: np.ndarray) -> np.ndarray:
    """``G_i = ∂r_i/∂x_i`` by central differences of the readings (six residual evaluations)."""
    ds = problem.dataset
    scale = max(float(ds.readings.max()), -float(ds.readings.min()), 1.0) * 1e-6
    blocks = None
    for axis in range(3):
        shift = np.zeros(3)
        shift[axis] = scale
        plus = type(problem)(replace(ds, readings=ds.readings + shift), _Box(problem), **problem.options)
        minus = type(problem)(replace(ds, readings=ds.readings - shift), _Box(problem), **problem.options)
        r_plus, r_minus = plus.residuals(theta), minus.residuals(theta)
        if blocks is None:
            blocks = np.empty((r_plus.size, 3))
        np.subtract(r_plus, r_minus, out=blocks[:, axis])
        blocks[:, axis] /= 2 * scale
    return blocks.reshape(ds.n, -1, 3)


class _Box:
    """The problem's own bounds, as the SearchBox interface a problem is built with."""

    def __init__(self, problem):
        self._b = (problem.lower, problem.upper)

    def bounds(self):
        """``(lower, upper)`` of the box, as the problem it stands in for gives them."""
        return self._b


def noise_free(problem):
    """The same problem on the noise-free readings ``W^-1 B_true + o``, when the scenario knows them (else ``problem``).

    The Fisher information is an expectation: its Jacobian belongs at the noise-free data. On
    noisy readings a direction the data cannot identify (e.g. two planar rings of readings for a
    scalar fit) would look weakly identified by the noise itself.
    """
    ds = problem.dataset
    if ds.field_body_true is None or ds.truth is None:
        return problem
    clean = ds.field_body_true @ np.linalg.inv(ds.truth.matrix).T + ds.truth.offset
    return type(problem)(replace(ds, readings=clean), _Box(problem), **problem.options)


def cramer_rao(problem, theta: np.ndarray | None = None) -> dict | None:
    """See :func:`_cramer_rao` (at ``theta``, default the truth; None when the noise or the point is unknown);
    infinities of unidentifiable problems are expected, not warned about."""
    with np.errstate(all="ignore"):
        return _cramer_rao(problem, theta)


def _cramer_rao(problem, theta: np.ndarray | None = None) -> dict | None:
    """Bounds at ``theta`` (default: the truth) for the dataset's noise; None if unknown.

    Returns ``rms_floor`` (expected best RMS of the problem's residual components), ``invariant_cov``
    (the CRB covariance of ``problem.invariants``), and the expected error sizes
    ``offset_bound`` (``sqrt(tr Cov(o))``) and ``gram_bound`` (relative, for ``W^T W``).

    Time and memory are O(N): nothing of size ``N m × N m`` is formed. With ``J_n`` the ``m × p``
    rows of reading ``n`` and ``Σ_n`` its noise block,

    .. math:: F = \\sum_n J_n^\\top Σ_n^{-1} J_n,\\qquad
              \\mathrm{tr}\\big((I - P) Σ (I - P)^\\top\\big) = \\mathrm{tr}\\,Σ - \\mathrm{tr}(Q^\\top Σ Q)
              = \\sum_n \\mathrm{tr}\\,Σ_n - \\mathrm{tr}\\big(S^{-1} V^\\top (\\textstyle\\sum_n J_n^\\top Σ_n J_n) V S^{-1}\\big)

    (``P = Q Q^T`` idempotent, ``Q = J V S^{-1}`` the left singular vectors of the column-scaled
    ``J`` for its ``rank`` kept singular values ``S``; the singular values and ``V`` come from the
    ``p × p`` Gram matrix ``J^T J``, whose eigenvalues are ``S²``). Only ``p × p`` products of
    ``J`` with itself (``J^T J``, ``J^T Σ^+ J``, ``J^T Σ J``) are formed.
    """
    ds = problem.dataset
    if theta is None:
        theta = problem.truth_theta()
    if theta is None or not ds.noise_std:
        return None
    sigma2 = float(ds.noise_std) ** 2
    problem = noise_free(problem)
    steps = 1e-6 * np.maximum(np.abs(theta), 1e-3 * np.maximum(np.abs(problem.upper - problem.lower), 1e-12))
    jac, g = jacobians(problem, theta, steps)  # (N*m, p), (N, m, 3)
    n, m = g.shape[:2]
    cov_blocks = sigma2 * np.einsum("nik,njk->nij", g, g)  # Σ_n, (N, m, m)
    fisher = _weighted_gram(jac, _pinv_blocks(cov_blocks))  # J^T Σ^+ J
    # invert with the parameters scaled to unit columns: their scales differ by orders of magnitude
    # (a gain vs an offset in nT), and a relative cut-off on the raw matrix would drop whole directions
    d = np.maximum(np.sqrt(np.diag(fisher)), 1e-300)
    cov = np.linalg.pinv(fisher / np.outer(d, d), rcond=1e-10, hermitian=True) / np.outer(d, d)
    h = invariant_jacobian(problem, theta, steps)
    inv_cov = h @ cov @ h.T
    # singular values and right singular vectors of the column-scaled J (column scale must not
    # decide the rank), from its p x p Gram matrix
    gram = jac.T @ jac
    colnorm = np.maximum(np.sqrt(np.diag(gram)), 1e-300)
    eig, vecs = np.linalg.eigh(gram / np.outer(colnorm, colnorm))
    order = np.argsort(eig)[::-1]
    sv = np.sqrt(np.maximum(eig[order], 0.0))
    vecs = vecs[:, order]
    rank = int(np.sum(sv > 1e-6 * sv[0]))
    # an invariant is identifiable only if its gradient lies in the row space of J; otherwise
    # the data cannot pin it down and its bound is infinite (the pseudo-inverse would hide that)
    row_space = vecs[:, :rank].T
    h_scaled = h / colnorm
    outside = np.linalg.norm(h_scaled - (h_scaled @ row_space.T) @ row_space, axis=1)
    blind = outside > 1e-5 * np.maximum(np.linalg.norm(h_scaled, axis=1), 1e-300)
    inv_cov[blind, :] = np.inf
    inv_cov[:, blind] = np.inf
    # expected in-sample RMS of the (unweighted) least-squares fit, block by block
    sandwich = _weighted_gram(jac, cov_blocks) / np.outer(colnorm, colnorm)  # scaled J^T Σ J
    basis = vecs[:, :rank] / sv[:rank]
    explained = float(np.trace(basis.T @ sandwich @ basis))
    total = float(np.einsum("naa->", cov_blocks))
    rms_floor = float(np.sqrt(max(total - explained, 0.0) / (n * m)))  # per residual component
    out = {"rms_floor": rms_floor, "invariant_cov": inv_cov, "identifiable": rank,
           "unidentified_invariants": int(blind.sum())}
    out.update(problem.invariant_bounds(theta, inv_cov))
    return out
