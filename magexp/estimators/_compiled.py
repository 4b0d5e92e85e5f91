"""Compiled (numba) steps of the swarm engine (:mod:`magexp.estimators.swarm`; imported on first
use when numba is available and ``MAGEXP_NUMBA`` is not ``0``).

:func:`engine` compiles the steps around one velocity rule's kernel: the best updates, then the
kernel, the clamp, ``x <- x + v`` and (for ``clip``) the clip, element by element, with exactly the
numbers of the numpy path (:func:`magexp.estimators.swarm.numpy_step`): the same operations in the
same order, no ``fastmath`` (no reassociation, no fused multiply-add), the random numbers drawn by
numpy in the same order. A test runs both paths from one seed, for every rule, bit for bit. Its
``run`` takes a block of iterations with the problem's compiled cost
(:func:`magexp.problems._compiled.swarm_cost`); :func:`circle_sequence` compiles the Circle-map
initialiser (:mod:`magexp.estimators.circle`). numba's disk cache keys a function by its own bytecode,
not the functions it inlines from other modules: :func:`_keyed_on` adds their sources to the key.
"""

from __future__ import annotations

import hashlib
import inspect
import sys
from functools import cache
from pathlib import Path
from types import SimpleNamespace

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
    """The personal bests where ``cost < pcost``, in place, and the global best."""
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
def mean_best(pbest, out):
    """The mean personal best (Yuan 2018 eq 13), :math:`M_j = \\frac1n \\sum_i p_{ij}`."""
    n, d = pbest.shape
    for j in range(d):
        out[j] = pbest[0, j]
    for i in range(1, n):
        for j in range(d):
            out[j] += pbest[i, j]
    for j in range(d):
        out[j] /= n
    return out


def source_of(*objects) -> bytes:
    """The sources of ``objects`` for :func:`_keyed_on`."""
    return b"".join(Path(inspect.getfile(o)).read_bytes() + getattr(o, "__qualname__", "").encode()
                    for o in objects)


def _keyed_on(dispatcher, *sources: bytes):
    """``dispatcher`` cached on disk under its target, signature, bytecode and ``sources``: numba's own key
    pickles a closure's compiled values, which differ in every process (it would recompile in each)."""
    stored = getattr(dispatcher, "_cache", None)
    if getattr(stored, "_index_key", None) is not None:
        code = hashlib.sha256(dispatcher.py_func.__code__.co_code).hexdigest()
        digest = hashlib.sha256(b"".join(sources)).hexdigest()
        stored._index_key = lambda sig, codegen: (sig, codegen.magic_tuple(), (code, digest))
    return dispatcher


@cache
def engine(kernel, needs_mean: bool = False):
    """The compiled steps of the swarm engine around one velocity rule's kernel: one specialisation per rule,
    the kernel inlined, cached under :func:`_keyed_on`'s key (the kernel's source, this module's, the costs')."""
    rule = _jit(kernel)
    key = source_of(kernel, sys.modules[__name__]) + bytes([needs_mean])

    def move(x, v, pbest, g, r, c, limits, clip_box):
        """Every particle moved in place (Ding 2024 eqs 10-11; Yuan 2018 eqs 16-17): the kernel, the clamp to
        ``limits[0]`` (``v_max``), ``x + v`` and, if ``clip_box``, the clip to ``limits[1:3]`` (lower, upper)."""
        n, d = x.shape
        mean = mean_best(pbest, np.empty(d)) if needs_mean else np.full(d, np.nan)  # NaN: read, it shows
        coef = (c[0], c[1], c[2])  # scalars: read once, not once per element (c may alias v for all numba knows)
        for i in range(n):
            for j in range(d):
                vel = rule(i, j, x, v, pbest, g, mean, r, coef)
                v[i, j], x[i, j] = _settle(x[i, j], vel, limits[0, j], limits[1, j], limits[2, j], clip_box)

    move = _keyed_on(_jit(move), key)

    def step(x, v, pbest, pcost, cost, moves, r, c, limits, clip_box):
        """:func:`update_best` with ``cost``, then, if ``moves``, ``move`` with ``r``, ``c``.
        Returns the global best's index (before the move)."""
        g = update_best(x, cost, pbest, pcost)
        if moves:
            move(x, v, pbest, g, r, c, limits, clip_box)
        return g

    def run(x, v, pbest, pcost, history, t, n_iterations, r, coef, limits, clip_box, problem):
        """The global best's index after iterations ``t .. t + n_iterations - 1`` in one call: each the cost
        (iteration 0's already in ``pcost``), :func:`update_best`, ``history``, and for the first ``len(coef)``
        a move.
        """
        kind, data, reference, params = problem
        g = 0
        for k in range(n_iterations):
            cost = pcost if t + k == 0 else swarm_cost(kind, x, data, reference, params)
            g = update_best(x, cost, pbest, pcost)
            history[t + k] = pcost[g]
            if k < coef.shape[0]:
                move(x, v, pbest, g, r[k], coef[k], limits, clip_box)
        return g

    return SimpleNamespace(move=move, step=_keyed_on(_jit(step), key),
                           run=_keyed_on(_jit(run), key, source_of(costs, kernels)))


@_jit
def circle_sequence(z0, n, burn_in, printed):
    """The Circle-map sequence (:meth:`magexp.estimators.initialisers.CircleMap.sequence`)."""
    z = z0.copy()
    out = np.empty((n, z.size))
    for k in range(burn_in + n):
        for j in range(z.size):  # element by element (a row assignment costs seconds of compilation)
            z[j] = _printed_step(z[j]) if printed else _usual_step(z[j])
            if k >= burn_in:
                out[k - burn_in, j] = z[j]
    return out


circle_sequence = _keyed_on(circle_sequence, source_of(circle))
