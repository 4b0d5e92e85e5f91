"""Fused (single-pass) swarm costs: every particle's objective in one pass over the readings.

Each kernel reads every reading once, keeps one accumulator per particle and never forms an ``N × P``
array (memory ``O(P + N)``). A compiled one (``numba.njit``, ``cache=True``; reading loop outside,
particle loop inside, so the inner loop vectorises without reassociating any sum: no ``fastmath``, no
threads) and a pure-numpy fallback (chunks of at most :data:`CHUNK` particle-readings, used when numba
is missing or ``MAGEXP_NUMBA=0``: the same operations in the same order, no BLAS product) compute the
same numbers: a particle's cost depends neither on the particles evaluated with it nor on the chunks.

numba is imported on the first swarm-cost call only: a closed-form run (``ellipsoid``, ``lm``) on
fewer than :data:`COMPILE_MIN_READINGS` readings never pays for it; from that size on, the scalar
residuals are compiled too (the O(N) bound evaluates them many times).

Scalar objective (Ding 2024, eq 17), with readings centred and scaled, ``u = (r - c)/s``:

.. math:: \\mathrm{RMS}_p = \\sqrt{\\tfrac1N \\textstyle\\sum_i \\big(\\sqrt{\\max(\\mathbf f_i^\\top
          \\mathbf a_p, 0)} - B_{a,i}\\big)^2},\\quad
          \\mathbf f_i = [x^2, y^2, z^2, 2xy, 2xz, 2yz, x, y, z, 1]_i

and ``a_p`` the ten coefficients of ``|W_p (r - o_p)|² = u^T A u - 2 o'^T A u + o'^T A o'``
(``A = s² W^T W``, ``o' = (o - c)/s``; :func:`scalar_coefficients`): ten multiply-adds and one square
root per particle-reading.

Vector objective (Yuan 2018, eq 8), each component formed as in the direct formula (no expansion of
the squared norm), so ``F`` is exact to rounding at a noise-free optimum:

.. math:: F_p = \\textstyle\\sum_i \\lVert \\mathbf v_i - W_p(\\mathbf r_i - \\mathbf o_p)\\rVert,
          \\quad \\mathbf v_i = C_i^b \\mathbf H_i
"""

from __future__ import annotations

import importlib.util
import os
from contextlib import contextmanager
from contextvars import ContextVar
from functools import cache

import numpy as np

from magexp.core.ellipsoid import quadratic_features
from magexp.errors import MagexpError

CHUNK = 1 << 16  # particle-readings per temporary of the numpy fallback
#: float64 temporaries of the numpy fallback per particle-reading of a chunk, by the components of a
#: reading's residual: the scalar cost (1) holds the product, its root, the error and its square; the
#: vector cost (3) the three differences ``d``, a row of ``W d``, a scratch array, the sum of squares and
#: numpy's transients (tracemalloc: 7.9 and 9.0 chunks at 5 000 and 50 particles)
CHUNK_TEMPORARIES = {1: 4, 3: 10}
#: float64 numbers the fused kernel holds per particle (its coefficients, accumulator and result)
FUSED_FLOATS_PER_PARTICLE = 14
#: float64 numbers the numpy fallback holds per particle beside its chunks: the coefficients and the
#: products that form them (tracemalloc: 29 a particle for the scalar cost, 100 000 particles)
FALLBACK_FLOATS_PER_PARTICLE = 32
COMPILE_MIN_READINGS = 1 << 14  # residuals of fewer readings stay in numpy (no numba import)


#: False within :func:`numpy_only`: the calls made there take the numpy path whatever ``MAGEXP_NUMBA`` says
_COMPILED_ALLOWED = ContextVar("magexp_compiled_allowed", default=True)


def fused_enabled() -> bool:
    """Whether the compiled kernels are wanted and installed (``MAGEXP_NUMBA`` not ``0``, numba
    findable, not within :func:`numpy_only`), without importing numba: the path :func:`compiled` takes.
    """
    return (_COMPILED_ALLOWED.get() and os.environ.get("MAGEXP_NUMBA", "1") != "0"
            and importlib.util.find_spec("numba") is not None)


