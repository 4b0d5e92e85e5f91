"""Compiled (numba) steps of the swarm engine (:mod:`magexp.estimators.swarm`; imported on first
use when numba is available and ``MAGEXP_NUMBA`` is not ``0``).

One call per iteration updates the personal bests with the last costs, finds the global best
and then moves the whole swarm in place for the next iteration: the velocity rule, the velocity
clamp, the move ``x <- x + v`` and (for ``clip`` boundaries) the clip to the box, element by
element. It computes exactly the numbers of the numpy path it replaces, operation by operation
and in the same order
(:func:`magexp.estimators.velocity.inertia_velocity`,
:func:`magexp.estimators.rdpso.random_drift_velocity`, ``np.minimum(np.maximum(.))``,
``np.clip``, ``np.copyto``, ``argmin``): no ``fastmath``, so no reassociation and no fused
multiply-add, and the random numbers are drawn by numpy from the run's generator in the same
order as before. A test runs both paths from one seed and compares ``x`` and ``fun`` bit for bit.

:func:`run` goes further: a block of iterations in one call, each with the problem's compiled
cost (:func:`magexp.problems._compiled.swarm_cost`). :func:`circle_sequence` compiles the
Circle-map initialiser's own step functions (:mod:`magexp.estimators.circle`). numba's
on-disk cache keys a function by its own file and bytecode, not by the functions it calls (and
inlines) from other modules: :func:`_keyed_on` adds those modules' sources to the key, so an edit
there recompiles these two instead of loading stale machine code.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
from numba import njit

from magexp.estimators import circle
from magexp.estimators.circle import printed_step, usual_step
from magexp.problems import _compiled as costs
from magexp.problems import kernels
from magexp.problems._compiled import swarm_cost

_jit = njit(cache=True, nogil=True, error_model="numpy")
_printed_step, _usual_step = _jit(printed_step), _jit(usual_step)


@_jit
def _settle(x, vel, vmax, lower, upper, clip_box):
    """``(v, x)`` of one coordinate: ``vel`` clamped to ``[-vmax, vmax]``, then ``x + v``, clipped
    to ``[lower, upper]`` if ``clip_box`` (NaN propagates, as through ``np.maximum``/``np.minimum``/
    ``np.clip``). Scalars only: no array crosses the call (no reference counting per element)."""
    if vel < -vmax:
        vel = -vmax
    if vel > vmax:
        vel = vmax
    pos = x + vel
    if clip_box:
        if pos < lower:
            pos = lower
        if pos > upper:
            pos = upper
    return vel, pos


@_jit
def update_best(x, cost, pbest, pcost):
    """Personal bests where ``cost < pcost``; returns the first index of the smallest ``pcost``
    (the first NaN if there is one, as ``argmin``)."""
    n, d = x.shape
    for i in range(n):
        if cost[i] < pcost[i]:
            pcost[i] = cost[i]
            for j in range(d):
                pbest[i, j] = x[i, j]
    best = 0
    for i in range(n):
        if np.isnan(pcost[i]):
            return i
        if pcost[i] < pcost[best]:
            best = i
    return best


@_jit
def inertia_move(x, v, pbest, g, r, w, c1, c2, limits, clip_box):
    """``v <- w v + c1 r1 (p - x) + c2 r2 (p_g - x)`` (Ding 2024 eq 10), clamp, move, clip, in
    place; ``r`` (2, n, d) holds ``r1, r2``, ``limits`` (3, d) ``v_max``, lower, upper."""
    n, d = x.shape
    for i in range(n):
        for j in range(d):
            xij = x[i, j]
            vel = w * v[i, j] + c1 * r[0, i, j] * (pbest[i, j] - xij) + c2 * r[1, i, j] * (pbest[g, j] - xij)
            v[i, j], x[i, j] = _settle(xij, vel, limits[0, j], limits[1, j], limits[2, j], clip_box)


@_jit
def drift_move(x, v, pbest, g, r, log_u, alpha, c1, c2, limits, clip_box):
    """``v <- α |M - x| φ + c1 r1 (p - x) + c2 r2 (p_g - x)`` (Yuan 2018 eq 16, ``M`` the mean
    personal best summed row by row as ``pbest.mean(axis=0)``), clamp, move, clip, in place;
    ``r`` (4, n, d) holds ``r1, r2, s, ·`` and ``log_u`` ``ln(1/u)``: ``φ = ±ln(1/u)``, ``+`` where
    ``s > 0.5`` (eq 14; a product with ±1, exact)."""
    n, d = x.shape
    mean = pbest[0].copy()
    for i in range(1, n):
        for j in range(d):
            mean[j] += pbest[i, j]
    for j in range(d):
        mean[j] /= n
    for i in range(n):
        for j in range(d):
            xij = x[i, j]
            phi = log_u[i, j] if r[2, i, j] > 0.5 else -1.0 * log_u[i, j]
            vel = alpha * np.abs(mean[j] - xij) * phi + c1 * r[0, i, j] * (pbest[i, j] - xij) \
                + c2 * r[1, i, j] * (pbest[g, j] - xij)
            v[i, j], x[i, j] = _settle(xij, vel, limits[0, j], limits[1, j], limits[2, j], clip_box)


@_jit
def inertia_step(x, v, pbest, pcost, cost, move, r, w, c1, c2, limits, clip_box):
    """:func:`update_best` with ``cost``, then, if ``move``, :func:`inertia_move`.
    Returns the global best's index (before the move)."""
    g = update_best(x, cost, pbest, pcost)
    if move:
        inertia_move(x, v, pbest, g, r, w, c1, c2, limits, clip_box)
    return g


