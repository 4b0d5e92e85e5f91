"""The numba kernels of :mod:`magexp.problems.kernels` (imported on first use; see there).

Loop order: readings outside, particles inside. The inner loop reads the particles'
coefficients as contiguous rows (structure of arrays) and updates one accumulator per
particle, so it vectorises across particles without reassociating any sum (no ``fastmath``:
the same bits in every process and on every call).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from magexp.problems.base import SCALAR

_jit = njit(cache=True, nogil=True, error_model="numpy")


@_jit
def _scalar_coefficients(w, o, centre, scale):
    """(10, P) coefficients; the same formula as ``kernels.scalar_coefficients``."""
    n_p = w.shape[0]
    coef = np.empty((10, n_p))
    s2 = scale * scale
    for p in range(n_p):
        a = np.empty((3, 3))
        for i in range(3):
            for j in range(3):
                a[i, j] = s2 * (w[p, 0, i] * w[p, 0, j] + w[p, 1, i] * w[p, 1, j] + w[p, 2, i] * w[p, 2, j])
        op0 = (o[p, 0] - centre[0]) / scale
        op1 = (o[p, 1] - centre[1]) / scale
        op2 = (o[p, 2] - centre[2]) / scale
        ao0 = a[0, 0] * op0 + a[0, 1] * op1 + a[0, 2] * op2
        ao1 = a[1, 0] * op0 + a[1, 1] * op1 + a[1, 2] * op2
        ao2 = a[2, 0] * op0 + a[2, 1] * op1 + a[2, 2] * op2
        coef[0, p] = a[0, 0]
        coef[1, p] = a[1, 1]
        coef[2, p] = a[2, 2]
        coef[3, p] = a[0, 1]
        coef[4, p] = a[0, 2]
        coef[5, p] = a[1, 2]
        coef[6, p] = -2 * ao0
        coef[7, p] = -2 * ao1
        coef[8, p] = -2 * ao2
        coef[9, p] = ao0 * op0 + ao1 * op1 + ao2 * op2
    return coef


@_jit
def scalar_cost(w, o, centre, scale, u, reference):
    """Total-field RMS of every particle in one pass over the readings."""
    coef = _scalar_coefficients(w, o, centre, scale)
    # contiguous row views (indexing, not tuple unpacking, which types them non-contiguous):
    # the inner loop then vectorises
    c0, c1, c2, c3, c4, c5, c6, c7, c8, c9 = coef[0], coef[1], coef[2], coef[3], coef[4], coef[5], \
        coef[6], coef[7], coef[8], coef[9]
    n_p, n = w.shape[0], u.shape[0]
    acc = np.zeros(n_p)
    for i in range(n):
        x, y, z = u[i, 0], u[i, 1], u[i, 2]
        f0, f1, f2, f3, f4, f5 = x * x, y * y, z * z, 2 * x * y, 2 * x * z, 2 * y * z
        r = reference[i]
        for p in range(n_p):
            q = (f0 * c0[p] + f1 * c1[p] + f2 * c2[p] + f3 * c3[p] + f4 * c4[p]
                 + f5 * c5[p] + x * c6[p] + y * c7[p] + z * c8[p] + c9[p])
            e = np.sqrt(max(q, 0.0)) - r
            acc[p] += e * e
    out = np.empty(n_p)
    for p in range(n_p):
        out[p] = np.sqrt(acc[p] / n)
    return out


@_jit
def _vector_coefficients(w, o):
    """(12, P): rows ``W`` (row-major), then ``o``."""
    n_p = w.shape[0]
    c = np.empty((12, n_p))
    for p in range(n_p):
        for k in range(9):
            c[k, p] = w[p, k // 3, k % 3]
        for k in range(3):
            c[9 + k, p] = o[p, k]
    return c


@_jit
def vector_cost(w, o, readings, reference):
    """``F = sum_i |v_i - W (r_i - o)|`` of every particle in one pass over the readings."""
    c = _vector_coefficients(w, o)
    c0, c1, c2, c3, c4, c5, c6, c7, c8, c9, c10, c11 = c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], \
        c[8], c[9], c[10], c[11]  # contiguous row views, as above
    n_p, n = w.shape[0], readings.shape[0]
    acc = np.zeros(n_p)
    for i in range(n):
        r0, r1, r2 = readings[i, 0], readings[i, 1], readings[i, 2]
        v0, v1, v2 = reference[i, 0], reference[i, 1], reference[i, 2]
        for p in range(n_p):
            d0, d1, d2 = r0 - c9[p], r1 - c10[p], r2 - c11[p]
            e0 = v0 - (c0[p] * d0 + c1[p] * d1 + c2[p] * d2)
            e1 = v1 - (c3[p] * d0 + c4[p] * d1 + c5[p] * d2)
            e2 = v2 - (c6[p] * d0 + c7[p] * d1 + c8[p] * d2)
            acc[p] += np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
    return acc


@_jit
def swarm_cost(kind, thetas, data, reference, params):
    """The cost of every particle ``thetas`` (P, 12) for ``kind`` :data:`~magexp.problems.base.SCALAR`
    (:func:`scalar_cost` on ``u``, ``B_a`` (N, 1), ``params = [c, s]``) or :data:`~magexp.problems.base.VECTOR`
    (:func:`vector_cost`, non-finite values ``inf``): one entry, so that the loop
    :func:`magexp.estimators._compiled.engine` compiles takes the cost as data, not as a function.
    """
    n_p = thetas.shape[0]
    w = np.empty((n_p, 3, 3))
    o = np.empty((n_p, 3))
    for p in range(n_p):
        for k in range(9):
            w[p, k // 3, k % 3] = thetas[p, k]
        for k in range(3):
            o[p, k] = thetas[p, 9 + k]
    if kind == SCALAR:
        # the column as a C-contiguous vector: the same compiled scalar_cost as a direct call
        return scalar_cost(w, o, params[:3], params[3], data, reference.reshape(reference.size))
    f = vector_cost(w, o, data, reference)
    for p in range(n_p):
        if not np.isfinite(f[p]):
            f[p] = np.inf
    return f


@_jit
def scalar_residuals(w, o, readings, reference):
    """``|W (r_i - o)| - B_a,i`` of one calibration."""
    n = readings.shape[0]
    out = np.empty(n)
    for i in range(n):
        d0, d1, d2 = readings[i, 0] - o[0], readings[i, 1] - o[1], readings[i, 2] - o[2]
        b0 = w[0, 0] * d0 + w[0, 1] * d1 + w[0, 2] * d2
        b1 = w[1, 0] * d0 + w[1, 1] * d1 + w[1, 2] * d2
        b2 = w[2, 0] * d0 + w[2, 1] * d1 + w[2, 2] * d2
        out[i] = np.sqrt(b0 * b0 + b1 * b1 + b2 * b2) - reference[i]
    return out