def working_floats(n_particles: int, rows: int = 1, *, fused: bool | None = None) -> int:
    """float64 numbers one swarm-cost call holds beyond the problem's data, on the path it takes (``fused``: None
    as :func:`fused_enabled` says, False the numpy fallback): :data:`FUSED_FLOATS_PER_PARTICLE` a particle
    compiled; in numpy :data:`CHUNK_TEMPORARIES` chunks of ``max(CHUNK, rows P)`` and the coefficients.
    """
    if fused_enabled() if fused is None else fused:
        return FUSED_FLOATS_PER_PARTICLE * n_particles
    per_chunk = max(CHUNK, rows * n_particles)
    return (CHUNK_TEMPORARIES[rows] * per_chunk + 10 * max(1, per_chunk // max(rows * n_particles, 1))
            + FALLBACK_FLOATS_PER_PARTICLE * n_particles)


@contextmanager
def numpy_only(on: bool = True):
    """Within the block (this thread or task only), :func:`compiled` is None when ``on``: ``magexp calibrate``'s
    ``compiled=False`` as an argument rather than the process's environment."""
    token = _COMPILED_ALLOWED.set(_COMPILED_ALLOWED.get() and not on)
    try:
        yield
    finally:
        _COMPILED_ALLOWED.reset(token)


def compiled():
    """The numba kernels (a namespace), or None when numba is unavailable, ``MAGEXP_NUMBA=0``, or within
    :func:`numpy_only`.
    """
    return _loaded() if _COMPILED_ALLOWED.get() else None


@cache
def _loaded():
    """The numba kernels, or None when numba is unavailable or ``MAGEXP_NUMBA=0`` (read once: :func:`compiled`)."""
    if not fused_enabled():
        return None
    try:  # lazy: numba, measured 205 ms CPU to import (min of 5, after numpy), which a closed-form run (lm, ellipsoid) never pays
        from magexp.problems import _compiled
    except ImportError:  # numba not installed
        return None
    return _compiled


compiled.cache_clear = _loaded.cache_clear  # MAGEXP_NUMBA read again (the tests change it)


def swarm_cost(kernel: tuple, thetas: np.ndarray) -> np.ndarray:
    """The cost of every particle ``thetas`` (P, 12) in one compiled call on a problem's prepared ``kernel``
    (:meth:`magexp.problems.base.CalibrationProblem.swarm_kernel`), with no per-call conversion."""
    thetas = np.ascontiguousarray(thetas, float)
    if thetas.ndim != 2:
        thetas = thetas.reshape(1, -1)
    if thetas.shape[1] != 12:  # the compiled kernel reads 12 columns unchecked
        raise MagexpError(f"parameter vectors of shape {thetas.shape} are not allowed: the cost takes (n, 12)")
    return compiled().swarm_cost(kernel[0], thetas, kernel[1], kernel[2], kernel[3])


# -- scalar objective ----------------------------------------------------------------------------
def scalar_coefficients(w: np.ndarray, o: np.ndarray, centre: np.ndarray, scale: float) -> np.ndarray:
    """The ten quadratic-form coefficients of every particle, shape ``(P, 10)`` (module docstring),
    element by element in the compiled kernel's order (no sum left to a library).
    """
    a = scale * scale * (w[:, 0, :, None] * w[:, 0, None, :] + w[:, 1, :, None] * w[:, 1, None, :]
                         + w[:, 2, :, None] * w[:, 2, None, :])
    op = (o - centre) / scale
    ao = a[:, :, 0] * op[:, None, 0] + a[:, :, 1] * op[:, None, 1] + a[:, :, 2] * op[:, None, 2]
    return np.column_stack([a[:, 0, 0], a[:, 1, 1], a[:, 2, 2], a[:, 0, 1], a[:, 0, 2], a[:, 1, 2],
                            -2 * ao, ao[:, 0] * op[:, 0] + ao[:, 1] * op[:, 1] + ao[:, 2] * op[:, 2]])


def _chunks(n: int, n_particles: int):
    """Slices of the ``n`` readings, at most :data:`CHUNK` particle-readings each: the numpy fallback's
    bound on memory."""
    step = max(1, CHUNK // max(n_particles, 1))
    return (slice(k, min(k + step, n)) for k in range(0, n, step))


def _add_rows(acc: np.ndarray, terms: np.ndarray) -> None:
    """``acc += terms[0] + terms[1] + ...`` row after row, the compiled accumulators' order (``terms`` overwritten),
    so a particle's sum depends on neither its neighbours nor the chunks; a lone column, which numpy would
    sum pairwise, is accumulated.
    """
    terms[0] += acc
    if terms.shape[1] == 1:
        acc[0] = np.add.accumulate(terms[:, 0])[-1]
    else:
        np.add.reduce(terms, axis=0, out=acc)


def scalar_cost_numpy(w, o, centre, scale, u, reference) -> np.ndarray:
    """Total-field RMS of every particle (fallback), chunk by chunk, in the compiled kernel's order element by
    element (no BLAS product, whose sums would depend on the other particles; :func:`_add_rows`)."""
    coef = scalar_coefficients(w, o, centre, scale).T.copy()  # (10, P), contiguous rows
    acc = np.zeros(coef.shape[1])
    for rows in _chunks(len(u), coef.shape[1]):
        f = quadratic_features(u[rows]).T[:, :, None]  # (10, rows, 1)
        q, tmp = f[0] * coef[0], np.empty((rows.stop - rows.start, coef.shape[1]))
        for k in range(1, 10):
            q += np.multiply(f[k], coef[k], out=tmp)
        err = np.sqrt(np.maximum(q, 0.0, out=q), out=q)
        err -= reference[rows, None]
        _add_rows(acc, np.multiply(err, err, out=err))
    return np.sqrt(acc / len(u))


def scalar_cost(w, o, centre, scale, u, reference) -> np.ndarray:
    """Total-field RMS of every particle, ``(P,)``, from ``W`` (P, 3, 3), ``o`` (P, 3), the
    normalisation ``centre``, ``scale``, the normalised readings ``u`` (N, 3) and ``B_a`` (N,).
    """
    nb = compiled()
    if nb is None:
        return scalar_cost_numpy(w, o, centre, scale, u, reference)
    return nb.scalar_cost(np.ascontiguousarray(w, float), np.ascontiguousarray(o, float),
                          np.asarray(centre, float), float(scale), u, reference)


def scalar_residuals(w, o, readings, reference) -> np.ndarray:
    """``|W (r_i - o)| - B_a,i`` of one calibration, ``(N,)`` (compiled for large ``N``)."""
    nb = compiled() if len(readings) >= COMPILE_MIN_READINGS else None
    if nb is None:
        return np.linalg.norm((readings - o) @ w.T, axis=1) - reference
    return nb.scalar_residuals(np.ascontiguousarray(w, float), np.ascontiguousarray(o, float), readings, reference)


# -- vector objective ----------------------------------------------------------------------------
def vector_cost_numpy(w, o, readings, reference, *, squared: bool = False) -> np.ndarray:
    """``F`` of every particle (fallback), chunk by chunk, in the compiled kernel's order element by element
    (:func:`_add_rows`); ``squared=True`` sums ``|e_i|^2`` instead of ``|e_i|`` (the least-squares form)."""
    acc = np.zeros(len(w))
    for rows in _chunks(len(readings), len(w)):
        r, v = readings[rows], reference[rows]
        d = [r[:, k, None] - o[:, k] for k in range(3)]  # (rows, P) each
        tmp, sq = np.empty_like(d[0]), None
        for j in range(3):
            e = w[:, j, 0] * d[0]
            e += np.multiply(w[:, j, 1], d[1], out=tmp)
            e += np.multiply(w[:, j, 2], d[2], out=tmp)
            e = np.subtract(v[:, j, None], e, out=e)
            e *= e
            sq = e if sq is None else np.add(sq, e, out=sq)
        _add_rows(acc, sq if squared else np.sqrt(sq, out=sq))
    return acc


def vector_cost(w, o, readings, reference) -> np.ndarray:
    """``F`` of every particle, ``(P,)``, from ``W`` (P, 3, 3), ``o`` (P, 3), readings and
    reference vectors ``v_i`` (N, 3); non-finite values become ``inf``.
    """
    nb = compiled()
    with np.errstate(invalid="ignore", over="ignore"):
        if nb is None:
            f = vector_cost_numpy(w, o, readings, reference)
        else:
            f = nb.vector_cost(np.ascontiguousarray(w, float), np.ascontiguousarray(o, float), readings, reference)
    return np.where(np.isfinite(f), f, np.inf)