@_jit
def drift_step(x, v, pbest, pcost, cost, move, r, log_u, alpha, c1, c2, limits, clip_box):
    """:func:`update_best` with ``cost``, then, if ``move``, :func:`drift_move`.
    Returns the global best's index (before the move)."""
    g = update_best(x, cost, pbest, pcost)
    if move:
        drift_move(x, v, pbest, g, r, log_u, alpha, c1, c2, limits, clip_box)
    return g


def _keyed_on(dispatcher, *modules):
    """``dispatcher`` with the sources of ``modules`` (those its code calls into) in its on-disk
    cache key (numba's key holds the function's own bytecode only); unchanged if this numba keeps
    its cache otherwise."""
    cache = getattr(dispatcher, "_cache", None)
    key = getattr(cache, "_index_key", None)
    if key is not None:
        digest = hashlib.sha256(b"".join(Path(m.__file__).read_bytes() for m in modules)).hexdigest()
        cache._index_key = lambda sig, codegen: (*key(sig, codegen), digest)
    return dispatcher


@_jit
def run(x, v, pbest, pcost, history, t, n_iterations, r, log_u, coef, drift, limits, clip_box, kernel):
    """Iterations ``t .. t + n_iterations - 1`` of the swarm in one call, each: the cost of every
    particle (:func:`magexp.problems._compiled.swarm_cost` with ``kernel = (kind, data,
    reference, params)``; iteration 0, the initial swarm, has its costs in ``pcost`` already),
    :func:`update_best`, ``history[t] = pcost[g]`` and, for the first ``len(coef)`` of them, the
    move (:func:`drift_move` if ``drift``, else :func:`inertia_move`) with the draws ``r[k]`` (and
    ``log_u[k]``) and the coefficients ``coef[k]`` (``w, c1, c2`` or ``α, c1, c2``). Returns the
    global best's index."""
    kind, data, reference, params = kernel
    g = 0
    for k in range(n_iterations):
        cost = pcost if t + k == 0 else swarm_cost(kind, x, data, reference, params)
        g = update_best(x, cost, pbest, pcost)
        history[t + k] = pcost[g]
        if k < coef.shape[0]:
            if drift:
                drift_move(x, v, pbest, g, r[k], log_u[k], coef[k, 0], coef[k, 1], coef[k, 2], limits, clip_box)
            else:
                inertia_move(x, v, pbest, g, r[k], coef[k, 0], coef[k, 1], coef[k, 2], limits, clip_box)
    return g


@_jit
def circle_sequence(z0, n, burn_in, printed):
    """:meth:`magexp.estimators.initialisers.CircleMap.sequence`: ``burn_in`` steps of the Circle
    map (``printed`` or ``usual`` form, the same functions compiled) from ``z0``, then the ``n``
    further iterates as rows; coordinate by coordinate, as numpy's element-wise steps."""
    z = z0.copy()
    out = np.empty((n, z.size))
    for k in range(burn_in + n):
        for j in range(z.size):  # element by element (a row assignment costs seconds of compilation)
            z[j] = _printed_step(z[j]) if printed else _usual_step(z[j])
            if k >= burn_in:
                out[k - burn_in, j] = z[j]
    return out


run = _keyed_on(run, costs, kernels)
circle_sequence = _keyed_on(circle_sequence, circle)
